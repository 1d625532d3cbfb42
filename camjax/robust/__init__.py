"""Robust cams: a scene's [tolerances] sampled, the nominal design evaluated for every sample in one
batched program, sensitivities by autodiff (:mod:`camjax.robust.tolerances`,
:mod:`camjax.robust.evaluate`, :mod:`camjax.robust.report`; the command is ``camjax robust``), and
designs that keep their limits over a fraction of the samples (:mod:`camjax.robust.design`,
``[design] robust``)."""
