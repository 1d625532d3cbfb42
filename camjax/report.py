"""Design report: scene + arrays -> a JSON-ready dict and the curves that plots and export draw.

Data flows one way and each step is a pure function:

1. :func:`camjax.analysis.scene_arrays` evaluates what the scene declares (once per scene);
2. :func:`design_block` picks the design (R_b, L) -- the one place an optimizer plugs in;
3. :func:`evaluate_design` computes geometry, stress and roller quantities at one base radius
   (:class:`DesignCurves`, NumPy arrays for plots and export);
4. :func:`design_report` condenses everything into a plain dict (degrees, SI or the unit in the
   key) with no NaN or infinity, so that it can be written as strict JSON.

Nothing here draws or writes files (``plots.py``, ``export.py`` and ``cli.py`` do).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, geometry, loads
from camjax.analysis import SceneArrays, scene_arrays
from camjax.program import joints
from camjax.scene import Scene

PRESSURE_ANGLE_LIMIT_DEG = 30.0  # rule of thumb for a translating roller follower (SPEC 3)
DRAWING_MARGIN_MM = 1.0  # without a [design], draw at the smallest admissible R_b + this, rounded up
FLCD_UNITS = {"jump_s": "mm", "jump_v": "mm/rad", "jump_a": "mm/rad^2", "jump_j": "mm/rad^3"}


# ------------------------------------------------------------------------------ extrema


def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


def extrema(values, theta_deg) -> dict[str, float]:
    """{max, max_deg, min, min_deg} of a sampled curve; the first sample wins on ties."""
    v, t = np.asarray(values), np.asarray(theta_deg)
    i, j = int(np.argmax(v)), int(np.argmin(v))
    return {"max": _f(v[i]), "max_deg": _f(t[i]), "min": _f(v[j]), "min_deg": _f(t[j])}


def peak(values, theta_deg) -> dict[str, float]:
    """{max, max_deg} of a sampled curve."""
    e = extrema(values, theta_deg)
    return {"max": e["max"], "max_deg": e["max_deg"]}


def trough(values, theta_deg) -> dict[str, float]:
    """{min, min_deg} of a sampled curve."""
    e = extrema(values, theta_deg)
    return {"min": e["min"], "min_deg": e["min_deg"]}


def _negative_ranges_deg(values, theta_deg) -> list[list[float]]:
    """[first, last] sample angles (deg) of each run where values < 0, wrapping over 360."""
    neg = np.asarray(values) < 0
    t = np.asarray(theta_deg)
    if not neg.any():
        return []
    if neg.all():
        return [[_f(t[0]), _f(t[-1])]]
    start = int(np.argmin(neg))  # a sample with contact; walk the cycle from there
    order = np.roll(np.arange(len(t)), -start)
    runs, current = [], None
    for k in order:
        if neg[k]:
            current = [_f(t[k]), _f(t[k])] if current is None else [current[0], _f(t[k])]
        elif current is not None:
            runs.append(current)
            current = None
    if current is not None:
        runs.append(current)
    return runs


# ------------------------------------------------------------------------ report pieces


def kinematics_block(arrays: SceneArrays) -> dict[str, Any]:
    """Follower motion extrema: displacement (mm), velocity, acceleration, jerk (SI), angles in deg."""
    t, m, k = arrays.theta_deg, arrays.motion, arrays.kin
    return {
        "displacement_mm": extrema(k.s, t),
        "velocity_m_s": extrema(m.velocity, t),
        "accel_m_s2": extrema(m.accel, t),
        "jerk_m_s3": extrema(m.jerk, t),
        "velocity_mm_per_rad": extrema(k.ds, t),
        "accel_mm_per_rad2": extrema(k.d2s, t),
    }


def flcd_block(scene: Scene) -> list[dict[str, Any]]:
    """Jumps of s, s', s'', s''' (mm, per rad; see FLCD_UNITS) and their FLCD class at every joint."""
    return [
        {"joint_deg": j.joint_deg, "before_segment": j.before, "after_segment": j.after,
         "jump_s": j.jump_s, "jump_v": j.jump_v, "jump_a": j.jump_a, "jump_j": j.jump_j,
         "class": j.flcd_class}
        for j in joints(scene.motion.program)
    ]


def loads_block(scene: Scene, arrays: SceneArrays) -> dict[str, Any] | None:
    """Force, torque, contact-loss check and (with a [guide]) guide reactions; None without loads."""
    if arrays.force_N is None:
        return None
    t, force = arrays.theta_deg, arrays.force_N
    out: dict[str, Any] = {
        "force_N": extrema(force, t),
        "torque_Nm": extrema(arrays.torque_Nm, t),
        "contact": {
            "min_force_N": _f(loads.contact_margin(force)),
            "min_force_deg": trough(force, t)["min_deg"],
            "lost": bool(np.any(np.asarray(force) < 0)),
            "lost_ranges_deg": _negative_ranges_deg(force, t),
        },
    }
    if scene.guide is not None:
        out.update(guide_block(scene, arrays))
    return out


def guide_block(scene: Scene, arrays: SceneArrays) -> dict[str, Any]:
    """Chen's guide reactions with P = the follower force and a = s' (mm), and the jamming check.

    The stem can jam only with the contact on the side a < 0 (see
    :func:`camjax.loads.jamming_limit_mm`); the check compares max(-a) with that limit and, as an
    independent statement of the same condition, reports min Gamma (> 0 while not jammed).
    """
    guide, t = scene.guide, arrays.theta_deg
    offset = geometry.flat_contact_offset(arrays.kin)
    r = loads.guide_reactions(guide, arrays.force_N, offset)
    limit = loads.jamming_limit_mm(guide)
    worst = trough(offset, t)  # most negative offset = furthest onto the jamming side
    reach = -worst["min"]
    gamma_min = trough(r.gamma, t)
    jams = bool(gamma_min["min"] <= 0.0)
    return {
        "guide_reactions": {
            "cam_force_N": extrema(r.cam_force, t),
            "reaction_1_N": extrema(r.reaction_1, t),
            "reaction_2_N": extrema(r.reaction_2, t),
            "gamma_mm": gamma_min,
        },
        "jamming_limit_mm": limit if math.isfinite(limit) else None,
        "jamming": {
            "offset_on_jamming_side_mm": reach,
            "offset_on_jamming_side_deg": worst["min_deg"],
            "margin_mm": (limit - reach) if math.isfinite(limit) else None,
            "jams": jams,
            "note": ("limit b/(2 mu) - mu0 b (1 + 2 xi)/2 from the corrected Gamma; "
                     "null limit = frictionless guide, never jams"),
        },
    }


# ------------------------------------------------------------------------- base radius


@jax.jit
def _roller_violation(base_radius_mm, roller_radius_mm, offset_mm, kin):
    """Largest violation (> 0 = violated) of |phi| <= 30 deg and no undercut, normalized."""
    g = geometry.roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin)
    phi_excess = jnp.max(jnp.abs(g.pressure_angle)) / jnp.deg2rad(PRESSURE_ANGLE_LIMIT_DEG) - 1.0
    undercut = -jnp.min(g.undercut_margin) / roller_radius_mm
    reach = jnp.abs(offset_mm) - (base_radius_mm + roller_radius_mm)  # prime circle must pass e
    return jnp.maximum(jnp.maximum(phi_excess, undercut), reach / roller_radius_mm)


def _roller_min_base_radius(scene: Scene, arrays: SceneArrays) -> float:
    """Smallest R_b (mm, to 1e-9 relative) with |phi| <= 30 deg and no undercut, by bisection.

    Both constraints relax as R_b grows (the pitch point moves out, tan phi falls, the pitch
    curve flattens), so the feasible set is an interval [R_min, inf).
    """
    f = scene.follower
    kin = arrays.kin

    def bad(r):
        return float(_roller_violation(r, f.roller_radius_mm, f.offset_mm, kin)) > 0.0

    lo, hi = 0.0, max(1.0, abs(f.offset_mm))
    while bad(hi):
        lo, hi = hi, 2.0 * hi
        if hi > 1e7:
            raise ValueError("no base radius below 1e7 mm satisfies the roller constraints")
    while hi - lo > 1e-9 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if bad(mid) else (lo, mid)
    return hi


def min_base_radius_block(scene: Scene, arrays: SceneArrays) -> dict[str, Any]:
    """Smallest admissible base radius (mm) and the cam angle (deg) where it binds.

    Flat face: max_theta -(s + s'') (rho >= 0). Roller: the smallest R_b with |phi| <= 30 deg
    and no undercut; the angle is where the pressure angle peaks at that radius.
    """
    t = np.asarray(arrays.theta_deg)
    if scene.follower.type == "flat":
        r, i = geometry.flat_min_base_radius(arrays.kin)
        return {"min_base_radius_mm": _f(r), "min_base_radius_deg": _f(t[int(i)]),
                "min_base_radius_rule": "flat face: rho = R_b + s + s'' >= 0 at every sample"}
    r = _roller_min_base_radius(scene, arrays)
    f = scene.follower
    g = geometry.roller_geometry(r, f.roller_radius_mm, f.offset_mm, arrays.kin)
    i = int(np.argmax(np.abs(np.asarray(g.pressure_angle))))
    return {"min_base_radius_mm": r, "min_base_radius_deg": _f(t[i]),
            "min_base_radius_rule": f"roller: |pressure angle| <= {PRESSURE_ANGLE_LIMIT_DEG:g} deg "
                                    "and no undercut at every sample (bisection)"}


def face_width_block(scene: Scene, arrays: SceneArrays) -> dict[str, Any]:
    """Minimum flat-face width (mm): symmetric 2 max|s'| and asymmetric max s' - min s'."""
    if scene.follower.type != "flat":
        return {}
    t, kin = arrays.theta_deg, arrays.kin
    return {
        "min_face_width_mm": _f(geometry.flat_face_width(kin, symmetric=True)),
        "min_face_width_asymmetric_mm": _f(geometry.flat_face_width(kin, symmetric=False)),
        "contact_offset_mm": extrema(geometry.flat_contact_offset(kin), t),
    }


