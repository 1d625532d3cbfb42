"""What a design run writes: the JSON report, the figures and the profile files.

``report`` formats a :class:`camjax.pipeline.DesignRun` as a JSON-ready dict, ``plots`` draws
:class:`camjax.evaluate.DesignCurves` (matplotlib loads only when drawing) and ``export`` writes
the profile CSV, DXF and the PNG figures; ``files`` writes strict JSON; ``folder`` checks a
command's output folder before any work, stages it and swaps it in whole.
``animation`` draws the mechanism turning (``motion.gif``) from plain arrays, and
``plots_dynamics`` the figures of a :class:`camjax.dynamics.DynamicsReport`.
"""
