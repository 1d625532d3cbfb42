"""Benchmark 2: weight sweep, >= 100 (alpha, gamma) weightings, global mode, at matched accuracy.

camjax solves all weightings in one program (:func:`camjax.solvers.sweep.solve_batch`) with each
solver: gradient, GA, and hybrid (GA, then the gradient solver from the GA's best). SciPy
(:mod:`camjax.solvers.scipy_baseline`) solves them one by one: SLSQP in epigraph form (from the
box centre, and a 4-start multistart) and ``differential_evolution`` (with its own local polish:
SciPy's hybrid).

Accuracy is judged against a dense-scan optimum of every weighting (:func:`dense_scan`: a 2-D grid
over the box, zoomed four times around the best feasible point, final spacing ~1e-6 mm),
cross-checked with the exact bisection reference :func:`camjax.followers.flat.problem.global_optimum`. For each
method: the worst relative objective gap (F - F_scan) / F_scan over weightings (negative = better
than the scan), the worst |dR_b| and |dL|, and how many results are infeasible.
"""

from __future__ import annotations

import warnings

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks import baselines
from benchmarks import fitness as fz
from benchmarks.harness import time_jit, time_python
from camjax.family import Weights, weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import ga
from camjax.solvers.sweep import solve_batch

SCAN_GRID = 101
SCAN_ZOOMS = 4
GAP_TOLERANCE = 1e-7  # relative objective gap within the dense scan's own resolution


def weightings(count: int) -> tuple[np.ndarray, np.ndarray]:
    """alpha + gamma = 1, gamma/alpha log-spaced over 1e-2 .. 1e2 (the source's 10:1 cases inside)."""
    ratio = np.logspace(-2, 2, count)
    return 1.0 / (1.0 + ratio), ratio / (1.0 + ratio)


def dense_scan(problem, weights: Weights) -> P.Design:
    """Best feasible point of a G x G grid over the box, zoomed SCAN_ZOOMS times (+-2 cells)."""
    scene = fz.fused_scene(problem)
    g = SCAN_GRID

    def one(w):
        lo = jnp.stack([problem.lower.base_radius_mm, problem.lower.face_width_mm])
        hi = jnp.stack([problem.upper.base_radius_mm, problem.upper.face_width_mm])
        box_lo, box_hi = lo, hi
        best = 0.5 * (lo + hi)
        for _ in range(SCAN_ZOOMS + 1):
            t = jnp.linspace(0.0, 1.0, g)
            r = lo[0] + t * (hi[0] - lo[0])
            length = lo[1] + t * (hi[1] - lo[1])
            rr, ll = jnp.meshgrid(r, length, indexing="ij")
            obj, vio = fz.fused_fitness(scene, w, P.Design(rr.ravel(), ll.ravel()))
            k = jnp.argmin(jnp.where(vio <= 0, obj, jnp.inf + vio))
            best = jnp.stack([rr.ravel()[k], ll.ravel()[k]])
            cell = 2.0 * (hi - lo) / (g - 1)
            lo, hi = jnp.maximum(best - cell, box_lo), jnp.minimum(best + cell, box_hi)
        return P.Design(best[0], best[1])

    return jax.lax.map(one, weights)


def _accuracy(problem, weights: Weights, designs: P.Design, scan: P.Design) -> dict:
    ev = jax.vmap(P.evaluate, in_axes=(None, 0, 0))(problem, weights, designs)
    ev_scan = jax.vmap(P.evaluate, in_axes=(None, 0, 0))(problem, weights, scan)
    gap = (np.asarray(ev.objective) - np.asarray(ev_scan.objective)) / np.abs(np.asarray(ev_scan.objective))
    return {
        "max_rel_objective_gap": float(np.max(gap)),
        "max_abs_diff_base_radius_mm": float(
            np.max(np.abs(np.asarray(designs.base_radius_mm) - np.asarray(scan.base_radius_mm)))
        ),
        "max_abs_diff_face_width_mm": float(
            np.max(np.abs(np.asarray(designs.face_width_mm) - np.asarray(scan.face_width_mm)))
        ),
        "infeasible": int(np.sum(~np.asarray(ev.feasible))),
    }


def _as_design(x: np.ndarray) -> P.Design:
    return P.Design(jnp.asarray(x[:, 0]), jnp.asarray(x[:, 1]))


