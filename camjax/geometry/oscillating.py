"""Oscillating (rocker) followers, roller and flat-face (SPEC section 3): one design, any grid.

Layout (follower frame, fixed; mm). The cam centre O is the origin and the pivot A = (d, 0) lies
on +X at the pivot distance d. The arm angle psi is measured at the pivot from the line of
centres A -> O; the arm's unit vector is u(psi) = (-cos psi, sin psi), so the arm points at the
cam centre for psi = 0 and swings up (+Y) as psi grows. The motion program gives psi = psi0 + s
with s in rad (``lift_deg`` in the scene), psi0 its value at s = 0.

- Roller: centre C(psi) = A + l u = (d - l cos psi, l sin psi) at arm length l, so
  |C|^2 = d^2 + l^2 - 2 d l cos psi grows with psi on (0, pi): a rise swings the roller away from
  the cam centre. The prime radius is R_p = |C(psi0)|, cos psi0 = (d^2 + l^2 - R_p^2) / (2 d l),
  which needs |d - l| < R_p < d + l (the roller reaches the prime circle), and psi0 + s must stay
  in (0, pi) (the arm never lies on the line of centres).
- Flat face: a line at distance f (``face_offset_mm``) from the pivot, parallel to the arm
  direction u and on the cam's side of it: {X : m . X = p}, m(psi) = (sin psi, cos psi) its unit
  normal pointing away from the cam, p(psi) = d sin psi - f its distance from O. The base radius
  is R_b = p(psi0), sin psi0 = (R_b + f) / d; a rise lifts the face while psi < pi/2 (p grows),
  so psi0 + s must stay in (0, pi/2).

Kinematic inversion. The cam frame turns with the cam as in :mod:`camjax.geometry.pitch`: a
follower-frame point x appears at P = R(-sigma theta) x in cam coordinates (sigma = +1 ccw, -1
cw; :func:`camjax.geometry.pitch.to_cam_frame`). The same physical layout serves both rotations;
the rotation enters every closed form below only through Q = 1 + sigma s', the rate at which the
arm turns relative to the cam (per rad of cam angle).

Roller closed forms (derived in :func:`oscillating_roller_tangent` and
:func:`oscillating_roller_pitch_curvature`), c = cos psi, sn = sin psi:

- pitch-curve tangent, follower-frame components: T = s' C_psi - sigma J C, |T|^2 = l^2 Q^2 -
  2 d l c Q + d^2 (J = rotation by +90 deg, C_psi = dC/dpsi = (l sn, l c));
- pressure angle: tan phi = (l Q - d c) / (d sn);
- pitch curvature (convex > 0): kappa = [l^2 Q^3 - d l c Q (Q + 1) + d^2 - d l sn s''] / |T|^3.

Flat-face closed forms (:func:`oscillating_flat_radius_of_curvature`): the cam outline is the
envelope of the face lines, radius of curvature rho = d sn (1 - s'^2/Q^2) - f + d c s''/Q^3;
the contact point lies on the face at xi = d c / Q from the foot of the pivot (towards the cam
centre), and the follower's pressure angle is tan phi = f / xi.

All lengths mm, angles rad; elementwise over the angle grid and jit/vmap/grad-safe, with
finite values and gradients for infeasible trial designs (capped or floored divisions).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.geometry import pitch
from camjax.geometry.pitch import DEFAULT_ROTATION, rotation_sign
from camjax.numerics import capped_divide, safe_sqrt
from camjax.program import Kinematics

# Default smallest admissible radius of curvature of an oscillating flat-face cam (mm), as for
# the translating flat face (camjax.geometry.flat.FLAT_MIN_CURVATURE_RADIUS_MM).
OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM = 1e-3
# Arm start angles scanned by the sizing functions before the bisection (see _first_admissible).
SIZING_SCAN = 2048
SIZING_BISECTIONS = 80
SIZING_BATCH_VALUES = 1 << 22  # arm angles x samples evaluated at once by the scan (~32 MB of float64)


# ----------------------------------------------------------------------------- layout


def relative_rate(kin: Kinematics, rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Q = 1 + sigma s' (rad/rad): the arm's turning rate relative to the cam, per rad of cam angle.

    In the cam frame the follower frame turns at +sigma per rad of cam angle (P = R(-sigma theta)
    x), so an arm at psi(theta) = psi0 + s turns at s' + sigma relative to the cam, sigma Q.
    """
    return 1.0 + rotation_sign(rotation) * kin.ds


def arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm) -> jax.Array:
    """psi0 (rad) that puts the roller centre on the prime circle: cos psi0 = (d^2 + l^2 - R_p^2)/(2dl).

    Clipped to [0, pi] where the geometry cannot close (|d - l| >= R_p or R_p >= d + l; the scene
    refuses such designs, :func:`oscillating_roller_reach_constraint` measures them).
    """
    d, l = pivot_distance_mm, arm_length_mm
    c = (d**2 + l**2 - prime_radius_mm**2) / (2.0 * d * l)
    # the clip is strict so that arccos keeps a finite gradient
    return jnp.arccos(jnp.clip(c, -1.0 + 1e-15, 1.0 - 1e-15))


def roller_centre(pivot_distance_mm, arm_length_mm, psi) -> tuple[jax.Array, jax.Array]:
    """Roller centre C = (d - l cos psi, l sin psi) in the follower frame, mm."""
    return pivot_distance_mm - arm_length_mm * jnp.cos(psi), arm_length_mm * jnp.sin(psi)


def roller_centre_distance(pivot_distance_mm, arm_length_mm, psi) -> jax.Array:
    """|C| = sqrt(d^2 + l^2 - 2 d l cos psi) (mm), the roller centre's distance from the cam centre."""
    d, l = pivot_distance_mm, arm_length_mm
    return safe_sqrt(d**2 + l**2 - 2.0 * d * l * jnp.cos(psi))


def face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm) -> jax.Array:
    """psi0 (rad) of a flat face tangent to the base circle: sin psi0 = (R_b + f) / d, psi0 < pi/2."""
    r = (base_radius_mm + face_offset_mm) / pivot_distance_mm
    return jnp.arcsin(jnp.clip(r, -1.0 + 1e-15, 1.0 - 1e-15))


def arm_angle(psi0, kin: Kinematics) -> jax.Array:
    """psi = psi0 + s (rad) at every sample."""
    return psi0 + kin.s


# ----------------------------------------------------------------------------- roller


class OscillatingRollerGeometry(NamedTuple):
    """Oscillating roller follower, per sample (shape (N,) each)."""

    arm_angle: jax.Array  # psi, rad, from the line of centres
    pressure_angle: jax.Array  # rad
    pitch_curvature: jax.Array  # 1/mm, signed: > 0 convex
    pitch_radius_of_curvature: jax.Array  # mm, 1 / pitch_curvature (saturated at inflections)
    cam_radius_of_curvature: jax.Array  # rho_c = rho_pitch - R_f, mm (convex > 0)
    undercut_margin: jax.Array  # mm, rho_c - min radius where convex, float max where concave


def oscillating_roller_tangent(pivot_distance_mm, arm_length_mm, psi0, kin: Kinematics,
                               rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Tangent dP/dtheta of the pitch curve, in follower-frame components T = (T_x, T_y), mm/rad.

    Derivation: P(theta) = R(-sigma theta) C(psi(theta)) and d/dtheta R(-sigma theta) =
    R(-sigma theta) (-sigma J), so dP/dtheta = R(-sigma theta) T with
    T = s' C_psi - sigma J C = (l sn (s' + sigma), l c (s' + sigma) - sigma d)
      = sigma (l sn Q, l c Q - d),  Q = 1 + sigma s'.
    A rotation keeps lengths and angles, so |T| and every angle are the cam frame's.
    """
    d, l, sigma = pivot_distance_mm, arm_length_mm, rotation_sign(rotation)
    psi = arm_angle(psi0, kin)
    q = relative_rate(kin, rotation)
    return sigma * l * jnp.sin(psi) * q, sigma * (l * jnp.cos(psi) * q - d)


def oscillating_roller_pressure_angle(pivot_distance_mm, arm_length_mm, psi0, kin: Kinematics,
                                      rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """phi (rad): the angle between the contact normal and the roller centre's path.

    tan phi = (l Q - d cos psi) / (d sin psi), Q = 1 + sigma s'. Derivation: the normal force on
    the roller points along n = sigma J T / |T| (outward from the cam), and the roller centre
    moves along C_psi / l (perpendicular to the arm). With T from
    :func:`oscillating_roller_tangent`: n . C_psi / l = d sn / |T| (= cos phi, > 0: the cam
    pushes the arm towards larger psi) and n . (C - A) / l = (l Q - d c) / |T| (= sin phi, the
    part along the arm: > 0 pulls the arm away from the pivot). At a dwell (Q = 1) this is the
    angle between the radius OC and the path, tan phi = (l - d c) / (d sn); for a cw cam
    (Q = 1 - s') it is the textbook (d c - l (1 - psi')) / (d sn) up to sign.
    """
    d, l = pivot_distance_mm, arm_length_mm
    psi = arm_angle(psi0, kin)
    q = relative_rate(kin, rotation)
    return jnp.arctan2(l * q - d * jnp.cos(psi), d * jnp.sin(psi))


def oscillating_roller_pitch_curvature(pivot_distance_mm, arm_length_mm, psi0, kin: Kinematics,
                                       rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Signed curvature (1/mm, convex > 0) of the pitch curve.

    kappa = [l^2 Q^3 - d l c Q (Q + 1) + d^2 - d l sn s''] / (l^2 Q^2 - 2 d l c Q + d^2)^(3/2).

    Derivation: d^2P/dtheta^2 = R(-sigma theta) (T' - sigma J T), T' the derivative of T's
    components, T' = s'' C_psi + s'^2 C_psipsi - sigma s' J C_psi with C_psipsi = (l c, -l sn) and
    J C_psi = C - A. The curve turns towards the cam centre (convex) with curvature
    -sigma (T x P'') / |T|^3 = (|T|^2 - sigma T x T') / |T|^3 (T x J T = |T|^2). Expanding,
    T x T' = -l^2 s' q^2 + sigma d l (sn s'' + c s' q) with q = s' + sigma = sigma Q, which gives
    the numerator above. A circle (s' = s'' = 0) gives 1/|C|.
    """
    return swing_pitch_curvature(pivot_distance_mm, arm_length_mm, arm_angle(psi0, kin),
                                 relative_rate(kin, rotation), kin.d2s)


