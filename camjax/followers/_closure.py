"""Positive drive: a roller held on its cam by a groove or by a conjugate cam instead of a spring.

One room for what a translating and a rocking roller share when no spring holds them on the cam
(the scene's ``[follower] closure``, :class:`camjax.scene.spec.ClosureSpec`):

- the closure keys read and checked (:func:`read_closure`);
- groove: the inner flank is the cam of a spring-closed roller (the pitch curve moved towards the
  cam centre by R_f); the outer flank is the pitch curve moved the other way by R_o = R_f + c
  (c = ``groove_clearance_mm``). Where the pitch curve is concave (curvature kappa < 0) the outer
  flank is concave too, of radius |rho_pitch| - R_o: a concavity radius of the pitch curve below
  R_o (+ the smallest radius allowed) cannot be cut (:func:`outer_flank_constraint`, the mirror
  image of the inner flank's undercut). Both flanks share the pitch curve's normal, so both see the
  same pressure angle;
- conjugate: the second roller's centre is another point of the follower (a yoke's second
  roller, a second arm's roller); its pitch curve, curvature and cam follow from that point's
  position and derivatives in the follower frame (:func:`point_pitch`);
- which contact carries the load: the force (torque) the follower needs is pushed by the first
  contact (inner flank, first cam) where it is > 0 and pulled by the second where it is < 0
  (:func:`split_load`).
- the design problems' second contact (:class:`GrooveTerms`, :class:`YokeTerms`, :class:`ArmTerms`
  and :func:`groove_second`, :func:`yoke_second`, :func:`arm_second`: g <= 0 per angle, each limit
  of each contact its own row, :func:`with_second_contact`) and the sizing's (:func:`second_limits`,
  :func:`first_admissible_size`).

The report's block and the drawings are :mod:`camjax.followers._closure_report` and
:mod:`camjax.followers._closure_drawing` (output layer, NumPy only).

Frames, rotation and signs: :mod:`camjax.followers._pitch`. Lengths mm, angles rad; every
function is elementwise over the angle grid and jit/vmap/grad-safe.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.numerics import capped_divide, safe_sqrt
from camjax.scene.reader import DEFAULT, TableReader, build
from camjax.scene.spec import SPRING, ClosureSpec

GROOVE_KEYS = ("groove_clearance_mm",)
YOKE_KEYS = ("yoke_span_mm", "second_roller_radius_mm")  # conjugate, translating
ARM_KEYS = ("second_arm_length_mm", "second_arm_angle_deg", "second_roller_radius_mm")  # conjugate, rocking
POSITIVE_CLOSURES = ("spring", "groove", "conjugate")


def closure_keys(rocking: bool) -> tuple[str, ...]:
    """The [follower] keys of the positive-drive closures of a roller (translating or rocking)."""
    return (*GROOVE_KEYS, *(ARM_KEYS if rocking else YOKE_KEYS))


def read_closure(r: TableReader, rocking: bool, roller_radius_mm: float) -> ClosureSpec:
    """``closure`` and its keys of a roller's [follower] table (SceneError naming the key).

    A key of another closure is refused naming the closure it belongs to; a spring key beside a
    groove or conjugate closure is allowed (a preloaded positive drive).
    """
    kind = r.choice("closure", POSITIVE_CLOSURES, "spring")
    own = {"spring": (), "groove": GROOVE_KEYS, "conjugate": ARM_KEYS if rocking else YOKE_KEYS}[kind]
    for key in closure_keys(rocking):
        if r.has(key) and key not in own:
            needs = "groove" if key in GROOVE_KEYS else "conjugate"
            raise r.error(key, r.table[key], f"only with closure = {needs!r}, not closure = {kind!r}",
                          f"closure = {needs!r}")
    if kind == "spring":
        return SPRING
    if kind == "groove":
        return build(ClosureSpec, kind=kind, clearance_mm=r.number("groove_clearance_mm", DEFAULT, low=0.0))
    second = r.number("second_roller_radius_mm", DEFAULT, low=0.0, low_open=True)
    second = roller_radius_mm if second is DEFAULT else second
    if not rocking:
        span = r.number("yoke_span_mm", low=0.0, low_open=True)
        if span <= roller_radius_mm + second:
            raise r.error("yoke_span_mm", span, "puts the second roller inside the first: the span must "
                          "exceed R_f + the second roller's radius, and reach past the shaft",
                          f"> {roller_radius_mm + second:g}")
        return ClosureSpec(kind, yoke_span_mm=span, second_roller_radius_mm=second)
    arm = r.number("second_arm_length_mm", low=0.0, low_open=True)
    angle = r.number("second_arm_angle_deg", low=0.0, high=360.0, low_open=True)
    if angle == 360.0:
        raise r.error("second_arm_angle_deg", angle, "puts the second arm on the first", "> 0 and < 360")
    return ClosureSpec(kind, second_roller_radius_mm=second, second_arm_length_mm=arm, second_arm_angle_deg=angle)


# ------------------------------------------------------------------------------ groove


def outer_flank(pitch_x, pitch_y, inner_x, inner_y, roller_radius_mm, clearance_mm):
    """The outer flank (X, Y), mm: the pitch curve moved away from the cam centre by R_f + c, along
    the normal the inner flank (the pitch curve moved inward by R_f) was moved along."""
    k = (roller_radius_mm + clearance_mm) / roller_radius_mm
    return pitch_x - k * (inner_x - pitch_x), pitch_y - k * (inner_y - pitch_y)


def outer_flank_constraint(pitch_curvature, outer_radius_mm, min_curvature_radius_mm=0.0):
    """g = (R_o + rho_min) (-kappa (R_o + rho_min) - 1) <= 0 (mm): the outer flank can be cut.

    Where the pitch curve is concave (kappa < 0) this is |rho_pitch| >= R_o + rho_min, i.e. the
    outer flank's concave radius |rho_pitch| - R_o >= rho_min; on convex parts it holds for every
    roller (the outer flank is then a concave wall of radius rho_pitch + R_o around the roller).
    Written on the curvature so that it stays finite through inflections.
    """
    reach = outer_radius_mm + min_curvature_radius_mm
    return reach * (-pitch_curvature * reach - 1.0)


def outer_flank_margin(pitch_curvature, outer_radius_mm, min_curvature_radius_mm=0.0):
    """|rho_pitch| - R_o - rho_min (mm) where the pitch curve is concave; the largest float where it
    is convex (no limit there). <= 0: the outer flank cannot be cut."""
    cap = jnp.finfo(jnp.result_type(pitch_curvature, float)).max
    rho = capped_divide(jnp.ones_like(pitch_curvature), -pitch_curvature)
    return jnp.where(pitch_curvature < 0, rho - outer_radius_mm - min_curvature_radius_mm, cap)


def groove_undercut(pitch_curvature, roller_radius_mm, min_curvature_radius_mm, clearance_mm):
    """The larger of the inner flank's undercut and the outer flank's concavity limit, both as g <= 0
    in mm (:func:`outer_flank_constraint`; the inner's is the spring-closed roller's). Only one of
    them can be above -R at an angle: the inner where kappa > 0, the outer where kappa < 0."""
    reach = roller_radius_mm + min_curvature_radius_mm
    inner = reach * (pitch_curvature * reach - 1.0)
    return jnp.maximum(inner, outer_flank_constraint(pitch_curvature, roller_radius_mm + clearance_mm,
                                                     min_curvature_radius_mm))


def groove_margin(inner_margin, pitch_curvature, roller_radius_mm, clearance_mm, min_curvature_radius_mm=0.0):
    """The smaller of the inner flank's undercut margin and the outer flank's (mm)."""
    return jnp.minimum(inner_margin, outer_flank_margin(pitch_curvature, roller_radius_mm + clearance_mm,
                                                        min_curvature_radius_mm))


def outer_equivalent_radius(pitch_curvature, roller_radius_mm, clearance_mm):
    """Hertz equivalent radius (mm) of the roller on the outer flank: 1 / (1/R_f - 1/rho_o).

    The outer flank's radius is rho_o = rho_pitch + R_o about the pitch curve's centre of
    curvature (R_o = R_f + c; concave towards the roller where the pitch curve is convex), so
    rho_eq = R_f (1 + R_o kappa) / (1 + c kappa); for c = 0 it is R_f (1 + R_f kappa), the mirror
    image of the inner flank's R_f (1 - R_f kappa).
    """
    outer = roller_radius_mm + clearance_mm
    return roller_radius_mm * capped_divide(1.0 + outer * pitch_curvature, 1.0 + clearance_mm * pitch_curvature)


# --------------------------------------------------------------------------- conjugate


class PointPitch(NamedTuple):
    """The pitch curve of a follower point, per sample (follower-frame components)."""

    tangent_x: jax.Array  # T = dP/dtheta seen in the follower frame, mm/rad
    tangent_y: jax.Array
    curvature: jax.Array  # 1/mm, > 0 where the pitch curve is convex
    normal_x: jax.Array  # unit normal towards the cam centre's side (the cam material)
    normal_y: jax.Array


def point_pitch(x, y, dx, dy, d2x, d2y, sign: float) -> PointPitch:
    """Tangent, curvature and inward normal of the curve a follower-frame point (x, y) traces on
    the cam, from its derivatives over the cam angle (dx, dy; d2x, d2y), ``sign`` +1 ccw, -1 cw.

    The cam-frame point is P = R(-sign theta) p, so P' = R(-sign theta) T with T = p' - sign J p,
    P'' = R(-sign theta) (T' - sign J T), T' = p'' - sign J p' (J: +90 deg). The curve turns
    towards the cam centre (convex) with curvature (|T|^2 - sign T x T') / |T|^3, and its inward
    normal is -sign J T / |T|. For a translating roller, p = (e, w), this is
    :func:`camjax.followers._pitch.pitch_curvature` and ``inward_normal``.
    """
    tx, ty = dx + sign * y, dy - sign * x  # p' - sign J p, J p = (-y, x)
    tdx, tdy = d2x + sign * dy, d2y - sign * dx
    q = tx**2 + ty**2
    cross = tx * tdy - ty * tdx
    kappa = capped_divide(q - sign * cross, q * safe_sqrt(q))
    inv = capped_divide(jnp.ones_like(q), safe_sqrt(q))
    return PointPitch(tx, ty, kappa, sign * ty * inv, -sign * tx * inv)


def path_pressure_angle(normal_x, normal_y, path_x, path_y):
    """Angle (rad) between the force a cam puts on a roller, along -(inward normal), and the
    direction (path_x, path_y) it drives the roller's centre (any length); signed, |.| < pi/2 where
    the cam pushes the roller along that path, positive when the force leans to the path's right."""
    return jnp.arctan2(normal_x * path_y - normal_y * path_x, -(normal_x * path_x + normal_y * path_y))


def conjugate_cam(x, y, dx, dy, d2x, d2y, path_x, path_y, roller_radius_mm, theta, rotation: str,
                  min_curvature_radius_mm=0.0) -> dict[str, jax.Array]:
    """The second cam of a conjugate pair from its roller centre (x, y) in the follower frame, its
    derivatives over the cam angle and the direction (path_x, path_y) that cam drives it along:
    pitch curve and cam (the pitch curve moved towards the cam centre by the second roller's
    radius) in cam coordinates, its pressure angle (deg, :func:`path_pressure_angle`), undercut
    margin (mm, as the first cam's) and pitch curvature (1/mm), named as profile.csv's columns."""
    from camjax.followers._pitch import rotation_sign, to_cam_frame
    from camjax.followers.roller.geometry import roller_undercut_margin

    pp = point_pitch(x, y, dx, dy, d2x, d2y, rotation_sign(rotation))
    pitch_x, pitch_y = to_cam_frame(x, y, theta, rotation)
    cam_x, cam_y = to_cam_frame(x + roller_radius_mm * pp.normal_x, y + roller_radius_mm * pp.normal_y,
                                theta, rotation)
    return {"conjugate_pitch_x_mm": pitch_x, "conjugate_pitch_y_mm": pitch_y, "conjugate_x_mm": cam_x,
            "conjugate_y_mm": cam_y,
            "conjugate_pressure_angle_deg": jnp.rad2deg(path_pressure_angle(pp.normal_x, pp.normal_y, path_x, path_y)),
            "conjugate_margin_mm": roller_undercut_margin(pp.curvature, roller_radius_mm, min_curvature_radius_mm),
            "conjugate_pitch_curvature": pp.curvature}


def _with_loads(out, first_pressure_angle, first_curvature, first_radius_mm, second_radius_mm, path_force_N,
                hertz):
    """The conjugate pair's curves with each cam's normal force and stress (:func:`flank_loads`)."""
    kappa2 = out.pop("conjugate_pitch_curvature")
    if path_force_N is not None:
        radii = (first_radius_mm * (1.0 - first_radius_mm * first_curvature),
                 second_radius_mm * (1.0 - second_radius_mm * kappa2))
        phi2 = jnp.deg2rad(out["conjugate_pressure_angle_deg"])
        out.update(flank_loads(path_force_N, (first_pressure_angle, phi2), radii, hertz))
    return out


def _refuse(key: str, value, problem: str, allowed: str):
    from camjax.errors import SceneError

    raise SceneError(f"follower.{key}", value, problem, allowed)


def yoke_curves(closure: ClosureSpec, base_radius_mm, roller_radius_mm, offset_mm, kin, rotation: str,
                min_curvature_radius_mm, geometry, path_force_N=None, hertz=None) -> dict[str, jax.Array]:
    """The second cam of a translating roller's yoke (Python: checks the span, a SceneError naming
    ``follower.yoke_span_mm`` where the second roller would reach the shaft).

    The second roller's centre sits on the follower axis ``yoke_span_mm`` L below the first, at
    (e, w - L) in the follower frame (w = sqrt(R_p^2 - e^2) + s), on the far side of the shaft; its
    cam pushes it away from the shaft, along -y, which pulls the follower back. ``geometry``: the
    first cam's :class:`camjax.followers.roller.geometry.RollerGeometry`."""
    import numpy as np

    from camjax.followers.roller.geometry import roller_pitch_height

    span, r2 = closure.yoke_span_mm, closure.second_roller_radius_mm
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    y2 = w - span
    reach = float(np.max(np.asarray(w))) + math.sqrt(max(r2**2 - offset_mm**2, 0.0))
    if span <= reach:
        _refuse("yoke_span_mm", span, f"puts the second roller on the shaft: at R_b = {base_radius_mm:g} mm the "
                f"first roller rises to {float(np.max(np.asarray(w))):g} mm above the centre", f"> {reach:g}")
    zero = jnp.zeros_like(w)
    out = conjugate_cam(offset_mm + zero, y2, zero, kin.ds, zero, kin.d2s, zero, -jnp.ones_like(w), r2,
                        kin.theta, rotation, min_curvature_radius_mm)
    return _with_loads(out, geometry.pressure_angle, geometry.pitch_curvature, roller_radius_mm, r2, path_force_N, hertz)


def arm_curves(closure: ClosureSpec, pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm, kin,
               rotation: str, min_curvature_radius_mm, moment_Nm=None, hertz=None) -> dict[str, jax.Array]:
    """The second cam of a rocker's second arm (Python: checks the arm, SceneErrors naming
    ``follower.second_arm_angle_deg`` or ``second_arm_length_mm``).

    The second arm, ``second_arm_length_mm`` l2 long, sits ``second_arm_angle_deg`` beta from the
    first, across the line of centres: its roller's centre is C2 = (d - l2 cos(psi - beta),
    l2 sin(psi - beta)) in the follower frame (the first's: psi), and psi - beta must stay in
    (-180, 0) deg, where pushing C2 away from the shaft swings the rocker back (|C2| falls as psi
    grows). Loads: the pivot torque M > 0 is the first cam's, M < 0 the second's, whose force along
    its roller's path is -M / l2."""
    import numpy as np

    from camjax.followers._swing import arm_angle
    from camjax.followers.oscillating_roller import geometry as rocker_geo

    l2, r2, beta = closure.second_arm_length_mm, closure.second_roller_radius_mm, math.radians(closure.second_arm_angle_deg)
    psi0 = rocker_geo.arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    psi = arm_angle(psi0, kin)
    a = psi - beta
    lo, hi = float(np.min(np.asarray(a))), float(np.max(np.asarray(a)))
    if not (-math.pi < lo and hi < 0.0):
        first = (math.degrees(float(np.min(np.asarray(psi)))), math.degrees(float(np.max(np.asarray(psi)))))
        _refuse("second_arm_angle_deg", closure.second_arm_angle_deg,
                f"must put the second arm across the line of centres from the first while it swings (the first "
                f"arm swings from {first[0]:.4g} to {first[1]:.4g} deg)",
                f"between {first[1]:.4g} and {first[0] + 180.0:.4g}")
    c, sn = jnp.cos(a), jnp.sin(a)
    x, y = pivot_distance_mm - l2 * c, l2 * sn
    dcx, dcy = l2 * sn, l2 * c  # dC2/dpsi
    ddx, ddy = l2 * c, -l2 * sn
    near = float(np.min(np.asarray(jnp.hypot(x, y))))
    if near <= r2:
        _refuse("second_arm_length_mm", l2, f"brings the second roller onto the shaft (its centre comes within "
                f"{near:.4g} mm of the cam centre, its radius is {r2:g} mm)", "a longer or shorter second arm")
    out = conjugate_cam(x, y, kin.ds * dcx, kin.ds * dcy, kin.d2s * dcx + kin.ds**2 * ddx,
                        kin.d2s * dcy + kin.ds**2 * ddy, -dcx, -dcy, r2, kin.theta, rotation, min_curvature_radius_mm)
    first = rocker_geo.oscillating_roller_geometry(pivot_distance_mm, arm_length_mm, roller_radius_mm,
                                                   prime_radius_mm, kin, rotation, min_curvature_radius_mm)
    force = None
    if moment_Nm is not None:  # along each roller's path: M / l for the first, -M / l2 for the second
        split = jnp.where(moment_Nm >= 0, moment_Nm / (arm_length_mm * 1e-3), moment_Nm / (l2 * 1e-3))
        force = split
    return _with_loads(out, first.pressure_angle, first.pitch_curvature, roller_radius_mm, r2, force, hertz)


# ------------------------------------------------------------------------------- loads


class SplitLoad(NamedTuple):
    """The load a positive drive carries, split between its two contacts (per sample)."""

    first: jax.Array  # the part > 0 (inner flank / first cam pushes), in the load's unit
    second: jax.Array  # the part < 0, as a positive value (outer flank / second cam)


def split_load(load):
    """(max(F, 0), max(-F, 0)) of the force (or torque) the follower needs: the first contact
    carries it where it is > 0, the second where it is < 0."""
    return SplitLoad(jnp.maximum(load, 0.0), jnp.maximum(-load, 0.0))


def free_travel_mm(clearance_mm, pressure_angle_rad):
    """How far the roller's centre moves along its path when the load reverses in a groove of
    clearance c: across the gap along the contact normal, c / cos phi (mm)."""
    return clearance_mm / jnp.cos(pressure_angle_rad)


def flank_loads(path_force_N, pressure_angle_rad, equivalent_radii_mm, hertz=None) -> dict[str, jax.Array]:
    """Per-sample loads of the two contacts of a positive drive, named as profile.csv's columns.

    ``path_force_N``: the force the follower needs along its roller's path (translating: the axial
    force; rocking: the pivot torque over the arm); the first contact pushes where it is > 0, the
    second where it is < 0 (:func:`split_load`). ``equivalent_radii_mm``: each contact's Hertz
    equivalent radius; ``pressure_angle_rad``: each contact's (one array for a groove, whose flanks
    share the normal). ``hertz``: None, or (cam width mm, cam material, follower material) for the
    stress on each. Normal forces P = F / cos phi (:func:`camjax.loads.normal_force`).
    """
    from camjax import contact, loads

    first, second = split_load(path_force_N)
    phi1, phi2 = (pressure_angle_rad if isinstance(pressure_angle_rad, tuple)
                  else (pressure_angle_rad, pressure_angle_rad))
    out = {"first_force_N": loads.normal_force(first, phi1), "second_force_N": loads.normal_force(second, phi2)}
    if hertz is not None:
        width, cam, follower = hertz
        for name, part, phi, rho in (("first", first, phi1, equivalent_radii_mm[0]),
                                     ("second", second, phi2, equivalent_radii_mm[1])):
            coefficient = contact.stress_coefficient(part, width, cam, follower)
            out[f"{name}_stress_MPa"] = contact.roller_stress(coefficient, phi, rho)
    return out


def groove_curves(closure: ClosureSpec, pitch_x, pitch_y, inner_x, inner_y, pitch_curvature, pressure_angle_rad,
                  roller_radius_mm, min_curvature_radius_mm=0.0, path_force_N=None, hertz=None) -> dict[str, jax.Array]:
    """A groove's own curves at one design, named as profile.csv's columns: both flanks in cam
    coordinates (``inner_*`` is the spring-closed cam, ``outer_*`` at R_f + c), the outer flank's
    concavity margin (:func:`outer_flank_margin`) and, with the follower's load, each flank's normal
    force and Hertz stress (:func:`flank_loads`)."""
    c = closure.clearance_mm
    outer_x, outer_y = outer_flank(pitch_x, pitch_y, inner_x, inner_y, roller_radius_mm, c)
    out = {"inner_x_mm": inner_x, "inner_y_mm": inner_y, "outer_x_mm": outer_x, "outer_y_mm": outer_y,
           "outer_margin_mm": outer_flank_margin(pitch_curvature, roller_radius_mm + c, min_curvature_radius_mm)}
    if path_force_N is not None:
        radii = (roller_radius_mm * (1.0 - roller_radius_mm * pitch_curvature),
                 outer_equivalent_radius(pitch_curvature, roller_radius_mm, c))
        loads = flank_loads(path_force_N, pressure_angle_rad, radii, hertz)
        out.update({k.replace("first", "inner").replace("second", "outer"): v for k, v in loads.items()})
    return out


def hertz_of(scene):
    """(cam width mm, cam material, follower material) of a scene's [contact]; None without it."""
    c = scene.contact
    return None if c is None else (c.cam_width_mm, c.cam, c.follower)


# ------------------------------------------------------------------------------ design


class GrooveTerms(NamedTuple):
    """A groove in a design problem (a pytree: the problem's ``closure`` field)."""

    clearance_mm: jax.Array  # ()
    second_coefficient: jax.Array  # (n,) Hertz coefficient of the outer flank's load, from max(-F, 0)


class YokeTerms(NamedTuple):
    """A translating roller's yoke in a design problem."""

    span_mm: jax.Array  # () L, between the roller centres
    roller_radius_mm: jax.Array  # () the second roller's
    second_coefficient: jax.Array  # (n,) Hertz coefficient of the second cam's load, from max(-F, 0)


class ArmTerms(NamedTuple):
    """A rocker's second arm in a design problem."""

    arm_length_mm: jax.Array  # () l2
    angle_rad: jax.Array  # () beta, from the first arm to the second
    roller_radius_mm: jax.Array  # () the second roller's
    second_coefficient: jax.Array  # (n,) moment coefficient of the second cam's load, from max(-M, 0)


def design_terms(scene, arrays, second_coefficient):
    """The closure's terms of a design problem (None: spring-closed); ``second_coefficient`` the
    (n,) Hertz coefficient of the load the second contact carries (zeros without [contact])."""
    c = scene.follower.closure
    dt = arrays.kin.s.dtype
    as_ = lambda v: jnp.asarray(v, dt)  # noqa: E731
    if c.kind == "groove":
        return GrooveTerms(as_(c.clearance_mm), second_coefficient)
    if c.kind == "conjugate" and c.yoke_span_mm is not None:
        return YokeTerms(as_(design_start(scene, "yoke_span_mm")), as_(c.second_roller_radius_mm),
                         second_coefficient)
    if c.kind == "conjugate":
        angle = math.radians(design_start(scene, "second_arm_angle_deg"))
        return ArmTerms(as_(c.second_arm_length_mm), as_(angle), as_(c.second_roller_radius_mm),
                        second_coefficient)
    return None


def design_start(scene, key: str) -> float:
    """The yoke span (mm) or second arm angle (deg) a conjugate pair's design problem is solved at: the
    [follower]'s, or the [design]'s where it sets one; where [design] frees it, the most permissive
    value (:mod:`camjax.followers._closure_design`): a yoke's largest span, a rocker's [follower]
    angle clipped into the bounds."""
    value = getattr(scene.follower.closure, key)
    if scene.design is None or key not in dict(scene.design.variables):
        return value
    low, high = scene.design.bounds(key)
    return high if key == "yoke_span_mm" else min(max(value, low), high)


def reversed_coefficient(force_N, cam_width_mm, cam, follower):
    """The Hertz coefficient of max(-F, 0): the second contact's (:func:`camjax.contact.stress_coefficient`)."""
    from camjax import contact

    return contact.stress_coefficient(jnp.maximum(-force_N, 0.0), cam_width_mm, cam, follower)


class SecondContact(NamedTuple):
    """The second contact's constraints of a design, g <= 0 per angle (mm), each its own row beside the
    first contact's (:func:`with_second_contact`), and what a report judges of it."""

    lean: jax.Array  # mm: its pressure-angle limit is |lean| - reach <= 0 (a groove's is the first's)
    reach: jax.Array  # mm
    undercut: jax.Array  # mm: the cut limit of its curvature
    stress: jax.Array  # mm (C^2 / (sigma_max^2 cos phi) - rho_eq)
    pressure_angle_rad: jax.Array  # |phi| of the second contact (the evaluation)
    margin_mm: jax.Array  # the second contact's cut margin (mm; <= rho_min: violated)
    stress_MPa: jax.Array  # the second contact's Hertz stress
    shaft: jax.Array | None = None  # mm: R2 - |C2| (conjugate): the second roller off the shaft
    side: jax.Array | None = None  # mm: l2 sin(psi - beta) (a second arm): across the line of centres


# A positive drive's constraint rows (its own NamedTuple per family and closure, declared with
# camjax.family.twin_type from the spring-closed Constraints): no max inside a row, so that the
# constraint set is smooth where two pieces cross. The pressure angle |lean| - reach <= 0 is two
# rows, lean - reach and -lean - reach (+phi_max and -phi_max: |s' - e~| is kinked at every
# dwell sample where s' = e~, and an interior-point path that crosses e~ = 0 over such rows
# oscillated there at the iteration cap); then each limit of the second contact on its own row.
# Each row names the spring-closed row of its limit (:data:`LIMIT_ROW`: what polish keeps and what
# the second contact is judged beside, :func:`second_excess`) and the SecondContact field it is.
PRESSURE_ROWS = ("pressure_angle_plus", "pressure_angle_minus")
GROOVE_ROWS = (*PRESSURE_ROWS, "outer_undercut", "outer_stress")  # one normal: one pressure angle
YOKE_ROWS = (*PRESSURE_ROWS, "second_pressure_angle_plus", "second_pressure_angle_minus", "second_undercut",
             "second_stress", "second_shaft")
ARM_ROWS = (*YOKE_ROWS, "second_side")
LIMIT_ROW = {"pressure_angle_plus": "pressure_angle", "pressure_angle_minus": "pressure_angle",
             "outer_undercut": "undercut", "outer_stress": "stress",
             "second_pressure_angle_plus": "pressure_angle", "second_pressure_angle_minus": "pressure_angle",
             "second_undercut": "undercut", "second_stress": "stress", "second_shaft": "undercut",
             "second_side": "pressure_angle"}
_SECOND_FIELD = {"outer_undercut": "undercut", "outer_stress": "stress", "second_undercut": "undercut",
                 "second_stress": "stress", "second_shaft": "shaft", "second_side": "side"}


_ROWS = {GrooveTerms: GROOVE_ROWS, YokeTerms: YOKE_ROWS, ArmTerms: ARM_ROWS}


def row_names(terms) -> tuple[str, ...]:
    """The rows a positive drive with closure ``terms`` adds to the spring-closed constraints, in
    place of their pressure angle (static)."""
    return _ROWS[type(terms)]


def with_second_contact(first, lean, reach, second: SecondContact, terms, types: dict):
    """A positive drive's constraints (g <= 0, mm, (n,) each), as ``types[type(terms)]`` (the family's
    NamedTuple, declared with :func:`positive_type`): the first contact's rows ``first`` (the
    family's spring-closed Constraints) less its pressure angle |lean| - reach, which is two rows
    (``lean`` and ``reach`` in mm), then the second contact's rows (:func:`row_names`)."""
    rows = {"pressure_angle_plus": lean - reach, "pressure_angle_minus": -lean - reach,
            "second_pressure_angle_plus": second.lean - second.reach,
            "second_pressure_angle_minus": -second.lean - second.reach}
    own = {name: rows[name] if name in rows else getattr(second, _SECOND_FIELD[name])
           for name in row_names(terms)}
    kept = {name: value for name, value in first._asdict().items() if name != "pressure_angle"}
    return types[type(terms)](**kept, **own)


def positive_type(name: str, constraints, terms_type, module: str):
    """A family's NamedTuple of a positive drive's constraints (:func:`with_second_contact`): its
    spring-closed ``constraints`` type without the pressure angle, then the rows of closure
    ``terms_type`` (:func:`camjax.family.twin_type`; ``module``: the declaring module's name)."""
    from camjax.family import twin_type

    return twin_type(name, constraints, f"{name}: g <= 0 (mm, (n,) each), the first contact's rows, the "
                     "pressure angle as two rows (+ and - the limit), then the second contact's.", module,
                     drop=("pressure_angle",), add=_ROWS[terms_type])


def second_excess(constraints, first) -> jax.Array:
    """Each second-contact row of a positive drive's ``constraints`` less what the spring-closed rows
    ``first`` of the same design allow there, max(that limit's row, 0) (mm, shape (rows, n)): <= 0
    where the second contact keeps every limit the first keeps, and is over by no more where the
    first is over."""
    names = [f for f in constraints._fields if f in LIMIT_ROW and f not in PRESSURE_ROWS]
    return jnp.stack([getattr(constraints, f) - jnp.maximum(getattr(first, LIMIT_ROW[f]), 0.0)
                      for f in names])


def exact_rows(names: tuple[str, ...], terms) -> tuple[str, ...]:
    """The rows a polish keeps at every angle (static): the spring-closed rows ``names`` and, with
    closure ``terms``, the rows of a positive drive of those limits (:data:`LIMIT_ROW`)."""
    if terms is None:
        return names
    kept = (f for f in names if f != "pressure_angle")
    return (*kept, *(f for f in row_names(terms) if LIMIT_ROW[f] in names))


_CONTACTS = {"groove": ("inner flank", "outer flank"), "conjugate": ("first cam", "second cam")}
_KINDS = {"second_shaft": "shaft_clearance", "second_side": "arm_side"}


def row_labels(terms) -> dict[str, tuple[str, str]]:
    """Row name -> (kind, contact) of a positive drive's constraint rows with closure ``terms`` (the
    certificate's labels): the kind of its limit (pressure_angle, undercut, stress, shaft_clearance,
    arm_side) and the contact ("inner flank", "outer flank", "inner and outer flanks": a groove's pressure
    angle; "first cam", "second cam"); {} for a spring-closed problem (``terms`` None)."""
    if terms is None:
        return {}
    groove = type(terms) is GrooveTerms
    first, second = _CONTACTS["groove" if groove else "conjugate"]
    labels = {"undercut": ("undercut", first), "stress": ("stress", first)}
    for name in row_names(terms):
        contact = ("inner and outer flanks" if groove else first) if name in PRESSURE_ROWS else second
        labels[name] = (_KINDS.get(name, LIMIT_ROW[name]), contact)
    return labels


def _second(sigma_max_MPa, coefficient, pressure, phi, undercut_g, margin, rho_eq,
            **clearances) -> SecondContact:
    """A second contact's constraints from its pressure-angle terms (lean, reach: |lean| - reach <= 0,
    mm), pressure angle (rad), cut constraint and margin (mm), Hertz equivalent radius (mm) and the
    coefficient of its load; ``clearances``: its ``shaft`` and ``side`` rows (mm) where it has them."""
    from camjax.contact import roller_stress
    from camjax.numerics import COS_FLOOR

    cos_phi = jnp.maximum(jnp.cos(phi), COS_FLOOR)
    need = coefficient**2 / (sigma_max_MPa**2 * cos_phi)
    return SecondContact(*pressure, undercut_g, need - rho_eq, jnp.abs(phi), margin,
                         roller_stress(coefficient, phi, rho_eq), **clearances)


def worst_of_both(sigma, phi, margin, second: SecondContact):
    """Per angle, the worse of the first contact's stress, |pressure angle| and undercut margin and the
    second contact's (:class:`SecondContact`): what a positive drive's report judges."""
    return (jnp.maximum(sigma, second.stress_MPa), jnp.maximum(phi, second.pressure_angle_rad),
            jnp.minimum(margin, second.margin_mm))


def groove_second(terms: GrooveTerms, kappa, roller_radius_mm, min_curvature_radius_mm, pressure, phi,
                  sigma_max_MPa, coefficient=None) -> SecondContact:
    """The outer flank: the first's pressure angle (shared normal: ``pressure`` = its (lean, reach), mm),
    its concavity limit and its stress (``coefficient``: the Hertz coefficient of the force along the
    roller's path, default the terms')."""
    c = terms.clearance_mm
    coefficient = terms.second_coefficient if coefficient is None else coefficient
    return _second(sigma_max_MPa, coefficient, pressure, phi,
                   outer_flank_constraint(kappa, roller_radius_mm + c, min_curvature_radius_mm),
                   outer_flank_margin(kappa, roller_radius_mm + c),
                   outer_equivalent_radius(kappa, roller_radius_mm, c))


def yoke_second(terms: YokeTerms, w, u, ds, d2s, signed_offset_mm, min_curvature_radius_mm, tan_limit,
                sigma_max_MPa) -> SecondContact:
    """The yoke's second cam (ccw formulas, e~ = sign e): its roller at depth D = L - w below the
    centre on the axis, tan phi2 = |s' - e~| / D; curvature of the pitch curve of (e~, w - L); the
    roller must stay off the shaft (D > R2: the ``shaft`` row). ``w``, ``u``: the first roller's
    height and s' - e~ (mm)."""
    from camjax.followers import _pitch as pitch
    from camjax.followers.roller.geometry import roller_undercut_margin

    r2, depth = terms.roller_radius_mm, terms.span_mm - w
    reach = r2 + min_curvature_radius_mm
    kappa2 = pitch.pitch_curvature(w - terms.span_mm, ds, d2s, signed_offset_mm)
    phi2 = jnp.arctan2(jnp.abs(u), depth)
    return _second(sigma_max_MPa, terms.second_coefficient, (u, tan_limit * depth), phi2,
                   reach * (kappa2 * reach - 1.0),
                   jnp.minimum(roller_undercut_margin(kappa2, r2), depth - r2),
                   r2 * (1.0 - r2 * kappa2), shaft=r2 - depth)


def arm_second(terms: ArmTerms, pivot_distance_mm, psi, ds, d2s, sign, min_curvature_radius_mm, tan_limit,
               sigma_max_MPa) -> SecondContact:
    """A rocker's second cam: its roller at C2 = (d - l2 cos(psi - beta), l2 sin(psi - beta)) driven
    along -dC2/dpsi (:func:`point_pitch`, :func:`path_pressure_angle`); the arm must stay across the
    line of centres (sin(psi - beta) < 0: the ``side`` row l2 sin(psi - beta)) and its roller off the
    shaft (|C2| > R2: the ``shaft`` row)."""
    from camjax.followers.roller.geometry import roller_undercut_margin

    l2, r2 = terms.arm_length_mm, terms.roller_radius_mm
    a = psi - terms.angle_rad
    c, sn = jnp.cos(a), jnp.sin(a)
    x, y = pivot_distance_mm - l2 * c, l2 * sn
    dcx, dcy, ddx, ddy = l2 * sn, l2 * c, l2 * c, -l2 * sn
    pp = point_pitch(x, y, ds * dcx, ds * dcy, d2s * dcx + ds**2 * ddx, d2s * dcy + ds**2 * ddy, sign)
    along = pp.normal_x * dcx + pp.normal_y * dcy  # -(n . m), m = -dC2/dpsi; |m| = l2
    across = -(pp.normal_x * dcy - pp.normal_y * dcx)
    phi2 = jnp.arctan2(across, along)
    reach = r2 + min_curvature_radius_mm
    coefficient = terms.second_coefficient * jax.lax.rsqrt(l2 * 1e-3)  # of the force -M / l2 on its path
    return _second(sigma_max_MPa, coefficient, (across, tan_limit * along), phi2,
                   reach * (pp.curvature * reach - 1.0),
                   jnp.minimum(roller_undercut_margin(pp.curvature, r2), jnp.hypot(x, y) - r2),
                   r2 * (1.0 - r2 * pp.curvature), shaft=r2 - jnp.hypot(x, y), side=y)


# ------------------------------------------------------------------------------ sizing


def second_limits(closure: ClosureSpec, kin, *, prime_radius_mm=None, signed_offset_mm=0.0, psi0=None,
                  pivot_distance_mm=None, arm_length_mm=None, sign=1.0, roller_radius_mm, min_curvature_radius_mm,
                  tan_limit):
    """The second contact's limits at one cam size, g <= 0 where admissible (shape (k, n): pressure
    angle, cut, and a conjugate cam's shaft clearance and a second arm's side), from the design
    problems' closed forms: a translating roller at prime radius
    ``prime_radius_mm`` (``signed_offset_mm``: sign e), a rocker at arm start angle ``psi0``."""
    from camjax.followers import _pitch as pitch

    zero = jnp.zeros_like(kin.s)
    if closure.kind == "groove":
        if psi0 is None:
            w = pitch.pitch_height(prime_radius_mm, signed_offset_mm, kin.s)
            kappa = pitch.pitch_curvature(w, kin.ds, kin.d2s, signed_offset_mm)
        else:
            from camjax.followers.oscillating_roller.geometry import swing_pitch_curvature

            kappa = swing_pitch_curvature(pivot_distance_mm, arm_length_mm, psi0 + kin.s, 1.0 + sign * kin.ds,
                                          kin.d2s)
        return jnp.stack([zero - 1.0, outer_flank_constraint(kappa, roller_radius_mm + closure.clearance_mm,
                                                             min_curvature_radius_mm)])
    if psi0 is None:
        terms = YokeTerms(closure.yoke_span_mm, closure.second_roller_radius_mm, zero)
        w = pitch.pitch_height(prime_radius_mm, signed_offset_mm, kin.s)
        second = yoke_second(terms, w, kin.ds - signed_offset_mm, kin.ds, kin.d2s, signed_offset_mm,
                             min_curvature_radius_mm, tan_limit, 1.0)
    else:
        terms = ArmTerms(closure.second_arm_length_mm, closure.second_arm_angle_deg * (math.pi / 180.0),
                         closure.second_roller_radius_mm, zero)
        second = arm_second(terms, pivot_distance_mm, psi0 + kin.s, kin.ds, kin.d2s, sign, min_curvature_radius_mm,
                            tan_limit, 1.0)
    pressure = jnp.abs(second.lean) - second.reach
    return jnp.stack([v for v in (pressure, second.undercut, second.shaft, second.side) if v is not None])


def first_admissible_size(bad, x0, hi, samples: int):
    """The smallest size x >= x0 (a prime radius, an arm start angle) where ``bad(x)`` is False:
    x0 itself where it is admissible, else the first admissible point of (x0, hi) by a scan and a
    bisection (:func:`camjax.followers._swing.first_admissible`). Returns (x, found)."""
    from camjax.followers._swing import first_admissible

    x, found = first_admissible(bad, x0, hi, samples)
    ok0 = ~bad(x0)
    return jnp.where(ok0, x0, x), ok0 | found
