"""Follower-train dynamics, follower jump and feedforward compensation (SPEC section 6).

Models, each a pure JAX function of one design (batch with ``vmap``):

- :class:`Plant`: the elastic follower train. The cam imposes the follower motion theta2; the
  load theta3 follows through k23, damped to ground by c3:
  I3 theta3'' + c3 theta3' + k23 theta3 = k23 theta2,  G(s) = k23 / (I3 s^2 + c3 s + k23).
- :func:`steady_state`: the periodic steady state at constant cam speed, harmonic by harmonic
  (Theta3[n] = G(i n Omega) Theta2[n]); :func:`integrate_train`: fixed-step RK4 in ``lax.scan``
  for transients. Both agree on the steady state (tests).
- :class:`Drive`: constant-speed motor -> flexible coupling (k01, c01) -> cam inertia I1, power
  balance through the cam, follower train behind it (:func:`simulate_drive`): cam-speed ripple.
- :func:`contact_force`, :func:`jump_speed`: follower jump of a force-closed cam.
- :func:`compensate_linear` (harmonic-wise inverse of G), :func:`compensate_time` (its time
  form), :func:`compensate_nonlinear` (drive flexibility, fitted back to a limited Fourier law),
  :func:`robustness_grid` and :func:`shape_law` (gradient-based law shaping through the model).

Cam laws are limited Fourier series over one revolution, :class:`CamHarmonics`
(f(phi) = a0 + sum_n a_n cos(n phi) + b_n sin(n phi)); a motion program becomes one through the
FFT of its samples (:func:`harmonics_from_samples`), exactly for a band-limited law such as the
thesis' nominal cam, by truncation otherwise.

Units: SI inside. The generalized coordinate is the follower displacement in m (translating
follower: I in kg, c in N s/m, k in N/m, forces in N) or the follower angle in rad (oscillating
follower: I in kg m^2, c in N m s/rad, k in N m/rad, "forces" are torques in N m). Cam angle phi
in rad, cam speed Omega in rad/s.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import optax

from camjax import program as prog

TWO_PI = 2.0 * math.pi

# ------------------------------------------------------------------------------ the plant


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


# ---------------------------------------------------------------------------- cam harmonics


class CamHarmonics(NamedTuple):
    """Limited Fourier law over one cam revolution, phi in rad.

    f(phi) = a_0 + sum_{n=1..H} (a_n cos(n phi) + b_n sin(n phi)), in motion units (m or rad).
    """

    cos: jax.Array  # (H+1,) a_0 .. a_H; a_0 is the mean
    sin: jax.Array  # (H+1,) b_0 .. b_H; b_0 multiplies sin(0) = 0 and is kept at 0


class CamValues(NamedTuple):
    """A cam law and its derivatives with respect to cam angle, each with the shape of phi."""

    f: jax.Array  # follower position (m or rad)
    df: jax.Array  # df/dphi, per rad
    d2f: jax.Array  # d2f/dphi2, per rad^2


def _complex(cam: CamHarmonics) -> jax.Array:
    """Z_n = a_n - i b_n, so that f = Re sum_n Z_n exp(i n phi)."""
    return cam.cos - 1j * cam.sin


def _from_complex(z: jax.Array) -> CamHarmonics:
    return CamHarmonics(jnp.real(z), -jnp.imag(z))


@partial(jax.jit, static_argnames="n_harmonics")
def harmonics_from_samples(values: jax.Array, n_harmonics: int) -> CamHarmonics:
    """The first ``n_harmonics`` harmonics of a law sampled at phi_k = 2 pi k / N, k = 0..N-1.

    Exact for a law band-limited below N/2 harmonics (the thesis' nominal cam has 9); otherwise
    the truncated (and slightly aliased) series. ``n_harmonics`` must be < N/2 (static).
    """
    n = values.shape[-1]
    if not 1 <= n_harmonics < n / 2:
        raise ValueError(f"n_harmonics: {n_harmonics} must be in [1, N/2) with N = {n} samples")
    z = jnp.fft.rfft(values)[: n_harmonics + 1] / n
    z = z.at[1:].multiply(2.0)
    return CamHarmonics(jnp.real(z), -jnp.imag(z).at[0].set(0.0))


def pad_harmonics(cam: CamHarmonics, n_harmonics: int) -> CamHarmonics:
    """Zero-pad (or truncate) to ``n_harmonics`` harmonics (static)."""
    h = cam.cos.shape[-1] - 1
    if n_harmonics <= h:
        return CamHarmonics(cam.cos[: n_harmonics + 1], cam.sin[: n_harmonics + 1])
    pad = jnp.zeros(n_harmonics - h, dtype=cam.cos.dtype)
    return CamHarmonics(jnp.concatenate([cam.cos, pad]), jnp.concatenate([cam.sin, pad]))


@jax.jit
def evaluate_cam(cam: CamHarmonics, phi: jax.Array) -> CamValues:
    """f, df/dphi, d2f/dphi2 at cam angles ``phi`` (rad, any shape)."""
    phi = jnp.asarray(phi)
    n = jnp.arange(cam.cos.shape[-1], dtype=phi.dtype)
    arg = phi[..., None] * n
    c, s = jnp.cos(arg), jnp.sin(arg)
    f = c @ cam.cos + s @ cam.sin
    df = (c * n) @ cam.sin - (s * n) @ cam.cos
    d2f = -(c * n**2) @ cam.cos - (s * n**2) @ cam.sin
    return CamValues(f, df, d2f)


def cam_grid(samples: int, dtype=None) -> jax.Array:
    """phi_k = 2 pi k / N, k = 0..N-1 (rad)."""
    return jnp.arange(samples, dtype=dtype or jnp.result_type(float)) * (TWO_PI / samples)


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
    return _from_complex(transfer(plant, n * cam_speed_rad_s) * _complex(cam))


@jax.jit
def tracking_error_harmonics(cam: CamHarmonics, target: CamHarmonics, plant: Plant,
                             cam_speed_rad_s) -> CamHarmonics:
    """Harmonics of the load tracking error theta3 - target when the cam ``cam`` runs at Omega.

    ``cam`` and ``target`` must have the same number of harmonics.
    """
    n = jnp.arange(cam.cos.shape[-1])
    z = transfer(plant, n * cam_speed_rad_s) * _complex(cam) - _complex(target)
    return _from_complex(z)


@jax.jit
def mean_square(cam: CamHarmonics) -> jax.Array:
    """Mean over the cycle of f(phi)^2 by Parseval: a_0^2 + (1/2) sum_{n>=1} (a_n^2 + b_n^2)."""
    return cam.cos[0] ** 2 + 0.5 * jnp.sum(cam.cos[1:] ** 2 + cam.sin[1:] ** 2)


@jax.jit
def max_abs(cam: CamHarmonics, phi: jax.Array) -> jax.Array:
    """max over the grid ``phi`` of |f(phi)| (the sampled maximum; a grid of N >> 2H is tight)."""
    return jnp.max(jnp.abs(evaluate_cam(cam, phi).f))


@jax.jit
def compensate_linear(cam: CamHarmonics, plant: Plant, cam_speed_rad_s) -> CamHarmonics:
    """Linear feedforward: the cam Z2bar_n = Z2_n / G(i n Omega) whose load reproduces ``cam``."""
    n = jnp.arange(cam.cos.shape[-1])
    return _from_complex(_complex(cam) / transfer(plant, n * cam_speed_rad_s))


@jax.jit
def compensate_time(values: CamValues, plant: Plant, cam_speed_rad_s) -> jax.Array:
    """Linear feedforward in time: theta2bar = theta2 + (c3/k23) theta2' + (I3/k23) theta2''.

    With theta2' = Omega df/dphi, theta2'' = Omega^2 d2f/dphi2 (constant cam speed). Same shape
    as ``values.f``; equal to :func:`compensate_linear` for a band-limited law.
    """
    w = cam_speed_rad_s
    return (values.f + plant.damping / plant.stiffness * w * values.df
            + plant.inertia / plant.stiffness * w**2 * values.d2f)


@jax.jit
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


# ------------------------------------------------------------------ time-domain integration


def _rk4(rhs, y, t, dt, u0, uh, u1):
    """One classical RK4 step of y' = rhs(t, y, u) with the input known at t, t+dt/2, t+dt."""
    k1 = rhs(t, y, u0)
    k2 = rhs(t + dt / 2, jax.tree_util.tree_map(lambda a, b: a + dt / 2 * b, y, k1), uh)
    k3 = rhs(t + dt / 2, jax.tree_util.tree_map(lambda a, b: a + dt / 2 * b, y, k2), uh)
    k4 = rhs(t + dt, jax.tree_util.tree_map(lambda a, b: a + dt * b, y, k3), u1)
    return jax.tree_util.tree_map(lambda a, b1, b2, b3, b4: a + dt / 6 * (b1 + 2 * b2 + 2 * b3 + b4),
                                  y, k1, k2, k3, k4)


class TrainState(NamedTuple):
    """State of the load (scalars)."""

    angle: jax.Array  # theta3, m or rad
    rate: jax.Array  # theta3', m/s or rad/s


def settling_cycles(plant: Plant, cam_speed_rad_s: float, tolerance: float = 1e-9,
                    max_cycles: int = 2000) -> int:
    """Cam cycles for a transient e^{-zeta omega_n t} to fall below ``tolerance`` (capped).

    Not traceable: the number of steps of a scan is static.
    """
    decay = float(damping_ratio(plant) * natural_frequency_rad_s(plant))
    period = TWO_PI / float(cam_speed_rad_s)
    if decay <= 0:
        return int(max_cycles)
    return int(min(max_cycles, math.ceil(math.log(1.0 / tolerance) / (decay * period)) + 1))


@partial(jax.jit, static_argnames=("n_cycles",))
def integrate_train(plant: Plant, follower_half_steps: jax.Array, cam_speed_rad_s,
                    n_cycles: int, initial: TrainState | None = None) -> TrainState:
    """RK4 of the follower train driven by a periodic follower motion, from rest (or ``initial``).

    Args:
      plant: the follower train.
      follower_half_steps: (2M,) theta2 at cam angles phi_j = pi j / M: the values at every step
        and half step of one cycle of M steps (dt = 2 pi / (Omega M)).
      cam_speed_rad_s: Omega.
      n_cycles: cycles to integrate (static); the last one is returned.
      initial: state at t = 0; default theta3 = theta2(0), theta3' = 0.

    Returns:
      TrainState of shape (M,) each: the load over the last cycle at phi_k = 2 pi k / M.
    """
    u = jnp.asarray(follower_half_steps)
    m = u.shape[0] // 2
    dt = TWO_PI / (cam_speed_rad_s * m)
    if initial is None:
        initial = TrainState(u[0], jnp.zeros_like(u[0]))

    def rhs(t, y, theta2):
        accel = (plant.stiffness * (theta2 - y.angle) - plant.damping * y.rate) / plant.inertia
        return TrainState(y.rate, accel)

    def step(y, j):
        y_next = _rk4(rhs, y, 0.0, dt, u[2 * j], u[2 * j + 1], u[(2 * j + 2) % (2 * m)])
        return y_next, y

    def cycle(y, _):
        y, _ = jax.lax.scan(step, y, jnp.arange(m))
        return y, None

    y, _ = jax.lax.scan(cycle, initial, None, length=n_cycles - 1)
    _, last = jax.lax.scan(step, y, jnp.arange(m))
    return last


# ------------------------------------------------------------------------- drive flexibility


class Drive(NamedTuple):
    """Motor at constant speed -> coupling k01, c01 -> cam inertia I1; follower inertia I2 (SI)."""

    cam_inertia: jax.Array  # I1, kg m^2
    follower_inertia: jax.Array  # I2, kg (translating) or kg m^2 (oscillating)
    coupling_stiffness: jax.Array  # k01, N m/rad
    coupling_damping: jax.Array  # c01, N m s/rad


class DriveState(NamedTuple):
    """Full model state (scalars)."""

    cam_lag: jax.Array  # theta1 - Omega t, rad (the coupling wind-up is -cam_lag)
    cam_rate: jax.Array  # theta1', rad/s
    load: jax.Array  # theta3
    load_rate: jax.Array  # theta3'


class DriveResponse(NamedTuple):
    """The last simulated cycle at motor angles Omega t_k = 2 pi k / M (shape (M,) each)."""

    cam_angle: jax.Array  # theta1 (rad, within about one revolution)
    cam_speed: jax.Array  # theta1', rad/s
    follower: jax.Array  # theta2 = f(theta1)
    load: jax.Array  # theta3
    cam_torque: jax.Array  # T1 = T2 f'(theta1), N m, torque the cam shaft must supply


def _drive_rhs(cam, drive, plant, omega):
    def rhs(motor_angle, y: DriveState, _):
        theta1 = motor_angle + y.cam_lag
        v = evaluate_cam(cam, theta1)
        spring = plant.stiffness * (v.f - y.load)
        # (I1 + I2 f'^2) theta1'' = k01 (theta0 - theta1) + c01 (Omega - theta1')
        #                           - f' (I2 f'' theta1'^2 + k23 (f - theta3))
        drive_torque = (-drive.coupling_stiffness * y.cam_lag
                        - drive.coupling_damping * (y.cam_rate - omega))
        eff = drive.cam_inertia + drive.follower_inertia * v.df**2
        accel1 = (drive_torque - v.df * (drive.follower_inertia * v.d2f * y.cam_rate**2 + spring)) / eff
        accel3 = (spring - plant.damping * y.load_rate) / plant.inertia
        return DriveState(y.cam_rate - omega, accel1, y.load_rate, accel3)

    return rhs


@partial(jax.jit, static_argnames=("n_cycles", "steps_per_cycle"))
def simulate_drive(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s,
                   n_cycles: int, steps_per_cycle: int = 720) -> DriveResponse:
    """RK4 of the full model (SPEC 6, drive flexibility) from theta1 = Omega t, rest load.

    I1 theta1'' = k01 (theta0 - theta1) + c01 (theta0' - theta1') - T1,  T1 theta1' = T2 theta2',
    T2 = I2 theta2'' + k23 (theta2 - theta3),  theta2 = f(theta1),
    I3 theta3'' = k23 (theta2 - theta3) - c3 theta3',  theta0 = Omega t.
    Returns the last of ``n_cycles`` motor revolutions (static), M = ``steps_per_cycle``.
    """
    omega = cam_speed_rad_s
    m = steps_per_cycle
    dt = TWO_PI / (omega * m)
    rhs = _drive_rhs(cam, drive, plant, omega)
    f0 = evaluate_cam(cam, jnp.zeros(()))
    zero = jnp.zeros_like(f0.f)
    y0 = DriveState(zero, zero + omega, f0.f, zero)

    def step_time(y, j):
        a0 = TWO_PI * j / m  # motor angle at the step start (the cam law is 2 pi periodic)

        def rhs_t(t, yy, _):
            return rhs(a0 + omega * t, yy, None)

        return _rk4(rhs_t, y, 0.0, dt, None, None, None), y

    def cycle(y, _):
        y, _ = jax.lax.scan(step_time, y, jnp.arange(m))
        return y, None

    y, _ = jax.lax.scan(cycle, y0, None, length=n_cycles - 1)
    _, last = jax.lax.scan(step_time, y, jnp.arange(m))
    motor = cam_grid(m, zero.dtype)
    theta1 = motor + last.cam_lag
    v = evaluate_cam(cam, theta1)
    rate = last.cam_rate
    spring = plant.stiffness * (v.f - last.load)
    accel1 = rhs(motor, last, None).cam_rate  # the drive equation, elementwise over the cycle
    accel2 = v.d2f * rate**2 + v.df * accel1
    torque = v.df * (drive.follower_inertia * accel2 + spring)
    return DriveResponse(theta1, rate, v.f, last.load, torque)


class NonlinearCompensation(NamedTuple):
    """Result of :func:`compensate_nonlinear`."""

    cam: CamHarmonics  # the fitted cam law f_nl(theta1)
    cam_angle: jax.Array  # (M,) theta1(t_k) predicted with the demanded torque
    follower: jax.Array  # (M,) theta2bar(t_k), the linearly compensated follower motion
    fit_rms: jax.Array  # RMS of f_nl(theta1(t_k)) - theta2bar(t_k), motion units


@partial(jax.jit, static_argnames=("n_harmonics", "n_cycles", "steps_per_cycle"))
def compensate_nonlinear(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s,
                         n_harmonics: int, n_cycles: int, steps_per_cycle: int = 720
                         ) -> NonlinearCompensation:
    """Nonlinear feedforward with drive flexibility (SPEC 6), fitted to a limited Fourier law.

    1. theta2bar(t) = linear compensation of ``cam`` at Omega; the load should follow
       theta3(t) = f(Omega t).
    2. The torque it demands, T2 = I2 theta2bar'' + k23 (theta2bar - theta3), enters the drive
       equation through the power balance T1 = T2 theta2bar' / theta1'; integrate it (RK4,
       ``n_cycles`` motor revolutions) to the periodic theta1(t).
    3. Cut the cam so that f_nl(theta1(t)) = theta2bar(t): least squares in ``n_harmonics``
       cosine and sine harmonics over the last revolution.
    """
    omega = cam_speed_rad_s
    m = steps_per_cycle
    dt = TWO_PI / (omega * m)
    lin = compensate_linear(cam, plant, omega)

    def rhs(motor_angle, y, _):
        bar = evaluate_cam(lin, motor_angle)
        nominal = evaluate_cam(cam, motor_angle).f
        t2 = drive.follower_inertia * omega**2 * bar.d2f + plant.stiffness * (bar.f - nominal)
        t1 = t2 * omega * bar.df / y[1]
        accel = (-drive.coupling_stiffness * y[0] - drive.coupling_damping * (y[1] - omega)
                 - t1) / drive.cam_inertia
        return jnp.stack([y[1] - omega, accel])

    def step(y, j):
        a0 = TWO_PI * j / m
        return _rk4(lambda t, yy, _: rhs(a0 + omega * t, yy, None), y, 0.0, dt, None, None,
                    None), y

    def cycle(y, _):
        y, _ = jax.lax.scan(step, y, jnp.arange(m))
        return y, None

    y0 = jnp.stack([jnp.zeros_like(lin.cos[0]), jnp.zeros_like(lin.cos[0]) + omega])
    y, _ = jax.lax.scan(cycle, y0, None, length=n_cycles - 1)
    _, last = jax.lax.scan(step, y, jnp.arange(m))
    motor = cam_grid(m, y0.dtype)
    theta1 = motor + last[:, 0]
    target = evaluate_cam(lin, motor).f
    fitted = fit_harmonics(theta1, target, n_harmonics)
    resid = evaluate_cam(fitted, theta1).f - target
    return NonlinearCompensation(fitted, theta1, target, jnp.sqrt(jnp.mean(resid**2)))


@partial(jax.jit, static_argnames="n_harmonics")
def fit_harmonics(phi: jax.Array, values: jax.Array, n_harmonics: int) -> CamHarmonics:
    """Least-squares limited Fourier law through scattered samples (phi (K,) rad, values (K,))."""
    n = jnp.arange(n_harmonics + 1, dtype=phi.dtype)
    arg = phi[:, None] * n
    basis = jnp.concatenate([jnp.cos(arg), jnp.sin(arg[:, 1:])], axis=1)
    coef, *_ = jnp.linalg.lstsq(basis, values)
    return CamHarmonics(coef[: n_harmonics + 1],
                        jnp.concatenate([jnp.zeros(1, coef.dtype), coef[n_harmonics + 1:]]))


# ---------------------------------------------------------------------------- follower jump


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
    """Lowest cam speed at which contact is lost."""

    speed_rad_s: jax.Array  # NaN when contact holds over the whole search range
    found: jax.Array  # bool


@partial(jax.jit, static_argnames=("n_grid", "n_bisect"))
def jump_speed(cam: CamHarmonics, plant: Plant, closure: ForceClosure, phi: jax.Array,
               speed_low_rad_s, speed_high_rad_s, n_grid: int = 256, n_bisect: int = 60) -> JumpSpeed:
    """Lowest speed in [low, high] where min_phi F = 0 (contact just lost).

    The minimum force is not monotone in speed (resonances), so a grid of ``n_grid`` speeds plus
    the resonant speeds omega_n / n finds the first sign change and ``n_bisect`` bisections
    refine it (to a relative width 2^-60 of the grid step).
    Contact must hold at ``speed_low_rad_s``; otherwise found = False.
    """
    def fmin(w):
        return min_contact_force(cam, plant, closure, w, phi)

    # add the resonant speeds omega_n / n: a lightly damped window of lost contact can be far
    # narrower than the grid spacing, and it always contains its resonance
    wn = natural_frequency_rad_s(plant)
    resonant = wn / jnp.arange(1, cam.cos.shape[-1], dtype=phi.dtype)
    grid = jnp.sort(jnp.clip(jnp.concatenate([jnp.linspace(speed_low_rad_s, speed_high_rad_s, n_grid),
                                              resonant]), speed_low_rad_s, speed_high_rad_s))
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
    return JumpSpeed(jnp.where(found, 0.5 * (lo + hi), jnp.nan), found)


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


# --------------------------------------------------------------------- gradient law shaping


class ShapingResult(NamedTuple):
    """Result of :func:`shape_law`."""

    cam: CamHarmonics  # shaped law
    objective: jax.Array  # (steps,) penalized objective per iteration
    tracking_rms: jax.Array  # final band-averaged RMS tracking error (motion units)
    constraint_max: jax.Array  # final max |f(phi_c) - value_c| (motion units)


@jax.jit
def band_tracking_ms(cam: CamHarmonics, plant: Plant, speeds_rad_s: jax.Array) -> jax.Array:
    """Mean over ``speeds_rad_s`` of the mean-square load tracking error theta3 - theta2 (Parseval)."""
    return jnp.mean(jax.vmap(lambda w: mean_square(tracking_error_harmonics(cam, cam, plant, w)))(
        speeds_rad_s))


@partial(jax.jit, static_argnames=("steps",))
def shape_law(cam0: CamHarmonics, plant: Plant, speeds_rad_s: jax.Array, constraint_phi: jax.Array,
              constraint_values: jax.Array, scale, steps: int = 200,
              penalty: float = 1e4) -> ShapingResult:
    """Gradient-based law shaping: minimize residual vibration over a speed band (goes beyond 003).

    Minimizes mean_speed mean_phi (theta3 - theta2)^2 / scale^2 + penalty * mean_c
    ((f(phi_c) - value_c) / scale)^2 over all coefficients of ``cam0`` with L-BFGS (optax,
    ``jax.grad`` through the steady-state dynamics), ``steps`` iterations in a ``lax.scan``.
    ``constraint_phi``/``constraint_values`` pin the lift and the dwells (rad, motion units);
    ``scale`` is the lift (motion units).
    """
    def unpack(x):
        return CamHarmonics(x[0], x[1].at[0].set(0.0))

    def objective(x):
        cam = unpack(x)
        err = evaluate_cam(cam, constraint_phi).f - constraint_values
        return (band_tracking_ms(cam, plant, speeds_rad_s) / scale**2
                + penalty * jnp.mean(err**2) / scale**2)

    # backtracking (Armijo) line search: a smaller program to compile than the default zoom
    opt = optax.lbfgs(linesearch=optax.scale_by_backtracking_linesearch(max_backtracking_steps=20,
                                                                        store_grad=True))
    x0 = jnp.stack([cam0.cos, cam0.sin])
    value_and_grad = optax.value_and_grad_from_state(objective)

    def step(carry, _):
        x, state = carry
        value, grad = value_and_grad(x, state=state)
        updates, state = opt.update(grad, state, x, value=value, grad=grad, value_fn=objective)
        return (optax.apply_updates(x, updates), state), value

    (x, _), history = jax.lax.scan(step, (x0, opt.init(x0)), None, length=steps)
    cam = unpack(x)
    err = evaluate_cam(cam, constraint_phi).f - constraint_values
    return ShapingResult(cam, history, jnp.sqrt(band_tracking_ms(cam, plant, speeds_rad_s)),
                         jnp.max(jnp.abs(err)))


# ------------------------------------------------------------------------------ scene level


class DynamicsReport(NamedTuple):
    """What :func:`scene_dynamics` computed: JSON-ready numbers and NumPy curves for plots."""

    summary: dict  # the content of dynamics.json (floats, ints, bools, lists, None)
    curves: dict  # name -> np.ndarray, for plots


def plant_of(spec) -> Plant:
    """The follower train of a :class:`~camjax.scene.DynamicsSpec`."""
    return Plant(jnp.asarray(spec.I3), jnp.asarray(spec.c3), jnp.asarray(spec.k23))


def drive_of(spec) -> Drive:
    """The drive of a DynamicsSpec with drive flexibility (I1, k01, c01 given)."""
    return Drive(jnp.asarray(spec.I1), jnp.asarray(spec.I2), jnp.asarray(spec.k01), jnp.asarray(spec.c01))


def closure_of(spec) -> ForceClosure:
    """The force closure of a DynamicsSpec with a spring."""
    return ForceClosure(jnp.asarray(spec.I2), jnp.asarray(spec.spring_rate),
                        jnp.asarray(spec.spring_preload), jnp.asarray(spec.follower_damping),
                        jnp.asarray(spec.weight))


def program_cam(scene, samples: int | None = None, n_harmonics: int | None = None) -> CamHarmonics:
    """The scene's motion program as CamHarmonics in SI (m or rad), from the FFT of its samples."""
    spec = scene.dynamics
    n = spec.samples if samples is None else samples
    kin = prog.evaluate(scene.motion.program, n)
    return harmonics_from_samples(kin.s * spec.motion_scale, spec.harmonics if n_harmonics is None
                                  else n_harmonics)


def _program_values(scene, angles_rad: jax.Array) -> CamValues:
    """Exact program law (not its harmonics) at arbitrary cam angles, SI."""
    kin = prog.motion_at(scene.motion.program, jnp.rad2deg(angles_rad))
    k = scene.dynamics.motion_scale
    return CamValues(kin.s * k, kin.ds * k, kin.d2s * k)


def trim_harmonics(cam: CamHarmonics, rtol: float = 1e-13) -> CamHarmonics:
    """Drop trailing harmonics below ``rtol`` times the largest (not traceable: sets a shape)."""
    mag = np.hypot(np.asarray(cam.cos), np.asarray(cam.sin))
    keep = np.nonzero(mag[1:] > rtol * max(mag[1:].max(initial=0.0), 1e-300))[0]
    return pad_harmonics(cam, int(keep[-1]) + 1 if keep.size else 1)


def _constraints(scene) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) and levels (SI) pinned by law shaping: every joint and dwell samples."""
    p = scene.motion.program
    angles = []
    for kind, start, width in zip(p.kinds, p.start_deg, p.angles_deg, strict=True):
        angles.extend(np.linspace(start, start + width, max(2, int(width // 5) + 1)) if kind == "dwell"
                      else [start])
    angles_deg = np.mod(np.asarray(angles), 360.0)
    levels = np.asarray(prog.motion_at(p, angles_deg).s) * scene.dynamics.motion_scale
    return np.deg2rad(angles_deg), levels


def _f(x) -> float:
    return float(np.asarray(x))


def _finite_or_none(x) -> float | None:
    v = _f(x)
    return v if math.isfinite(v) else None


def scene_dynamics(scene) -> DynamicsReport:
    """Run every analysis the scene's [dynamics] section lists. Not traceable (a report).

    Raises ValueError if the scene has no [dynamics] section.
    """
    spec = scene.dynamics
    if spec is None:
        raise ValueError("scene has no [dynamics] section")
    plant = plant_of(spec)
    omega = TWO_PI * spec.cam_speed_hz
    wn, zeta = natural_frequency_rad_s(plant), damping_ratio(plant)
    phi = cam_grid(spec.samples)
    cam = program_cam(scene)
    nominal_err = tracking_error_harmonics(cam, cam, plant, omega)
    n_res, r_res = resonant_harmonic(plant, omega)
    unit = "m" if spec.follower == "translating" else "rad"
    out: dict = {
        "scene": scene.name,
        "follower": spec.follower,
        "units": {"motion": unit, "force": "N" if unit == "m" else "N m",
                  "speed": "Hz (cam revolutions per second)"},
        "cam_speed_hz": spec.cam_speed_hz,
        "natural_frequency_hz": _f(wn) / TWO_PI,
        "damping_ratio": _f(zeta),
        "resonant_harmonic": {"n": n_res, "frequency_ratio": r_res,
                              "amplification": _f(jnp.abs(transfer(plant, n_res * omega)))},
        "samples": spec.samples,
        "harmonics": spec.harmonics,
        "nominal": {"max_tracking_error": _f(max_abs(nominal_err, phi)),
                    "rms_tracking_error": _f(jnp.sqrt(mean_square(nominal_err)))},
    }
    nom_vals = evaluate_cam(cam, phi)
    curves = {"phi_deg": np.rad2deg(np.asarray(phi)), "nominal": np.asarray(nom_vals.f),
              "nominal_load": np.asarray(evaluate_cam(steady_state(cam, plant, omega), phi).f)}
    comp = compensate_linear(cam, plant, omega)
    if "compensation" in spec.compute or "robustness" in spec.compute:
        comp_err = tracking_error_harmonics(comp, cam, plant, omega)
        comp_time = compensate_time(_program_values(scene, phi), plant, omega)
        comp_vals = np.asarray(evaluate_cam(comp, phi).f)
        comp_trim = trim_harmonics(comp)
        mis = []
        for est in (0.9, 1.1):
            c_est = compensate_linear(cam, perturbed_plant(plant, 1.0, est), omega)
            e = _f(max_abs(tracking_error_harmonics(c_est, cam, plant, omega), phi))
            mis.append({"wn_estimate_factor": est, "compensated_max_tracking_error": e,
                        "nominal_over_compensated": out["nominal"]["max_tracking_error"] / e})
        out["compensated"] = {
            "max_tracking_error": _f(max_abs(comp_err, phi)),
            "rms_tracking_error": _f(jnp.sqrt(mean_square(comp_err))),
            "time_form_max_difference": float(np.max(np.abs(np.asarray(comp_time) - comp_vals))),
            "max_cam_change": float(np.max(np.abs(comp_vals - np.asarray(nom_vals.f)))),
            "coefficients": {"cos": np.asarray(comp_trim.cos).tolist(),
                             "sin": np.asarray(comp_trim.sin).tolist()},
            "wn_misestimate": mis,
        }
        curves["compensated"] = comp_vals
    if "robustness" in spec.compute:
        mu, lam, kap = (np.asarray(v) for v in (spec.damping_factors, spec.speed_factors,
                                                  spec.wn_factors))
        grid = np.asarray(robustness_grid(comp, cam, plant, omega, mu, lam, kap, phi))
        grid_nom = np.asarray(robustness_grid(cam, cam, plant, omega, mu, lam, kap, phi))
        out["robustness"] = [
            {"damping_factor": float(mu[i]), "speed_factor": float(lam[j]), "wn_factor": float(kap[k]),
             "max_tracking_error": float(grid[i, j, k]),
             "nominal_max_tracking_error": float(grid_nom[i, j, k])}
            for i in range(mu.size) for j in range(lam.size) for k in range(kap.size)]
        # lambda / kappa: the compensated error depends on speed and omega_n only through their ratio
        ratios = (lam[:, None] / kap[None, :]).ravel()
        at_ratio = np.asarray(robustness_grid(comp, cam, plant, omega, np.array([1.0]), ratios,
                                              np.array([1.0]), phi))[0, :, 0]
        i1 = int(np.argmin(np.abs(mu - 1.0)))
        diff = np.abs(grid[i1].ravel() - at_ratio)
        out["speed_wn_equivalence"] = {
            "max_abs_difference": float(diff.max()),
            "max_error_where_speed_equals_wn_factor": float(max(
                [grid[i1, j, k] for j in range(lam.size) for k in range(kap.size)
                 if abs(lam[j] - kap[k]) < 1e-12] or [0.0])),
            "note": "error(mu=1, lambda, kappa) vs error(mu=1, lambda/kappa, 1)",
        }
        curves.update(rob_mu=mu, rob_lam=lam, rob_kap=kap, rob=grid, rob_nominal=grid_nom,
                      rob_ratio=ratios, rob_at_ratio=at_ratio)
    m = spec.steps_per_cycle
    needs_drive = spec.has_drive and ("drive" in spec.compute or "nonlinear" in spec.compute)
    if "time_domain" in spec.compute or needs_drive:
        cycles = settling_cycles(plant, omega, spec.transient_tolerance, spec.max_cycles)
    if "time_domain" in spec.compute:
        half = cam_grid(2 * m)
        exact = _program_values(scene, half)
        load = integrate_train(plant, exact.f, omega, cycles).angle
        grid_m = cam_grid(m)
        harm = evaluate_cam(steady_state(cam, plant, omega), grid_m).f
        load_c = integrate_train(plant, compensate_time(exact, plant, omega), omega, cycles).angle
        target = _program_values(scene, grid_m).f
        out["time_domain"] = {
            "method": "RK4, lax.scan, from rest",
            "cycles": cycles, "steps_per_cycle": m,
            "transients_decayed_to": float(math.exp(-_f(zeta * wn) * cycles * TWO_PI / omega)),
            "nominal_max_difference_vs_harmonic": _f(jnp.max(jnp.abs(load - harm))),
            "nominal_max_tracking_error": _f(jnp.max(jnp.abs(load - target))),
            "compensated_max_tracking_error": _f(jnp.max(jnp.abs(load_c - target))),
        }
    if needs_drive:
        drive = drive_of(spec)
        target = evaluate_cam(cam, cam_grid(m)).f
        cams = {"nominal": cam, "linear": comp}
        if "nonlinear" in spec.compute:
            nl = compensate_nonlinear(trim_harmonics(cam), drive, plant, omega, spec.harmonics,
                                      cycles, m)
            cams["nonlinear"] = nl.cam
            out["nonlinear"] = {"fit_rms": _f(nl.fit_rms), "harmonics": spec.harmonics,
                                "coefficients": {"cos": np.asarray(nl.cam.cos).tolist(),
                                                 "sin": np.asarray(nl.cam.sin).tolist()}}
        dr = {"cycles": cycles, "drive_natural_frequency_hz": math.sqrt(spec.k01 / spec.I1) / TWO_PI}
        curves["drive_phi_deg"] = np.rad2deg(np.asarray(cam_grid(m)))
        curves["drive_target"] = np.asarray(target)
        for name, c in cams.items():
            r = simulate_drive(trim_harmonics(c), drive, plant, omega, cycles, m)
            dr[name] = {"max_speed_ripple": _f(jnp.max(jnp.abs(r.cam_speed - omega)) / omega),
                        "max_tracking_error": _f(jnp.max(jnp.abs(r.load - target))),
                        "max_cam_torque": _f(jnp.max(jnp.abs(r.cam_torque)))}
            curves[f"drive_{name}_speed"] = np.asarray(r.cam_speed) / TWO_PI
            curves[f"drive_{name}_load"] = np.asarray(r.load)
        out["drive"] = dr
        if "nonlinear" in out:
            out["nonlinear"]["max_tracking_error"] = dr["nonlinear"]["max_tracking_error"]
    if "jump" in spec.compute:
        closure = closure_of(spec)
        lo_hz, hi_hz = spec.jump_speed_range_hz or (0.05 * spec.cam_speed_hz, 10 * spec.cam_speed_hz)
        js = jump_speed(cam, plant, closure, phi, TWO_PI * lo_hz, TWO_PI * hi_hz)
        force = contact_force(cam, plant, closure, omega, phi)
        # plot grid: even steps plus every resonant speed and a close look around the jump
        res_hz = _f(wn) / TWO_PI / np.arange(1, spec.harmonics + 1)
        speeds = [np.linspace(lo_hz, hi_hz, 400), res_hz * 0.999, res_hz, res_hz * 1.001]
        if bool(js.found):
            j_hz = _f(js.speed_rad_s) / TWO_PI
            speeds.append(np.linspace(0.98 * j_hz, 1.02 * j_hz, 81))
        speeds = np.unique(np.clip(np.concatenate(speeds), lo_hz, hi_hz))
        fmins = np.asarray(jax.vmap(lambda w: min_contact_force(cam, plant, closure, w, phi))(
            jnp.asarray(speeds) * TWO_PI))
        out["jump"] = {
            "search_range_hz": [lo_hz, hi_hz],
            "jump_speed_hz": _f(js.speed_rad_s) / TWO_PI if bool(js.found) else None,
            "min_contact_force": _f(jnp.min(force)),
            "contact_lost_at_cam_speed": bool(jnp.min(force) <= 0),
            "min_spring_preload": _f(min_preload(cam, plant, closure, omega, phi)),
            # inf (no rate helps: the spring is slack somewhere) is written as null
            "min_spring_rate": _finite_or_none(min_spring_rate(cam, plant, closure, omega, phi)),
        }
        curves.update(jump_speeds_hz=speeds, jump_fmin=fmins, contact_force=np.asarray(force))
    if "shaping" in spec.compute:
        c_phi, c_val = _constraints(scene)
        band = omega * jnp.linspace(spec.shaping_band[0], spec.shaping_band[1], 9)
        cam0 = pad_harmonics(cam, spec.shaping_harmonics)
        lift = max(float(np.max(c_val) - np.min(c_val)), 1e-300)
        res = shape_law(cam0, plant, band, jnp.asarray(c_phi), jnp.asarray(c_val), lift,
                        steps=spec.shaping_steps)
        shaped = pad_harmonics(res.cam, spec.harmonics)
        out["shaping"] = {
            "speed_band_hz": [spec.shaping_band[0] * spec.cam_speed_hz,
                              spec.shaping_band[1] * spec.cam_speed_hz],
            "harmonics": spec.shaping_harmonics,
            "initial_band_rms_tracking_error": _f(jnp.sqrt(band_tracking_ms(cam0, plant, band))),
            "band_rms_tracking_error": _f(res.tracking_rms),
            "max_tracking_error": _f(max_abs(tracking_error_harmonics(shaped, shaped, plant, omega),
                                             phi)),
            "constraint_max_violation": _f(res.constraint_max),
            "coefficients": {"cos": np.asarray(res.cam.cos).tolist(),
                             "sin": np.asarray(res.cam.sin).tolist()},
        }
        curves["shaped"] = np.asarray(evaluate_cam(shaped, phi).f)
        curves["shaped_load"] = np.asarray(evaluate_cam(steady_state(shaped, plant, omega), phi).f)
    return DynamicsReport(out, curves)
