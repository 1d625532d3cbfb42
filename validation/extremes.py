"""The numerical-stability matrix: camjax at the edges of its inputs, against float64 references.

Each :class:`Case` records a computed value, an independent float64 reference (closed form,
NumPy, or a float64 run of the same quantity for the precision table), the error, the tolerance
with its reason, and pass/fail. ``camjax check-extremes`` runs :func:`run_matrix` and writes it.
An oscillating follower runs its own geometry, speed, precision and optimization cases (the
rocker_* functions: its sizing, pivot and arm; no flat-face formula). A group that needs a model
the scene does not declare (loads, [contact], [design]) is skipped;
:func:`skipped_groups` says which and why.

This module lives beside the package, not in it: it is a test framework, shipped with the source
checkout (``pip install -e .``) and not with an installed wheel.

Not for ``jit``: this module drives the library from Python and reports; everything it calls is
jitted/differentiated inside.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, followers, loads, program
from camjax.evaluate import scene_arrays
from camjax.followers.flat import geometry as flat_geo
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.laws import LAWS, boundary_condition_number, polynomial_coefficients, polynomial_law
from camjax.numerics import RHO_FLOOR_MM, STRESS_RTOL, precision_warning
from camjax.program import MotionProgram, Segment
from camjax.scene import Scene, load_scene


class Case(NamedTuple):
    """One row of the matrix."""

    group: str
    name: str
    value: float
    reference: float
    error: float
    tolerance: float
    passed: bool
    note: str = ""

    def as_dict(self) -> dict:
        d = self._asdict()
        for k in ("value", "reference", "error", "tolerance"):
            v = d[k]
            d[k] = v if math.isfinite(v) else str(v)  # JSON has no inf/nan
        return d


def _case(group, name, value, reference, tol, *, relative=False, note="") -> Case:
    value, reference = float(value), float(reference)
    err = abs(value - reference)
    if relative:
        err = err / max(abs(reference), 1e-300)
    ok = math.isfinite(value) and math.isfinite(err) and err <= tol
    return Case(group, name, value, reference, err, float(tol), bool(ok), note)


def _count_nonfinite(*arrays) -> int:
    leaves = jax.tree_util.tree_leaves(arrays)
    return int(sum(int(np.sum(~np.isfinite(np.asarray(a)))) for a in leaves))


def _finite_case(group, name, *arrays, note="") -> Case:
    bad = _count_nonfinite(*arrays)
    return Case(
        group,
        name,
        float(bad),
        0.0,
        float(bad),
        0.0,
        bad == 0,
        note or "number of non-finite entries in values and gradients",
    )


# ------------------------------------------------------------------------------------ laws


def law_cases() -> list[Case]:
    """Boundary conditions at 0, 1 and 1e-15 from them; closed forms vs autodiff on a dense grid."""
    out = []
    ends = jnp.asarray([0.0, 1e-15, 1.0 - 1e-15, 1.0])
    x = jnp.linspace(0.0, 1.0, 4001)
    for name, law in LAWS.items():
        v = law(ends)
        bc = max(abs(float(v.p[0])), abs(float(v.p[3]) - 1.0),
                 abs(float(v.dp[0]) - law.end_velocity), abs(float(v.dp[3]) - law.end_velocity))
        # 1e-15 inside an end: p moves by at most max|p'| 1e-15 ~ 3e-15
        near = max(abs(float(v.p[1] - v.p[0])), abs(float(v.p[2] - v.p[3])))
        out.append(
            _case(
                "laws",
                f"{name}: boundary conditions p(0)=0, p(1)=1, p'={law.end_velocity:g}",
                bc,
                0.0,
                1e-13,
                note="round-off of sin/cos at the ends (a few ulps of the peak values)",
            )
        )
        out.append(
            _case(
                "laws",
                f"{name}: p within 1e-15 of the ends",
                near,
                0.0,
                1e-14,
                note="|p(1e-15) - p(0)| <= max|p'| * 1e-15 plus round-off",
            )
        )
        vals = law(x)
        worst = 0.0
        for k, closed in enumerate((vals.dp, vals.d2p, vals.d3p)):
            ad = jax.vmap(jax.grad(lambda t, k=k, law=law: law(t)[k]))(x)
            scale = max(1.0, float(jnp.max(jnp.abs(closed))))
            worst = max(worst, float(jnp.max(jnp.abs(closed - ad))) / scale)
        out.append(
            _case(
                "laws",
                f"{name}: closed-form derivatives vs jax.grad (4001 points)",
                worst,
                0.0,
                1e-10,
                note="relative to the peak; both are float64 evaluations of one formula",
            )
        )
        out.append(_finite_case("laws", f"{name}: values and autodiff finite on [0, 1]", vals))
    return out


def polynomial_cases() -> list[Case]:
    """General polynomial laws up to exponent 12: boundary residual vs condition number."""
    out = []
    sets = [tuple(range(3, k + 1)) for k in range(4, 13)] + [(2, 5, 9, 12), (3, 7, 11), (5, 12), (1, 12)]
    for exps in sets:
        law = polynomial_law(exps)
        end = law(jnp.asarray(1.0))
        resid = abs(float(end.p) - 1.0)
        for k, d in enumerate((end.dp, end.d2p, end.d3p), start=1):
            if k < len(exps):
                resid = max(resid, abs(float(d)))
        cond = boundary_condition_number(exps)
        coef = sum(abs(float(c)) for c in polynomial_coefficients(exps))
        # evaluation at x = 1 sums terms of size ~ sum |c_k| [e_k]_3: round-off ~ eps times that
        tol = 64 * np.finfo(float).eps * coef * max(exps) ** 3
        out.append(
            _case(
                "polynomials",
                f"exponents {'-'.join(map(str, exps))} (cond {cond:.1e})",
                resid,
                0.0,
                tol,
                note=f"boundary residual; coefficients exact (rational), sum|c| = {coef:.3g}",
            )
        )
    return out


# -------------------------------------------------------------------------------- programs


def _cycloid_numpy(theta_deg, rise_deg, lift):
    """s, s' of dwell-free rise(rise_deg)-return(360-rise_deg) cycloidal program, NumPy float64."""
    th = np.asarray(theta_deg, dtype=np.float64)
    ret = 360.0 - rise_deg
    s, v = np.zeros_like(th), np.zeros_like(th)
    m = th < rise_deg
    x = th[m] / rise_deg
    s[m] = lift * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    v[m] = lift * (1 - np.cos(2 * np.pi * x)) / math.radians(rise_deg)
    x = (th[~m] - rise_deg) / ret
    s[~m] = lift * (1 - (x - np.sin(2 * np.pi * x) / (2 * np.pi)))
    v[~m] = -lift * (1 - np.cos(2 * np.pi * x)) / math.radians(ret)
    return s, v


