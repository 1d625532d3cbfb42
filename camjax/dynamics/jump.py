"""Follower jump of a force-closed cam (SPEC 6): contact force in steady state, the lowest
speed at which contact is lost, and the smallest preload or spring rate that keeps it.

Forces in N (translating follower) or torques in N m (oscillating); speeds in rad/s.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax import runtime
from camjax.dynamics.harmonics import CamHarmonics, evaluate_cam
from camjax.dynamics.plant import Plant, natural_frequency_rad_s, steady_state


class ForceClosure(NamedTuple):
    """What keeps a force-closed follower on its cam (units of the follower kind, SI)."""

    follower_inertia: jax.Array  # I2 (kg or kg m^2)
    spring_rate: jax.Array  # k_s, N/m or N m/rad
    spring_preload: jax.Array  # x0, spring compression at theta2 = 0, m or rad
    follower_damping: jax.Array = 0.0  # c2 to ground, N s/m or N m s/rad
    weight: jax.Array = 0.0  # constant load pressing on the cam (m g, N; 0 for oscillating)


@jax.jit
def contact_force(cam: CamHarmonics, plant: Plant, closure: ForceClosure, cam_speed_rad_s,
                  phi: jax.Array) -> jax.Array:
    """Cam-follower contact force of the elastic model in steady state (N or N m), shape of phi.

    F = I2 theta2'' + c2 theta2' + k_s (theta2 + x0) + k23 (theta2 - theta3) + weight, with
    theta3 the steady-state load. F < 0: the cam would have to pull; the follower jumps.
    """
    w = cam_speed_rad_s
    v = evaluate_cam(cam, phi)
    load = evaluate_cam(steady_state(cam, plant, w), phi).f
    return (closure.follower_inertia * w**2 * v.d2f + closure.follower_damping * w * v.df
            + closure.spring_rate * (v.f + closure.spring_preload)
            + plant.stiffness * (v.f - load) + closure.weight)


@jax.jit
def min_contact_force(cam, plant, closure, cam_speed_rad_s, phi) -> jax.Array:
    """min over the grid ``phi`` of the contact force (N or N m): <= 0 means the follower jumps."""
    return jnp.min(contact_force(cam, plant, closure, cam_speed_rad_s, phi))


class JumpSpeed(NamedTuple):
    """Lowest cam speed at which contact is lost, or why there is none.

    Exactly one holds: ``found`` (contact holds at the low end and is lost at ``speed_rad_s``),
    ``lost_at_low`` (already lost at the lowest speed scanned: no speed of the range keeps it
    below), or neither (contact holds at every speed scanned).
    """

    speed_rad_s: jax.Array  # NaN unless found
    found: jax.Array  # bool
    lost_at_low: jax.Array  # bool: min F <= 0 already at speed_low_rad_s


@runtime.program_cache(static_argnames=("n_grid", "n_bisect"))
def jump_speed(cam: CamHarmonics, plant: Plant, closure: ForceClosure, phi: jax.Array,
               speed_low_rad_s, speed_high_rad_s, n_grid: int = 256, n_bisect: int = 60,
               include_rad_s=None) -> JumpSpeed:
    """Lowest speed in [low, high] where min_phi F = 0 (contact just lost).

    The minimum force is not monotone in speed (resonances), so a grid of ``n_grid`` speeds plus
    the resonant speeds omega_n / n plus ``include_rad_s`` (None or an array of speeds, those
    outside [low, high] clipped to it: e.g. the cam speed, so that contact lost there is found
    at or below it) finds the first sign change and ``n_bisect`` bisections refine it (to a
    relative width 2^-60 of the grid step).
    Contact must hold at ``speed_low_rad_s``; otherwise found = False and lost_at_low = True.
    """
    def fmin(w):
        return min_contact_force(cam, plant, closure, w, phi)

    # add the resonant speeds omega_n / n: a lightly damped window of lost contact can be far
    # narrower than the grid spacing, and it always contains its resonance
    wn = natural_frequency_rad_s(plant)
    resonant = wn / jnp.arange(1, cam.cos.shape[-1], dtype=phi.dtype)
    parts = [jnp.linspace(speed_low_rad_s, speed_high_rad_s, n_grid), resonant]
    if include_rad_s is not None:
        parts.append(jnp.ravel(jnp.asarray(include_rad_s, dtype=phi.dtype)))
    grid = jnp.sort(jnp.clip(jnp.concatenate(parts), speed_low_rad_s, speed_high_rad_s))
    values = jax.vmap(fmin)(grid)
    negative = values <= 0
    first = jnp.argmax(negative)
    found = jnp.any(negative) & (first > 0)
    lo = grid[jnp.maximum(first - 1, 0)]
    hi = grid[first]

    def bisect(_, bounds):
        a, b = bounds
        mid = 0.5 * (a + b)
        neg = fmin(mid) <= 0
        return jnp.where(neg, a, mid), jnp.where(neg, mid, b)

    lo, hi = jax.lax.fori_loop(0, n_bisect, bisect, (lo, hi))
    return JumpSpeed(jnp.where(found, 0.5 * (lo + hi), jnp.nan), found, negative[0])


@jax.jit
def min_preload(cam, plant, closure, cam_speed_rad_s, phi) -> jax.Array:
    """Smallest spring preload x0 keeping F >= 0 over ``phi`` at this speed (m or rad).

    F is affine in x0 with slope k_s > 0: x0 >= max_phi (-(F - k_s x0) / k_s).
    """
    f = contact_force(cam, plant, closure, cam_speed_rad_s, phi)
    return jnp.max(closure.spring_preload - f / closure.spring_rate)


@jax.jit
def min_spring_rate(cam, plant, closure, cam_speed_rad_s, phi) -> jax.Array:
    """Smallest spring rate k_s keeping F >= 0 at this speed with the given preload.

    F = F0 + k_s (theta2 + x0); requires theta2 + x0 > 0 everywhere (a compressed spring),
    otherwise no rate helps and the result is inf.
    """
    v = evaluate_cam(cam, phi)
    comp = v.f + closure.spring_preload
    f0 = contact_force(cam, plant, closure, cam_speed_rad_s, phi) - closure.spring_rate * comp
    need = jnp.where(comp > 0, -f0 / jnp.where(comp > 0, comp, 1.0), jnp.where(f0 < 0, jnp.inf, 0.0))
    return jnp.maximum(jnp.max(need), 0.0)
