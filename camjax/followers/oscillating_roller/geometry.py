"""Oscillating (rocker) roller follower (SPEC section 3): one design, any grid.

Layout and kinematic inversion: :mod:`camjax.followers._swing`. The roller's centre is
C(psi) = A + l u = (d - l cos psi, l sin psi) at arm length l, so |C|^2 = d^2 + l^2 - 2 d l cos psi
grows with psi on (0, pi): a rise swings the roller away from the cam centre. The prime radius is
R_p = |C(psi0)|, cos psi0 = (d^2 + l^2 - R_p^2) / (2 d l), which needs |d - l| < R_p < d + l (the
roller reaches the prime circle), and psi0 + s must stay in (0, pi) (the arm never lies on the line
of centres).

Closed forms (derived in :func:`oscillating_roller_tangent` and
:func:`oscillating_roller_pitch_curvature`), c = cos psi, sn = sin psi, Q = 1 + sigma s':

- pitch-curve tangent, follower-frame components: T = s' C_psi - sigma J C, |T|^2 = l^2 Q^2 -
  2 d l c Q + d^2 (J = rotation by +90 deg, C_psi = dC/dpsi = (l sn, l c));
- pressure angle: tan phi = (l Q - d c) / (d sn);
- pitch curvature (convex > 0): kappa = [l^2 Q^3 - d l c Q (Q + 1) + d^2 - d l sn s''] / |T|^3.

All lengths mm, angles rad; elementwise over the angle grid and jit/vmap/grad-safe, with
finite values and gradients for infeasible trial designs (capped or floored divisions).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers import _pitch as pitch
from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign
from camjax.followers._swing import ArmTrig, arm_angle, arm_trig, first_admissible, of_angle, relative_rate
from camjax.numerics import capped_divide, safe_sqrt
from camjax.program import Kinematics


def arm_start_angle(prime_radius_mm, pivot_distance_mm, arm_length_mm) -> jax.Array:
    """psi0 (rad) that puts the roller centre on the prime circle: cos psi0 = (d^2 + l^2 - R_p^2)/(2dl).

    Clipped to [0, pi] where the geometry cannot close (|d - l| >= R_p or R_p >= d + l; the scene
    refuses such designs, :func:`oscillating_roller_reach_constraint` measures them).
    """
    return jnp.arccos(arm_start_cosine(prime_radius_mm, pivot_distance_mm, arm_length_mm))


def arm_start_cosine(prime_radius_mm, pivot_distance_mm, arm_length_mm) -> jax.Array:
    """cos psi0 = (d^2 + l^2 - R_p^2)/(2dl), clipped strictly inside [-1, 1] (as :func:`arm_start_angle`)."""
    d, l = pivot_distance_mm, arm_length_mm
    c = (d**2 + l**2 - prime_radius_mm**2) / (2.0 * d * l)
    # the clip is strict so that arccos (and sin psi0 = sqrt(1 - c^2)) keeps a finite gradient
    return jnp.clip(c, -1.0 + 1e-15, 1.0 - 1e-15)


def arm_trig_of(prime_radius_mm, pivot_distance_mm, arm_length_mm, s_rad) -> ArmTrig:
    """cos psi and sin psi at every sample (psi = psi0 + s, psi0 of :func:`arm_start_angle`: in
    (0, pi), so sin psi0 = sqrt(1 - cos^2 psi0)), without a trigonometric function of the design
    (:func:`camjax.followers._swing.arm_trig`)."""
    c0 = arm_start_cosine(prime_radius_mm, pivot_distance_mm, arm_length_mm)
    return arm_trig(c0, jnp.sqrt(1.0 - c0 * c0), s_rad)


def roller_centre(pivot_distance_mm, arm_length_mm, psi) -> tuple[jax.Array, jax.Array]:
    """Roller centre C = (d - l cos psi, l sin psi) in the follower frame, mm."""
    return pivot_distance_mm - arm_length_mm * jnp.cos(psi), arm_length_mm * jnp.sin(psi)


def roller_centre_distance(pivot_distance_mm, arm_length_mm, psi) -> jax.Array:
    """|C| = sqrt(d^2 + l^2 - 2 d l cos psi) (mm), the roller centre's distance from the cam centre."""
    d, l = pivot_distance_mm, arm_length_mm
    return safe_sqrt(d**2 + l**2 - 2.0 * d * l * jnp.cos(psi))


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
    return arm_pitch_curvature(pivot_distance_mm, arm_length_mm, of_angle(psi), rate, d2s)


def arm_pitch_curvature(pivot_distance_mm, arm_length_mm, arm: ArmTrig, rate, d2s) -> jax.Array:
    """:func:`swing_pitch_curvature` in cos psi and sin psi (``arm``)."""
    d, l, q = pivot_distance_mm, arm_length_mm, rate
    c, sn = arm
    num = l**2 * q**3 - d * l * c * q * (q + 1.0) + d**2 - d * l * sn * d2s
    den = (l**2 * q**2 - 2.0 * d * l * c * q + d**2) ** 1.5
    return capped_divide(num, den)


def oscillating_roller_geometry(pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm,
                                kin: Kinematics, rotation: str = DEFAULT_ROTATION,
                                min_curvature_radius_mm=0.0) -> OscillatingRollerGeometry:
    """Arm angle, pressure angle, pitch and cam-surface curvature and undercut margin per sample.

    The cam surface is the pitch curve offset inward by R_f (SPEC 3): rho_c = rho_pitch - R_f, and
    the undercut test is the translating roller's (:func:`roller_geo.roller_undercut_margin`).
    """
    from camjax.followers.roller.geometry import roller_undercut_margin

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
    admissible psi0 lie in between, and the first one is found by :func:`first_admissible`.
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
    psi0, found = first_admissible(bad_one, jnp.zeros_like(psi_hi), psi_hi, kin.s.shape[-1])
    rp = roller_centre_distance(d, l, psi0)
    kappa = oscillating_roller_pitch_curvature(d, l, psi0, kin, rotation)
    phi = oscillating_roller_pressure_angle(d, l, psi0, kin, rotation)
    undercut = jnp.max(kappa) * reach >= jnp.max(jnp.abs(jnp.tan(phi))) / tan_lim
    index = jnp.where(undercut, jnp.argmax(kappa), jnp.argmax(jnp.abs(phi)))
    return OscillatingRollerSizing(rp, rp - roller_radius_mm, psi0, found, undercut, index)


def sizing_limits(kin: Kinematics, psi0, params) -> jax.Array:
    """The sizing's two limits at arm start angle psi0 (rad), <= 0 where admissible (shape
    (2, *kin.s.shape)): |phi| <= lim written without the arctan and scaled by d,
    |l Q - d c| / d - tan(lim) sn, and the undercut, kappa (R_f + rho_min) - 1. ``params``:
    (d, l, sigma, tan(lim), R_f + rho_min), arrays (the exact sizing,
    :func:`camjax.followers._sizing.exact_boundary`)."""
    d, l, sigma, tan_lim, reach = params
    psi = psi0 + kin.s
    q = 1.0 + sigma * kin.ds
    phi = jnp.abs(l * q - d * jnp.cos(psi)) / d - tan_lim * jnp.sin(psi)
    kappa = swing_pitch_curvature(d, l, psi, q, kin.d2s)
    return jnp.stack([phi, kappa * reach - 1.0])