def swing_pitch_curvature(pivot_distance_mm, arm_length_mm, psi, rate, d2s) -> jax.Array:
    """The closed form of :func:`oscillating_roller_pitch_curvature` in the arm angle psi (rad), the
    relative rate Q = 1 + sigma s' and s'' (rad/rad^2): for callers that hold sigma as data."""
    d, l, q = pivot_distance_mm, arm_length_mm, rate
    c, sn = jnp.cos(psi), jnp.sin(psi)
    num = l**2 * q**3 - d * l * c * q * (q + 1.0) + d**2 - d * l * sn * d2s
    den = (l**2 * q**2 - 2.0 * d * l * c * q + d**2) ** 1.5
    return capped_divide(num, den)


def oscillating_roller_geometry(pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm,
                                kin: Kinematics, rotation: str = DEFAULT_ROTATION,
                                min_curvature_radius_mm=0.0) -> OscillatingRollerGeometry:
    """Arm angle, pressure angle, pitch and cam-surface curvature and undercut margin per sample.

    The cam surface is the pitch curve offset inward by R_f (SPEC 3): rho_c = rho_pitch - R_f, and
    the undercut test is the translating roller's (:func:`camjax.geometry.roller_undercut_margin`).
    """
    from camjax.geometry.roller import roller_undercut_margin

    psi0 = arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    phi = oscillating_roller_pressure_angle(pivot_distance_mm, arm_length_mm, psi0, kin, rotation)
    kappa = oscillating_roller_pitch_curvature(pivot_distance_mm, arm_length_mm, psi0, kin, rotation)
    rho = pitch.radius_of_curvature(kappa)
    rho_c = jnp.where(jnp.abs(rho) < jnp.finfo(rho.dtype).max, rho - roller_radius_mm, rho)
    margin = roller_undercut_margin(kappa, roller_radius_mm, min_curvature_radius_mm)
    return OscillatingRollerGeometry(arm_angle(psi0, kin), phi, kappa, rho, rho_c, margin)


