"""The outer search of a co-design and the scene it hands to the normal design run.

BFGS on the laws' free coordinates z (:class:`camjax.codesign.problem.Codesign` gives F(z) and its
envelope gradient), from the best built-in combination fitted onto the B-spline space and from
the law-only synthesis (or the starting law); the result is compared with the best built-in
combination (:mod:`camjax.codesign.builtin`) and the better one written into the scene as fixed
laws (:func:`fixed_scene`), on which ``camjax design`` runs as usual. With a designed spring
(:mod:`camjax.codesign.spring`) x = (z, u): the rate's coordinate u follows z, the fixed scene
carries the designed spring, and a box that keeps contact for no start is refused saying by how
much (:func:`spring_infeasible`).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import numpy as np

import camjax.codesign.helical as helical
import camjax.codesign.joint as joint
import camjax.codesign.peaks as peaks_mod
import camjax.codesign.spring as spring_mod
from camjax.codesign.builtin import (
    best_builtin_combination,
    builtin_kinematics,
    builtin_law_value,
    fitted_coordinates,
)
from camjax.codesign.problem import INNER_SOLVER, Codesign, CodesignError, Inner
from camjax.laws import LAWS
from camjax.program import MotionProgram
from camjax.solvers import quasi_newton as qn

MAX_ITERATIONS = 400  # BFGS steps of the outer search (the built-in scene stops by itself after ~200)

class SearchResult(NamedTuple):
    z: np.ndarray
    objective: float  # F on the grid
    inner: Inner
    iterations: int
    start: str  # "synthesis" or "builtin_fit"
    history: list  # F after each iteration


def bfgs(cd: Codesign, z0, f0: float, inner0: Inner, max_iterations: int = MAX_ITERATIONS,
         gtol: float = 1e-9, ftol: float = 1e-12) -> tuple[np.ndarray, float, Inner, int, list]:
    """BFGS with Armijo backtracking on F (:func:`backtrack`, or halving; inverse Hessian started at
    the identity scaled by the first step), each trial's inner solve from the inner optimum at z.
    Stops on a small gradient, no decrease, or ``max_iterations``; returns z, F, the inner
    optimum, the number of accepted steps and F after each."""
    z, f, inner = np.asarray(z0, dtype=np.float64), f0, inner0
    # the quadratic backtracking where F repeats to its last digits (the interior-point inner solve,
    # 1e-12); on the gradient solver's F (~3e-9) the halving (with the quadratic, the search of
    # tests/test_codesign_slsqp ended 2.6 % above SLSQP's optimum, past its 0.5 %)
    smooth = cd.inner_solver == INNER_SOLVER
    g = cd.gradient(z, inner)
    H = None
    history = [f]
    for _ in range(max_iterations):
        if not np.isfinite(f) or np.linalg.norm(g, np.inf) < gtol:
            break
        p = -(g if H is None else H @ g)
        slope = float(g @ p)
        if slope >= 0.0:  # not a descent direction: restart from steepest descent
            H, p, slope = None, -g, -float(g @ g)
        step = 1.0 if H is not None else min(1.0, 0.1 / max(np.linalg.norm(g, np.inf), 1e-300))
        least = step * 0.5**29  # the smallest step tried (30 halvings' worth)
        accepted = False
        while step >= least:
            zn = z + step * p
            fn, innern = cd.value(zn, inner.design)  # warm: from z's inner optimum
            if fn <= f + qn.ARMIJO * step * slope:
                accepted = True
                break
            step = backtrack(step, slope, f, fn) if smooth else 0.5 * step
        if not accepted:
            if H is None:
                break
            H = None  # retry along the gradient
            continue
        gn = cd.gradient(zn, innern)
        s_, y_ = zn - z, gn - g
        sy = float(s_ @ y_)
        if qn.curvature_ok(sy, np.linalg.norm(s_), np.linalg.norm(y_)):
            eye = np.eye(z.size)
            if H is None:
                H = qn.first_scaling(sy, float(y_ @ y_), eye)
            H = qn.inverse_hessian_update(H, s_, y_, sy, eye, np)
        decrease = f - fn
        z, f, g, inner = zn, fn, gn, innern
        history.append(f)
        if decrease <= ftol * max(1.0, abs(f)):
            break
    return z, f, inner, len(history) - 1, history


def backtrack(step: float, slope: float, f: float, f_step: float) -> float:
    """The next step length after ``step`` failed the Armijo test
    (:func:`camjax.solvers.quasi_newton.backtrack`): the minimizer of the quadratic through F
    (``f``), the slope along the direction and F at the step (``f_step``), kept within
    [0.1, 0.5] x ``step``; half the step where F there is +inf (an infeasible inner problem) or the
    quadratic has no minimum."""
    return float(qn.backtrack(step, slope, f, f_step, 0.5, np))


def search(cd: Codesign, x0, f0: float, inner0: Inner, max_iterations: int = MAX_ITERATIONS):
    """:func:`bfgs` from x0; with peak terms (:mod:`camjax.codesign.peaks`) a continuation: one BFGS
    per stage of the smoothing's schedule, each from the last one's answer; the answer is the start
    or a stage's answer with the least F with the exact maxima (the same returns as :func:`bfgs`;
    the iterations and history of every stage, the history in the stages' smoothed F)."""
    if cd.peaks is None:
        return bfgs(cd, x0, f0, inner0, max_iterations)
    x, inner, iterations, history = np.asarray(x0, dtype=np.float64), inner0, 0, []
    best = (f0, x, inner)  # the least F with the exact maxima: the start, then each stage's answer
    try:
        for taus in peaks_mod.schedule(cd.peaks, x[: cd.nz]):
            cd.taus = taus
            f = inner.objective + cd.law_value(x)  # the same inner optimum, the stage's smoothing
            x, f, inner, it, hist = bfgs(cd, x, f, inner, max_iterations)
            iterations += it
            history += hist
            cd.taus = None
            exact = inner.objective + cd.law_value(x)
            if exact < best[0]:
                best = (exact, x, inner)
    finally:
        cd.taus = None
    return best[1], best[0], best[2], iterations, history


