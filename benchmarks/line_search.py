"""The newton solver's line search: its step lengths tried all at once or a chunk at a time.

For each follower type of :data:`benchmarks.follower_sweep.SCENES` (the built-in scene, grid
extrema) the 100-weighting sweep of :func:`benchmarks.follower_sweep.weightings` solved by one
vmapped, jitted :func:`camjax.solvers.newton.minimize`, twice in one run: with
``line_search_chunk`` = ``line_search_trials`` (30: every trial length evaluated at once, one
``vmap``: the solver before ee501b2) and with the default chunk (6 at a time in a ``while_loop``
until one is accepted). Both pick the first accepted trial, so they take the same steps:
``max_rel_objective_difference`` compares their t at the end. Per follower: compile seconds and
the median of warm runs (:func:`benchmarks.harness.time_jit`), iterations, and ``speedup``
(all-at-once seconds / chunked seconds); ``median_speedup`` over the types.

``python -m benchmarks.line_search --out benchmarks/results/line_search.json``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks.follower_sweep import SCENES, grid_problem, weightings
from benchmarks.harness import environment, time_jit
from camjax.family import weights_of
from camjax.solvers import newton

WEIGHTINGS = 100


def run_follower(name: str) -> dict:
    problem = grid_problem(SCENES[name][0])
    alpha, gamma = weightings(WEIGHTINGS)
    weights = weights_of(jnp.asarray(alpha), jnp.asarray(gamma))
    base = newton.DEFAULT_SETTINGS
    out, ends = {}, {}
    for label, chunk in (("all_at_once", base.line_search_trials), ("chunked", base.line_search_chunk)):
        settings = dataclasses.replace(base, line_search_chunk=chunk)
        timing, res = time_jit(lambda p, w, s=settings: jax.vmap(lambda wi: newton.minimize(p, wi, None, s))(w),
                               problem, weights, repeats=3)
        its = np.asarray(res.iterations)
        ends[label] = np.asarray(res.z[:, -1])
        out[label] = {"chunk": chunk, "time_s": timing.median_s, "compile_s": timing.compile_s,
                      "iterations_median": float(np.median(its)), "iterations_max": int(its.max()),
                      "converged": int(np.sum(np.asarray(res.converged)))}
    out["speedup"] = out["all_at_once"]["time_s"] / out["chunked"]["time_s"]
    out["max_rel_objective_difference"] = float(np.max(np.abs(ends["chunked"] - ends["all_at_once"])
                                                       / np.abs(ends["all_at_once"])))
    return out


def run(names=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    result = {"weightings": WEIGHTINGS, "trials": newton.DEFAULT_SETTINGS.line_search_trials}
    for name in names or SCENES:
        result[name] = run_follower(name)
        print(f"{name}: all at once {result[name]['all_at_once']['time_s']:.2f} s, "
              f"chunked {result[name]['chunked']['time_s']:.2f} s", file=sys.stderr)
    speedups = [result[n]["speedup"] for n in names or SCENES]
    result["median_speedup"] = statistics.median(speedups)
    result["min_speedup"] = min(speedups)
    result["environment"] = environment("float64")
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("followers", nargs="*", help=f"of {', '.join(SCENES)} (default: all)")
    parser.add_argument("--out", type=Path, help="write the JSON here")
    args = parser.parse_args(argv)
    result = run(args.followers or None)
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