def oscillating_roller_pitch_curve(pivot_distance_mm, arm_length_mm, prime_radius_mm, kin: Kinematics,
                                   rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Pitch curve (X, Y), mm, cam coordinates: the roller centre seen from the cam."""
    psi0 = arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    x, y = roller_centre(pivot_distance_mm, arm_length_mm, arm_angle(psi0, kin))
    return pitch.to_cam_frame(x, y, kin.theta, rotation)


def oscillating_roller_profile(pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm,
                               kin: Kinematics,
                               rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y), mm: the pitch curve moved towards the cam centre by R_f.

    The inward unit normal is -sigma J T / |T| in follower-frame components (on a dwell,
    T = -sigma J C and it is -C/|C|).
    """
    sigma = rotation_sign(rotation)
    psi0 = arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    tx, ty = oscillating_roller_tangent(pivot_distance_mm, arm_length_mm, psi0, kin, rotation)
    inv = capped_divide(jnp.ones_like(tx), safe_sqrt(tx**2 + ty**2))
    nx, ny = sigma * ty * inv, -sigma * tx * inv  # -sigma J T / |T|, J T = (-T_y, T_x)
    x, y = roller_centre(pivot_distance_mm, arm_length_mm, arm_angle(psi0, kin))
    return pitch.to_cam_frame(x + roller_radius_mm * nx, y + roller_radius_mm * ny, kin.theta, rotation)


def oscillating_roller_reach_constraint(prime_radius_mm, pivot_distance_mm, arm_length_mm) -> jax.Array:
    """g = max(|d - l| - R_p, R_p - (d + l)) (mm); g < 0 when the roller can reach the prime circle."""
    d, l = pivot_distance_mm, arm_length_mm
    return jnp.maximum(jnp.abs(d - l) - prime_radius_mm, prime_radius_mm - (d + l))


# --------------------------------------------------------------------------- flat face


class OscillatingFlatGeometry(NamedTuple):
    """Oscillating flat-face follower, per sample (shape (N,) each)."""

    arm_angle: jax.Array  # psi, rad
    radius_of_curvature: jax.Array  # rho of the cam outline, mm (must stay > 0)
    contact_distance: jax.Array  # xi, mm along the face from the foot of the pivot (> 0: cam side)
    pressure_angle: jax.Array  # rad, atan(f / xi)


def oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin: Kinematics,
                                      rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """xi = d cos psi / Q (mm): the contact point's distance along the face from the pivot's foot.

    Derivation: with alpha the polar angle of the face normal m in the cam frame,
    alpha = pi/2 - psi - sigma theta, so dalpha/dtheta = -sigma Q. The envelope of the lines
    m(alpha) . X = p touches each line at X = p m + (dp/dalpha) J m, J m = u, and
    dp/dalpha = (d c s') / (-sigma Q). The foot of the pivot on the face, A - f m, sits at
    coordinate A . u = -d c along u, so the contact point lies at dp/dalpha + d c
    = d c (1 - sigma s'/Q) = d c / Q from it (Q - sigma s' = 1), positive towards the cam centre.
    """
    psi = arm_angle(psi0, kin)
    q = relative_rate(kin, rotation)
    return capped_divide(pivot_distance_mm * jnp.cos(psi), q)


def oscillating_flat_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi0, kin: Kinematics,
                                         rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """rho = d sn (1 - s'^2/Q^2) - f + d c s''/Q^3 (mm), the cam outline's radius of curvature.

    Derivation: the envelope of lines with support function p(alpha) has radius p + d^2p/dalpha^2.
    With p = d sn - f, dp/dalpha = -sigma d c s'/Q (see :func:`oscillating_flat_contact_distance`)
    and d/dalpha = (-sigma / Q) d/dtheta: d^2p/dalpha^2 = (1/Q) d/dtheta (d c s'/Q)
    = d [Q (c s'' - sn s'^2) - sigma c s' s''] / Q^3 = d (c s'' - sn s'^2 Q) / Q^3,
    using Q - sigma s' = 1. A dwell gives rho = p, the base circle.
    """
    return swing_face_radius_of_curvature(pivot_distance_mm, face_offset_mm, arm_angle(psi0, kin),
                                          relative_rate(kin, rotation), kin.ds, kin.d2s)


def swing_face_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi, rate, ds, d2s) -> jax.Array:
    """The closed form of :func:`oscillating_flat_radius_of_curvature` in the arm angle psi (rad),
    Q = 1 + sigma s', s' and s'': for callers that hold sigma as data."""
    d, f = pivot_distance_mm, face_offset_mm
    c, sn = jnp.cos(psi), jnp.sin(psi)
    inv_q = capped_divide(jnp.ones_like(rate), rate)
    return d * sn * (1.0 - (ds * inv_q) ** 2) - f + d * c * d2s * inv_q**3


def oscillating_flat_geometry(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                              rotation: str = DEFAULT_ROTATION) -> OscillatingFlatGeometry:
    """Arm angle, radius of curvature, contact distance and pressure angle per sample.

    The pressure angle is the angle between the face normal m and the path of the follower point
    in contact, perpendicular to A -> contact = -f m + xi u: cos phi = |xi| / sqrt(f^2 + xi^2),
    tan phi = f / xi (0 for a face through the pivot).
    """
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    rho = oscillating_flat_radius_of_curvature(pivot_distance_mm, face_offset_mm, psi0, kin, rotation)
    return OscillatingFlatGeometry(arm_angle(psi0, kin), rho, xi, jnp.arctan2(face_offset_mm, xi))


