"""Per-follower sweep benchmark: 100 weightings of one follower's design problem, camjax against SciPy.

One benchmark for every follower type (:data:`SCENES`: each registered type's built-in scene);
its free variables are those the scene's [design] declares (the JSON lists them). Keys
``<follower>.*``, e.g. ``roller.*`` (R_b, R_f, e), ``oscillating_roller.*`` (R_b and the pivot
distance d).

camjax solves all weightings in one program (:func:`camjax.solvers.base.solve_batch`, global
mode) with each solver of ``--solvers`` (default: the interior-point ``newton``, the first-order
``gradient``, the GA and the hybrid). ``gradient_speedup`` is SLSQP's time over the second-order
solver's (``newton``; the first-order ``gradient`` where newton was not run), named in
``gradient_speedup_method``; ``first_order_speedup`` is SLSQP's over the first-order solver's.
SciPy solves them one by one on the same grid: SLSQP in epigraph form from the box centre, and
``differential_evolution`` (polished by SciPy: its own hybrid). The roller's SciPy side is
:mod:`camjax.solvers.scipy_roller` (NumPy, written from SPEC 3, finite-difference Jacobians); every
other type's is :mod:`camjax.solvers.scipy_family` (SciPy calling the family's jitted JAX functions
and their JAX Jacobians).

Accuracy: every weighting's reference objective F* is the best feasible one found by any method
(tests/test_roller_solvers.py and tests/test_scipy_family.py check the solvers' optimum against
SciPy separately). For each method: the worst relative gap (F - F*) / F* and the number of
infeasible results. "Matched accuracy": a camjax method is compared with a SciPy one when its
worst gap is no larger (or both are within GAP_TOLERANCE) and it has no more infeasible results;
the GA figure uses the faster of the GA and the hybrid among those that match differential
evolution, else the hybrid (named in the JSON).

SciPy runs on evenly spaced subsets of the weightings (:data:`SUBSETS`); its time is scaled to
all weightings by the mean per weighting and the JSON says so (``extrapolated``). The SciPy
baseline's one-off JIT compilation (rockers) is done before the clock starts. Timings on a
shared machine are noisy: the JSON records the load average before and after each follower.
Several followers are measured each in a fresh process, one after another (:func:`main`), as a
user's ``camjax sweep`` of one scene runs: in one process the oscillating roller's interior point,
measured after four other types' solvers and SciPy runs, took 0.173 s where it took 0.136 s
alone (2 cores, the same code, 7 December).

Run alone: ``python -m benchmarks.follower_sweep roller --out benchmarks/results/roller.json`` and
``python -m benchmarks.follower_sweep oscillating_roller oscillating_flat --out
benchmarks/results/followers.json`` (an existing file keeps the followers not run; ``all`` runs
every type), ``--quick`` for 20 weightings, ``--solvers newton,ga,hybrid`` for a subset;
``benchmarks/run.py`` runs the roller's (``roller.*``).
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import json
import os
import subprocess
import sys
import time
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax
from benchmarks.harness import environment, time_jit
from camjax.family import Weights, weights_of
from camjax.solvers.base import (
    DEFAULT_SETTINGS,
    family_of,
    for_problem,
    problem_from_scene,
    solve_batch,
    weighting_keys,
)

GAP_TOLERANCE = 1e-7  # relative objective gaps below this count as equal
# follower -> (built-in scene, SciPy baseline module)
SCENES = {
    "flat": ("default", "camjax.solvers.scipy_family"),
    "knife_edge": ("knife-edge", "camjax.solvers.scipy_family"),
    "roller": ("roller", "camjax.solvers.scipy_roller"),
    "curved_face": ("curved-face", "camjax.solvers.scipy_family"),
    "oscillating_roller": ("oscillating-roller", "camjax.solvers.scipy_family"),
    "oscillating_flat": ("oscillating-flat", "camjax.solvers.scipy_family"),
    "oscillating_curved_face": ("oscillating-curved-face", "camjax.solvers.scipy_family"),
}
SOLVERS = ("newton", "gradient", "ga", "hybrid")  # camjax's, in the order they are run
SLOW_S = 5.0  # a camjax solve of all weightings longer than this is timed once (harness.time_jit)
SUBSETS = {"full": (20, 10), "quick": (4, 2)}  # SciPy weightings measured: (SLSQP, differential evolution)


def weightings(count: int) -> tuple[np.ndarray, np.ndarray]:
    """alpha + gamma = 1, gamma/alpha log-spaced over 1e-2 .. 1e2."""
    ratio = np.logspace(-2, 2, count)
    return 1.0 / (1.0 + ratio), ratio / (1.0 + ratio)


def grid_problem(scene_name: str):
    """The design problem of a built-in scene with grid extrema (the solvers' kernels compared)."""
    scene = camjax.load_scene(scene_name)
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema="grid"))
    return problem_from_scene(scene)


