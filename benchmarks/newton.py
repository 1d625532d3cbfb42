"""The newton solver (:mod:`camjax.solvers.newton`) against SciPy SLSQP on every follower type.

For each registered follower type (its example scene, grid extrema, ``--samples`` angles) and a
few weightings: newton's iterations, whether it converged (scaled KKT residual <= 1e-9), its
warm wall time per weighting (one compiled ``jax.jit(newton.minimize)``, compile timed apart),
SLSQP's iterations and wall time (:func:`camjax.solvers.scipy_family.slsqp`, its JAX functions
compiled before the clock starts), and the relative gap (F_newton - F_slsqp) / F_slsqp with both
feasible flags. Timings are single runs on whatever machine runs it (a shared 2-core CPU when
this file's JSON was written: noisy; the load average is recorded).

``python -m benchmarks.newton --out benchmarks/results/newton.json``
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time

WEIGHTINGS = ((1.0, 1.0), (0.9, 0.1), (0.1, 0.9))


def run(samples: int = 90, names=None) -> dict:
    import jax

    import camjax
    from camjax import followers
    from camjax.family import weights_of
    from camjax.solvers import newton, scipy_family
    from camjax.solvers.base import family_of, problem_from_scene

    solve = jax.jit(newton.minimize)
    out = {"samples": samples, "weightings": [list(w) for w in WEIGHTINGS], "followers": {},
           "loadavg_before": os.getloadavg()[0]}
    for name in names or followers.names():
        scene = camjax.load_scene(followers.get(name).example_scene)
        scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=samples,
                                                                       extrema="grid"))
        problem = problem_from_scene(scene)
        fam = family_of(problem)
        rows = []
        t0 = time.perf_counter()
        jax.block_until_ready(solve(problem, weights_of(*WEIGHTINGS[0])))
        compile_s = time.perf_counter() - t0
        scipy_family.slsqp(problem, *WEIGHTINGS[0], maxiter=1)  # SciPy side's JIT, off the clock
        for a, g in WEIGHTINGS:
            w = weights_of(a, g)
            t0 = time.perf_counter()
            res = jax.block_until_ready(solve(problem, w))
            newton_s = time.perf_counter() - t0
            ev = fam.evaluate(problem, w, res.design)
            ref = scipy_family.slsqp(problem, a, g)
            rows.append({"alpha": a, "gamma": g, "newton_iterations": int(res.iterations),
                         "newton_converged": bool(res.converged), "newton_s": newton_s,
                         "newton_feasible": bool(ev.feasible), "newton_objective": float(ev.objective),
                         "slsqp_iterations": ref.iterations, "slsqp_s": ref.seconds,
                         "slsqp_feasible": ref.max_violation < 1e-9, "slsqp_objective": ref.objective,
                         "relative_gap": (float(ev.objective) - ref.objective) / ref.objective})
        out["followers"][name] = {"newton_compile_s": compile_s, "runs": rows}
        print(name, json.dumps(rows), flush=True)
    out["loadavg_after"] = os.getloadavg()[0]
    return out


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("names", nargs="*", help="follower types (default: all)")
    p.add_argument("--samples", type=int, default=90)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    data = run(args.samples, args.names)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(data, f, indent=1)


if __name__ == "__main__":
    main()
