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
- the design problems' second contact and the sizing's: :mod:`camjax.followers._closure_problem`.

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
                min_curvature_radius_mm, geometry, path_force_N=None,
                hertz=None) -> tuple[dict[str, jax.Array], jax.Array]:
    """The second cam of a translating roller's yoke, and the first roller's highest centre above
    the cam centre (mm, for :func:`check_yoke`); traceable, the closure's numbers included
    (``rotation`` is static).

    The second roller's centre sits on the follower axis ``yoke_span_mm`` L below the first, at
    (e, w - L) in the follower frame (w = sqrt(R_p^2 - e^2) + s), on the far side of the shaft; its
    cam pushes it away from the shaft, along -y, which pulls the follower back. ``geometry``: the
    first cam's :class:`camjax.followers.roller.geometry.RollerGeometry`."""
    from camjax.followers.roller.geometry import roller_pitch_height

    span, r2 = closure.yoke_span_mm, closure.second_roller_radius_mm
    w = roller_pitch_height(base_radius_mm, roller_radius_mm, offset_mm, kin)
    zero = jnp.zeros_like(w)
    out = conjugate_cam(offset_mm + zero, w - span, zero, kin.ds, zero, kin.d2s, zero, -jnp.ones_like(w), r2,
                        kin.theta, rotation, min_curvature_radius_mm)
    out = _with_loads(out, geometry.pressure_angle, geometry.pitch_curvature, roller_radius_mm, r2,
                      path_force_N, hertz)
    return out, jnp.max(w)


def check_yoke(closure: ClosureSpec, base_radius_mm: float, offset_mm: float, top_mm: float) -> None:
    """A SceneError naming ``follower.yoke_span_mm`` where the yoke's second roller would reach the
    shaft: the span must exceed the first roller's highest centre ``top_mm`` (:func:`yoke_curves`)
    plus the second roller's reach past the axis."""
    span, r2 = closure.yoke_span_mm, closure.second_roller_radius_mm
    reach = float(top_mm) + math.sqrt(max(r2**2 - offset_mm**2, 0.0))
    if span <= reach:
        _refuse("yoke_span_mm", span, f"puts the second roller on the shaft: at R_b = {base_radius_mm:g} mm "
                f"the first roller rises to {float(top_mm):g} mm above the centre", f"> {reach:g}")


class ArmReach(NamedTuple):
    """Where a rocker's two arms go while it swings (:func:`arm_curves`, for :func:`check_arm`)."""

    first_min: jax.Array  # rad: the first arm's angle psi, least and greatest
    first_max: jax.Array
    second_min: jax.Array  # rad: the second arm's, psi - beta
    second_max: jax.Array
    nearest_mm: jax.Array  # the second roller centre's closest approach to the cam centre


def arm_curves(closure: ClosureSpec, pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm, kin,
               rotation: str, min_curvature_radius_mm, moment_Nm=None,
               hertz=None) -> tuple[dict[str, jax.Array], ArmReach]:
    """The second cam of a rocker's second arm and where the arms go (for :func:`check_arm`);
    traceable, the closure's numbers included (``rotation`` is static).

    The second arm, ``second_arm_length_mm`` l2 long, sits ``second_arm_angle_deg`` beta from the
    first, across the line of centres: its roller's centre is C2 = (d - l2 cos(psi - beta),
    l2 sin(psi - beta)) in the follower frame (the first's: psi), and psi - beta must stay in
    (-180, 0) deg, where pushing C2 away from the shaft swings the rocker back (|C2| falls as psi
    grows). Loads: the pivot torque M > 0 is the first cam's, M < 0 the second's, whose force along
    its roller's path is -M / l2."""
    from camjax.followers._swing import arm_angle
    from camjax.followers.oscillating_roller import geometry as rocker_geo

    l2, r2 = closure.second_arm_length_mm, closure.second_roller_radius_mm
    beta = jnp.deg2rad(closure.second_arm_angle_deg)
    psi0 = rocker_geo.arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    psi = arm_angle(psi0, kin)
    a = psi - beta
    c, sn = jnp.cos(a), jnp.sin(a)
    x, y = pivot_distance_mm - l2 * c, l2 * sn
    dcx, dcy = l2 * sn, l2 * c  # dC2/dpsi
    ddx, ddy = l2 * c, -l2 * sn
    reach = ArmReach(jnp.min(psi), jnp.max(psi), jnp.min(a), jnp.max(a), jnp.min(jnp.hypot(x, y)))
    out = conjugate_cam(x, y, kin.ds * dcx, kin.ds * dcy, kin.d2s * dcx + kin.ds**2 * ddx,
                        kin.d2s * dcy + kin.ds**2 * ddy, -dcx, -dcy, r2, kin.theta, rotation, min_curvature_radius_mm)
    first = rocker_geo.oscillating_roller_geometry(pivot_distance_mm, arm_length_mm, roller_radius_mm,
                                                   prime_radius_mm, kin, rotation, min_curvature_radius_mm)
    force = None
    if moment_Nm is not None:  # along each roller's path: M / l for the first, -M / l2 for the second
        force = jnp.where(moment_Nm >= 0, moment_Nm / (arm_length_mm * 1e-3), moment_Nm / (l2 * 1e-3))
    out = _with_loads(out, first.pressure_angle, first.pitch_curvature, roller_radius_mm, r2, force, hertz)
    return out, reach


def check_arm(closure: ClosureSpec, reach: ArmReach) -> None:
    """SceneErrors naming ``follower.second_arm_angle_deg`` where the second arm does not stay across
    the line of centres from the first while it swings, or ``follower.second_arm_length_mm`` where
    its roller comes onto the shaft (``reach``: :func:`arm_curves`'s)."""
    lo, hi = float(reach.second_min), float(reach.second_max)
    if not (-math.pi < lo and hi < 0.0):
        first = (math.degrees(float(reach.first_min)), math.degrees(float(reach.first_max)))
        _refuse("second_arm_angle_deg", closure.second_arm_angle_deg,
                f"must put the second arm across the line of centres from the first while it swings (the "
                f"first arm swings from {first[0]:.4g} to {first[1]:.4g} deg)",
                f"between {first[1]:.4g} and {first[0] + 180.0:.4g}")
    near, l2, r2 = float(reach.nearest_mm), closure.second_arm_length_mm, closure.second_roller_radius_mm
    if near <= r2:
        _refuse("second_arm_length_mm", l2, f"brings the second roller onto the shaft (its centre comes "
                f"within {near:.4g} mm of the cam centre, its radius is {r2:g} mm)",
                "a longer or shorter second arm")


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
