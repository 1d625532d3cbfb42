"""Co-design of law and geometry against SciPy's SLSQP on the same discretization.

Each problem: the built-in scene ``codesign`` (flat face; a rise and a return designed as cubic
B-splines at rest at the dwells; base radius and face width free; α size + γ stress + l2_jerk)
on a coarser grid, varied reproducibly (rise lift, rise and return angles, α/γ, the l2_jerk
weight). Both sides start from the same point: the best built-in law combination (each with its
own optimal geometry, :func:`camjax.codesign.best_builtin_combination`) fitted onto the B-spline
space (:func:`camjax.codesign.builtin.fitted_coordinates`), and its optimal geometry.

- **camjax**: the co-design's outer search as ``camjax design`` runs it: BFGS on the laws' free
  coordinates z (:func:`camjax.codesign.search.bfgs`), each step an inner geometry solve and the
  envelope gradient (:class:`camjax.codesign.Codesign`). Timed: F at the start and the search. Its
  jitted pieces are compiled before the clock (one compile per problem: the pieces close over
  the problem's data).
- **SciPy**: ``scipy.optimize.minimize(method="SLSQP")`` on the joint variables (z, the free
  design variables, an epigraph variable t), one problem at a time: minimize t + law(z) subject to
  t ≥ f_i(z, d) at every angle (f_i the one-angle objective, α size / N + γ σ_i / σ_max, as
  :mod:`camjax.solvers.scipy_family` writes the global problem) and -g(z, d) / N ≥ 0 for every
  constraint row at every angle, the design box as bounds. The rows and their Jacobian in
  (z, d, t) are one jitted JAX function (``jax.jacfwd`` through the problem's construction from
  kinematics(z), :meth:`Codesign.problem`), compiled before the clock; law(z) is the co-design's
  own quadratic (:func:`camjax.synthesis.linear.law_quadratics`).

Both ends are evaluated by the same jitted function: the family's objective (true max over the
grid's angles) + law(z), and the largest constraint row g / N. Reported: per problem both times,
objectives, iterations; medians; ``slsqp_speedup`` = median over problems of (SLSQP time / camjax
time), with the ratio of the totals beside it; the relative gaps; the load average. Where
camjax's time goes is an estimate: ``share_in_inner_solves`` = inner solves × the median time of
one inner solve at the search's end point / the search's time (it can exceed 1 where the end
point's solve takes more solver steps than the average step's, or the load changed), likewise
``share_in_gradients``.

    python -m benchmarks.codesign [--quick] [--out benchmarks/results/codesign.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax  # noqa: F401  (x64)
from camjax.codesign import Codesign, best_builtin_combination
from camjax.codesign.builtin import fitted_coordinates
from camjax.codesign.search import bfgs
from camjax.scene import builtin_scene_text, scene_from_dict
from camjax.solvers.base import family_of

SAMPLES = 120  # grid of every problem (the built-in scene searches on 360)
CONTROLS = 12  # control values of each designed B-spline (the built-in scene has 16)
FEASIBLE_TOL = 1e-6  # largest constraint row g / N counted as feasible
ACCURACY_RTOL = 5e-3  # the "same optimum within 0.5 %"


def scene_data(lift=10.0, rise_deg=90.0, return_deg=80.0, alpha=1.0, gamma=1.0, l2_jerk=1e-6,
               samples=SAMPLES, controls=CONTROLS) -> dict:
    """The built-in ``codesign`` scene with the given rise/return, weights and grid (the dwells
    take up what the rise and the return leave of the turn, in the built-in proportions)."""
    data = tomllib.loads(builtin_scene_text("codesign"))
    data["motion"]["samples"] = samples
    dwell, rise, dwell2, ret = data["motion"]["segments"]
    rest = 360.0 - rise_deg - return_deg
    dwell["angle_deg"] = rest * 100.0 / 190.0
    dwell2["angle_deg"] = rest - dwell["angle_deg"]
    rise.update(angle_deg=rise_deg, lift_mm=lift, control_count=controls)
    ret.update(angle_deg=return_deg, lift_mm=lift, control_count=controls)
    data["design"].update(alpha=alpha, gamma=gamma)
    data["synthesis"] = {"objective": {"l2_jerk": l2_jerk}}
    return data


def problem_set(count: int, seed: int = 0, samples=SAMPLES, controls=CONTROLS) -> list[dict]:
    """``count`` reproducible variations of the scene (the first one is the scene itself)."""
    rng = np.random.default_rng(seed)
    out = [dict(lift=10.0, rise_deg=90.0, return_deg=80.0, alpha=1.0, gamma=1.0, l2_jerk=1e-6)]
    while len(out) < count:
        out.append(dict(lift=float(rng.uniform(7.0, 13.0)), rise_deg=float(rng.uniform(75.0, 110.0)),
                        return_deg=float(rng.uniform(70.0, 100.0)), alpha=float(rng.uniform(0.5, 1.0)),
                        gamma=float(rng.uniform(0.5, 1.5)), l2_jerk=float(10 ** rng.uniform(-7.0, -5.0))))
    return [p | {"samples": samples, "controls": controls} for p in out]


class Joint:
    """The co-design as one nonlinear program in (z, free design variables, t) for SLSQP, and the
    common evaluation of both ends (jitted JAX; built on a :class:`Codesign`'s pure pieces)."""

    def __init__(self, cd: Codesign):
        self.cd = cd
        problem = cd.problem(cd.kinematics(cd.lin.z0))
        family = family_of(problem)
        lower, upper = family.bounds(problem)
        self.design_type = type(lower)
        self.lo = np.array([float(v) for v in lower])
        self.hi = np.array([float(v) for v in upper])
        self.free = self.hi > self.lo
        self.m = cd.lin.free
        self.P, self.q, self.c = (np.asarray(cd.law_P), np.asarray(cd.law_q), float(cd.law_c))
        self.rows = jax.jit(self._rows_and_jacobian)
        self.evaluate = jax.jit(self._evaluate)

    def _design(self, d_free):
        full, k = [], 0
        for i, fixed in enumerate(~self.free):
            if fixed:
                full.append(jnp.asarray(self.lo[i]))
            else:
                full.append(d_free[k])
                k += 1
        return self.design_type(*full)

    def _h(self, x):
        """SLSQP's inequality rows h >= 0 without t: -f_i (every angle), then -g / N."""
        z, d = x[: self.m], self._design(x[self.m:])
        problem = self.cd.problem(self.cd.kinematics(z))
        family = family_of(problem)
        f_i = jax.vmap(lambda p: family.objective(p, self.cd.weights, d))(family.per_angle(problem))
        g = jnp.concatenate([jnp.ravel(v) for v in family.constraints(problem, d)])
        return jnp.concatenate([-f_i, -g / family.size_norm(problem)]), f_i.shape[0]

    def _rows_and_jacobian(self, x, t):
        values, n = self._h(x)
        jac = jax.jacfwd(lambda y: self._h(y)[0])(x)
        dt = jnp.concatenate([jnp.ones(n), jnp.zeros(values.shape[0] - n)])
        return values + t * dt, jnp.concatenate([jac, dt[:, None]], axis=1)

    def _evaluate(self, z, d_free):
        """(family objective with the true max over the angles, largest row g / N, max f_i)."""
        d = self._design(d_free)
        problem = self.cd.problem(self.cd.kinematics(z))
        family = family_of(problem)
        g = jnp.concatenate([jnp.ravel(v) for v in family.constraints(problem, d)])
        return family.objective(problem, self.cd.weights, d), jnp.max(g) / family.size_norm(problem)

    def law(self, z) -> float:
        return float(0.5 * z @ self.P @ z + self.q @ z + self.c)

    def total(self, z, d_free) -> tuple[float, float]:
        """F(z, d) = family objective + law(z), and the largest constraint row g / N."""
        f, viol = jax.device_get(self.evaluate(jnp.asarray(z), jnp.asarray(d_free)))
        return float(f) + self.law(np.asarray(z)), float(viol)

    def free_design(self, design) -> np.ndarray:
        return np.array([float(v) for v in jax.tree.leaves(design)])[self.free]

    def slsqp(self, z0, d0_free, ftol=1e-12, maxiter=1000):
        """SLSQP from (z0, d0); returns (z, d_free, result)."""
        from scipy.optimize import minimize

        m, k = self.m, int(self.free.sum())
        cache: dict = {}

        def rows(x):  # SLSQP asks for the values and the Jacobian at the same point
            key = x.tobytes()
            if key not in cache:
                cache.clear()
                v, j = jax.device_get(self.rows(jnp.asarray(x[:-1]), jnp.asarray(x[-1])))
                cache[key] = (np.asarray(v), np.asarray(j))
            return cache[key]

        def fun(x):
            z = x[:m]
            return float(x[-1] + 0.5 * z @ self.P @ z + self.q @ z + self.c)

        def jac(x):
            z = x[:m]
            return np.concatenate([self.P @ z + self.q, np.zeros(k), [1.0]])

        x0 = np.concatenate([z0, d0_free])
        t0 = float(-np.min(rows(np.append(x0, 0.0))[0][: self.cd.samples]))
        bounds = [(None, None)] * m + list(zip(self.lo[self.free], self.hi[self.free], strict=True))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            res = minimize(fun, np.append(x0, t0), jac=jac, method="SLSQP", bounds=[*bounds, (None, None)],
                           constraints=[{"type": "ineq", "fun": lambda x: rows(x)[0],
                                         "jac": lambda x: rows(x)[1]}],
                           options={"ftol": ftol, "maxiter": maxiter})
        d = np.clip(res.x[m: m + k], self.lo[self.free], self.hi[self.free])
        return res.x[:m], d, res


def prepare(params: dict):
    """Codesign, joint program and the common start of one problem; every piece compiled here."""
    p = dict(params)
    samples, controls = p.pop("samples"), p.pop("controls")
    scene = scene_from_dict(scene_data(**p, samples=samples, controls=controls), "codesign-bench")
    t0 = time.perf_counter()
    cd = Codesign(scene)
    builtin = best_builtin_combination(cd)  # compiles the inner solve
    z0 = fitted_coordinates(cd, builtin[0])
    f0, inner0 = cd.value(z0)
    cd.gradient(z0, inner0)  # compiles the envelope gradient's pieces
    camjax_compile = time.perf_counter() - t0
    t0 = time.perf_counter()
    joint = Joint(cd)
    d0 = joint.free_design(inner0.design)
    jax.block_until_ready(joint.rows(jnp.asarray(np.concatenate([z0, d0])), jnp.asarray(0.0)))
    joint.total(z0, d0)
    slsqp_compile = time.perf_counter() - t0
    return cd, joint, builtin, z0, f0, d0, camjax_compile, slsqp_compile


def _median_time(call, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def run_problem(params: dict) -> dict:
    cd, joint, builtin, z0, f0, d0, cj_compile, sp_compile = prepare(params)
    cd.evaluations = 0
    t0 = time.perf_counter()
    f_start, inner_start = cd.value(z0)
    z_c, f_c, inner_c, iters, _ = bfgs(cd, z0, f_start, inner_start)
    camjax_s = time.perf_counter() - t0
    evaluations = cd.evaluations
    t0 = time.perf_counter()
    z_s, d_s, res = joint.slsqp(z0, d0)
    slsqp_s = time.perf_counter() - t0
    F_c, viol_c = joint.total(z_c, joint.free_design(inner_c.design))
    F_s, viol_s = joint.total(z_s, d_s)
    feasible_s = viol_s <= FEASIBLE_TOL
    # camjax's own bilevel F at SLSQP's laws (its inner geometry solve): equal to SLSQP's objective
    # when SLSQP's geometry is the inner optimum of its z, i.e. both programs are the same problem
    F_cd_at_s = cd.value(z_s)[0]
    # where camjax's time goes: one inner solve (F) and one envelope gradient at its end, each the
    # median of 5 calls, times how often the search made them
    value_s = _median_time(lambda: cd.value(z_c), 5)
    gradient_s = _median_time(lambda: cd.gradient(z_c, inner_c), 5)
    return {
        "params": params, "free_coordinates": int(cd.lin.free),
        "best_builtin": list(builtin[0]), "best_builtin_objective": float(builtin[1]),
        "start_objective": float(f0),
        "camjax": {"seconds": camjax_s, "compile_s": cj_compile, "objective": F_c,
                   "search_objective": float(f_c), "max_violation": viol_c, "iterations": int(iters),
                   "inner_solves": int(evaluations), "inner_solve_s": value_s,
                   "gradients": int(iters) + 1, "gradient_s": gradient_s,
                   "share_in_inner_solves": evaluations * value_s / camjax_s,
                   "share_in_gradients": (iters + 1) * gradient_s / camjax_s},
        "slsqp": {"seconds": slsqp_s, "compile_s": sp_compile, "objective": F_s, "max_violation": viol_s,
                  "feasible": bool(feasible_s), "success": bool(res.success), "message": str(res.message),
                  "iterations": int(res.nit), "evaluations": int(res.nfev), "jacobians": int(res.njev)},
        "camjax_F_at_slsqp_laws": float(F_cd_at_s),
        "rel_gap": (F_s - F_c) / abs(F_c),
        "speedup": slsqp_s / camjax_s,
    }


def main(argv=None) -> dict:
    from benchmarks.harness import environment

    ap = argparse.ArgumentParser()
    ap.add_argument("--problems", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="4 problems")
    ap.add_argument("--samples", type=int, default=SAMPLES)
    ap.add_argument("--controls", type=int, default=CONTROLS)
    ap.add_argument("--out", default="benchmarks/results/codesign.json")
    args = ap.parse_args(argv)
    count = 4 if args.quick else args.problems
    env = environment("float64")
    wall = time.perf_counter()
    rows = []
    for i, params in enumerate(problem_set(count, samples=args.samples, controls=args.controls)):
        r = run_problem(params)
        rows.append(r)
        print(f"{i:2d}  camjax {r['camjax']['seconds']:7.2f} s F={r['camjax']['objective']:.6f}   "
              f"slsqp {r['slsqp']['seconds']:7.2f} s F={r['slsqp']['objective']:.6f} "
              f"viol={r['slsqp']['max_violation']:.1e} ({r['slsqp']['message']})   "
              f"gap {r['rel_gap']:+.2e}  x{r['speedup']:.2f}", flush=True)
    cj = np.array([r["camjax"]["seconds"] for r in rows])
    sp = np.array([r["slsqp"]["seconds"] for r in rows])
    gaps = np.array([r["rel_gap"] for r in rows])
    ok = [r["slsqp"]["feasible"] for r in rows]
    within = [bool(abs(r["rel_gap"]) <= ACCURACY_RTOL) for r in rows]
    result = {"codesign": {
        "problems": count, "samples": args.samples, "control_values": args.controls,
        "scene": "built-in 'codesign' varied: rise lift 7-13 mm, rise 75-110 deg, return 70-100 deg, "
                 "alpha 0.5-1, gamma 0.5-1.5, l2_jerk 1e-7..1e-5 (log-uniform); problem 0 the scene "
                 "itself",
        "start": "best built-in law combination fitted onto the B-splines, with its optimal geometry "
                 "(both sides)",
        "timing": "one timed run per problem (camjax then SLSQP), every jitted piece compiled before "
                  "the clock; camjax: F at the start + BFGS; SLSQP: minimize() alone",
        "slsqp_speedup": float(np.median(sp / cj)),
        "slsqp_speedup_definition": "median over problems of SLSQP seconds / camjax seconds",
        "slsqp_speedup_of_totals": float(sp.sum() / cj.sum()),
        "camjax_median_s": float(np.median(cj)), "slsqp_median_s": float(np.median(sp)),
        "camjax_total_s": float(cj.sum()), "slsqp_total_s": float(sp.sum()),
        "camjax_median_s_per_inner_solve": float(np.median(
            [r["camjax"]["seconds"] / r["camjax"]["inner_solves"] for r in rows])),
        "camjax_median_share_in_inner_solves": float(np.median(
            [r["camjax"]["share_in_inner_solves"] for r in rows])),
        "camjax_median_share_in_gradients": float(np.median(
            [r["camjax"]["share_in_gradients"] for r in rows])),
        "camjax_median_inner_solves": float(np.median([r["camjax"]["inner_solves"] for r in rows])),
        "camjax_median_iterations": float(np.median([r["camjax"]["iterations"] for r in rows])),
        "slsqp_median_iterations": float(np.median([r["slsqp"]["iterations"] for r in rows])),
        "slsqp_median_s_per_jacobian": float(np.median(
            [r["slsqp"]["seconds"] / max(r["slsqp"]["jacobians"], 1) for r in rows])),
        "max_rel_difference_camjax_F_at_slsqp_laws": float(np.max(
            [abs(r["camjax_F_at_slsqp_laws"] - r["slsqp"]["objective"]) / abs(r["slsqp"]["objective"])
             for r in rows])),
        "camjax_compile_median_s": float(np.median([r["camjax"]["compile_s"] for r in rows])),
        "slsqp_compile_median_s": float(np.median([r["slsqp"]["compile_s"] for r in rows])),
        "rel_gap_definition": "(F_slsqp - F_camjax) / |F_camjax|, both evaluated by the same function "
                              "(family objective, true max over the grid, + law terms); < 0: SLSQP lower",
        "max_abs_rel_gap": float(np.max(np.abs(gaps))), "median_rel_gap": float(np.median(gaps)),
        "within_0.5_percent": int(sum(within)),
        "slsqp_lower_by_more_than_0.5_percent": int(sum(g < -ACCURACY_RTOL for g in gaps)),
        "camjax_lower_by_more_than_0.5_percent": int(sum(g > ACCURACY_RTOL for g in gaps)),
        "slsqp_infeasible": int(count - sum(ok)),
        "slsqp_not_success": int(sum(not r["slsqp"]["success"] for r in rows)),
        "load_average_1min": [env["load_average_at_start"][0] if env["load_average_at_start"] else None,
                              os.getloadavg()[0]],
        "wall_s": time.perf_counter() - wall,
        "per_problem": rows,
    }, "environment": env}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    summary = {k: v for k, v in result["codesign"].items() if k != "per_problem"}
    print(json.dumps(summary, indent=2))
    return result


if __name__ == "__main__":
    main()