def program_cases(sample_counts: Iterable[int] = (1, 2, 7, 360, 36_000, 360_000)) -> list[Case]:
    """Rise angles 0.5..359 deg, lifts 1e-6..1e3 mm, grids of 1..360 000 samples."""
    out = []
    cyc = LAWS["cycloidal"]
    for rise_deg in (0.5, 1.0, 90.0, 359.0, 359.5):
        for lift in (1e-6, 1.0, 1e3):
            prog = MotionProgram.from_segments(
                [Segment("rise", rise_deg, cyc, lift), Segment("return", 360.0 - rise_deg, cyc, lift)]
            )
            for n in sample_counts:
                if n > 36_000 and not (lift == 1.0 and rise_deg == 0.5):
                    continue  # the largest grid once, on the hardest segment ratio
                kin = program.evaluate(prog, n)
                s_ref, v_ref = _cycloid_numpy(np.arange(n) * 360.0 / n, rise_deg, lift)
                err = float(np.max(np.abs(np.asarray(kin.s) - s_ref))) / lift
                verr = float(
                    np.max(np.abs(np.asarray(kin.ds) - v_ref) / np.maximum(np.max(np.abs(v_ref)), 1e-300))
                )
                name = f"rise {rise_deg:g} deg, lift {lift:g} mm, N = {n}"
                out.append(
                    _case(
                        "programs",
                        f"{name}: s vs NumPy (relative to lift)",
                        max(err, verr),
                        0.0,
                        1e-12,
                        note="two float64 evaluations of the same closed form",
                    )
                )
    # joints exactly on samples and between them
    prog = MotionProgram.from_segments(
        [
            Segment("dwell", 100),
            Segment("rise", 80, cyc, 5.0),
            Segment("dwell", 120),
            Segment("return", 60, cyc, 5.0),
        ]
    )
    for n in (360, 7, 1000):
        kin = program.evaluate(prog, n)
        th = np.arange(n) * 360.0 / n
        on = np.isin(np.round(th, 9), [100.0, 180.0, 300.0])
        expected = np.where(th < 100, 0.0, np.where(th < 180, np.nan, np.where(th < 300, 5.0, np.nan)))
        ok = np.isnan(expected) | (np.abs(np.asarray(kin.s) - np.nan_to_num(expected)) < 1e-12)
        out.append(
            Case(
                "programs",
                f"reference program, N = {n}: dwell levels exact ({int(on.sum())} samples on joints)",
                float((~ok).sum()),
                0.0,
                float((~ok).sum()),
                0.0,
                bool(ok.all()),
                "samples on a joint belong to the segment that starts there",
            )
        )
    # FLCD: exact one-sided jumps, not sampled differences
    j = {jt.joint_deg: jt for jt in program.joints(prog)}[100.0]
    out.append(
        _case(
            "programs",
            "FLCD jump of s''' at 100 deg vs h 4 pi^2 / beta^3",
            j.jump_j,
            5.0 * 4 * math.pi**2 / math.radians(80) ** 3,
            1e-12,
            relative=True,
            note="one-sided limits of the closed form at the joint",
        )
    )
    return out


# ------------------------------------------------------------------------ geometry, stress


def geometry_cases(scene: Scene) -> list[Case]:
    """Base radius 1e-3x..10x the minimum, rho -> 0+, rho <= 0, gradients everywhere (an
    oscillating follower: :func:`rocker_geometry_cases`)."""
    if followers.of(scene).rocking:
        return rocker_geometry_cases(scene)
    out = []
    arrays = scene_arrays(scene)
    rb_min = float(flat_geo.flat_min_base_radius(arrays.kin)[0])

    def peak_stress(rb):
        rho = flat_geo.flat_radius_of_curvature(rb, arrays.kin)
        return jnp.max(contact.stress_from_coefficient(arrays.stress_coefficient, rho))

    vg = jax.jit(jax.value_and_grad(peak_stress))
    for factor in (1e-3, 0.1, 0.5, 0.99, 1.0, 1.0 + 1e-12, 1.01, 2.0, 10.0):
        rb = rb_min * factor
        val, grad = vg(rb)
        rho_min = float(jnp.min(flat_geo.flat_radius_of_curvature(rb, arrays.kin)))
        feasible = rho_min > 0
        out.append(
            _finite_case(
                "geometry",
                f"R_b = {factor:g} x min ({rb:.6g} mm): sigma and "
                f"d sigma/dR_b finite; {'feasible' if feasible else 'infeasible (rho <= 0)'}",
                val,
                grad,
            )
        )
    return out + stress_cases(scene)


