"""Feedforward compensation (SPEC 6): linear (harmonic-wise and in time), nonlinear with drive
flexibility, and the robustness of the linear one to a misestimated plant and speed.

Units as in :mod:`camjax.dynamics.plant`; cam speed Omega in rad/s.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax import runtime
from camjax.dynamics.harmonics import (
    TWO_PI,
    CamHarmonics,
    CamValues,
    cam_grid,
    complex_harmonics,
    evaluate_cam,
    fit_harmonics,
    from_complex,
    max_abs,
)
from camjax.dynamics.integrate import Drive, cycle_bound, cycles_data, periodic_rk4
from camjax.dynamics.plant import Plant, perturbed_plant, tracking_error_harmonics, transfer


@jax.jit
def compensate_linear(cam: CamHarmonics, plant: Plant, cam_speed_rad_s) -> CamHarmonics:
    """Linear feedforward: the cam Z2bar_n = Z2_n / G(i n Omega) whose load reproduces ``cam``."""
    n = jnp.arange(cam.cos.shape[-1])
    return from_complex(complex_harmonics(cam) / transfer(plant, n * cam_speed_rad_s))


@jax.jit
def compensate_time(values: CamValues, plant: Plant, cam_speed_rad_s) -> jax.Array:
    """Linear feedforward in time: theta2bar = theta2 + (c3/k23) theta2' + (I3/k23) theta2''.

    With theta2' = Omega df/dphi, theta2'' = Omega^2 d2f/dphi2 (constant cam speed). Same shape
    as ``values.f``; equal to :func:`compensate_linear` for a band-limited law.
    """
    w = cam_speed_rad_s
    return (values.f + plant.damping / plant.stiffness * w * values.df
            + plant.inertia / plant.stiffness * w**2 * values.d2f)


@runtime.program_cache
def robustness_grid(cam: CamHarmonics, target: CamHarmonics, plant: Plant, cam_speed_rad_s,
                    damping_factors: jax.Array, speed_factors: jax.Array, wn_factors: jax.Array,
                    phi: jax.Array) -> jax.Array:
    """max |theta3 - target| over ``phi`` with the true plant and speed perturbed.

    The cam was cut for ``plant`` at ``cam_speed_rad_s`` (the estimates); the true values are
    mu zeta, lambda Omega, kappa omega_n for every mu in ``damping_factors``, lambda in
    ``speed_factors``, kappa in ``wn_factors``. Returns shape (len(mu), len(lambda), len(kappa)).
    """

    def one(mu, lam, kappa):
        err = tracking_error_harmonics(cam, target, perturbed_plant(plant, mu, kappa),
                                       lam * cam_speed_rad_s)
        return max_abs(err, phi)

    f = jax.vmap(jax.vmap(jax.vmap(one, (None, None, 0)), (None, 0, None)), (0, None, None))
    return f(jnp.asarray(damping_factors), jnp.asarray(speed_factors), jnp.asarray(wn_factors))


class NonlinearCompensation(NamedTuple):
    """Result of :func:`compensate_nonlinear`."""

    cam: CamHarmonics  # the fitted cam law f_nl(theta1)
    cam_angle: jax.Array  # (M,) theta1(t_k) predicted with the demanded torque
    follower: jax.Array  # (M,) theta2bar(t_k), the linearly compensated follower motion
    fit_rms: jax.Array  # RMS of f_nl(theta1(t_k)) - theta2bar(t_k), motion units


def compensate_nonlinear(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s,
                         n_harmonics: int, n_cycles, steps_per_cycle: int = 720, max_cycles: int | None = None
                         ) -> NonlinearCompensation:
    """Nonlinear feedforward with drive flexibility (SPEC 6), fitted to a limited Fourier law.

    1. theta2bar(t) = linear compensation of ``cam`` at Omega; the load should follow
       theta3(t) = f(Omega t).
    2. The torque it demands, T2 = I2 theta2bar'' + k23 (theta2bar - theta3), enters the drive
       equation through the power balance T1 = T2 theta2bar' / theta1'; integrate it (RK4,
       ``n_cycles`` motor revolutions: data, bounded by the static ``max_cycles``, None:
       ``n_cycles``; see :func:`~camjax.dynamics.integrate.periodic_rk4`) to the periodic theta1(t).
    3. Cut the cam so that f_nl(theta1(t)) = theta2bar(t): least squares in ``n_harmonics``
       cosine and sine harmonics over the last revolution.
    """
    return _compensate_nonlinear(cam, drive, plant, cam_speed_rad_s, n_harmonics, cycles_data(n_cycles),
                                 steps_per_cycle, cycle_bound(n_cycles, max_cycles))


@runtime.program_cache(static_argnames=("n_harmonics", "steps_per_cycle", "max_cycles"))
def _compensate_nonlinear(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s, n_harmonics: int,
                          n_cycles, steps_per_cycle: int, max_cycles: int) -> NonlinearCompensation:
    omega = cam_speed_rad_s
    m = steps_per_cycle
    dt = TWO_PI / (omega * m)
    lin = compensate_linear(cam, plant, omega)

    def rhs(motor_angle, y):
        bar = evaluate_cam(lin, motor_angle)
        nominal = evaluate_cam(cam, motor_angle).f
        t2 = drive.follower_inertia * omega**2 * bar.d2f + plant.stiffness * (bar.f - nominal)
        t1 = t2 * omega * bar.df / y[1]
        accel = (-drive.coupling_stiffness * y[0] - drive.coupling_damping * (y[1] - omega)
                 - t1) / drive.cam_inertia
        return jnp.stack([y[1] - omega, accel])

    def rhs_cycle(j, t, y, _):
        # motor angle: the step's start (the cam law is 2 pi periodic) plus Omega t
        return rhs(TWO_PI * j / m + omega * t, y)

    y0 = jnp.stack([jnp.zeros_like(lin.cos[0]), jnp.zeros_like(lin.cos[0]) + omega])
    last = periodic_rk4(rhs_cycle, y0, dt, m, n_cycles, max_cycles=max_cycles)
    motor = cam_grid(m, y0.dtype)
    theta1 = motor + last[:, 0]
    target = evaluate_cam(lin, motor).f
    fitted = fit_harmonics(theta1, target, n_harmonics)
    resid = evaluate_cam(fitted, theta1).f - target
    return NonlinearCompensation(fitted, theta1, target, jnp.sqrt(jnp.mean(resid**2)))
