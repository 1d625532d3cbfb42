"""Kinetostatic loads on the cam and in the follower guide (SPEC section 4).

SI inside: masses kg, springs N/m, lengths m, forces N, torques N m.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.numerics import COS_FLOOR, capped_divide, floor_positive
from camjax.program import TimeKinematics


class FollowerTrain(NamedTuple):
    """Lumped follower train of a translating follower."""

    mass_kg: float = 0.0
    spring_N_per_m: float = 0.0
    preload_mm: float = 0.0  # spring compression at s = 0
    damping_Ns_per_m: float = 0.0
    gravity_m_s2: float = 9.81


class ForceParts(NamedTuple):
    """The terms of the kinetostatic contact force, N, each with the shape of the motion arrays."""

    inertia: jax.Array  # m y''
    damping: jax.Array  # c y'
    spring: jax.Array  # k (y + x0)
    gravity: jax.Array  # m g, constant over the cycle


def force_parts(train: FollowerTrain, motion: TimeKinematics) -> ForceParts:
    """Inertia, damping, spring and gravity terms of F (N); plain arithmetic, so NumPy arrays in
    give NumPy arrays out (the figures draw them without a JAX dispatch)."""
    return ForceParts(
        train.mass_kg * motion.accel,
        train.damping_Ns_per_m * motion.velocity,
        train.spring_N_per_m * (motion.y + train.preload_mm * 1e-3),
        train.mass_kg * train.gravity_m_s2 + 0.0 * motion.y,
    )


def kinetostatic_force(train: FollowerTrain, motion: TimeKinematics) -> jax.Array:
    """Cam-follower contact force F = m y'' + c y' + k (y + x0) + m g, N (< 0: contact lost)."""
    p = force_parts(train, motion)
    return p.inertia + p.damping + p.spring + p.gravity


def cam_torque(force_N: jax.Array, ds_mm_per_rad: jax.Array) -> jax.Array:
    """Torque on the cam shaft from the power balance T w = F y', i.e. T = F s' (N m).

    Written with s' (mm/rad) rather than y'/w so that it holds at rest and has no 1/w in its
    gradient at vanishing speed.
    """
    return force_N * ds_mm_per_rad * 1e-3


class RockerTrain(NamedTuple):
    """Lumped follower train of an oscillating (rocker) follower, about its pivot (SI, rad)."""

    inertia_kg_m2: float = 0.0
    spring_N_m_per_rad: float = 0.0
    preload_rad: float = 0.0  # spring wind-up at s = 0
    damping_N_m_s_per_rad: float = 0.0


def rocker_torque(train: RockerTrain, kin, cam_speed_rad_s) -> jax.Array:
    """Torque the cam must apply to the arm about the pivot, M = I psi'' + c psi' + k (s + x0), N m.

    The kinetostatic balance of SPEC 4 turned about the pivot: psi' = s' omega, psi'' = s'' omega^2
    (s in rad, constant cam speed); M < 0 means the spring cannot hold the arm on the cam (contact lost).
    Positive M turns the arm towards larger psi (away from the cam).
    """
    w = cam_speed_rad_s
    return (train.inertia_kg_m2 * kin.d2s * w**2 + train.damping_N_m_s_per_rad * kin.ds * w
            + train.spring_N_m_per_rad * (kin.s + train.preload_rad))


def rocker_cam_torque(torque_Nm: jax.Array, ds_rad_per_rad: jax.Array) -> jax.Array:
    """Torque on the cam shaft from the power balance T w = M psi', i.e. T = M s' (N m)."""
    return torque_Nm * ds_rad_per_rad


def rocker_roller_contact_force(torque_Nm, arm_length_mm, pressure_angle_rad) -> jax.Array:
    """Normal contact force P = M / (l cos phi) (N) on an oscillating roller.

    The normal force acts through the roller centre at arm length l; only its part along the
    roller's path (perpendicular to the arm), P cos phi, has a moment about the pivot. cos phi is
    floored like :func:`normal_force`.
    """
    return normal_force(torque_Nm / (arm_length_mm * 1e-3), pressure_angle_rad)


