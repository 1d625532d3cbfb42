"""Law synthesis against SciPy's HiGHS: a batch of peak-objective syntheses, same discretization.

Each problem: a uniform cubic B-spline of 32 control values, s, v, a given at both ends (random
end velocities and accelerations, normalized), objective w1 peak |a| + w2 peak |j| + w3 peak |v|
with random weights. camjax solves the batch in one ``jit(vmap)`` (interior point, epigraph form);
SciPy solves the same LP (the same rows, the same epigraph variables) one problem at a time with
``linprog(method="highs")``. Reported: the worst relative difference of the optima, both times
and the speed-up ``synthesis.linprog_speedup`` (JAX after compilation; compile time reported too).

    python -m benchmarks.synthesis [--batch 256] [--out benchmarks/results/synthesis.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import jax
import numpy as np

import camjax  # noqa: F401  (x64)
from camjax.synthesis import Condition, batch_synthesizer, build_problem, kept_values, make_basis

TERMS = ("peak_velocity", "peak_accel", "peak_jerk")


def problems(batch: int, seed: int = 0):
    conds = [Condition(0.0, 0, "start.s"), Condition(1.0, 0, "end.s")]
    conds += [Condition(x, r, f"{x}.{r}") for x in (0.0, 1.0) for r in (1, 2)]
    p = build_problem(make_basis(3, 32), conds, TERMS)
    rng = np.random.default_rng(seed)
    values = np.column_stack([np.zeros(batch), np.ones(batch), rng.uniform(0, 1.5, batch),
                              rng.uniform(-3, 3, batch), rng.uniform(0, 1.5, batch),
                              rng.uniform(-3, 3, batch)])
    weights = rng.uniform(0.1, 1.0, (batch, len(TERMS)))
    return p, kept_values(p, values), weights


def linprog_one(p, values, weights):
    from scipy.optimize import linprog

    cp = p.A_pinv @ values
    N = p.null
    nz, k = N.shape[1], len(p.peak_rows)
    rows, rhs = [], []
    for j, M in enumerate(p.peak_rows):
        e = np.zeros((len(M), k))
        e[:, j] = -1.0
        rows += [np.hstack([M @ N, e]), np.hstack([-M @ N, e])]
        rhs += [-(M @ cp), M @ cp]
    r = linprog(np.r_[np.zeros(nz), weights], A_ub=np.vstack(rows), b_ub=np.concatenate(rhs),
                bounds=[(None, None)] * (nz + k), method="highs")
    assert r.status == 0, r.message
    return r.fun


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--batch", type=int, default=256)
    ap.add_argument("--out", default="benchmarks/results/synthesis.json")
    args = ap.parse_args(argv)
    p, values, weights = problems(args.batch)
    solve = batch_synthesizer(p)
    t0 = time.perf_counter()
    jax.block_until_ready(solve(values, weights))
    compile_s = time.perf_counter() - t0
    load_before = os.getloadavg()[0]
    jax_times, scipy_times = [], []
    for _ in range(3):  # rounds alternate the two, so that both see the same machine
        t0 = time.perf_counter()
        out = jax.block_until_ready(solve(values, weights))
        jax_times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        ref = np.asarray([linprog_one(p, values[i], weights[i]) for i in range(args.batch)])
        scipy_times.append(time.perf_counter() - t0)
    best, scipy_s = float(np.median(jax_times)), float(np.median(scipy_times))
    # the LP optimum is the discretized objective (peak |v| sampled, peaks of a and j exact)
    rel = np.abs(np.asarray(out.model_objective) - ref) / np.abs(ref)
    result = {"synthesis": {
        "batch": args.batch, "basis": "uniform cubic, 32 control values", "terms": list(TERMS),
        "jax_s": best, "jax_compile_s": compile_s, "linprog_s": scipy_s,
        "linprog_speedup": scipy_s / best, "max_rel_difference": float(rel.max()),
        "all_converged": bool(np.all(out.converged)), "timing": "median of 3 alternating rounds",
        "load_average_1min": [load_before, os.getloadavg()[0]],
        "device": jax.devices()[0].device_kind, "machine": platform.machine(),
    }}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