# ------------------------------------------------------------------------------ design


def design_block(scene: Scene, arrays: SceneArrays) -> dict[str, Any] | None:
    """The optimized design (R_b, L) of a scene with a [design] section; None without one.

    Solved by :func:`camjax.solvers.sweep.solve` with the scene's mode, alpha, gamma, solver and
    seed (SPEC 5; keys of :meth:`camjax.solvers.base.Solution.to_json`: mode, solver,
    base_radius_mm, face_width_mm, objective, feasible, violated, iterations, ..., and in
    pointwise mode base_radius_deg, face_width_deg and the per-angle ``pointwise`` arrays).
    Added for the report: ``peak_stress_MPa`` (the design's peak stress computed exactly as the
    report's stress curve), the smallest admissible R_b and L (``required_*``) with the
    constraint that binds there, and ``violations`` as readable sentences.
    """
    if scene.design is None:
        return None
    from camjax import problem as P
    from camjax.solvers.sweep import solve

    d, kin, t = scene.design, arrays.kin, np.asarray(arrays.theta_deg)
    problem = P.problem_from_scene(scene, arrays)
    out = solve(problem, d.alpha, d.gamma, mode=d.mode, solver=d.solver, seed=d.seed).to_json(problem)

    rho = geometry.flat_radius_of_curvature(out["base_radius_mm"], kin)
    sigma_peak = _f(jnp.max(contact.stress_from_coefficient(arrays.stress_coefficient, rho)))
    stress_rho = np.asarray(P.stress_rho_need(problem))
    need = np.asarray(P.rho_need(problem) - problem.q_mm)  # max over angles: P.required_base_radius
    i = int(np.argmax(need))
    required, required_width = float(need[i]), _f(P.required_face_width(problem))
    rb_hi, l_hi = d.base_radius_mm[1], d.face_width_mm[1]
    sentences = {
        "curvature": f"rho <= {float(problem.rho_min_mm):g} mm somewhere (min rho "
                     f"{out['rho_min_mm']:.6g} mm): the flat face cannot follow the profile",
        "stress": f"peak stress {sigma_peak:.6g} MPa > sigma_max {d.sigma_max_MPa:g} MPa",
        "face_width": f"face width needs {required_width:.6g} mm > upper bound {l_hi:g} mm",
        "bounds": "a design variable is outside its bounds",
    }
    violations = [sentences[name] for name in out["violated"]]
    if required > rb_hi:
        violations.insert(0, f"base radius needs {required:.6g} mm > upper bound {rb_hi:g} mm")
    out.update({
        "peak_stress_MPa": sigma_peak,
        "violations": violations,
        "required_base_radius_mm": required,
        "required_base_radius_deg": _f(t[i]),
        "binding_constraint": "stress" if stress_rho[i] >= float(problem.rho_min_mm) else "curvature",
        "required_face_width_mm": required_width,
    })
    return out