def stress_cases(scene: Scene) -> list[Case]:
    """Hertz line stress of the scene's [contact] in closed form down to rho = 1e-12 mm, and its
    saturation at rho <= 0 (any follower type: the materials and the width only)."""
    out = []
    c = scene.contact
    # sigma ~ rho^-1/2 down to rho = 1e-12 mm
    k = contact.compliance(c.cam, c.follower)
    for rho in (1.0, 1e-3, 1e-6, 1e-9, 1e-12):
        s = contact.hertz_line_stress(50.0, rho, c.cam_width_mm, c.cam, c.follower)
        ref = 0.564 * math.sqrt(50.0 / c.cam_width_mm / (rho * float(k)))
        out.append(
            _case(
                "stress",
                f"sigma at rho = {rho:g} mm (F = 50 N)",
                s,
                ref,
                1e-14,
                relative=True,
                note="closed form; sqrt and divide are correctly rounded",
            )
        )
    sat = contact.hertz_line_stress(50.0, -1.0, c.cam_width_mm, c.cam, c.follower)
    ref = 0.564 * math.sqrt(50.0 / c.cam_width_mm / (RHO_FLOOR_MM * float(k)))
    out.append(
        _case(
            "stress",
            "sigma at rho = -1 mm saturates at the floor value",
            sat,
            ref,
            1e-14,
            relative=True,
            note=f"rho floored at {RHO_FLOOR_MM:g} mm: finite, flagged infeasible",
        )
    )
    return out


def speed_cases(scene: Scene) -> list[Case]:
    """Cam speeds 0 .. 20 000 rpm: forces and torques finite, contact loss reported (an
    oscillating follower: :func:`rocker_speed_cases`)."""
    if followers.of(scene).rocking:
        return rocker_speed_cases(scene)
    out = []
    arrays = scene_arrays(scene)
    train = scene.follower.train
    for rpm in (0.0, 1.0, 240.0, 2000.0, 20_000.0):
        w = program.rpm_to_rad_s(rpm)

        def peak_force(w):
            motion = program.time_kinematics(arrays.kin, w)
            f = loads.kinetostatic_force(train, motion)
            return jnp.max(f) + jnp.max(loads.cam_torque(f, arrays.kin.ds))

        val, grad = jax.value_and_grad(peak_force)(jnp.asarray(w))
        motion = program.time_kinematics(arrays.kin, w)
        margin = float(loads.contact_margin(loads.kinetostatic_force(train, motion)))
        state = "contact kept" if margin > 0 else "contact LOST (reported)"
        out.append(
            _finite_case("speed", f"{rpm:g} rpm: force, torque and gradient finite; {state}", val, grad)
        )
    # static: force equals spring preload + weight at s = 0 (0 rpm)
    motion = program.time_kinematics(arrays.kin, 0.0)
    f0 = float(loads.kinetostatic_force(train, motion)[0])
    ref = train.spring_N_per_m * train.preload_mm * 1e-3 + train.mass_kg * train.gravity_m_s2
    out.append(_case("speed", "0 rpm: force at 0 deg = k x0 + m g", f0, ref, 1e-12, relative=True))
    return out


# ------------------------------------------------------------------------------ precision


def _report_figures(scene: Scene, dtype, base_radius_mm: float) -> dict[str, float]:
    a = scene_arrays(scene, dtype=dtype)
    rb = jnp.asarray(base_radius_mm, dtype)
    rho = flat_geo.flat_radius_of_curvature(rb, a.kin)
    figs = {
        "velocity max (m/s)": jnp.max(a.motion.velocity),
        "velocity min (m/s)": jnp.min(a.motion.velocity),
        "accel max (m/s^2)": jnp.max(a.motion.accel),
        "accel min (m/s^2)": jnp.min(a.motion.accel),
        "jerk max (m/s^3)": jnp.max(a.motion.jerk),
        "jerk min (m/s^3)": jnp.min(a.motion.jerk),
        "force max (N)": jnp.max(a.force_N),
        "force min (N)": jnp.min(a.force_N),
        "torque max (N m)": jnp.max(a.torque_Nm),
        "torque min (N m)": jnp.min(a.torque_Nm),
        "min base radius (mm)": flat_geo.flat_min_base_radius(a.kin)[0],
        "min face width (mm)": flat_geo.flat_face_width(a.kin),
        f"rho min at R_b = {base_radius_mm:g} (mm)": jnp.min(rho),
        f"stress max at R_b = {base_radius_mm:g} (MPa)": jnp.max(
            contact.stress_from_coefficient(a.stress_coefficient, rho)
        ),
    }
    return {k: float(v) for k, v in figs.items()}