def rocker_flat_contact_force(torque_Nm, contact_distance_mm) -> jax.Array:
    """Normal contact force P = M / xi (N) on an oscillating flat face.

    The force acts along the face normal at the contact point, xi along the face from the pivot's
    foot: its moment about the pivot is P xi (the face offset is parallel to the force and has no
    arm). Saturates (finite) where the contact reaches the pivot's foot (xi -> 0).
    """
    return capped_divide(torque_Nm, contact_distance_mm * 1e-3)


def normal_force(axial_force_N: jax.Array, pressure_angle_rad: jax.Array) -> jax.Array:
    """Normal contact force P = F / cos phi (N) of a roller, F along the follower's motion.

    cos phi is floored at :data:`camjax.numerics.COS_FLOOR` (phi -> 90 deg is a jammed
    follower): finite in value and gradient for every trial design.
    """
    return axial_force_N / floor_positive(jnp.cos(pressure_angle_rad), COS_FLOOR)


def contact_margin(force_N: jax.Array) -> jax.Array:
    """min over the cycle of the contact force (N): <= 0 means the follower jumps."""
    return jnp.min(force_N)


class Guide(NamedTuple):
    """Flat-face follower stem in its guide (Chen 1982)."""

    length_mm: float  # b
    cam_friction: float  # mu0, cam / face
    guide_friction: float  # mu, stem / guide
    overhang_ratio: float  # xi, guide length to overhang


class GuideReactions(NamedTuple):
    """Per sample, N."""

    cam_force: jax.Array  # F_c = b P / Gamma
    reaction_1: jax.Array  # N1
    reaction_2: jax.Array  # N2
    gamma: jax.Array  # Gamma, mm (> 0 while the follower is not jammed)


def guide_reactions(guide: Guide, load_N, contact_offset_mm) -> GuideReactions:
    """Chen's guide reactions, as corrected in the optimal-design thesis.

    Gamma = b + 2 mu a - mu mu0 b (1 + 2 xi), F_c = b P / Gamma,
    N1 = -[a - mu0 b (1 + xi)] P / Gamma, N2 = -(a - mu0 xi b) P / Gamma.
    Near Gamma = 0 (jamming) the forces are capped at a finite value rather than NaN.
    """
    b, mu0, mu, xi = guide.length_mm, guide.cam_friction, guide.guide_friction, guide.overhang_ratio
    a = contact_offset_mm
    gamma = b + 2.0 * mu * a - mu * mu0 * b * (1.0 + 2.0 * xi)
    inv = capped_divide(1.0, gamma)
    return GuideReactions(
        b * load_N * inv,
        -(a - mu0 * b * (1.0 + xi)) * load_N * inv,
        -(a - mu0 * xi * b) * load_N * inv,
        gamma,
    )


def jamming_limit_mm(guide: Guide) -> float:
    """Largest contact offset (mm) on the jamming side before the stem jams in its guide.

    Jamming is Gamma -> 0. With Gamma = b + 2 mu a - mu mu0 b (1 + 2 xi), Gamma > 0 holds while
    -a < b / (2 mu) - mu0 b (1 + 2 xi) / 2: the offset a < 0 (contact on the side where friction
    tilts the stem against the guide) is the one that can jam. The thesis prints the limit as
    b/(2 mu) - mu0 (1 + 2 xi)/2, which is dimensionally inconsistent (a length minus a pure
    number); the form here follows from its own corrected Gamma (README, "Physics choices").
    """
    b, mu0, mu, xi = guide.length_mm, guide.cam_friction, guide.guide_friction, guide.overhang_ratio
    if mu == 0:
        return float("inf")
    return b / (2.0 * mu) - mu0 * b * (1.0 + 2.0 * xi) / 2.0