def drawing_base_radius(design: dict | None, min_base_radius_mm: float,
                        override_mm: float | None = None) -> tuple[float, str]:
    """Base radius (mm) the geometry is evaluated and drawn at, and where it comes from."""
    if override_mm is not None:
        return float(override_mm), "option --base-radius"
    if design is not None:
        return design["base_radius_mm"], "design"
    r = float(math.ceil(max(min_base_radius_mm, 0.0) + DRAWING_MARGIN_MM))
    return r, f"smallest admissible + {DRAWING_MARGIN_MM:g} mm, rounded up to whole mm"


# -------------------------------------------------------------------------- evaluation


class DesignCurves(NamedTuple):
    """Everything plots and export need at one design, as NumPy arrays of shape (N,) or scalars.

    Optional entries are None when the scene does not ask for the model.
    """

    theta_deg: np.ndarray  # cam angle, deg
    s_mm: np.ndarray
    ds_mm: np.ndarray  # mm/rad
    d2s_mm: np.ndarray  # mm/rad^2
    velocity_m_s: np.ndarray
    accel_m_s2: np.ndarray
    jerk_m_s3: np.ndarray
    segment_starts_deg: tuple[float, ...]
    follower_type: str  # "flat" or "roller"
    base_radius_mm: float
    face_width_mm: float | None  # flat face only
    profile_x_mm: np.ndarray  # cam outline, cam coordinates (geometry.py convention)
    profile_y_mm: np.ndarray
    rho_mm: np.ndarray | None  # flat face: radius of curvature of the cam profile
    force_N: np.ndarray | None
    torque_Nm: np.ndarray | None
    stress_MPa: np.ndarray | None
    sigma_max_MPa: float | None  # allowed stress of the [design], for plots
    roller_radius_mm: float | None
    offset_mm: float | None
    pitch_x_mm: np.ndarray | None  # roller: pitch curve
    pitch_y_mm: np.ndarray | None
    pressure_angle_deg: np.ndarray | None
    pitch_rho_mm: np.ndarray | None
    undercut_margin_mm: np.ndarray | None