def precision_cases(scene: Scene, base_radii: Iterable[float] = (28.4,), rtol32: float = 1e-5) -> list[Case]:
    """Every reference-report figure in float32 vs float64; near rho -> 0 float32 must warn (an
    oscillating follower: :func:`rocker_precision_cases`, at its own drawing radius)."""
    if followers.of(scene).rocking:
        return rocker_precision_cases(scene, rtol32)
    out = []
    for rb in base_radii:
        f64 = _report_figures(scene, jnp.float64, rb)
        f32 = _report_figures(scene, jnp.float32, rb)
        for name, ref in f64.items():
            out.append(
                _case(
                    "precision",
                    f"float32 {name}",
                    f32[name],
                    ref,
                    rtol32,
                    relative=True,
                    note="float32 eps = 1.2e-7; figures are sums of a few terms",
                )
            )
    # near the curvature limit float32 loses accuracy: the guard must say so
    a64, a32 = scene_arrays(scene), scene_arrays(scene, dtype=jnp.float32)
    rb_min = float(flat_geo.flat_min_base_radius(a64.kin)[0])
    for gap in (1e-1, 1e-2, 1e-3):
        rb = rb_min + gap
        s64 = contact.stress_from_coefficient(
            a64.stress_coefficient, flat_geo.flat_radius_of_curvature(rb, a64.kin)
        )
        rho32 = flat_geo.flat_radius_of_curvature(jnp.float32(rb), a32.kin)
        s32 = contact.stress_from_coefficient(a32.stress_coefficient, rho32)
        err = abs(float(jnp.max(s32)) - float(jnp.max(s64))) / float(jnp.max(s64))
        warned = precision_warning(jnp.float32(rb), a32.kin.s, a32.kin.d2s, rho32, jnp.float32) is not None
        honest = warned or err <= STRESS_RTOL["float32"]
        out.append(
            Case(
                "precision",
                f"float32 stress at R_b = min + {gap:g} mm: {'warns' if warned else 'no warning'}",
                float(jnp.max(s32)),
                float(jnp.max(s64)),
                err,
                STRESS_RTOL["float32"],
                bool(honest),
                "passes when within tolerance or when precision_warning fires",
            )
        )
    return out


# ---------------------------------------------------------------------------- optimization


def optimization_cases(scene: Scene) -> list[Case]:
    """Weights 0 and 1e-6..1e6, unreachable sigma_max, collapsed bounds, tiny populations, one
    weighting, one angle, and GA determinism; references from the exact global optimum (an
    oscillating follower: :func:`rocker_optimization_cases`)."""
    if followers.of(scene).rocking:
        return rocker_optimization_cases(scene)
    from camjax.family import weights_of
    from camjax.followers.flat import optimum
    from camjax.followers.flat import problem as pb
    from camjax.solvers import ga, sweep

    out = []
    prob = pb.problem_from_scene(scene)
    for alpha, gamma in [
        (0.0, 1.0),
        (1.0, 0.0),
        (1e-6, 1.0),
        (1.0, 1e-6),
        (1e6, 1.0),
        (1.0, 1e6),
        (1.0, 1.0),
    ]:
        res = sweep.solve(prob, alpha, gamma)
        ref = optimum.global_optimum(prob, weights_of(alpha, gamma))
        out.append(
            _case(
                "optimization",
                f"global gradient, alpha = {alpha:g}, gamma = {gamma:g}: R_b vs exact",
                res.base_radius_mm,
                ref.base_radius_mm,
                1e-4,
                note="exact optimum by bisection on the convex 1-D problem",
            )
        )
        out.append(
            _finite_case(
                "optimization",
                f"alpha = {alpha:g}, gamma = {gamma:g}: result finite",
                res.objective,
                res.base_radius_mm,
                res.face_width_mm,
                res.violation,
            )
        )
    # sigma_max below any achievable stress: infeasible, named, finite
    tight = prob._replace(sigma_max_MPa=jnp.asarray(1.0, prob.q_mm.dtype))
    res = sweep.solve(tight, 1.0, 1.0)
    names = pb.violated_constraints(tight, res.violation)
    out.append(
        Case(
            "optimization",
            f"sigma_max = 1 MPa: infeasible, violated {names}",
            float(res.feasible),
            0.0,
            float(res.feasible),
            0.0,
            (not bool(res.feasible)) and names == ["stress"],
            "feasible flag 0 and exactly the stress constraint named",
        )
    )
    out.append(_finite_case("optimization", "sigma_max = 1 MPa: result finite", res.objective, res.violation))
    # bounds collapsed to a point
    point = pb.with_bounds(prob, base_radius_mm=(30.0, 30.0), face_width_mm=(20.0, 20.0))
    res = sweep.solve(point, 1.0, 1.0)
    out.append(
        _case(
            "optimization",
            "bounds collapsed to R_b = 30, L = 20: R_b",
            res.base_radius_mm,
            30.0,
            0.0,
            note="the only admissible point, exactly",
        )
    )
    # GA with population 1 and 2, a single weighting, one angle
    try:  # a population of one cannot select or recombine: it must be refused by name
        sweep.solve(prob, 1.0, 1.0, solver="ga", ga_settings=ga.GASettings(population=1, elite=1))
        message = ""
    except ValueError as exc:
        message = str(exc)
    refused = message.startswith("population")
    out.append(
        Case(
            "optimization",
            f"GA population 1: refused ({message or 'not refused'})",
            float(not refused),
            0.0,
            float(not refused),
            0.0,
            refused,
            "a clear error naming the field",
        )
    )
    res = sweep.solve(
        prob, 1.0, 1.0, solver="ga", ga_settings=ga.GASettings(population=2, generations=20, elite=1)
    )
    out.append(
        _finite_case(
            "optimization", "GA population 2: result finite", res.objective, res.base_radius_mm, res.violation
        )
    )
    one = pb.problem_from_scene(scene, samples=1, extrema="grid")
    res = sweep.solve(one, 1.0, 1.0, mode="pointwise")
    ref = optimum.pointwise_optimum(one, weights_of(1.0, 1.0))
    out.append(
        _case(
            "optimization",
            "single-angle grid (N = 1), pointwise: R_b vs closed form",
            res.base_radius_mm,
            float(jnp.max(ref.base_radius_mm)),
            1e-6,
        )
    )
    a = sweep.solve(prob, 1.0, 1.0, solver="ga", seed=7)
    b = sweep.solve(prob, 1.0, 1.0, solver="ga", seed=7)
    same = all(
        np.array_equal(np.asarray(x), np.asarray(y))
        for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b), strict=True)
    )
    out.append(
        Case(
            "determinism",
            "GA seed 7 twice: bitwise identical results",
            float(not same),
            0.0,
            float(not same),
            0.0,
            same,
            "every leaf of the result compared with array_equal",
        )
    )
    return out