def free_variables(problem) -> list[str]:
    """The design variables the problem's box leaves free (lower < upper)."""
    lower, upper = family_of(problem).bounds(problem)
    return [name for name, lo, hi in zip(lower._fields, lower, upper, strict=True) if float(hi) > float(lo)]


def _evaluate(problem, weights: Weights, designs):
    ev = jax.vmap(family_of(problem).evaluate, in_axes=(None, 0, 0))(problem, weights, designs)
    return np.asarray(ev.objective), np.asarray(ev.feasible)


def _accuracy(objective, feasible, reference) -> dict:
    gap = (objective - reference) / np.abs(reference)
    return {"max_rel_objective_gap": float(np.max(gap)), "median_rel_objective_gap": float(np.median(gap)),
            "infeasible": int(np.sum(~feasible))}


def run_follower(follower: str, quick: bool = False, solvers: tuple[str, ...] = SOLVERS) -> dict:
    """The sweep benchmark of one follower of :data:`SCENES` with camjax's ``solvers`` (the GA and
    the hybrid always among them): the dict stored under its name."""
    scene_name, baseline_name = SCENES[follower]
    baseline = importlib.import_module(baseline_name)
    load_before = os.getloadavg()
    count = 20 if quick else 100
    problem = grid_problem(scene_name)
    lower, _ = family_of(problem).bounds(problem)
    alpha, gamma = weightings(count)
    weights = weights_of(alpha, gamma)
    keys = weighting_keys(0, count)

    results = {}
    for solver in solvers:
        # the settings solve_batch gives itself from a concrete problem (the interior point's count
        # of free variables: a static of its program), which a traced problem cannot give
        settings = for_problem(problem, solver, DEFAULT_SETTINGS)
        t, sol = time_jit(lambda p, w, k, solver=solver, settings=settings: solve_batch(
            p, w, k, "global", solver, settings), problem, weights, keys, repeats=3, slow_s=SLOW_S)
        its = np.asarray(sol.iterations)
        results["camjax_" + solver] = (t.median_s, t.compile_s, count, sol.design,
                                       {"iterations_max": int(np.max(its)),
                                        "iterations_median": float(np.median(its)), "timed_runs": t.repeats})
    n_slsqp, n_de = SUBSETS["quick" if quick else "full"]
    for name, n, solve_one in (("scipy_slsqp", n_slsqp, baseline.slsqp),
                               ("scipy_de", n_de, baseline.differential_evolution)):
        subset = np.linspace(0, count - 1, n).round().astype(int)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            solve_one(problem, float(alpha[0]), float(gamma[0]))  # compiles the JAX it calls (rockers)
            t0 = time.perf_counter()
            out = [solve_one(problem, float(alpha[i]), float(gamma[i])) for i in subset]
            seconds = time.perf_counter() - t0
        x = np.stack([o.design for o in out])
        designs = type(lower)(*(jnp.asarray(x[:, j]) for j in range(x.shape[1])))
        results[name] = (seconds, 0.0, subset, designs,
                         {"iterations_max": int(max(o.iterations for o in out)),
                          "iterations_median": float(np.median([o.iterations for o in out]))})

    # reference: the best feasible objective any method reached, per weighting
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
        entry = {"weightings": len(sub), **_accuracy(obj[sub], ok[sub], reference[sub]), **iterations}
        if name.startswith("camjax"):
            entry.update(time_s=seconds, compile_s=compile_s)
        else:
            entry.update(time_s=seconds * count / len(sub), measured_s=seconds,
                         per_weighting_s=seconds / len(sub), extrapolated=len(sub) != count)
        methods[name] = entry

    def matched(a: str, b: str) -> bool:
        ga_, gb = methods[a]["max_rel_objective_gap"], methods[b]["max_rel_objective_gap"]
        return ga_ <= max(gb, GAP_TOLERANCE) and methods[a]["infeasible"] <= methods[b]["infeasible"]

    ga_matched = [name for name in ("camjax_ga", "camjax_hybrid") if matched(name, "scipy_de")]
    ga_name = min(ga_matched, key=lambda name: methods[name]["time_s"]) if ga_matched else "camjax_hybrid"
    second = "camjax_newton" if "camjax_newton" in methods else "camjax_gradient"
    first = {"first_order_speedup": methods["scipy_slsqp"]["time_s"] / methods["camjax_gradient"]["time_s"],
             "first_order_accuracy_matched": matched("camjax_gradient", "scipy_slsqp")} \
        if "camjax_gradient" in methods else {}
    return {
        "scene": scene_name,
        "weightings": count,
        "free_variables": free_variables(problem),
        "samples": int(problem.theta_deg.shape[0]),
        "scipy_baseline": baseline_name,
        "gradient_speedup": methods["scipy_slsqp"]["time_s"] / methods[second]["time_s"],
        "gradient_speedup_method": second,
        "gradient_accuracy_matched": matched(second, "scipy_slsqp"),
        **first,
        "ga_speedup": methods["scipy_de"]["time_s"] / methods[ga_name]["time_s"],
        "ga_speedup_method": ga_name,
        "ga_accuracy_matched": matched(ga_name, "scipy_de"),
        "ga_alone_speedup": methods["scipy_de"]["time_s"] / methods["camjax_ga"]["time_s"],
        "hybrid_vs_slsqp_speedup": methods["scipy_slsqp"]["time_s"] / methods["camjax_hybrid"]["time_s"],
        "hybrid_accuracy_matched_slsqp": matched("camjax_hybrid", "scipy_slsqp"),
        "gap_tolerance": GAP_TOLERANCE,
        "scipy_weightings_measured": {k: methods[k]["weightings"] for k in ("scipy_slsqp", "scipy_de")},
        "load_average_1min": [load_before[0], os.getloadavg()[0]],
        "note": "SciPy times measured on evenly spaced subsets and scaled to all weightings; "
                f"{os.cpu_count()} CPU cores; on a shared machine the timings are noisy "
                "(load_average_1min: before, after)",
        "methods": methods,
    }


