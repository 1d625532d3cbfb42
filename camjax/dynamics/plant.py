"""The elastic follower train (SPEC 6, load side) and its periodic steady state.

The cam imposes the follower motion theta2; the load theta3 follows through k23, damped to
ground by c3: I3 theta3'' + c3 theta3' + k23 theta3 = k23 theta2,
G(s) = k23 / (I3 s^2 + c3 s + k23).

Units per follower kind: translating kg, N s/m, N/m (motion in m); oscillating kg m^2,
N m s/rad, N m/rad (motion in rad). Frequencies in rad/s.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.dynamics.harmonics import CamHarmonics, complex_harmonics, from_complex


class Plant(NamedTuple):
    """Elastic follower train (load side of SPEC 6). Scalars (or arrays that broadcast).

    Units per follower kind: translating kg, N s/m, N/m; oscillating kg m^2, N m s/rad, N m/rad.
    """

    inertia: jax.Array  # I3, load inertia (mass)
    damping: jax.Array  # c3, load damping to ground
    stiffness: jax.Array  # k23, follower-to-load stiffness


@jax.jit
def natural_frequency_rad_s(plant: Plant) -> jax.Array:
    """omega_n = sqrt(k23 / I3), rad/s."""
    return jnp.sqrt(plant.stiffness / plant.inertia)


@jax.jit
def damping_ratio(plant: Plant) -> jax.Array:
    """zeta = c3 / (2 sqrt(k23 I3)), dimensionless."""
    return plant.damping / (2.0 * jnp.sqrt(plant.stiffness * plant.inertia))


def perturbed_plant(plant: Plant, damping_factor=1.0, wn_factor=1.0) -> Plant:
    """The plant with zeta -> mu zeta and omega_n -> kappa omega_n at the same inertia.

    k23 -> kappa^2 k23 and c3 -> mu kappa c3 (source 003's mu, kappa: true over estimated).
    """
    return Plant(plant.inertia, plant.damping * damping_factor * wn_factor,
                 plant.stiffness * wn_factor**2)


@jax.jit
def transfer(plant: Plant, omega_rad_s: jax.Array) -> jax.Array:
    """G(i omega) = k23 / (k23 - I3 omega^2 + i c3 omega), complex, shape of ``omega_rad_s``."""
    w = jnp.asarray(omega_rad_s)
    return plant.stiffness / (plant.stiffness - plant.inertia * w**2 + 1j * plant.damping * w)


def resonant_harmonic(plant: Plant, cam_speed_rad_s) -> tuple[int, float]:
    """(n, n Omega / omega_n) for the harmonic n >= 1 of the cam nearest the resonance.

    Not traceable (returns Python numbers).
    """
    ratio = float(natural_frequency_rad_s(plant) / cam_speed_rad_s)
    n = max(1, round(ratio))
    return n, n / ratio


# ------------------------------------------------------------------ periodic steady state


@jax.jit
def steady_state(cam: CamHarmonics, plant: Plant, cam_speed_rad_s) -> CamHarmonics:
    """Load motion theta3 in periodic steady state, harmonic by harmonic: Z3_n = G(i n Omega) Z2_n."""
    n = jnp.arange(cam.cos.shape[-1])
    return from_complex(transfer(plant, n * cam_speed_rad_s) * complex_harmonics(cam))


@jax.jit
def tracking_error_harmonics(cam: CamHarmonics, target: CamHarmonics, plant: Plant,
                             cam_speed_rad_s) -> CamHarmonics:
    """Harmonics of the load tracking error theta3 - target when the cam ``cam`` runs at Omega.

    ``cam`` and ``target`` must have the same number of harmonics.
    """
    n = jnp.arange(cam.cos.shape[-1])
    z = transfer(plant, n * cam_speed_rad_s) * complex_harmonics(cam) - complex_harmonics(target)
    return from_complex(z)