class Outcome(NamedTuple):
    """A co-design: the scene to run the normal design on, and what the report says of it."""

    scene: Any  # the scene with every designed segment's law fixed (the chosen laws)
    chosen: str  # "codesign" (the designed B-splines) or "best_builtin"
    controls: list  # normalized control values of the designed laws (the search's best)
    objective: float  # F on the grid of the chosen laws
    codesign_objective: float  # F on the grid of the designed B-splines
    best_builtin: tuple[tuple[str, ...], float] | None  # (laws, F on the grid)
    iterations: int
    start: str
    evaluations: int  # inner solves
    history: list
    law_objective: float  # the [synthesis] terms of the chosen laws
    tables: list  # the designed segments as fixed [motion] segment tables (the chosen laws)
    samples: int  # the search's grid
    segments: list  # camjax.synthesis.segments.SegmentSynthesis of the designed B-splines
    spring: dict | None = None  # the designed spring (spring_report), None when not designed
    # the follower train the law terms are measured on (vibration.Train; law_train), or None
    train: Any = None
    # "joint" (camjax.codesign.joint) or "bilevel" (BFGS on F(z), the envelope gradient)
    method: str = "bilevel"


def codesign_scene(scene, samples: int | None = None, max_iterations: int = MAX_ITERATIONS) -> Outcome:
    """Co-design the scene's designed laws and its [design] geometry (see the module docstring).

    Raises :class:`CodesignError` (naming the scene field) for what the co-design does not take.
    """
    return codesign_outcome(Codesign(scene, samples), max_iterations)


