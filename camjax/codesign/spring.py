"""The follower's spring as a co-design variable: rate and preload with contact kept at an overspeed.

**Translating followers.** [synthesis] may give ``spring_N_per_m`` and ``preload_N`` (the spring
force at s = 0, N) as [low, high] ranges, and ``min_contact_force_N`` (F_min) and ``overspeed`` (a
factor on [motion] rpm). The contact force of the project's loads model
(:func:`camjax.loads.kinetostatic_force`, F = m y'' + c y' + k y + P + m g with P = k x0 the preload
force) must stay >= F_min at every angle at the overspeed omega_os:

    P >= P_min(k) = max_theta [F_min - F_0(theta; k, omega_os)],

F_0 the force with no preload. P enters F at every angle by the same amount, so the contact
stress (sqrt of F) at every angle, the design objective (alpha size + gamma peak stress) and the
stress constraint all grow with P for every geometry: the optimum over P is the least feasible
one, P = max(P_min(k), P_low), exactly (tests/test_codesign_spring.py checks the monotony). It is
eliminated in closed form; P_min(k) > P_high means no preload in the box keeps contact at this k
(the co-design counts it infeasible, +inf).

**Rockers** (a follower whose ``rocking`` is true: an arm about a pivot, s in rad): the same with
the moment about the pivot in place of the force. [synthesis] gives ``spring_N_m_per_rad`` (the
torsion spring's rate k, N m/rad), ``preload_N_m`` (its moment at s = 0, P = k x0 in N m, x0 the
wind-up in rad) and ``min_contact_torque_N_m`` (M_min). The moment the cam applies to the arm,
:func:`camjax.loads.rocker_torque` M = I psi'' + c psi' + k (s + x0) = M_0(theta; k, omega_os) + P,
must stay >= M_min at every angle at the overspeed, so P_min(k) = max_theta [M_min - M_0] in closed
form as above. The condition is on the moment, not the contact force: the force of a given moment
depends on the design's arm (a roller's P_c = M / (l cos phi), a flat face's P_c = M / xi), and a
margin on M keeps the least preload independent of the geometry. Both forces (and so the Hertz
stress, its coefficient C_M = 0.564 sqrt(M / (w K)), the objective and the stress constraint) grow
with M at every angle for every geometry, so P = max(P_min(k), P_low) is again the optimum over P,
exactly (tests/test_codesign_spring_rocker.py checks the monotony); M >= M_min > 0 also keeps every
contact force positive.

The rate is an outer variable beside the laws' coordinates, box-bounded by the transform
k(u) = exp(log k_lo + (log k_hi - log k_lo) sigmoid(u)): every u is inside the box, the gradient
finite everywhere (it vanishes towards the ends; the search starts inside). A fixed rate (low ==
high, or none given: the [follower]'s) is no variable.

Pure JAX functions of a :class:`SpringBox` (static NumPy floats); which train (translating or
rocker) is the box's :attr:`SpringBox.rocking`, from the follower's contract.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import loads, program
from camjax.program import Kinematics

PRELOAD_TOL = 1e-9  # N: P_min(k) above P_high by more than this is infeasible (rounding of the max)


class SpringUnits(NamedTuple):
    """The scene keys and units of one kind of spring (translating or rocker)."""

    rate: str  # [synthesis] key of the rate
    preload: str  # of the preload
    margin: str  # of the least contact load
    rate_unit: str
    load_unit: str  # of the preload and the contact load
    load: str  # words for the contact load
    train_rate: str  # the follower train's field of the rate
    train_keys: str  # the [follower] keys that give the train


TRANSLATING = SpringUnits("spring_N_per_m", "preload_N", "min_contact_force_N", "N/m", "N", "contact force",
                          "spring_N_per_m", "follower.mass_kg and follower.spring_N_per_m")
ROCKER = SpringUnits("spring_N_m_per_rad", "preload_N_m", "min_contact_torque_N_m", "N m/rad", "N m",
                     "contact torque about the pivot", "spring_N_m_per_rad",
                     "follower.inertia_kg_m2 and follower.spring_N_m_per_rad")


class SpringBox(NamedTuple):
    """The spring's bounds and contact condition of a co-design (SI: a translating follower's N/m, N;
    a rocker's N m/rad, N m; rad/s)."""

    rate: tuple[float, float]  # N/m, or N m/rad
    preload: tuple[float, float]  # N, the spring force at s = 0; or N m, its moment
    min_force: float  # N, the least contact force; or N m, the least moment about the pivot
    overspeed: float
    omega_os: float  # rad/s, the overspeed
    train: loads.FollowerTrain | loads.RockerTrain  # the scene's (mass, damping, ...; its spring replaced)
    rocking: bool = False  # a rocker's spring: a torsion spring about the pivot

    @property
    def free_rate(self) -> bool:
        return self.rate[1] > self.rate[0]

    @property
    def units(self) -> SpringUnits:
        return ROCKER if self.rocking else TRANSLATING

    @property
    def scene_rate(self) -> float:
        """The [follower] train's rate (N/m or N m/rad)."""
        return float(getattr(self.train, self.units.train_rate))