def _camjax(problem, weights: Weights, repeats: int) -> dict:
    """The three camjax solvers, each over all weightings in one program (``sweep.solve_batch``)."""
    keys = ga.weighting_keys(0, weights.alpha.shape[0])
    out = {}
    for solver in ("gradient", "ga", "hybrid"):
        t, res = time_jit(
            lambda k, p, w, solver=solver: solve_batch(p, w, k, "global", solver),
            keys,
            problem,
            weights,
            repeats=repeats,
        )
        out[solver] = (
            t,
            P.Design(res.base_radius_mm, res.face_width_mm),
            int(np.max(np.asarray(res.iterations))),
        )
    return out


def run(scene, quick: bool) -> dict:
    """Benchmark 2: 100 weightings (--quick: 20, SciPy on 4 of them, its time extrapolated, said so)."""
    count = 20 if quick else 100
    problem = P.problem_from_scene(scene, extrema="grid")
    alpha, gamma = weightings(count)
    weights = weights_of(alpha, gamma)
    scan = jax.jit(dense_scan)(problem, weights)
    exact = jax.vmap(optimum.global_optimum, in_axes=(None, 0))(problem, weights)
    scan_vs_exact = _accuracy(problem, weights, exact, scan)

    jx = _camjax(problem, weights, repeats=3 if quick else 5)
    # SciPy subsets (evenly spaced weightings); a time measured on a subset is scaled to all
    # weightings by the mean per weighting, and the JSON says so ("extrapolated").
    n_slsqp, n_multi, n_de = (4, 4, 4) if quick else (count, 25, 50)
    scipy_runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, n, make in (
            ("scipy_slsqp", n_slsqp, lambda p: baselines.sweep_slsqp(problem, p)),
            (
                "scipy_slsqp_multistart",
                n_multi,
                lambda p: baselines.sweep_slsqp(problem, p, starts_per_weighting=4),
            ),
            ("scipy_de", n_de, lambda p: baselines.sweep_de(problem, p)),
        ):
            subset = np.linspace(0, count - 1, n).round().astype(int)
            loop = make([(float(alpha[i]), float(gamma[i])) for i in subset])
            t, out = time_python(loop.solve, repeats=1, warmup=0)
            scipy_runs[name] = (subset, loop.source, t, out)

    methods = {}
    for solver, (t, designs, iterations) in jx.items():
        methods["camjax_" + solver] = {
            "time_s": t.median_s,
            "compile_s": t.compile_s,
            "weightings": count,
            "iterations_max": iterations,
            **_accuracy(problem, weights, designs, scan),
        }
    for name, (subset, src, t, out) in scipy_runs.items():
        sub_w = Weights(weights.alpha[subset], weights.gamma[subset])
        sub_scan = jax.tree.map(lambda v, subset=subset: v[subset], scan)
        methods[name] = {
            "time_s": t.median_s * count / len(subset),
            "measured_s": t.median_s,
            "weightings": len(subset),
            "per_weighting_s": t.median_s / len(subset),
            "extrapolated": len(subset) != count,
            "source": src,
            **_accuracy(problem, sub_w, _as_design(out), sub_scan),
        }

    def matched(a: str, b: str) -> bool:
        """camjax method a as accurate as SciPy method b or better (or within the scan's resolution)."""
        return (
            methods[a]["max_rel_objective_gap"] <= max(methods[b]["max_rel_objective_gap"], GAP_TOLERANCE)
            and methods[a]["infeasible"] <= methods[b]["infeasible"]
        )

    ga_name = "camjax_ga" if matched("camjax_ga", "scipy_de") else "camjax_hybrid"
    return {
        "weightings": count,
        "scipy_weightings_measured": {k: int(len(v[0])) for k, v in scipy_runs.items()},
        "scipy_extrapolated": {k: bool(len(v[0]) != count) for k, v in scipy_runs.items()},
        "gradient_speedup": methods["scipy_slsqp"]["time_s"] / methods["camjax_gradient"]["time_s"],
        "gradient_speedup_vs_multistart": methods["scipy_slsqp_multistart"]["time_s"]
        / methods["camjax_gradient"]["time_s"],
        "gradient_accuracy_matched": matched("camjax_gradient", "scipy_slsqp"),
        "ga_speedup": methods["scipy_de"]["time_s"] / methods[ga_name]["time_s"],
        "ga_speedup_method": ga_name,
        "ga_accuracy_matched": matched(ga_name, "scipy_de"),
        "ga_alone_speedup": methods["scipy_de"]["time_s"] / methods["camjax_ga"]["time_s"],
        "gap_tolerance": GAP_TOLERANCE,
        "scan": {"grid": SCAN_GRID, "zooms": SCAN_ZOOMS, "vs_exact": scan_vs_exact},
        "methods": methods,
    }