# --------------------------------------------------------------------- oscillating followers

_EPS32 = float(np.finfo(np.float32).eps)


def _rocker_base(scene: Scene):
    """(arrays, sizing, drawing radius) of a rocker scene: the radius `camjax design` draws at."""
    follower = followers.of(scene)
    arrays = scene_arrays(scene)
    sizing = follower.sizing(scene, arrays.kin)
    radius, _ = follower.drawing_radius(scene, arrays.kin, sizing)
    return arrays, sizing, radius


def _rocker_curves(scene: Scene, kin, w, base_radius_mm):
    """{name: array} of a rocker at one base radius, composed from camjax.geometry, loads and
    contact as :meth:`camjax.followers._rocking.RockingFollower.evaluate` composes them, but kept
    in JAX so that it can be differentiated in the base radius and the cam speed (loads and
    [contact] required; another rocking type: its ``point_curves``, differentiable in the speed)."""
    f, c, rot = scene.follower, scene.contact, scene.motion.rotation
    d = f.pivot_distance_mm
    moment = loads.rocker_torque(f.train, kin, w)
    if f.type == "oscillating_roller":
        rf, arm = f.roller_radius_mm, f.arm_length_mm
        g = rocker_roller_geo.oscillating_roller_geometry(d, arm, rf, base_radius_mm + rf, kin, rot,
                                                 f.min_curvature_radius_mm)
        phi = g.pressure_angle
        force = loads.rocker_roller_contact_force(moment, arm, phi)
        coeff = contact.stress_coefficient(moment / (arm * 1e-3), c.cam_width_mm, c.cam, c.follower)
        stress = contact.roller_stress(coeff, phi, roller_geo.roller_equivalent_radius(g.pitch_curvature, rf))
        limit = g.undercut_margin  # <= 0: undercut
    elif f.type != "oscillating_flat":  # any other rocking follower: its own curves (a float radius)
        c = followers.of(scene).point_curves(scene, kin, w, base_radius_mm)
        limit = c["undercut_margin"] if "undercut_margin" in c else c["rho"] - f.min_curvature_radius_mm
        return {"moment": c["pivot_torque"], "force": c["contact_force"], "cam_torque": c["torque"],
                "pressure_angle": c["pressure_angle"], "stress": c.get("stress"), "limit": limit,
                "arm_angle": c["arm_angle"]}
    else:
        g = rocker_flat_geo.oscillating_flat_geometry(d, f.face_offset_mm, base_radius_mm, kin, rot)
        phi = g.pressure_angle
        force = loads.rocker_flat_contact_force(moment, g.contact_distance)
        stress = contact.hertz_line_stress(force, g.radius_of_curvature, c.cam_width_mm, c.cam, c.follower)
        limit = g.radius_of_curvature - f.min_curvature_radius_mm  # < 0: the face cannot follow
    return {"moment": moment, "force": force, "cam_torque": loads.rocker_cam_torque(moment, kin.ds),
            "pressure_angle": phi, "stress": stress, "limit": limit, "arm_angle": g.arm_angle}