def codesign_outcome(cd: Codesign, max_iterations: int = MAX_ITERATIONS) -> Outcome:
    """The co-design of ``cd``'s scene at its current weighting (:func:`codesign_scene` with a
    :class:`Codesign` built already: ``camjax sweep`` reweights one, :meth:`Codesign.set_weights`)."""
    from camjax.synthesis.segments import synthesize_segments

    scene = cd.scene
    builtin = best_builtin_combination(cd)
    starts = []
    if builtin is not None:
        starts.append(("builtin_fit", fitted_coordinates(cd, builtin[0])))
    if cd.law_weights:
        spec = scene.synthesis
        train = law_train(cd) if set(cd.law_weights) & {"peak_force", "residual_vibration"} else None
        law_only = synthesize_segments(cd.designed, cd.law_weights, spec.samples_per_span, train)
        starts.append(("synthesis", cd.lin.coordinates([r.control for r in law_only])))
    else:
        starts.append(("starting_law", cd.lin.z0))
    best = None
    for name, z0 in starts:
        x0 = _with_rate(cd, z0, builtin)
        f0, inner0 = cd.value(x0)
        if not np.isfinite(f0) and cd.u0 is not None:  # the laws' own best rate
            u, inner0 = cd.best_rate(cd.kinematics(z0))
            x0, f0 = np.append(z0, u), inner0.objective + cd.law_value(z0)
        if not np.isfinite(f0):
            continue
        if joint.supports(cd):  # the laws and the geometry in one program (camjax.codesign.joint)
            z, f, inner, it, hist = joint.search(cd, x0, f0, inner0)
        else:
            z, f, inner, it, hist = search(cd, x0, f0, inner0, max_iterations)
        if best is None or f < best.objective:
            best = SearchResult(z, f, inner, it, name, hist)
    if best is None and (builtin is None or not np.isfinite(builtin[1])):
        if cd.spring is not None:
            raise spring_infeasible(cd, [z for _, z in starts], builtin)
        raise CodesignError("design", "no start of the co-design has a feasible geometry within [design]'s "
                            "bounds, and no built-in law meets the designed segments' conditions")
    controls = cd.lin.control(best.z[: cd.nz]) if best is not None else cd.lin.control(cd.lin.z0)
    designed_f = best.objective if best is not None else math.inf
    use_builtin = builtin is not None and builtin[1] <= designed_f
    laws = ([LAWS[n] for n in builtin[0]] if use_builtin else
            [_designed_law(ds, c) for ds, c in zip(cd.designed, controls, strict=True)])
    tables = _segment_tables(scene, controls, builtin[0] if use_builtin else None)
    law_f = builtin_law_value(cd, builtin[0]) if use_builtin else cd.law_value(cd.lin.coordinates(controls))
    inner = builtin[2] if use_builtin else best.inner
    train = None if inner.spring is None else spring_mod.train_of(cd.spring, *inner.spring)
    fixed = fixed_scene(scene, laws, tables, train)
    return Outcome(fixed,
                   "best_builtin" if use_builtin else "codesign", controls,
                   builtin[1] if use_builtin else designed_f, designed_f,
                   None if builtin is None else (builtin[0], builtin[1]),
                   0 if best is None else best.iterations, "" if best is None else best.start,
                   cd.evaluations, [] if best is None else best.history, law_f, tables, cd.samples,
                   segment_results(cd, controls),
                   helical.with_helical(scene, fixed, spring_report(cd, fixed, inner.spring)), law_train(cd),
                   "joint" if joint.supports(cd) else "bilevel")


def law_train(cd: Codesign):
    """The co-design's follower train for the law terms and figures, or None without [dynamics]:
    with ``peak_force`` the train with [dynamics]' spring (a designed spring is refused with it),
    else for the residual vibration alone (no spring: no force figures; the co-design's spring may
    differ from [dynamics'])."""
    if cd.train is None or "peak_force" in cd.law_weights:
        return cd.train
    return cd.train._replace(spring_rate=None)


