"""The newton solver (:mod:`camjax.solvers.newton`) against SciPy SLSQP on every follower type.

For each registered follower type (its example scene, grid extrema, ``--samples`` angles) and a
few weightings: newton's iterations, whether it converged (scaled KKT residual <= 1e-9), its
warm wall time per weighting and the compile time of the program a ``camjax design --solver
newton`` runs (:func:`camjax.solvers.base.solve_batch`: the solve, the judgement on the grid and
the KKT certificate, jitted here as one program; ``newton_compile_s``), SLSQP's iterations and wall time
(:func:`camjax.solvers.scipy_family.slsqp`, its JAX functions compiled before the clock starts),
and the relative gap (F_newton - F_slsqp) / F_slsqp with both feasible flags; ``summary``:
counts over all runs (``matched_slsqp``: feasible and at most 1e-7 above SLSQP's objective),
medians of iterations and times. Timings are single
runs on whatever machine runs it (a shared 2-core CPU when this file's JSON was written: noisy;
the load average is recorded).

``python -m benchmarks.newton --out benchmarks/results/newton.json``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import time

WEIGHTINGS = ((1.0, 1.0), (0.9, 0.1), (0.1, 0.9))


def run(samples: int = 90, names=None) -> dict:
    import jax

    import camjax
    from camjax import followers
    from camjax.family import weights_of
    from camjax.solvers import scipy_family
    from camjax.solvers.base import problem_from_scene, solve_batch, weighting_keys

    out = {"samples": samples, "weightings": [list(w) for w in WEIGHTINGS], "followers": {},
           "loadavg_before": os.getloadavg()[0]}
    for name in names or followers.names():
        scene = camjax.load_scene(followers.get(name).example_scene)
        scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=samples,
                                                                       extrema="grid"))
        problem = problem_from_scene(scene)
        keys = weighting_keys(0, 1)
        rows = []
        t0 = time.perf_counter()
        whole = jax.jit(solve_batch, static_argnames=("mode", "solver", "settings"))
        program = whole.lower(problem, weights_of([1.0], [1.0]), keys, "global", "newton").compile()
        compile_s = time.perf_counter() - t0
        scipy_family.slsqp(problem, *WEIGHTINGS[0], maxiter=1)  # SciPy side's JIT, off the clock
        for a, g in WEIGHTINGS:
            t0 = time.perf_counter()
            res = jax.device_get(program(problem, weights_of([a], [g]), keys))[0]
            newton_s = time.perf_counter() - t0
            kkt = res.certificate.result.kkt
            ref = scipy_family.slsqp(problem, a, g)
            rows.append({"alpha": a, "gamma": g, "newton_iterations": int(res.iterations),
                         "newton_converged": bool(res.converged), "newton_kkt": float(kkt.error),
                         "newton_s": newton_s, "newton_feasible": bool(res.feasible),
                         "newton_objective": float(res.objective),
                         "slsqp_iterations": ref.iterations, "slsqp_s": ref.seconds,
                         "slsqp_feasible": ref.max_violation < 1e-9, "slsqp_objective": ref.objective,
                         "relative_gap": (float(res.objective) - ref.objective) / ref.objective})
        out["followers"][name] = {"newton_compile_s": compile_s, "runs": rows}
        print(name, f"compile {compile_s:.1f} s", json.dumps(rows), flush=True)
    runs = [r for f in out["followers"].values() for r in f["runs"]]
    out["summary"] = {
        "runs": len(runs),
        "converged": sum(r["newton_converged"] for r in runs),
        "feasible": sum(r["newton_feasible"] for r in runs),
        "matched_slsqp": sum(r["newton_feasible"] and r["relative_gap"] <= 1e-7 for r in runs),
        "median_iterations": statistics.median(r["newton_iterations"] for r in runs),
        "over_40_iterations": sum(r["newton_iterations"] > 40 for r in runs),
        "median_newton_s": statistics.median(r["newton_s"] for r in runs),
        "median_slsqp_s": statistics.median(r["slsqp_s"] for r in runs),
    }
    out["loadavg_after"] = os.getloadavg()[0]
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", help="follower types (default: all)")
    p.add_argument("--samples", type=int, default=90)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    data = run(args.samples, args.names)
    print(json.dumps(data["summary"]))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(data, f, indent=1)


if __name__ == "__main__":
    main()