def run(scene=None, quick: bool = False) -> dict:
    """The roller's sweep (``scene``: ignored, the built-in roller scene is used); the dict that
    benchmarks/run.py stores under "roller"."""
    return run_follower("roller", quick)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("followers", nargs="+", choices=[*sorted(SCENES), "all"])
    parser.add_argument("--out", type=Path, required=True, help="JSON file (followers not run are kept)")
    parser.add_argument("--quick", action="store_true", help="20 weightings, SciPy on 4 and 2")
    parser.add_argument("--solvers", default=",".join(SOLVERS),
                        help=f"camjax's solvers, comma-separated (ga and hybrid always run; default "
                        f"{','.join(SOLVERS)})")
    args = parser.parse_args(argv)
    solvers = tuple(dict.fromkeys([*args.solvers.split(","), "ga", "hybrid"]))
    unknown = sorted(set(solvers) - set(SOLVERS))
    if unknown:
        parser.error(f"--solvers: {', '.join(unknown)} not allowed; use {', '.join(SOLVERS)}")
    names = list(SCENES) if "all" in args.followers else args.followers
    if len(names) > 1:  # each follower in a fresh process (see the module docstring), in turn
        for follower in names:
            options = ["--solvers", args.solvers, *(["--quick"] if args.quick else [])]
            command = [sys.executable, "-m", "benchmarks.follower_sweep", follower, "--out", str(args.out)]
            subprocess.run([*command, *options], check=True)
        return 0
    data = json.loads(args.out.read_text()) if args.out.exists() else {}
    for follower in names:
        data[follower] = run_follower(follower, quick=args.quick, solvers=solvers)
        data.setdefault("environment", {})[follower] = environment("float64")
        r = data[follower]
        print(f"{follower}.gradient_speedup = {r['gradient_speedup']:.1f} via {r['gradient_speedup_method']} "
              f"(matched: {r['gradient_accuracy_matched']})")
        print(f"{follower}.ga_speedup = {r['ga_speedup']:.1f} via {r['ga_speedup_method']} "
              f"(matched: {r['ga_accuracy_matched']})", flush=True)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(data, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