def segment_results(cd: Codesign, controls) -> list:
    """Each designed B-spline's figures as ``camjax synthesize`` reports them (normalized measures,
    with [dynamics] the residual vibration, its [synthesis] terms, the best built-in law of its
    class for those terms alone)."""
    from camjax.synthesis.basis import span_points
    from camjax.synthesis.problem import MEASURE_PER_SPAN, OBJECTIVES, build_problem
    from camjax.synthesis.segments import ORDERS, SegmentSynthesis, best_builtin, term_value
    from camjax.synthesis.solve import measures
    from camjax.synthesis.vibration import force_matrix, residual_figures

    out = []
    train = law_train(cd)
    for k, (ds, c) in enumerate(zip(cd.designed, controls, strict=True)):
        basis = ds.basis()
        m = measures(build_problem(basis, ds.conditions, ()), c)
        meas = {n: (float(getattr(m, n)) if ORDERS[n] <= ds.degree else None) for n in OBJECTIVES}
        if cd.residual is not None:
            meas.update(residual_figures(np.linalg.norm(cd.residual[k][0] @ np.asarray(c), axis=1)))
        if "peak_force" in cd.law_weights:  # the train's contact force on the reported points
            dense = force_matrix(basis, cd.train, ds, span_points(basis, MEASURE_PER_SPAN))
            meas["peak_force"] = float(np.max(np.abs(dense @ np.asarray(c))))
        law_f = sum(w * term_value(n, meas[n]) for n, w in cd.law_weights.items())
        out.append(SegmentSynthesis(ds, basis.knots, np.asarray(c), meas, law_f, law_f, True, 0.0,
                                    best_builtin(ds, cd.law_weights, train) if cd.law_weights else None))
    return out


def _designed_law(ds, control):
    from camjax.scene.designed import law_from_control

    return law_from_control(ds, control)[0]


def _segment_tables(scene, controls, builtin_names) -> list[dict]:
    """The designed segments as fixed [motion] segment tables (what result.json's scene_segment
    holds): the B-spline's control values, or the chosen built-in law."""
    from camjax.scene.designed import law_from_control

    out = []
    from camjax import followers

    lift_key = "lift_deg" if followers.of(scene).rocking else "lift_mm"
    for k, (ds, c) in enumerate(zip(scene.motion.designed, controls, strict=True)):
        table = {"kind": ds.kind, "angle_deg": ds.angle_deg, lift_key: ds.lift}
        if builtin_names is not None:
            table["law"] = builtin_names[k]
        else:
            table.update({"law": "bspline", "degree": ds.degree,
                          "control": [float(v) for v in law_from_control(ds, c)[1]]})
            if ds.knots is not None:
                table["knots"] = list(ds.knots)
        out.append(table)
    return out


def fixed_scene(scene, laws, tables, train=None):
    """The scene with designed segment k moving by ``laws[k]`` (no segment designed any more), its
    reported segment table ``tables[k]``; ``train``: the follower train (a designed spring)."""
    motion = scene.motion
    program = motion.program
    new_laws, reported = list(program.laws), list(motion.segments)
    for ds, law, table in zip(motion.designed, laws, tables, strict=True):
        new_laws[ds.index] = law
        reported[ds.index] = table
    fixed = MotionProgram(program.kinds, program.angles_deg, new_laws, program.lifts)
    motion = dataclasses.replace(motion, program=fixed, segments=tuple(reported), designed=())
    if train is not None:
        scene = dataclasses.replace(scene, follower=dataclasses.replace(scene.follower, train=train))
    return dataclasses.replace(scene, motion=motion)


def _with_rate(cd: Codesign, z, builtin) -> np.ndarray:
    """The outer x of laws z: z, then (a free rate) the best built-in combination's rate, or the start's."""
    if cd.u0 is None:
        return np.asarray(z, dtype=np.float64)
    spring = builtin[2].spring if builtin is not None and np.isfinite(builtin[1]) else None
    u = cd.u0 if spring is None else spring_mod.u_of(cd.spring, spring[0])
    return np.append(np.asarray(z, dtype=np.float64), u)


