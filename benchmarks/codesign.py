"""Co-design of law and geometry against SciPy's SLSQP on the same discretization.

Each problem: the built-in scene ``codesign`` (flat face; a rise and a return designed as cubic
B-splines at rest at the dwells; base radius and face width free; α size + γ stress + l2_jerk)
on a coarser grid, varied reproducibly (rise lift, rise and return angles, α/γ, the l2_jerk
weight). Both sides start from the same point: the best built-in law combination (each with its
own optimal geometry, :func:`camjax.codesign.best_builtin_combination`) fitted onto the B-spline
space (:func:`camjax.codesign.builtin.fitted_coordinates`), and its optimal geometry.

- **camjax**: the co-design as ``camjax design`` runs it on such a scene: the joint program of
  :mod:`camjax.codesign.joint` (the laws' z, the geometry and an epigraph variable in one
  problem, solved by the scene's solver, ``newton``: the interior point; ``--solver gradient``: the
  gradient solver's augmented-Lagrangian BFGS; then the geometry of its laws solved as the
  inner solve does), the 20 problems stacked and solved in one vmapped, jitted program (timed
  after a compiling run; seconds per problem = the batch's / problems: ``slsqp_speedup_batched``),
  and each problem alone by one compiled single solve, as ``camjax design`` runs it
  (``slsqp_speedup``).
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
time), both one problem at a time, with the totals' ratio and the batched ratio beside it; the
relative gaps; the load average.

    python -m benchmarks.codesign [--quick] [--solver newton|gradient]
        [--out benchmarks/results/codesign.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tomllib
import warnings
from functools import partial
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import camjax  # noqa: F401  (x64)
import camjax.codesign.joint as joint_mod
from camjax.codesign import Codesign, best_builtin_combination
from camjax.codesign.builtin import fitted_coordinates
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


def _pick(tree, k: int):
    return jax.tree.map(lambda x: x[k], tree)


def camjax_batch(prepared, solver: str = "newton"):
    """The camjax side: every problem's joint program (:mod:`camjax.codesign.joint`) from its
    start, stacked; the batch solved in one vmapped program (timed after a compiling run), and
    each problem alone by the same compiled single solve (timed one by one after a compiling run).
    Returns (batched results, batch seconds, compile seconds, seconds of each alone)."""
    problems, starts = [], []
    for cd, _, _, z0, _, _, _, _ in prepared:
        _, inner0 = cd.value(z0)
        jp, st = joint_mod.joint_problem(cd, z0, inner0.design)
        problems.append(jp)
        starts.append(st)
    batch = joint_mod.stack(problems)
    batch_starts = jax.tree.map(lambda *x: jnp.stack(x), *starts)
    t0 = time.perf_counter()
    jax.block_until_ready(joint_mod.solve_batch(batch, batch_starts, solver=solver))
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = jax.device_get(joint_mod.solve_batch(batch, batch_starts, solver=solver))
    batch_s = time.perf_counter() - t0
    one = jax.jit(partial(joint_mod.solve, solver=solver))
    jax.block_until_ready(one(_pick(batch, 0), _pick(batch_starts, 0)))
    alone = []
    for k in range(len(prepared)):
        p_k, s_k = _pick(batch, k), _pick(batch_starts, k)
        t0 = time.perf_counter()
        jax.block_until_ready(one(p_k, s_k))
        alone.append(time.perf_counter() - t0)
    return res, batch_s, compile_s, alone


def run_slsqp(prep) -> dict:
    cd, joint, builtin, z0, f0, d0, cj_compile, sp_compile = prep
    t0 = time.perf_counter()
    z_s, d_s, res = joint.slsqp(z0, d0)
    slsqp_s = time.perf_counter() - t0
    F_s, viol_s = joint.total(z_s, d_s)
    return {"seconds": slsqp_s, "compile_s": sp_compile, "objective": F_s, "max_violation": viol_s,
            "feasible": bool(viol_s <= FEASIBLE_TOL), "success": bool(res.success),
            "message": str(res.message),
            "iterations": int(res.nit), "evaluations": int(res.nfev), "jacobians": int(res.njev),
            # camjax's own bilevel F at SLSQP's laws (its inner geometry solve): equal to SLSQP's
            # objective when SLSQP's geometry is the inner optimum of its z: the same problem
            "camjax_F_at_slsqp_laws": float(cd.value(z_s)[0])}


def main(argv=None) -> dict:
    from benchmarks.harness import environment

    ap = argparse.ArgumentParser()
    ap.add_argument("--problems", type=int, default=20)
    ap.add_argument("--quick", action="store_true", help="4 problems")
    ap.add_argument("--samples", type=int, default=SAMPLES)
    ap.add_argument("--controls", type=int, default=CONTROLS)
    ap.add_argument("--solver", default="newton", choices=("newton", "gradient"),
                    help="the joint program's solver (default newton, the built-in scenes')")
    ap.add_argument("--out", default="benchmarks/results/codesign.json")
    args = ap.parse_args(argv)
    count = 4 if args.quick else args.problems
    env = environment("float64")
    wall = time.perf_counter()
    params = problem_set(count, samples=args.samples, controls=args.controls)
    prepared = [prepare(p) for p in params]
    res, batch_s, batch_compile_s, alone = camjax_batch(prepared, args.solver)
    per_problem_s = batch_s / count
    rows = []
    for k, (p, prep) in enumerate(zip(params, prepared, strict=True)):
        cd, joint, builtin, z0, f0 = prep[:5]
        z_c = np.asarray(res.laws[k])
        F_c, viol_c = joint.total(z_c, joint.free_design(_pick(res.design, k)))
        sp = run_slsqp(prep)
        r = {
            "params": p, "free_coordinates": int(cd.lin.free),
            "best_builtin": list(builtin[0]), "best_builtin_objective": float(builtin[1]),
            "start_objective": float(f0),
            "camjax": {"seconds_in_batch": per_problem_s, "seconds_alone": alone[k], "objective": F_c,
                       "solver_objective": float(res.objective[k]), "max_violation": viol_c,
                       "feasible": bool(res.feasible[k]), "evaluations": int(res.iterations[k]),
                       "laws_at_box": bool(res.at_box[k]), "compile_s": prep[6]},
            "slsqp": sp,
            "rel_gap": (sp["objective"] - F_c) / abs(F_c),
            "speedup": sp["seconds"] / alone[k],
            "speedup_batched": sp["seconds"] / per_problem_s,
        }
        rows.append(r)
        print(f"{k:2d}  camjax {per_problem_s:6.3f} s/problem in the batch, {alone[k]:6.3f} s alone "
              f"F={F_c:.6f}   slsqp {sp['seconds']:6.2f} s F={sp['objective']:.6f} "
              f"viol={sp['max_violation']:.1e}   gap {r['rel_gap']:+.2e}  x{r['speedup']:.1f} "
              f"(batched x{r['speedup_batched']:.1f})", flush=True)
    sp = np.array([r["slsqp"]["seconds"] for r in rows])
    alone = np.array(alone)
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
        "camjax_solver": args.solver,
        "camjax_method": "the joint program (camjax.codesign.joint: laws, geometry and an epigraph "
                         "variable in one problem, solved by camjax_solver (newton: the interior "
                         "point; gradient: the augmented-Lagrangian BFGS), then the geometry of its "
                         "laws solved as camjax design solves it): each problem alone by one compiled "
                         "single solve (slsqp_speedup), and the problems stacked in one vmapped, "
                         "jitted solve (slsqp_speedup_batched)",
        "timing": "camjax: one timed run of the batch after a compiling run (seconds per problem = the "
                  "batch's / problems), and each problem alone by one compiled single solve; SLSQP: "
                  "minimize() alone, one problem at a time, its Jacobian compiled before the clock",
        "slsqp_speedup": float(np.median(sp / alone)),
        "slsqp_speedup_definition": "median over problems of SLSQP seconds / camjax seconds, both one "
                                    "problem at a time",
        "slsqp_speedup_of_totals": float(sp.sum() / alone.sum()),
        "slsqp_speedup_batched": float(np.median(sp / per_problem_s)),
        "slsqp_speedup_batched_definition": "median over problems of SLSQP seconds / camjax seconds per "
                                            "problem in the vmapped batch (every member runs until the "
                                            "batch's slowest ends)",
        "camjax_batch_s": batch_s, "camjax_per_problem_in_batch_s": per_problem_s,
        "camjax_alone_median_s": float(np.median(alone)), "camjax_alone_total_s": float(alone.sum()),
        "slsqp_median_s": float(np.median(sp)), "slsqp_total_s": float(sp.sum()),
        "camjax_batch_compile_s": batch_compile_s,
        "camjax_evaluations_definition": "the joint solve's iterations: Newton steps (newton) or "
                                         "evaluations of the augmented Lagrangian and its gradient "
                                         "(gradient)",
        "camjax_median_evaluations": float(np.median([r["camjax"]["evaluations"] for r in rows])),
        "camjax_max_evaluations": int(np.max([r["camjax"]["evaluations"] for r in rows])),
        "camjax_laws_at_box": int(sum(r["camjax"]["laws_at_box"] for r in rows)),
        "camjax_infeasible": int(sum(not r["camjax"]["feasible"] for r in rows)),
        "slsqp_median_iterations": float(np.median([r["slsqp"]["iterations"] for r in rows])),
        "max_rel_difference_camjax_F_at_slsqp_laws": float(np.max(
            [abs(r["slsqp"]["camjax_F_at_slsqp_laws"] - r["slsqp"]["objective"])
             / abs(r["slsqp"]["objective"]) for r in rows])),
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
