"""What a design run writes: the JSON report, the figures and the profile files.

``report`` holds the blocks every follower's result.json shares and builds a run's report (each
follower's ``report.py`` assembles its own, :mod:`camjax.followers`); ``plots`` holds what every
figure shares (the figures are each follower family's, drawn without JAX); ``export`` writes the
profile CSV, DXF and the PNG figures; ``files`` writes strict JSON; ``folder`` checks a command's
output folder before any work, stages it and swaps it in whole; ``drawing`` draws in processes of
their own. ``animation`` draws the mechanism turning (``motion.gif``) from plain arrays, and
``plots_dynamics`` the figures of a :class:`camjax.dynamics.DynamicsReport`.
"""