def rocker_geometry_cases(scene: Scene) -> list[Case]:
    """An oscillating follower at base radii 1e-3x..10x its smallest admissible one: every radius
    is either refused by name (the geometry cannot close) or gives finite stress, pressure angle
    and curvature with finite gradients; at the smallest radius its binding limit holds with
    equality; at the drawing radius the pitch points (roller) or contact points (flat face) lie
    where the pivot, arm and face put them; the Hertz closed forms of :func:`stress_cases`."""
    from camjax.followers._pitch import to_cam_frame
    closure_problem = followers.of(scene).closure_problem

    out = []
    f, rot = scene.follower, scene.motion.rotation
    arrays, sizing, drawn = _rocker_base(scene)
    kin, w = arrays.kin, arrays.cam_speed_rad_s

    def peaks(rb):
        c = _rocker_curves(scene, kin, w, rb)
        return jnp.stack([jnp.max(c["stress"]), jnp.max(jnp.abs(c["pressure_angle"])), jnp.min(c["limit"])])

    value_and_jac = jax.jit(lambda rb: (peaks(rb), jax.jacfwd(peaks)(rb)))
    for factor in (1e-3, 0.1, 0.5, 0.99, 1.0, 1.0 + 1e-12, 1.01, 2.0, 10.0):
        rb = sizing.min_base_radius_mm * factor
        name = f"R_b = {factor:.13g} x min ({rb:.6g} mm)"
        why = closure_problem(scene, kin, rb)
        if why is not None:  # refused with a sentence (exit 2 in the CLI), never NaN
            out.append(Case("rocker geometry", f"{name}: refused ({why})", 0.0, 0.0, 0.0, 0.0, bool(why),
                            "a radius at which the geometry cannot close is refused by name"))
            continue
        val, jac = value_and_jac(rb)
        state = "feasible" if float(val[2]) >= 0 and (
            f.type != "oscillating_roller" or float(val[1]) <= math.radians(f.max_pressure_angle_deg) + 1e-12
        ) else "infeasible (reported)"
        out.append(_finite_case("rocker geometry", f"{name}: sigma, |phi|, curvature and d/dR_b finite; "
                                f"{state}", val, jac))
    # the sizing's binding limit at its own radius: bisection in the arm angle to float64 resolution
    c = _rocker_curves(scene, kin, w, sizing.min_base_radius_mm)
    if sizing.binding == "pressure_angle":
        value = math.degrees(float(jnp.max(jnp.abs(c["pressure_angle"]))))
        ref, what, unit = f.max_pressure_angle_deg, "max |phi|", "deg"
    else:
        value, ref, what, unit = float(jnp.min(c["limit"])), 0.0, "min curvature margin", "mm"
    out.append(_case("rocker geometry", f"smallest admissible R_b = {sizing.min_base_radius_mm:.6g} mm "
                     f"({sizing.binding} binds): {what} vs its limit", value, ref, 1e-9,
                     note=f"bisection to float64 resolution; 1e-9 {unit} leaves round-off of the geometry"))
    # positions at the drawing radius: independent of the curvature and pressure-angle formulas
    theta = np.asarray(kin.theta)
    px, py = (np.asarray(v) for v in to_cam_frame(f.pivot_distance_mm, 0.0, theta, rot))  # the pivot
    psi = np.asarray(_rocker_curves(scene, kin, w, drawn)["arm_angle"])
    if f.type == "oscillating_roller":
        x, y = (np.asarray(v) for v in rocker_roller_geo.oscillating_roller_pitch_curve(
            f.pivot_distance_mm, f.arm_length_mm, drawn + f.roller_radius_mm, kin, rot))
        err = float(np.max(np.abs(np.hypot(x - px, y - py) - f.arm_length_mm)))
        name = f"R_b = {drawn:g} mm: pitch points at the arm length from the pivot"
    else:
        x, y = (np.asarray(v) for v in rocker_flat_geo.oscillating_flat_profile(
            f.pivot_distance_mm, f.face_offset_mm, drawn, kin, rot))
        # the face normal (sin psi, cos psi) in the fixed frame, turned into the cam frame with the pivot
        tip = to_cam_frame(f.pivot_distance_mm + np.sin(psi), np.cos(psi), theta, rot)
        mx, my = (np.asarray(v) - q for v, q in zip(tip, (px, py), strict=True))
        err = float(np.max(np.abs((x - px) * mx + (y - py) * my + f.face_offset_mm)))
        name = f"R_b = {drawn:g} mm: contact points on the face line, f from the pivot"
    scale = f.pivot_distance_mm + getattr(f, "arm_length_mm", 0.0)  # d + l (a face: d)
    out.append(_case("rocker geometry", name, err, 0.0, 1e-12 * scale,
                     note="distances from positions; round-off of a few operations on lengths of d + l"))
    return out + stress_cases(scene)


def rocker_speed_cases(scene: Scene) -> list[Case]:
    """An oscillating follower at cam speeds 0 .. 20 000 rpm, drawn at its drawing radius: the
    torque about the pivot, contact force, cam torque and their speed gradients finite, contact
    loss (M < 0) reported; at 0 rpm the torque is the spring's, k (s + x0), at every sample."""
    out = []
    arrays, _, drawn = _rocker_base(scene)
    kin = arrays.kin
    train = scene.follower.train

    def peak(w):
        c = _rocker_curves(scene, kin, w, drawn)
        return jnp.max(c["moment"]) + jnp.max(c["force"]) + jnp.max(c["cam_torque"])

    value_and_grad = jax.jit(jax.value_and_grad(peak))
    for rpm in (0.0, 1.0, 240.0, 2000.0, 20_000.0):
        w = program.rpm_to_rad_s(rpm)
        val, grad = value_and_grad(jnp.asarray(w))
        lost = float(jnp.min(loads.rocker_torque(train, kin, w))) < 0
        state = "contact LOST (reported)" if lost else "contact kept"
        out.append(_finite_case("rocker speed", f"{rpm:g} rpm: torque, force, cam torque and gradient "
                                f"finite; {state}", val, grad))
    moment = np.asarray(loads.rocker_torque(train, kin, 0.0))
    static = train.spring_N_m_per_rad * (np.asarray(kin.s) + train.preload_rad)
    scale = float(np.max(np.abs(static))) or 1.0
    out.append(_case("rocker speed", "0 rpm: torque about the pivot = k (s + x0) at every sample",
                     float(np.max(np.abs(moment - static))) / scale, 0.0, 1e-14,
                     note="relative to the largest static torque; the inertia and damping terms vanish"))
    return out