def _np(x):
    return None if x is None else np.asarray(x)


def evaluate_design(scene: Scene, arrays: SceneArrays, base_radius_mm: float,
                    face_width_mm: float | None = None) -> DesignCurves:
    """Geometry, stress and roller quantities at one base radius (mm)."""
    kin, f = arrays.kin, scene.follower
    rho = stress = pitch_x = pitch_y = phi = pitch_rho = margin = None
    if f.type == "flat":
        x, y = geometry.flat_profile(base_radius_mm, kin)
        rho = geometry.flat_radius_of_curvature(base_radius_mm, kin)
        if arrays.stress_coefficient is not None:
            stress = contact.stress_from_coefficient(arrays.stress_coefficient, rho)
        if face_width_mm is None:
            face_width_mm = _f(geometry.flat_face_width(kin, symmetric=True))
    else:
        rf, e = f.roller_radius_mm, f.offset_mm
        x, y = geometry.roller_profile(base_radius_mm, rf, e, kin)
        pitch_x, pitch_y = geometry.roller_pitch_curve(base_radius_mm, rf, e, kin)
        g = geometry.roller_geometry(base_radius_mm, rf, e, kin)
        phi, pitch_rho, margin = jnp.rad2deg(g.pressure_angle), g.pitch_radius_of_curvature, \
            g.undercut_margin
        face_width_mm = None
    m = arrays.motion
    return DesignCurves(
        np.asarray(arrays.theta_deg), np.asarray(kin.s), np.asarray(kin.ds), np.asarray(kin.d2s),
        np.asarray(m.velocity), np.asarray(m.accel), np.asarray(m.jerk),
        scene.motion.program.start_deg, f.type, float(base_radius_mm),
        None if face_width_mm is None else float(face_width_mm),
        np.asarray(x), np.asarray(y), _np(rho), _np(arrays.force_N), _np(arrays.torque_Nm),
        _np(stress), None if scene.design is None else scene.design.sigma_max_MPa,
        f.roller_radius_mm if f.type == "roller" else None,
        f.offset_mm if f.type == "roller" else None,
        _np(pitch_x), _np(pitch_y), _np(phi), _np(pitch_rho), _np(margin),
    )


