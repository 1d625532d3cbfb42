"""Scene -> arrays -> problem -> solve -> curves: the one place a scene's design is run.

Data flows one way and each step is a pure function of the one before:

1. :func:`camjax.evaluate.scene_arrays` evaluates what the scene declares (once per scene);
2. the scene's follower (:mod:`camjax.followers`) runs its design: the [design] solved by
   :mod:`camjax.solvers` (the one place an optimizer plugs in), the smallest admissible cam, the
   radius the cam is drawn at, the curves there and the constraints they break.

:func:`run_design` returns that run, typed (the follower family's ``DesignRun`` or ``RockerRun``);
:func:`analyse` adds the report dict its follower's ``report.py`` formats (:func:`design_report`:
the dict alone). :func:`sweep_scene` solves the
[design] problem for many weightings in this process (the CLI hands blocks to
``camjax.scaleout`` instead when asked; a scene with designed laws co-designs them at every
weighting, :mod:`camjax.codesign.sweep`). Nothing here formats, draws or writes files
(:mod:`camjax.output` and :mod:`camjax.cli` do).
"""

from __future__ import annotations

from typing import Any, NamedTuple

from camjax import followers
from camjax.evaluate import SceneArrays
from camjax.scene import Scene


def design_problem(scene: Scene, arrays: SceneArrays | None = None, *, samples: int | None = None):
    """The design problem of the scene's [design] section (its follower's ``problem.py``)."""
    from camjax.solvers.base import problem_from_scene

    return problem_from_scene(scene, arrays, samples=samples)


def run_design(scene: Scene, arrays: SceneArrays | None = None, *,
               base_radius_mm: float | None = None, dtype=None):
    """Run every model the scene declares: arrays, the design, the smallest cam, the curves.

    Args:
      scene: a validated scene.
      arrays: precomputed :func:`camjax.evaluate.scene_arrays` (computed here if None).
      base_radius_mm: evaluate and draw the geometry at this base radius instead of the design's
        (or, without a [design], instead of the smallest admissible radius + 1 mm, rounded up).
      dtype: floating dtype when ``arrays`` is computed here (default float64).
    Returns:
      the follower family's run (``.curves`` are what its drawing module draws; its report
      formats the whole run).
    """
    return followers.of(scene).run(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)


class Report(NamedTuple):
    """A scene's report (JSON-ready dict) with the curves and arrays behind it."""

    data: dict[str, Any]
    curves: Any  # the follower family's curves (what its drawing module draws)
    arrays: SceneArrays


def analyse(scene: Scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> Report:
    """:func:`run_design` and its report dict, formatted by the follower's ``report.py`` (see
    :func:`run_design` for the arguments)."""
    run = run_design(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)
    return Report(followers.of(scene).report(scene, run), run.curves, run.arrays)


def design_report(scene: Scene, arrays: SceneArrays | None = None, *,
                  base_radius_mm: float | None = None, dtype=None) -> dict[str, Any]:
    """The report of a scene as a plain, JSON-ready dict (see :func:`run_design` for the
    arguments)."""
    return analyse(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype).data


def sweep_scene(scene: Scene, alphas, gammas, *, mode: str, solver: str, seed: int = 0,
                chunk_size: int | None = None):
    """Solve the scene's [design] problem for every (alpha, gamma) pair of two lists, in this process.

    A scene with designed segments (``design = true``) co-designs its laws with the geometry at
    every weighting (:func:`camjax.codesign.sweep.codesign_sweep`, one weighting at a time:
    ``chunk_size`` does not apply; ``mode`` must be "global").

    Returns :class:`camjax.solvers.sweep.SweepResult` (its ``records()`` are the JSON rows).
    A scene with [design] robust is refused (:func:`camjax.robust.design.refuse_sweep`).
    """
    from camjax.robust.design import refuse_sweep

    refuse_sweep(scene)
    if scene.motion.designed:
        from camjax.codesign.sweep import codesign_sweep
        from camjax.scene import with_design

        return codesign_sweep(with_design(scene, mode=mode, solver=solver, seed=seed), alphas, gammas)
    from camjax.solvers.sweep import sweep

    problem = design_problem(scene)
    return sweep(problem, alphas, gammas, mode=mode, solver=solver, seed=seed,
                 chunk_size=chunk_size)
