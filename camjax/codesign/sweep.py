"""``camjax sweep`` of a co-design scene: the laws and the geometry co-designed at every weighting.

A scene with [design] and ``design = true`` segments has no fixed motion to sweep the geometry
around: at each (alpha, gamma) of the sweep the laws are co-designed with the geometry at that
weighting (:func:`camjax.codesign.search.codesign_outcome` on the scene with ``design.alpha`` and
``design.gamma`` replaced: the bilevel search, the best built-in combination its floor), and the
sweep point is the [design] solve of the scene with the chosen laws fixed, by the scene's solver,
mode and seed: what ``camjax design --alpha a --gamma g`` writes for that scene, bit for bit
(tests/test_codesign_sweep.py). The rows are the plain sweep's (:class:`camjax.solvers.sweep.SweepResult`)
with a ``codesign`` block each: which laws were chosen and the co-design objective.

One co-design per weighting, in a Python loop with a progress bar (each takes seconds to minutes).
The weightings share the co-design's compiled pieces (the weights are an argument of them, as in
``camjax design``: :class:`camjax.codesign.problem.ProblemShape`) and the built-in laws'
kinematics and residuals (:attr:`Codesign.builtin_cache`), which do not depend on the weights.

Python (a driver of jitted pieces): not traceable.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from camjax.codesign.problem import Codesign, check_scene
from camjax.codesign.search import MAX_ITERATIONS, Outcome, codesign_outcome


def codesign_sweep(scene, alphas, gammas, *, samples: int | None = None, progress: bool | None = None,
                   max_iterations: int = MAX_ITERATIONS):
    """Co-design ``scene``'s designed laws and its geometry at every (alpha, gamma) pair of two lists
    (alpha-major, as :func:`camjax.solvers.sweep.weight_grid`); the geometry of each weighting's
    chosen laws is its sweep point, solved by the scene's [design] mode, solver and seed.

    Args:
      scene: a scene with [design] and designed segments (``mode = "global"``).
      samples: the co-design's search grid (default the scene's ``motion.samples``).
      progress: a tqdm bar (stderr) over the weightings; default when there is more than one.
      max_iterations: BFGS steps of each search.
    Returns:
      :class:`camjax.solvers.sweep.SweepResult`: each row the plain sweep's, plus ``codesign``
      (:func:`codesign_record`).
    Raises :class:`camjax.codesign.problem.CodesignError` (naming the scene field) for what the
    co-design does not take.
    """
    from tqdm.auto import tqdm

    from camjax.solvers.registry import check_weights
    from camjax.solvers.sweep import SweepResult, pareto_mask, weight_grid

    a, g = weight_grid(alphas, gammas)
    if a.size == 0:
        raise ValueError("alpha, gamma: the sweep needs at least one weighting")
    check_weights(a, g)
    check_scene(scene)  # what the co-design refuses, before the first weighting's work
    d = scene.design
    cache: dict = {}  # the built-in laws' kinematics and residuals: the same at every weighting
    rows = []
    show = a.size > 1 if progress is None else progress
    for alpha, gamma in tqdm(list(zip(a, g, strict=True)), desc=f"co-design sweep ({d.solver}, {d.mode})",
                             unit="weighting", disable=not show):
        rows.append(codesign_point(scene, float(alpha), float(gamma), samples, max_iterations, cache)[0])
    result = SweepResult(d.mode, d.solver, rows, np.zeros(len(rows), bool))
    column = result.column
    mask = pareto_mask(column("size_mm"), column("stress_max_MPa"), column("feasible", bool))
    return SweepResult(d.mode, d.solver, rows, mask)


def codesign_point(scene, alpha: float, gamma: float, samples: int | None = None,
                   max_iterations: int = MAX_ITERATIONS, cache: dict | None = None
                   ) -> tuple[dict[str, Any], Outcome]:
    """One weighting of :func:`codesign_sweep`: (its pareto.json row, the co-design's outcome).

    The laws are co-designed on the scene with [design]'s alpha, gamma replaced; the row is the
    [design] solve (:func:`camjax.solvers.base.solve`, the scene's mode, solver and seed) of the
    scene with the chosen laws fixed, as ``camjax design`` solves it, and its ``codesign`` block.
    ``cache``: :attr:`Codesign.builtin_cache` shared between the weightings of one sweep.
    """
    import dataclasses

    from camjax.solvers.base import problem_from_scene, solve

    design = dataclasses.replace(scene.design, alpha=alpha, gamma=gamma)
    weighted = dataclasses.replace(scene, design=design)
    start = time.perf_counter()
    outcome = codesign_outcome(Codesign(weighted, samples, builtin_cache=cache), max_iterations)
    fixed = outcome.scene
    problem = problem_from_scene(fixed)
    d = fixed.design
    sol = solve(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver, seed=d.seed)
    row = sol.record(problem)
    row["codesign"] = codesign_record(outcome, row["objective"], time.perf_counter() - start)
    return row, outcome


def codesign_record(outcome: Outcome, design_objective: float, seconds: float) -> dict[str, Any]:
    """A sweep row's ``codesign`` block: the chosen laws (``chosen``: ``codesign`` or
    ``best_builtin``; ``laws``: per designed segment ``bspline`` or the built-in law's name;
    ``scene_segments``: the chosen laws as fixed [motion] segments), the co-design objective on the
    search grid (``objective``) and of the written geometry (``objective_exact``: the row's
    objective plus the [synthesis] terms), the search's best and the best built-in combination,
    each with its own optimal geometry; the keys of result.json's ``synthesis.codesign``."""
    best = outcome.best_builtin
    if best is not None and not math.isfinite(best[1]):  # no built-in combination is feasible
        best = None
    finite = math.isfinite(outcome.codesign_objective)
    return {
        "chosen": outcome.chosen,
        "laws": [table["law"] for table in outcome.tables],
        "objective": float(outcome.objective),
        "objective_exact": float(design_objective) + float(outcome.law_objective),
        "design_objective": float(design_objective),
        "law_objective": float(outcome.law_objective),
        "codesign_objective": float(outcome.codesign_objective) if finite else None,
        "best_builtin": None if best is None else {"law": list(best[0]), "objective": float(best[1])},
        "improvement": None if best is None else float((best[1] - outcome.objective) / best[1]),
        "iterations": int(outcome.iterations),
        "start": outcome.start,
        "method": outcome.method,
        "inner_solves": int(outcome.evaluations),
        "samples": int(outcome.samples),
        "spring": outcome.spring,
        "scene_segments": outcome.tables,
        "seconds": float(seconds),
    }
