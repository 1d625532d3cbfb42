"""The follower's spring as a co-design variable: rate and preload with contact kept at an overspeed.

[synthesis] may give ``spring_N_per_m`` and ``preload_N`` (the spring force at s = 0, N) as
[low, high] ranges, and ``min_contact_force_N`` (F_min) and ``overspeed`` (a factor on [motion]
rpm). The contact force of the project's loads model (:func:`camjax.loads.kinetostatic_force`,
F = m y'' + c y' + k y + P + m g with P = k x0 the preload force) must stay >= F_min at every angle
at the overspeed omega_os:

    P >= P_min(k) = max_theta [F_min - F_0(theta; k, omega_os)],

F_0 the force with no preload. P enters F at every angle by the same amount, so the contact
stress (sqrt of F) at every angle, the design objective (alpha size + gamma peak stress) and the
stress constraint all grow with P for every geometry: the optimum over P is the least feasible
one, P = max(P_min(k), P_low), exactly (tests/test_codesign_spring.py checks the monotony). It is
eliminated in closed form; P_min(k) > P_high means no preload in the box keeps contact at this k
(the co-design counts it infeasible, +inf).

The rate is an outer variable beside the laws' coordinates, box-bounded by the transform
k(u) = exp(log k_lo + (log k_hi - log k_lo) sigmoid(u)): every u is inside the box, the gradient
finite everywhere (it vanishes towards the ends; the search starts inside). A fixed rate (low ==
high, or none given: the [follower]'s) is no variable.

Pure JAX functions of a :class:`SpringBox` (static NumPy floats).
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


class SpringBox(NamedTuple):
    """The spring's bounds and contact condition of a co-design (SI: N/m, N, rad/s)."""

    rate: tuple[float, float]  # N/m
    preload: tuple[float, float]  # N, the spring force at s = 0
    min_force: float  # N
    overspeed: float
    omega_os: float  # rad/s, the overspeed
    train: loads.FollowerTrain  # the scene's (mass, damping, gravity; its spring replaced)

    @property
    def free_rate(self) -> bool:
        return self.rate[1] > self.rate[0]


def spring_box(scene, error) -> SpringBox | None:
    """The scene's :class:`SpringBox`, None without [synthesis] spring keys. ``error(field, msg)``
    makes the exception for what the co-design cannot take (a rocker, no follower train)."""
    from camjax import followers

    spec = scene.synthesis.spring if scene.synthesis is not None else None
    if spec is None:
        return None
    key = ("synthesis.spring_N_per_m" if spec.rate_N_per_m is not None else "synthesis.preload_N"
           if spec.preload_N is not None else "synthesis.min_contact_force_N"
           if spec.min_contact_force_N > 0 else "synthesis.overspeed")
    if followers.of(scene).rocking:
        raise error(key, "a designed spring is supported for translating followers only (a rocker's "
                    "contact force depends on its arm: not yet)")
    train = scene.follower.train
    if train is None:
        raise error(key, "a designed spring needs the follower's loads (allowed: give follower.mass_kg "
                    "and follower.spring_N_per_m)")
    k0 = float(train.spring_N_per_m)
    rate = spec.rate_N_per_m or (k0, k0)
    if rate[0] <= 0.0:
        raise error("follower.spring_N_per_m", f"{k0:g} N/m: the contact condition needs a spring "
                    "(allowed: > 0, or synthesis.spring_N_per_m = [low, high])")
    p0 = k0 * float(train.preload_mm) * 1e-3
    preload = spec.preload_N or (p0, p0)
    omega = program.rpm_to_rad_s(scene.motion.rpm) * spec.overspeed
    return SpringBox(tuple(map(float, rate)), tuple(map(float, preload)), float(spec.min_contact_force_N),
                     float(spec.overspeed), float(omega), train)


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


def train_of(box: SpringBox, k, preload_N) -> loads.FollowerTrain:
    """The scene's follower train with rate k (N/m) and preload force ``preload_N`` (N): x0 = P / k."""
    return box.train._replace(spring_N_per_m=k, preload_mm=1e3 * preload_N / k)


def contact_force(box: SpringBox, kin4, k, preload_N, omega=None) -> jax.Array:
    """The contact force (N) at every sample of the kinematics ``kin4`` (4, n) at cam speed ``omega``
    (default the overspeed): the project's loads model with the spring (k, P)."""
    kin = Kinematics(jnp.zeros_like(kin4[0]), kin4[0], kin4[1], kin4[2], kin4[3])
    motion = program.time_kinematics(kin, box.omega_os if omega is None else omega)
    return loads.kinetostatic_force(train_of(box, k, preload_N), motion)


def least_preload(box: SpringBox, kin4, k) -> jax.Array:
    """P_min(k) = max_theta [F_min - F_0(theta)] (N), F_0 the force at the overspeed without preload."""
    return jnp.max(box.min_force - contact_force(box, kin4, k, 0.0))


def preload_of(box: SpringBox, kin4, k) -> tuple[jax.Array, jax.Array]:
    """(P, P_min(k)): the optimal preload max(P_min, P_low) (N) and the least one keeping contact."""
    need = least_preload(box, kin4, k)
    return jnp.maximum(need, box.preload[0]), need


def contact_deficit(box: SpringBox, kin4, rates=None) -> tuple[float, float, float]:
    """How far the box is from keeping contact on ``kin4``: min over the rates (default 33, geometric
    over the box) of P_min(k) - P_high (N, <= 0: feasible), with the rate and the angle index where
    the least contact force is reached. Python (NumPy floats)."""
    if rates is None:
        rates = np.geomspace(box.rate[0], box.rate[1], 33) if box.free_rate else np.asarray([box.rate[0]])
    best = None
    for k in rates:
        f = np.asarray(contact_force(box, kin4, float(k), box.preload[1]))
        d = box.min_force - float(f.min())
        if best is None or d < best[0]:
            best = (d, float(k), int(np.argmin(f)))
    return best