def rocker_precision_cases(scene: Scene, rtol32: float = 1e-5) -> list[Case]:
    """An oscillating follower's report figures in float32 vs float64 at its drawing radius, and
    the smallest admissible base radius found in each.

    Sums of a few terms are held to ``rtol32``; a radius of curvature is a difference of lengths of
    size up to d + l, so its float32 error is a few eps d / |rho| relative (tolerance 32 eps32
    (d + l) / |rho|, at least ``rtol32``), and the stress (sigma ~ rho^-1/2) half of that.
    """
    evaluate_rocker, rocker_sizing = followers.of(scene).evaluate, followers.of(scene).sizing

    out = []
    f = scene.follower
    a64, sizing, drawn = _rocker_base(scene)
    a32 = scene_arrays(scene, dtype=jnp.float32)
    c64 = evaluate_rocker(scene, a64.kin, a64.cam_speed_rad_s, drawn)
    c32 = evaluate_rocker(scene, a32.kin, a32.cam_speed_rad_s, np.float32(drawn))
    length = f.pivot_distance_mm + getattr(f, "arm_length_mm", 0.0)  # d + l (a face: d)
    rho_tol = max(rtol32, 32 * _EPS32 * length / max(float(np.min(np.abs(c64.rho_mm))), 1e-300))
    figures = [("swing_deg", "swing (deg)", rtol32),
               ("angular_velocity_rad_s", "angular velocity (rad/s)", rtol32),
               ("angular_accel_rad_s2", "angular accel (rad/s^2)", rtol32),
               ("angular_jerk_rad_s3", "angular jerk (rad/s^3)", rtol32),
               ("pressure_angle_deg", "pressure angle (deg)", rtol32),
               ("pivot_torque_Nm", "torque about the pivot (N m)", rtol32),
               ("contact_force_N", "contact force (N)", rtol32), ("torque_Nm", "cam torque (N m)", rtol32),
               ("stress_MPa", f"stress at R_b = {drawn:g} (MPa)", max(rtol32, 0.5 * rho_tol))]
    for field, label, tol in figures:
        v64, v32 = getattr(c64, field), getattr(c32, field)
        for pick, word in ((np.max, "max"), (np.min, "min")):
            ref = float(pick(v64))
            if ref == 0.0:  # e.g. the swing's dwell at 0: both exact
                out.append(_case("rocker precision", f"float32 {label} {word}", float(pick(v32)), ref, 0.0))
                continue
            out.append(_case("rocker precision", f"float32 {label} {word}", float(pick(v32)), ref, tol,
                             relative=True, note="float32 eps = 1.2e-7; figures are sums of a few terms"))
    out.append(_case("rocker precision", f"float32 rho min at R_b = {drawn:g} (mm)",
                     float(np.min(c32.rho_mm)), float(np.min(c64.rho_mm)), rho_tol, relative=True,
                     note="a difference of lengths up to d + l: 32 eps32 (d + l) / |rho| relative"))
    rb32 = rocker_sizing(scene, a32.kin).min_base_radius_mm
    out.append(_case("rocker precision", "float32 min base radius (mm)", rb32, sizing.min_base_radius_mm,
                     max(rtol32, 32 * _EPS32 * length / sizing.min_base_radius_mm), relative=True,
                     note="bisection on float32 geometry: a few eps32 (d + l) absolute"))
    return out


def rocker_optimization_cases(scene: Scene) -> list[Case]:
    """An oscillating follower's [design] problem on the solver interface: the size-only optimum
    with the pivot and arm (or face) fixed at the scene's against the independent sizing
    (bisection in the arm angle), weights 0 and 1e-6..1e6 finite, an unreachable sigma_max named,
    bounds collapsed to one closing design returned exactly, GA determinism."""
    from camjax.solvers.base import problem_from_scene, solve

    out = []
    f = scene.follower
    _, sizing, drawn = _rocker_base(scene)
    problem = problem_from_scene(scene)
    design_type = type(problem.lower)
    dt = problem.sigma_max_MPa.dtype
    at_scene = {k: getattr(f, k) for k in design_type._fields if k != "base_radius_mm"}

    def box(low: dict, high: dict):
        lo = design_type(**{k: jnp.asarray(low[k], dt) for k in design_type._fields})
        hi = design_type(**{k: jnp.asarray(high[k], dt) for k in design_type._fields})
        return problem._replace(lower=lo, upper=hi)

    rb_lo = min(float(problem.lower.base_radius_mm), 0.5 * sizing.min_base_radius_mm)
    rb_hi = max(float(problem.upper.base_radius_mm), 2.0 * sizing.min_base_radius_mm)
    fixed = box({**at_scene, "base_radius_mm": rb_lo}, {**at_scene, "base_radius_mm": rb_hi})
    loose = fixed._replace(sigma_max_MPa=jnp.asarray(1e12, dt))  # stress never binds
    # on the samples, as the sizing is: no polish between them (program None)
    res = solve(loose._replace(program=None), (1.0, 0.0))
    out.append(_case("rocker optimization", "size only, pivot and arm (or face) fixed at the scene's: R_b vs "
                     "the sizing", float(res.base_radius_mm), sizing.min_base_radius_mm, 1e-5,
                     note="the same admissible set's boundary: bisection to float64 resolution, the solver "
                          "to its feasibility tolerance (1e-7 rad in phi ~ 1e-5 mm)"))
    for alpha, gamma in [(0.0, 1.0), (1e-6, 1.0), (1.0, 1e-6), (1e6, 1.0), (1.0, 1e6), (1.0, 1.0)]:
        res = solve(problem, (alpha, gamma))
        out.append(_finite_case("rocker optimization", f"alpha = {alpha:g}, gamma = {gamma:g}: result finite",
                                res.objective, res.design, res.violation))
    tight = problem._replace(sigma_max_MPa=jnp.asarray(1.0, dt))
    res = solve(tight, (1.0, 1.0))
    names = res.violated(tight)
    ok = (not bool(res.feasible)) and "stress" in names
    out.append(Case("rocker optimization", f"sigma_max = 1 MPa: infeasible, violated {names}",
                    float(res.feasible), 0.0, float(res.feasible), 0.0, ok,
                    "feasible flag 0 and the stress constraint named"))
    point = {**at_scene, "base_radius_mm": drawn}  # the drawing radius closes (camjax.followers._rocking)
    res = solve(box(point, point), (1.0, 1.0))
    err = max(abs(float(getattr(res.design, k)) - v) for k, v in point.items())
    out.append(_case("rocker optimization", f"bounds collapsed to the scene's design at R_b = {drawn:g} mm",
                     err, 0.0, 0.0, note="the only admissible point, exactly"))
    a, b = (solve(problem, (1.0, 1.0), solver="ga", seed=7) for _ in range(2))
    same = all(np.array_equal(np.asarray(x), np.asarray(y))
               for x, y in zip(jax.tree_util.tree_leaves((a.design, a.objective, a.violation)),
                               jax.tree_util.tree_leaves((b.design, b.objective, b.violation)), strict=True))
    out.append(Case("determinism", "rocker GA seed 7 twice: bitwise identical results", float(not same), 0.0,
                    float(not same), 0.0, same, "design, objective and violation compared with array_equal"))
    return out


