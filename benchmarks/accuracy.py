"""Benchmark 3: the speed/accuracy trade (grid size N, float32/float64, solver iterations).

Every configuration's figures are compared with a float64, 36 000-sample reference of the same
figures: the smallest base radius with rho >= 0 (curvature only), the optimal base radius of the
global problem (alpha = gamma = 1, exact by bisection: :func:`camjax.followers.flat.problem.global_optimum`),
the peak cam force and the peak contact stress at the reference optimum design (so that it
measures the grid, not a moved design). Time is the steady-state time of one jitted call that
goes scene -> kinematics -> loads -> problem -> those figures.

The solver knobs (gradient iterations, GA population and generations) run on the default N = 360,
float64 grid; their error is measured against the same 36 000-sample reference and against the
exact optimum on their own grid (the solver's own error).
"""

from __future__ import annotations

import dataclasses
from functools import partial

import jax
import jax.numpy as jnp

from benchmarks.harness import time_jit
from camjax import evaluate
from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import ga, gradient

SAMPLES = (90, 180, 360, 720, 3600, 36000)
REFERENCE_SAMPLES = 36000
DEFAULT_SAMPLES = 360
FIGURES = ("min_base_radius_mm", "optimal_base_radius_mm", "peak_force_N", "peak_stress_MPa")


def _with_program(scene, program):
    """The scene with its motion program replaced (lets the lifts be traced arguments)."""
    return dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, program=program))


def design_figures(program, design, scene, samples: int, dtype) -> dict:
    """Scene -> the four figures on an N-sample grid (traceable; ``scene`` and N are static)."""
    sc = _with_program(scene, program)
    arrays = evaluate.scene_arrays(sc, samples=samples, dtype=dtype)
    problem = P.problem_from_scene(sc, arrays, extrema="grid")
    weights = weights_of(1.0, 1.0, dtype)
    need = -(problem.q_mm)
    best = optimum.global_optimum(problem, weights)
    d = jax.tree.map(lambda x: jnp.asarray(x, dtype), design)
    return {
        "min_base_radius_mm": jnp.max(need),
        "optimal_base_radius_mm": best.base_radius_mm,
        "peak_force_N": jnp.max(arrays.force_N),
        "peak_stress_MPa": jnp.max(P.stress(problem, d)),
    }


def _errors(values: dict, reference: dict) -> dict:
    out = {}
    for k in FIGURES:
        err = abs(float(values[k]) - float(reference[k]))
        out[k] = float(values[k])
        out[k + "_abs_error"] = err
        out[k + "_rel_error"] = err / abs(float(reference[k]))
    out["max_rel_error"] = max(out[k + "_rel_error"] for k in FIGURES)
    return out


def reference(scene) -> tuple[dict, P.Design]:
    """Float64, 36 000-sample figures and the reference optimum design."""
    problem = P.problem_from_scene(scene, samples=REFERENCE_SAMPLES, dtype=jnp.float64, extrema="grid")
    best = optimum.global_optimum(problem, weights_of(1.0, 1.0))
    figures = design_figures(scene.motion.program, best, scene, REFERENCE_SAMPLES, jnp.float64)
    return {k: float(v) for k, v in figures.items()}, best


def grid_trade(scene, ref: dict, ref_design, samples, repeats: int) -> list[dict]:
    """Error vs time for each N and dtype."""
    rows = []
    for dtype in (jnp.float64, jnp.float32):
        for n in samples:
            fn = partial(design_figures, scene=scene, samples=n, dtype=dtype)
            t, out = time_jit(fn, scene.motion.program, ref_design, repeats=repeats)
            rows.append(
                {
                    "knob": "grid",
                    "samples": n,
                    "dtype": jnp.dtype(dtype).name,
                    "time_s": t.median_s,
                    "compile_s": t.compile_s,
                    "default": n == DEFAULT_SAMPLES and dtype == jnp.float64,
                    **_errors(out, ref),
                }
            )
    return rows


def _solver_row(knob: str, label: str, t, design, exact_mm: float, ref: dict, default: bool) -> dict:
    r = float(design.base_radius_mm)
    rel_error = abs(r - ref["optimal_base_radius_mm"]) / ref["optimal_base_radius_mm"]
    return {
        "knob": knob,
        "setting": label,
        "samples": DEFAULT_SAMPLES,
        "dtype": "float64",
        "time_s": t.median_s,
        "compile_s": t.compile_s,
        "default": default,
        "optimal_base_radius_mm": r,
        "optimal_base_radius_mm_abs_error": abs(r - ref["optimal_base_radius_mm"]),
        "optimal_base_radius_mm_rel_error": rel_error,
        "solver_abs_error_mm": abs(r - exact_mm),
        "max_rel_error": rel_error,
    }


def solver_trade(scene, ref: dict, quick: bool, repeats: int) -> list[dict]:
    """Gradient iterations and GA population x generations on the default grid (global, alpha=gamma=1)."""
    problem = P.problem_from_scene(scene, samples=DEFAULT_SAMPLES, extrema="grid")
    weights = weights_of(1.0, 1.0)
    exact_mm = float(optimum.global_optimum(problem, weights).base_radius_mm)
    rows = []
    default_steps = gradient.DEFAULT_SETTINGS.max_steps
    steps = (20, default_steps) if quick else (10, 20, 40, 80, 160, 400, 1000, default_steps)
    for k in sorted(set(steps)):
        settings = dataclasses.replace(gradient.DEFAULT_SETTINGS, max_steps=k)
        fn = partial(gradient.minimize, settings=settings)
        t, res = time_jit(fn, problem, weights, repeats=repeats)
        rows.append(
            _solver_row(
                "gradient",
                f"max_steps={k} (used {int(res.iterations)})",
                t,
                res.design,
                exact_mm,
                ref,
                k == default_steps,
            )
        )
    d = ga.DEFAULT_SETTINGS
    combos = (
        [(d.population, d.generations)]
        if quick
        else [
            (20, 50),
            (20, 200),
            (48, 60),
            (d.population, d.generations),
            (48, 400),
            (200, 120),
            (200, 400),
            (1000, 400),
        ]
    )
    key = jax.random.key(0)
    for pop, gens in combos:
        settings = dataclasses.replace(d, population=pop, generations=gens)
        fn = partial(ga.run, settings=settings)
        t, res = time_jit(fn, key, problem, weights, repeats=repeats)
        rows.append(
            _solver_row(
                "ga",
                f"population={pop} generations={gens}",
                t,
                res.design,
                exact_mm,
                ref,
                (pop, gens) == (d.population, d.generations),
            )
        )
    return rows


def run(scene, quick: bool) -> dict:
    """Benchmark 3."""
    ref, ref_design = reference(scene)
    samples = (90, 360, 36000) if quick else SAMPLES
    grid = grid_trade(scene, ref, ref_design, samples, repeats=3 if quick else 5)
    solvers = solver_trade(scene, ref, quick, repeats=3)
    default = next(r for r in grid if r["default"])
    return {
        "reference": {
            "samples": REFERENCE_SAMPLES,
            "dtype": "float64",
            **ref,
            "design_mm": [float(ref_design.base_radius_mm), float(ref_design.face_width_mm)],
        },
        "default_max_rel_error": default["max_rel_error"],
        "grid": grid,
        "solvers": solvers,
    }
