"""Roller benchmark: a 100-weighting sweep of the roller design problem, 3 free variables (R_b, R_f, e).

camjax solves all weightings in one program (:func:`camjax.solvers.base.solve_batch`, global
mode) with the gradient, GA and hybrid solvers. SciPy (:mod:`camjax.solvers.scipy_roller`, NumPy
with no JAX in the loop) solves them one by one: SLSQP in epigraph form from the box centre, and
``differential_evolution`` (polished by SciPy: its own hybrid).

Accuracy: every weighting's reference objective F* is the best feasible one found by any method
(tests/test_roller_solvers.py checks the solvers' optimum against a dense scan over the box and
against SciPy separately). For each method: the worst relative gap (F - F*) / F* and the number of infeasible
results. "Matched accuracy": a camjax method is compared with a SciPy one when its worst gap is
no larger (or both are within GAP_TOLERANCE) and it has no more infeasible results; the GA
figure uses the GA if it matches differential evolution, else the hybrid (named in the JSON).

SciPy runs on evenly spaced subsets of the weightings (SLSQP 0.04 to 0.7 s and differential
evolution 0.7 to 4 s per weighting on this machine, depending on its load); its time is scaled
to all weightings by the mean per weighting and the JSON says so (``extrapolated``). Timings on a
shared machine are noisy.

Run alone: ``python -m benchmarks.roller --out roller.json [--quick]`` (keys ``roller.*``), or as
part of ``benchmarks/run.py``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax
from benchmarks.harness import time_jit
from camjax.family import Weights, weights_of
from camjax.followers.roller import problem as R
from camjax.solvers import scipy_roller
from camjax.solvers.base import solve_batch, weighting_keys

GAP_TOLERANCE = 1e-7  # relative objective gaps below this count as equal


def weightings(count: int) -> tuple[np.ndarray, np.ndarray]:
    """alpha + gamma = 1, gamma/alpha log-spaced over 1e-2 .. 1e2."""
    ratio = np.logspace(-2, 2, count)
    return 1.0 / (1.0 + ratio), ratio / (1.0 + ratio)


def _evaluate(problem, weights: Weights, designs: R.Design):
    ev = jax.vmap(R.evaluate, in_axes=(None, 0, 0))(problem, weights, designs)
    return np.asarray(ev.objective), np.asarray(ev.feasible)


def _accuracy(objective, feasible, reference) -> dict:
    gap = (objective - reference) / np.abs(reference)
    return {"max_rel_objective_gap": float(np.max(gap)), "median_rel_objective_gap": float(np.median(gap)),
            "infeasible": int(np.sum(~feasible))}


def run(scene=None, quick: bool = False) -> dict:
    """The roller benchmark (``scene``: ignored, the built-in roller scene is used); the dict
    that benchmarks/run.py stores under "roller"."""
    count = 20 if quick else 100
    problem = R.problem_from_scene(camjax.load_scene("roller"), extrema="grid")  # grid kernels compared
    alpha, gamma = weightings(count)
    weights = weights_of(alpha, gamma)
    keys = weighting_keys(0, count)

    results = {}
    for solver in ("gradient", "ga", "hybrid"):
        t, sol = time_jit(lambda p, w, k, solver=solver: solve_batch(p, w, k, "global", solver),
                          problem, weights, keys, repeats=3)
        results["camjax_" + solver] = (t.median_s, t.compile_s, count, sol.design,
                                       int(np.max(np.asarray(sol.iterations))))
    n_slsqp, n_de = (4, 2) if quick else (20, 10)
    for name, n, solve_one in (("scipy_slsqp", n_slsqp, scipy_roller.slsqp),
                               ("scipy_de", n_de, scipy_roller.differential_evolution)):
        subset = np.linspace(0, count - 1, n).round().astype(int)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            out = [solve_one(problem, float(alpha[i]), float(gamma[i])) for i in subset]
            seconds = time.perf_counter() - t0
        x = np.stack([o.design for o in out])
        results[name] = (seconds, 0.0, subset, R.Design(*(jnp.asarray(x[:, j]) for j in range(3))), None)

    # reference: the best feasible objective any method (or the scan) reached, per weighting
    judged = {}
    for name, (_, _, n, designs, _) in results.items():
        sub = np.arange(count) if isinstance(n, int) else n
        w = Weights(weights.alpha[sub], weights.gamma[sub])
        obj, ok = _evaluate(problem, w, designs)
        full_obj, full_ok = np.full(count, np.inf), np.zeros(count, bool)
        full_obj[sub], full_ok[sub] = obj, ok
        judged[name] = (full_obj, full_ok)
    reference = np.min(np.stack([np.where(ok, obj, np.inf) for obj, ok in judged.values()]), axis=0)

    methods = {}
    for name, (seconds, compile_s, n, _, iterations) in results.items():
        sub = np.arange(count) if isinstance(n, int) else n
        obj, ok = judged[name]
        entry = {"weightings": len(sub), **_accuracy(obj[sub], ok[sub], reference[sub])}
        if name.startswith("camjax"):
            entry.update(time_s=seconds, compile_s=compile_s, iterations_max=iterations)
        else:
            entry.update(time_s=seconds * count / len(sub), measured_s=seconds,
                         per_weighting_s=seconds / len(sub), extrapolated=len(sub) != count)
        methods[name] = entry

    def matched(a: str, b: str) -> bool:
        ga_, gb = methods[a]["max_rel_objective_gap"], methods[b]["max_rel_objective_gap"]
        return ga_ <= max(gb, GAP_TOLERANCE) and methods[a]["infeasible"] <= methods[b]["infeasible"]

    ga_name = "camjax_ga" if matched("camjax_ga", "scipy_de") else "camjax_hybrid"
    return {
        "weightings": count,
        "free_variables": list(R.VARIABLES),
        "samples": int(problem.theta_deg.shape[0]),
        "gradient_speedup": methods["scipy_slsqp"]["time_s"] / methods["camjax_gradient"]["time_s"],
        "gradient_accuracy_matched": matched("camjax_gradient", "scipy_slsqp"),
        "ga_speedup": methods["scipy_de"]["time_s"] / methods[ga_name]["time_s"],
        "ga_speedup_method": ga_name,
        "ga_accuracy_matched": matched(ga_name, "scipy_de"),
        "ga_alone_speedup": methods["scipy_de"]["time_s"] / methods["camjax_ga"]["time_s"],
        "gap_tolerance": GAP_TOLERANCE,
        "scipy_weightings_measured": {k: methods[k]["weightings"] for k in ("scipy_slsqp", "scipy_de")},
        "note": "SciPy times measured on evenly spaced subsets and scaled to all weightings; shared "
                "2-core machine, timings noisy",
        "methods": methods,
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--quick", action="store_true", help="20 weightings, SciPy on 4 and 2")
    args = parser.parse_args(argv)
    data = {"roller": run(quick=args.quick)}
    args.out.write_text(json.dumps(data, indent=1, default=float))
    r = data["roller"]
    print(f"roller.gradient_speedup = {r['gradient_speedup']:.1f} "
          f"(matched: {r['gradient_accuracy_matched']})")
    print(f"roller.ga_speedup = {r['ga_speedup']:.1f} via {r['ga_speedup_method']} "
          f"(matched: {r['ga_accuracy_matched']})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