def evaluated_block(curves: DesignCurves) -> dict[str, Any]:
    """Stress, curvature and roller figures at the evaluated design."""
    t = curves.theta_deg
    out: dict[str, Any] = {}
    if curves.rho_mm is not None:
        out["rho_mm"] = trough(curves.rho_mm, t)
    if curves.stress_MPa is not None:
        out["stress_MPa"] = peak(curves.stress_MPa, t)
    if curves.follower_type == "roller":
        phi = curves.pressure_angle_deg
        i = int(np.argmax(np.abs(phi)))
        j = int(np.argmin(np.abs(curves.pitch_rho_mm)))
        out["roller"] = {
            "roller_radius_mm": curves.roller_radius_mm,
            "offset_mm": curves.offset_mm,
            "pressure_angle_deg": {**extrema(phi, t), "max_abs": _f(abs(phi[i])),
                                   "max_abs_deg": _f(t[i])},
            "pressure_angle_limit_deg": PRESSURE_ANGLE_LIMIT_DEG,
            "pressure_angle_ok": bool(abs(phi[i]) <= PRESSURE_ANGLE_LIMIT_DEG),
            "pitch_rho_mm": {"min_abs": _f(abs(curves.pitch_rho_mm[j])), "min_abs_deg": _f(t[j]),
                             "concave": bool(np.any(curves.pitch_rho_mm < 0))},
            "undercut_margin_mm": trough(curves.undercut_margin_mm, t),
            "undercut": bool(np.any(curves.undercut_margin_mm <= 0)),
        }
    return out


# ------------------------------------------------------------------------------ report


class Report(NamedTuple):
    """A scene's report (JSON-ready dict) with the curves behind it."""

    data: dict[str, Any]
    curves: DesignCurves
    arrays: SceneArrays


def analyse(scene: Scene, arrays: SceneArrays | None = None, *, base_radius_mm: float | None = None,
            dtype=None) -> Report:
    """Run every model the scene declares and assemble the report.

    Args:
      scene: a validated scene.
      arrays: precomputed :func:`camjax.analysis.scene_arrays` (computed here if None).
      base_radius_mm: evaluate and draw the geometry at this base radius instead of the design's
        (or, without a [design], instead of the smallest admissible radius + 1 mm, rounded up).
      dtype: floating dtype when ``arrays`` is computed here (default float64).
    """
    import camjax  # the version lives in the package

    if arrays is None:
        arrays = scene_arrays(scene, dtype=dtype)
    data: dict[str, Any] = {
        "camjax_version": camjax.__version__,
        "scene": scene.name,
        "dtype": str(arrays.kin.s.dtype),
        "models": sorted(scene.needs()),
        "samples": int(arrays.theta_deg.shape[0]),
        "cam_speed_rpm": scene.motion.rpm,
        "cam_speed_rad_s": _f(arrays.cam_speed_rad_s),
        "follower_type": scene.follower.type,
        "segments": [dict(s) for s in scene.motion.segments],
        "kinematics": kinematics_block(arrays),
        "flcd": flcd_block(scene),
        "flcd_units": FLCD_UNITS,
    }
    block = loads_block(scene, arrays)
    if block is not None:
        data["loads"] = block
    minimum = min_base_radius_block(scene, arrays)
    data.update(minimum)
    data.update(face_width_block(scene, arrays))
    design = design_block(scene, arrays)
    if design is not None:
        data["design"] = design
    radius, source = drawing_base_radius(design, minimum["min_base_radius_mm"], base_radius_mm)
    width = design["face_width_mm"] if design is not None else None
    curves = evaluate_design(scene, arrays, radius, width)
    data["evaluated_at"] = {"base_radius_mm": radius, "face_width_mm": curves.face_width_mm,
                            "source": source}
    data.update(evaluated_block(curves))
    return Report(data, curves, arrays)


def design_report(scene: Scene, arrays: SceneArrays | None = None, *,
                  base_radius_mm: float | None = None, dtype=None) -> dict[str, Any]:
    """The report of a scene as a plain, JSON-ready dict (see :func:`analyse` for the arguments)."""
    return analyse(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype).data