def oscillating_flat_contact_point(pivot_distance_mm, face_offset_mm, psi0, kin: Kinematics,
                                   rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Contact point A - f m + xi u in the follower frame (mm), u = (-c, sn), m = (sn, c)."""
    psi = arm_angle(psi0, kin)
    c, sn = jnp.cos(psi), jnp.sin(psi)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    return pivot_distance_mm - face_offset_mm * sn - xi * c, -face_offset_mm * c + xi * sn


def oscillating_flat_profile(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                             rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """Cam outline (X, Y), mm, cam coordinates: the contact point seen from the cam."""
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    x, y = oscillating_flat_contact_point(pivot_distance_mm, face_offset_mm, psi0, kin, rotation)
    return pitch.to_cam_frame(x, y, kin.theta, rotation)


def oscillating_flat_face_extent(pivot_distance_mm, face_offset_mm, base_radius_mm, kin: Kinematics,
                                 rotation: str = DEFAULT_ROTATION) -> tuple[jax.Array, jax.Array]:
    """(min xi, max xi) (mm): the stretch of the face, from the pivot's foot, the contact sweeps.

    The face length needed is max xi - min xi (a face reaching from min xi to max xi).
    """
    psi0 = face_start_angle(base_radius_mm, pivot_distance_mm, face_offset_mm)
    xi = oscillating_flat_contact_distance(pivot_distance_mm, psi0, kin, rotation)
    return jnp.min(xi), jnp.max(xi)


# ------------------------------------------------------------------------------ sizing


def _first_admissible(bad, lo, hi, samples: int, scan: int = SIZING_SCAN,
                      bisections: int = SIZING_BISECTIONS):
    """Smallest x in (lo, hi) with bad(x) False: a scan of ``scan`` points, then a bisection.

    The scan finds the first admissible grid point x_k; bisecting [x_{k-1}, x_k] moves to the
    boundary (80 halvings: below float64 resolution for brackets < 1e5). Returns (x, found);
    x = hi where nothing on the scan is admissible. ``bad`` maps one x (shape ()) to a bool over
    the whole grid of ``samples`` angles; the scan evaluates it in batches of ~SIZING_BATCH_VALUES
    / samples points, so memory stays bounded on dense grids. jit/vmap-safe; not differentiable
    (a search), nor meant to be.
    """
    xs = lo + (hi - lo) * (jnp.arange(1, scan + 1) / (scan + 1))
    ok = ~jax.lax.map(bad, xs, batch_size=max(1, min(scan, SIZING_BATCH_VALUES // max(samples, 1))))
    found = jnp.any(ok)
    k = jnp.argmax(ok)
    a = jnp.where(k > 0, xs[jnp.maximum(k - 1, 0)], lo)
    b = xs[k]

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        is_bad = bad(m)
        return jnp.where(is_bad, m, a), jnp.where(is_bad, b, m)

    a, b = jax.lax.fori_loop(0, bisections, halve, (a, b))
    return jnp.where(found, b, hi), found


class OscillatingRollerSizing(NamedTuple):
    """Smallest admissible prime circle of an oscillating roller follower with d and l given."""

    prime_radius_mm: jax.Array  # R_p, mm (the largest reachable where nothing is admissible)
    base_radius_mm: jax.Array  # R_p - R_f, mm
    arm_start_angle: jax.Array  # psi0, rad
    found: jax.Array  # bool: an admissible prime radius exists
    undercut_binds: jax.Array  # bool: undercut (else the pressure angle) sets R_p
    index: jax.Array  # int: the sample where the binding limit is reached


def oscillating_roller_min_prime_radius(kin: Kinematics, pivot_distance_mm, arm_length_mm, roller_radius_mm,
                                        max_pressure_angle_rad, min_curvature_radius_mm=0.0,
                                        rotation: str = DEFAULT_ROTATION) -> OscillatingRollerSizing:
    """Smallest R_p (mm) with |phi| <= the limit and no undercut at every sample, d and l given.

    R_p = |C(psi0)| grows with psi0 on (0, pi), so the search runs over psi0 in
    (0, pi - max s) (the arm stays off the line of centres): |phi| -> 90 deg at both ends, the
    admissible psi0 lie in between, and the first one is found by :func:`_first_admissible`.
    """
    d, l = pivot_distance_mm, arm_length_mm
    reach = roller_radius_mm + min_curvature_radius_mm
    tan_lim = jnp.tan(max_pressure_angle_rad)

    def bad_one(psi0):
        psi = psi0 + kin.s
        q = relative_rate(kin, rotation)
        # |phi| <= lim written without the arctan: |l Q - d c| <= tan(lim) d sn (sn > 0 here)
        phi_bad = jnp.abs(l * q - d * jnp.cos(psi)) > tan_lim * d * jnp.sin(psi)
        kappa = oscillating_roller_pitch_curvature(d, l, psi0, kin, rotation)
        return jnp.any(phi_bad | (kappa * reach > 1.0))

    psi_hi = math.pi - jnp.max(kin.s)
    psi0, found = _first_admissible(bad_one, jnp.zeros_like(psi_hi), psi_hi, kin.s.shape[-1])
    rp = roller_centre_distance(d, l, psi0)
    kappa = oscillating_roller_pitch_curvature(d, l, psi0, kin, rotation)
    phi = oscillating_roller_pressure_angle(d, l, psi0, kin, rotation)
    undercut = jnp.max(kappa) * reach >= jnp.max(jnp.abs(jnp.tan(phi))) / tan_lim
    index = jnp.where(undercut, jnp.argmax(kappa), jnp.argmax(jnp.abs(phi)))
    return OscillatingRollerSizing(rp, rp - roller_radius_mm, psi0, found, undercut, index)


class OscillatingFlatSizing(NamedTuple):
    """Smallest admissible base circle of an oscillating flat-face follower with d and f given."""

    base_radius_mm: jax.Array  # R_b, mm
    arm_start_angle: jax.Array  # psi0, rad
    found: jax.Array  # bool
    index: jax.Array  # int: the sample where rho is smallest at that radius
    face_min_mm: jax.Array  # min xi, mm from the pivot's foot
    face_max_mm: jax.Array  # max xi, mm
    face_length_mm: jax.Array  # max xi - min xi


def oscillating_flat_min_base_radius(kin: Kinematics, pivot_distance_mm, face_offset_mm,
                                     min_curvature_radius_mm=OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM,
                                     rotation: str = DEFAULT_ROTATION) -> OscillatingFlatSizing:
    """Smallest R_b (mm) with rho >= rho_min and R_b > 0, and the face the contact needs there.

    R_b = d sin psi0 - f grows with psi0 on (0, pi/2); the search runs over psi0 in
    (0, pi/2 - max s) (the face keeps rising), by :func:`_first_admissible`.
    """
    d, f = pivot_distance_mm, face_offset_mm

    def bad_one(psi0):
        rho = oscillating_flat_radius_of_curvature(d, f, psi0, kin, rotation)
        return (jnp.min(rho) < min_curvature_radius_mm) | (d * jnp.sin(psi0) - f <= 0.0)

    psi_hi = 0.5 * math.pi - jnp.max(kin.s)
    psi0, found = _first_admissible(bad_one, jnp.zeros_like(psi_hi), psi_hi, kin.s.shape[-1])
    rb = d * jnp.sin(psi0) - f
    rho = oscillating_flat_radius_of_curvature(d, f, psi0, kin, rotation)
    xi = oscillating_flat_contact_distance(d, psi0, kin, rotation)
    lo, hi = jnp.min(xi), jnp.max(xi)
    return OscillatingFlatSizing(rb, psi0, found, jnp.argmin(rho), lo, hi, hi - lo)


__all__ = [
    "OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM", "OscillatingFlatGeometry", "OscillatingFlatSizing",
    "OscillatingRollerGeometry", "OscillatingRollerSizing", "arm_angle", "arm_start_angle",
    "face_start_angle", "oscillating_flat_contact_distance", "oscillating_flat_contact_point",
    "oscillating_flat_face_extent", "oscillating_flat_geometry", "oscillating_flat_min_base_radius",
    "oscillating_flat_profile", "oscillating_flat_radius_of_curvature", "oscillating_roller_geometry",
    "oscillating_roller_min_prime_radius", "oscillating_roller_pitch_curvature",
    "oscillating_roller_pitch_curve", "oscillating_roller_pressure_angle", "oscillating_roller_profile",
    "oscillating_roller_reach_constraint", "oscillating_roller_tangent", "relative_rate",
    "roller_centre", "roller_centre_distance", "swing_face_radius_of_curvature",
    "swing_pitch_curvature",
]
