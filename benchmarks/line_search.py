"""The newton solver's line search: its step lengths tried all at once, six or one at a time.

For each follower type of :data:`benchmarks.follower_sweep.SCENES` (the built-in scene, grid
extrema) the 100-weighting sweep of :func:`benchmarks.follower_sweep.weightings` searched by
:func:`camjax.solvers.base.search_batch` as :func:`camjax.solvers.base.solve_batch` runs it (on the
CPU in chunks of :data:`camjax.solvers.base.SEARCH_CHUNK` weightings), three times in one run, with
``line_search_chunk`` = ``line_search_trials`` (30: every trial length evaluated at once, one
``vmap``: the solver before ee501b2), 6 (the default before 1 was) and the default (one at a time
in a ``while_loop`` until one is accepted). All pick the first accepted trial, so they take the
same steps: ``max_rel_objective_difference`` compares the objectives of the designs with
the all-at-once ones'. Per follower: compile seconds and the median of warm runs
(:func:`benchmarks.harness.time_jit`), iterations, ``speedup`` (all-at-once seconds / default
seconds) and ``speedup_over_six`` (six-at-a-time seconds / default seconds); ``median_speedup``,
``min_speedup`` and ``median_speedup_over_six`` over the types.

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
from camjax.solvers import base, newton

WEIGHTINGS = 100


def run_follower(name: str) -> dict:
    problem = grid_problem(SCENES[name][0])
    alpha, gamma = weightings(WEIGHTINGS)
    weights = weights_of(jnp.asarray(alpha), jnp.asarray(gamma))
    keys = base.weighting_keys(0, WEIGHTINGS)
    chunk = base.search_chunk(weights)
    default = newton.DEFAULT_SETTINGS
    evaluate = jax.jit(jax.vmap(base.family_of(problem).evaluate, in_axes=(None, 0, 0)))
    out, ends = {}, {}
    for label, trials_at_once in (("all_at_once", default.line_search_trials), ("six_at_a_time", 6),
                                  ("default", default.line_search_chunk)):
        # with the count of free variables solve_batch gives itself from the concrete problem
        own = dataclasses.replace(newton.for_problem(problem, default), line_search_chunk=trials_at_once)
        settings = base.Settings.of_solvers(newton=own)

        def search(p, w, k, settings=settings):
            return base.search_batch(p, w, k, "global", "newton", settings, chunk)[0]

        timing, raw = time_jit(search, problem, weights, keys, repeats=5)
        its = np.asarray(raw.iterations)
        ends[label] = np.asarray(evaluate(problem, weights, raw.design).objective)
        out[label] = {"line_search_chunk": trials_at_once, "time_s": timing.median_s,
                      "compile_s": timing.compile_s, "iterations_median": float(np.median(its)),
                      "iterations_max": int(its.max())}
    out["search_chunk"] = chunk
    out["speedup"] = out["all_at_once"]["time_s"] / out["default"]["time_s"]
    out["speedup_over_six"] = out["six_at_a_time"]["time_s"] / out["default"]["time_s"]
    out["max_rel_objective_difference"] = max(
        float(np.max(np.abs(ends[label] - ends["all_at_once"]) / np.abs(ends["all_at_once"])))
        for label in ("six_at_a_time", "default"))
    return out


def run(names=None) -> dict:
    jax.config.update("jax_enable_x64", True)
    result = {"weightings": WEIGHTINGS, "trials": newton.DEFAULT_SETTINGS.line_search_trials}
    for name in names or SCENES:
        r = result[name] = run_follower(name)
        print(f"{name}: all at once {r['all_at_once']['time_s']:.3f} s, six at a time "
              f"{r['six_at_a_time']['time_s']:.3f} s, default ({r['default']['line_search_chunk']}) "
              f"{r['default']['time_s']:.3f} s", file=sys.stderr)
    names = names or list(SCENES)
    result["median_speedup"] = statistics.median(result[n]["speedup"] for n in names)
    result["min_speedup"] = min(result[n]["speedup"] for n in names)
    result["median_speedup_over_six"] = statistics.median(result[n]["speedup_over_six"] for n in names)
    result["min_speedup_over_six"] = min(result[n]["speedup_over_six"] for n in names)
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