# ----------------------------------------------------------------------------------- runner


class Group(NamedTuple):
    """One group of the matrix and the scene models it needs (names as in :meth:`Scene.needs`)."""

    name: str
    needs: frozenset[str]
    run: Callable[[Scene], list[Case]]
    followers: frozenset[str] | None = None  # the follower types it has cases for (None: any)


# a translating roller has no geometry, precision or optimization cases here (its geometry and
# design problem are tested in tests/test_roller_*.py); the flat face's would be meaningless on it
_NOT_ROLLER = frozenset({"flat", "oscillating_roller", "oscillating_flat"})


# What each model means in a scene file, for the line that says why a group was skipped.
_MODEL_SOURCE = {
    "loads": "loads (follower.mass_kg and/or follower.spring_N_per_m)",
    "contact": "contact stress (a [contact] section)",
    "design": "a design problem (a [design] section)",
}

GROUPS: tuple[Group, ...] = (
    Group("laws", frozenset(), lambda scene: law_cases()),
    Group("polynomials", frozenset(), lambda scene: polynomial_cases()),
    Group("programs", frozenset(), lambda scene: program_cases()),
    Group("geometry and stress", frozenset({"loads", "contact"}), geometry_cases, _NOT_ROLLER),
    Group("speed", frozenset({"loads"}), speed_cases),
    Group("precision", frozenset({"loads", "contact"}), precision_cases, _NOT_ROLLER),
    Group("optimization", frozenset({"loads", "contact", "design"}), optimization_cases, _NOT_ROLLER),
)


def _missing(scene: Scene, group: Group) -> list[str]:
    return [m for m in _MODEL_SOURCE if m in group.needs and m not in scene.needs()]


def _skip_reason(scene: Scene, group: Group) -> str | None:
    """Why :func:`run_matrix` leaves ``group`` out on ``scene`` (None: it runs)."""
    if group.followers is not None and scene.follower.type not in group.followers:
        return (f"has no cases for follower.type = {scene.follower.type!r} of scene {scene.name!r} "
                f"(only {', '.join(repr(t) for t in sorted(group.followers))})")
    missing = _missing(scene, group)
    if missing:
        wants = [_MODEL_SOURCE[m] for m in missing]
        wants = " and ".join([", ".join(wants[:-1]), wants[-1]] if len(wants) > 1 else wants)
        return f"needs {wants}, not declared by scene {scene.name!r}"
    return None


def skipped_groups(scene: Scene) -> list[dict[str, str]]:
    """The groups :func:`run_matrix` skips on ``scene``: ``{"group": name, "reason": sentence}``."""
    return [{"group": g.name, "reason": why} for g in GROUPS if (why := _skip_reason(scene, g)) is not None]


def run_matrix(
    scene: Scene | None = None,
    progress: Callable[[str], None] | None = None,
    extra_groups: Iterable[Callable[[Scene], list[Case]]] = (),
) -> list[Case]:
    """Run every group of the matrix that ``scene`` supports (default: the embedded reference scene).

    Groups needing a model the scene lacks, or without cases for its follower type, are left out
    (see :func:`skipped_groups`).
    """
    scene = scene or load_scene()
    groups = [g for g in GROUPS if _skip_reason(scene, g) is None]
    groups += [Group(fn.__name__, frozenset(), fn) for fn in extra_groups]
    cases: list[Case] = []
    for group in groups:
        if progress:
            progress(group.name)
        cases.extend(group.run(scene))
    return cases


def format_table(cases: Iterable[Case]) -> str:
    """A short text table: group, case, value, reference, error, tolerance, PASS/FAIL."""
    lines = [f"{'group':12s} {'case':78s} {'value':>12s} {'reference':>12s} {'error':>9s} {'tol':>8s}"]
    for c in cases:
        lines.append(
            f"{c.group:12s} {c.name[:78]:78s} {c.value:12.6g} {c.reference:12.6g} {c.error:9.2e} "
            f"{c.tolerance:8.1e} {'pass' if c.passed else 'FAIL'}"
        )
    return "\n".join(lines)


def format_markdown(cases: list[Case]) -> str:
    """Markdown summary (``extremes.md``): per-group results and the float32/float64 table."""
    groups: dict[str, list[Case]] = {}
    for c in cases:
        groups.setdefault(c.group, []).append(c)
    lines = ["| group | cases | passed | largest error / tolerance |", "|---|---:|---:|---:|"]
    for g, cs in groups.items():
        ratio = max(
            (c.error / c.tolerance if c.tolerance > 0 else (0.0 if c.error == 0 else math.inf)) for c in cs
        )
        lines.append(f"| {g} | {len(cs)} | {sum(c.passed for c in cs)} | {ratio:.2g} |")
    prec = [c for c in cases if c.group == "precision"]
    if prec:
        lines += [
            "",
            "| figure (reference scene) | float64 | float32 | relative difference | tolerance | |",
            "|---|---:|---:|---:|---:|---|",
        ]
        for c in prec:
            label = c.name.removeprefix("float32 ")
            lines.append(
                f"| {label} | {c.reference:.7g} | {c.value:.7g} | {c.error:.1e} | {c.tolerance:.0e} | "
                f"{'pass' if c.passed else 'FAIL'} |"
            )
    return "\n".join(lines)