def spring_infeasible(cd: Codesign, starts, builtin) -> CodesignError:
    """The error of a co-design whose spring box keeps contact for none of its starting laws (nor the
    best built-in combination): which constraint binds, and by how much at the box's best."""
    kins = [cd.kinematics(z) for z in starts]
    if builtin is not None:
        kins.append(builtin_kinematics(cd, builtin[0]))
    box = cd.spring
    n = box.units
    deficit, k, at = min(spring_mod.contact_deficit(box, kin4) for kin4 in kins)
    rpm = cd.scene.motion.rpm * box.overspeed
    if deficit <= 0.0:
        return CodesignError("design", "no start of the co-design has a feasible geometry within [design]'s "
                             f"bounds with a spring that keeps contact ({n.rate} = {k:g}, {n.preload} "
                             f"<= {box.preload[1]:g})")
    deg = at * 360.0 / cd.samples  # the grid's sample angles
    u = n.load_unit
    return CodesignError(f"synthesis.{n.margin}", (
        f"{box.min_force:g} {u}: no spring in the box keeps contact at {box.overspeed:g} x rpm = {rpm:g} "
        "rpm: "
        f"the constraint {n.load} >= {box.min_force:g} {u} binds at {deg:.4g} deg, where the best "
        f"spring for it ({n.rate} = {k:g}, {n.preload} = {box.preload[1]:g}) gives "
        f"{box.min_force - deficit:.4g} {u}, {deficit:.4g} {u} short (allowed: larger {n.rate} or "
        f"{n.preload} bounds, a smaller {n.margin} or overspeed)"))


def spring_report(cd: Codesign, fixed, spring) -> dict | None:
    """result.json's ``synthesis.codesign.spring``: the designed rate and preload, and the least
    contact load of the chosen design at the overspeed by the loads model of ``fixed`` (the scene
    the design is written from) on the search grid, with where it is reached and what binds. A
    translating follower's keys are in N/m and N (the contact force), a rocker's in N m/rad and
    N m (the moment about the pivot; the preload also as the wind-up in rad)."""
    if spring is None:
        return None
    box = cd.spring
    rpm = fixed.motion.rpm * box.overspeed
    theta_deg, load = spring_mod.scene_load(box, fixed, cd.samples)
    k, p = spring
    need = box.min_force - float(load.min()) + p  # the least preload keeping the margin
    binding = ("contact" if abs(p - need) <= 1e-6 * max(1.0, abs(p)) else
               "preload_low" if box.preload[1] > box.preload[0] else "none")
    at_bound = ("low" if k <= box.rate[0] * (1 + 1e-4) else "high" if k >= box.rate[1] * (1 - 1e-4)
                else None) if box.free_rate else "fixed"
    least, where = float(load.min()), float(theta_deg[int(np.argmin(load))])
    if box.rocking:
        return {
            "rate_N_m_per_rad": k, "preload_N_m": p, "preload_rad": p / k,
            "rate_bounds_N_m_per_rad": list(box.rate), "preload_bounds_N_m": list(box.preload),
            "min_contact_torque_N_m": box.min_force, "overspeed": box.overspeed, "rpm_overspeed": rpm,
            "min_contact_torque_at_overspeed_N_m": least, "min_contact_torque_at_overspeed_deg": where,
            "binding": binding, "rate_at_bound": at_bound,
        }
    return {
        "rate_N_per_m": k, "preload_N": p, "preload_mm": 1e3 * p / k,
        "rate_bounds_N_per_m": list(box.rate), "preload_bounds_N": list(box.preload),
        "min_contact_force_N": box.min_force, "overspeed": box.overspeed, "rpm_overspeed": rpm,
        "min_contact_force_at_overspeed_N": least, "min_contact_force_at_overspeed_deg": where,
        "binding": binding, "rate_at_bound": at_bound,
    }