def spring_box(scene, error) -> SpringBox | None:
    """The scene's :class:`SpringBox`, None without [synthesis] spring keys. ``error(field, msg)``
    makes the exception for what the co-design cannot take (no follower train, no spring)."""
    from camjax import followers

    spec = scene.synthesis.spring if scene.synthesis is not None else None
    if spec is None:
        return None
    rocking = bool(followers.of(scene).rocking)
    units = ROCKER if rocking else TRANSLATING
    if rocking:
        given_rate, given_preload = spec.rate_N_m_per_rad, spec.preload_N_m
        margin = spec.min_contact_torque_N_m
    else:
        given_rate, given_preload, margin = spec.rate_N_per_m, spec.preload_N, spec.min_contact_force_N
    key = (units.rate if given_rate is not None else units.preload if given_preload is not None
           else units.margin if margin > 0 else "overspeed")
    key = f"synthesis.{key}"
    train = scene.follower.train
    if train is None:
        raise error(key, f"a designed spring needs the follower's loads (allowed: give {units.train_keys})")
    k0 = float(getattr(train, units.train_rate))
    rate = given_rate or (k0, k0)
    if rate[0] <= 0.0:
        raise error(f"follower.{units.train_rate}", f"{k0:g} {units.rate_unit}: the contact condition "
                    f"needs a spring (allowed: > 0, or synthesis.{units.rate} = [low, high])")
    p0 = k0 * (float(train.preload_rad) if rocking else float(train.preload_mm) * 1e-3)
    preload = given_preload or (p0, p0)
    omega = program.rpm_to_rad_s(scene.motion.rpm) * spec.overspeed
    return SpringBox(tuple(map(float, rate)), tuple(map(float, preload)), float(margin),
                     float(spec.overspeed), float(omega), train, rocking)


def rate_of(box: SpringBox, u) -> jax.Array:
    """k(u), N/m: inside [k_lo, k_hi] for every u (the box transform); k_lo for a fixed rate."""
    lo, hi = math.log(box.rate[0]), math.log(box.rate[1])
    if not box.free_rate:
        return jnp.asarray(box.rate[0])
    return jnp.exp(lo + (hi - lo) * jax.nn.sigmoid(u))


def u_of(box: SpringBox, k: float) -> float:
    """The u of rate k (clipped a little inside the box, where the transform's slope is not 0)."""
    if not box.free_rate:
        return 0.0
    lo, hi = math.log(box.rate[0]), math.log(box.rate[1])
    t = min(max((math.log(k) - lo) / (hi - lo), 1e-6), 1.0 - 1e-6)
    return float(math.log(t / (1.0 - t)))


def train_of(box: SpringBox, k, preload):
    """The scene's follower train with rate k and preload ``preload``: a translating follower's
    (N/m; the force P, N: x0 = P / k in mm) or a rocker's (N m/rad; the moment P, N m: x0 = P / k, rad)."""
    if box.rocking:
        return box.train._replace(spring_N_m_per_rad=k, preload_rad=preload / k)
    return box.train._replace(spring_N_per_m=k, preload_mm=1e3 * preload / k)


def contact_load(box: SpringBox, kin4, k, preload, omega=None) -> jax.Array:
    """The contact load at every sample of the kinematics ``kin4`` (4, n) at cam speed ``omega``
    (default the overspeed), by the project's loads model with the spring (k, P): a translating
    follower's contact force (N, :func:`camjax.loads.kinetostatic_force`), a rocker's moment about
    the pivot (N m, :func:`camjax.loads.rocker_torque`; s in rad)."""
    kin = Kinematics(jnp.zeros_like(kin4[0]), kin4[0], kin4[1], kin4[2], kin4[3])
    w = box.omega_os if omega is None else omega
    if box.rocking:
        return loads.rocker_torque(train_of(box, k, preload), kin, w)
    return loads.kinetostatic_force(train_of(box, k, preload), program.time_kinematics(kin, w))


def scene_load(box: SpringBox, scene, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(theta_deg, load): the contact load (as :func:`contact_load`: N, or a rocker's N m) of a scene
    with fixed laws at the box's overspeed on a grid of ``samples``, by the loads model of the scene's
    own follower train (what a design written from the scene has; Python, NumPy arrays)."""
    import dataclasses

    from camjax.evaluate import scene_arrays

    motion = dataclasses.replace(scene.motion, rpm=scene.motion.rpm * box.overspeed)
    fast = dataclasses.replace(scene, motion=motion)
    arrays = scene_arrays(fast, samples=samples, extrema="grid")
    load = (loads.rocker_torque(scene.follower.train, arrays.kin, arrays.cam_speed_rad_s) if box.rocking
            else arrays.force_N)
    return np.asarray(arrays.theta_deg), np.asarray(load)


def least_preload(box: SpringBox, kin4, k) -> jax.Array:
    """P_min(k) = max_theta [F_min - F_0(theta)] (N; a rocker's in N m, moments), F_0 the contact
    load at the overspeed without preload."""
    return jnp.max(box.min_force - contact_load(box, kin4, k, 0.0))


def preload_of(box: SpringBox, kin4, k) -> tuple[jax.Array, jax.Array]:
    """(P, P_min(k)): the optimal preload max(P_min, P_low) (N or N m) and the least one keeping contact."""
    need = least_preload(box, kin4, k)
    return jnp.maximum(need, box.preload[0]), need


def contact_deficit(box: SpringBox, kin4, rates=None) -> tuple[float, float, float]:
    """How far the box is from keeping contact on ``kin4``: min over the rates (default 33, geometric
    over the box) of P_min(k) - P_high (N or N m, <= 0: feasible), with the rate and the angle index
    where the least contact load is reached. Python (NumPy floats)."""
    if rates is None:
        rates = np.geomspace(box.rate[0], box.rate[1], 33) if box.free_rate else np.asarray([box.rate[0]])
    best = None
    for k in rates:
        f = np.asarray(contact_load(box, kin4, float(k), box.preload[1]))
        d = box.min_force - float(f.min())
        if best is None or d < best[0]:
            best = (d, float(k), int(np.argmin(f)))
    return best
