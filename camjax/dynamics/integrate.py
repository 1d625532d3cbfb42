"""Time-domain integration over cam cycles: one periodic RK4 helper and the models it drives.

Every time-domain model of the package (the follower train, the drive with its flexible
coupling, the nonlinear compensation's drive equation) runs through :func:`periodic_rk4`: start
from a state, run whole cycles of M fixed RK4 steps until the transient has decayed, and return
the states over the last cycle. :func:`settling` says how many cycles that takes.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import runtime
from camjax.dynamics.harmonics import TWO_PI, CamHarmonics, cam_grid, evaluate_cam
from camjax.dynamics.plant import Plant, damping_ratio, natural_frequency_rad_s


def rk4_step(rhs, y, t, dt, u0, uh, u1):
    """One classical RK4 step of y' = rhs(t, y, u) with the input known at t, t+dt/2, t+dt.

    ``y`` is any pytree of arrays; local error O(dt^5), global O(dt^4).
    """
    k1 = rhs(t, y, u0)
    k2 = rhs(t + dt / 2, jax.tree_util.tree_map(lambda a, b: a + dt / 2 * b, y, k1), uh)
    k3 = rhs(t + dt / 2, jax.tree_util.tree_map(lambda a, b: a + dt / 2 * b, y, k2), uh)
    k4 = rhs(t + dt, jax.tree_util.tree_map(lambda a, b: a + dt * b, y, k3), u1)
    return jax.tree_util.tree_map(lambda a, b1, b2, b3, b4: a + dt / 6 * (b1 + 2 * b2 + 2 * b3 + b4),
                                  y, k1, k2, k3, k4)


def periodic_rk4(rhs, initial, dt, steps_per_cycle: int, n_cycles, half_step_inputs=None,
                 max_cycles: int | None = None):
    """Settle, then record the last cycle: ``n_cycles`` cycles of M fixed RK4 steps of length dt.

    Traceable. ``steps_per_cycle`` and ``max_cycles`` are Python ints (they set loop lengths);
    ``n_cycles`` is data: the settling loop runs ``max_cycles - 1`` times and skips (``lax.cond``)
    the cycles past ``n_cycles - 1``, so one compiled program runs every count up to the bound
    (a scene whose inertia or speed changes its settling count compiles nothing again). Skipped
    cycles cost a comparison each; ``jax.grad`` works (reverse mode stores every bounded cycle),
    and under ``vmap`` over ``n_cycles`` every cycle up to the bound is computed.

    Args:
      rhs: ``rhs(step, t, y, u) -> dy/dt``, with ``step`` the index j (traced int, 0..M-1) of the
        step within the cycle, ``t`` the time since that step's start (s: 0, dt/2 or dt), ``y``
        the state (a pytree) and ``u`` the input at that instant (or None).
      initial: state at t = 0 (a pytree of arrays).
      dt: step length, s (one cycle lasts M dt).
      steps_per_cycle: M.
      n_cycles: cycles to run (an integer >= 1, Python or array); the first n_cycles - 1 only
        settle the transient. Counts above ``max_cycles`` run ``max_cycles``.
      half_step_inputs: None or (2M,) periodic input at every step and half step of a cycle,
        u[2j] at the start of step j, u[2j+1] at its middle.
      max_cycles: the largest count this program runs; None: ``n_cycles`` itself (a Python int).

    Returns:
      The state at the start of each step of the last cycle: ``initial``'s pytree with a leading
      axis of M.
    """
    m = steps_per_cycle
    u = half_step_inputs

    def step(y, j):
        if u is None:
            u0 = uh = u1 = None
        else:
            u0, uh, u1 = u[2 * j], u[2 * j + 1], u[(2 * j + 2) % (2 * m)]
        y_next = rk4_step(lambda t, yy, uu: rhs(j, t, yy, uu), y, 0.0, dt, u0, uh, u1)
        return y_next, y

    def cycle(y):
        y, _ = jax.lax.scan(step, y, jnp.arange(m))
        return y

    def settle(y, k):
        return jax.lax.cond(k < n_cycles - 1, cycle, lambda y: y, y), None

    bound = cycle_bound(n_cycles, max_cycles)
    y, _ = jax.lax.scan(settle, initial, jnp.arange(bound - 1))
    _, last = jax.lax.scan(step, y, jnp.arange(m))
    return last


def cycle_bound(n_cycles, max_cycles: int | None) -> int:
    """The settling loop's bound: ``max_cycles``, else ``n_cycles`` as a Python int (>= 1)."""
    if max_cycles is None:
        try:
            max_cycles = int(n_cycles)
        except TypeError:  # a tracer (jax's ConcretizationTypeError is one) or no number at all
            raise TypeError("n_cycles: a traced cycle count needs max_cycles (a Python int) to bound "
                            "the settling loop") from None
    if int(max_cycles) < 1:
        raise ValueError(f"max_cycles: {max_cycles} must be >= 1")
    return int(max_cycles)


def cycles_data(n_cycles):
    """A cycle count as program data: an int32 scalar (NumPy where it is concrete: no device call),
    so that a program compiled for one count runs another."""
    if isinstance(n_cycles, jax.core.Tracer):
        return n_cycles.astype(jnp.int32)
    return np.int32(n_cycles)


class Settling(NamedTuple):
    """How many cycles a periodic run needs for its transient to decay (Python numbers)."""

    cycles: int  # cycles simulated: min(cycles_needed, max_cycles)
    cycles_needed: int | None  # for e^{-zeta omega_n t} to fall below the tolerance; None: never
    residual_factor: float  # e^{-zeta omega_n t} after ``cycles`` cycles (transient left)
    settled: bool  # residual_factor <= tolerance, i.e. max_cycles did not cut the run short


def settling(plant: Plant, cam_speed_rad_s: float, tolerance: float, max_cycles: int) -> Settling:
    """Cycles for a transient e^{-zeta omega_n t} of the train to fall below ``tolerance``.

    The count is capped at ``max_cycles`` (the scene's [dynamics].max_cycles); ``settled`` is
    False when the cap stopped it first. Undamped trains never settle. Not traceable (the count
    is a scan length).
    """
    decay = float(damping_ratio(plant) * natural_frequency_rad_s(plant))
    period = TWO_PI / float(cam_speed_rad_s)
    if decay <= 0:
        return Settling(int(max_cycles), None, 1.0, False)
    needed = math.ceil(math.log(1.0 / tolerance) / (decay * period)) + 1
    cycles = int(min(max_cycles, needed))
    residual = math.exp(-decay * cycles * period)
    return Settling(cycles, int(needed), residual, cycles >= needed)


def settling_cycles(plant: Plant, cam_speed_rad_s: float, tolerance: float, max_cycles: int) -> int:
    """``settling(...).cycles``: the cycles to simulate (capped at ``max_cycles``)."""
    return settling(plant, cam_speed_rad_s, tolerance, max_cycles).cycles


# ----------------------------------------------------------------------------- follower train


class TrainState(NamedTuple):
    """State of the load (scalars)."""

    angle: jax.Array  # theta3, m or rad
    rate: jax.Array  # theta3', m/s or rad/s


def integrate_train(plant: Plant, follower_half_steps: jax.Array, cam_speed_rad_s, n_cycles,
                    initial: TrainState | None = None, max_cycles: int | None = None) -> TrainState:
    """RK4 of the follower train driven by a periodic follower motion, from rest (or ``initial``).

    Args:
      plant: the follower train.
      follower_half_steps: (2M,) theta2 at cam angles phi_j = pi j / M: the values at every step
        and half step of one cycle of M steps (dt = 2 pi / (Omega M)).
      cam_speed_rad_s: Omega.
      n_cycles: cycles to integrate (an integer, data: see :func:`periodic_rk4`); the last one is
        returned.
      initial: state at t = 0; default theta3 = theta2(0), theta3' = 0.
      max_cycles: the largest ``n_cycles`` the compiled program runs (static); None: ``n_cycles``.

    Returns:
      TrainState of shape (M,) each: the load over the last cycle at phi_k = 2 pi k / M.
    """
    return _integrate_train(plant, follower_half_steps, cam_speed_rad_s, cycles_data(n_cycles), initial,
                            cycle_bound(n_cycles, max_cycles))


@partial(jax.jit, static_argnames=("max_cycles",))
def _integrate_train(plant, follower_half_steps, cam_speed_rad_s, n_cycles, initial, max_cycles: int):
    u = jnp.asarray(follower_half_steps)
    m = u.shape[0] // 2
    dt = TWO_PI / (cam_speed_rad_s * m)
    if initial is None:
        initial = TrainState(u[0], jnp.zeros_like(u[0]))

    def rhs(_step, _t, y, theta2):
        accel = (plant.stiffness * (theta2 - y.angle) - plant.damping * y.rate) / plant.inertia
        return TrainState(y.rate, accel)

    return periodic_rk4(rhs, initial, dt, m, n_cycles, u, max_cycles)


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


def simulate_drive(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s,
                   n_cycles, steps_per_cycle: int = 720, max_cycles: int | None = None) -> DriveResponse:
    """RK4 of the full model (SPEC 6, drive flexibility) from theta1 = Omega t, rest load.

    I1 theta1'' = k01 (theta0 - theta1) + c01 (theta0' - theta1') - T1,  T1 theta1' = T2 theta2',
    T2 = I2 theta2'' + k23 (theta2 - theta3),  theta2 = f(theta1),
    I3 theta3'' = k23 (theta2 - theta3) - c3 theta3',  theta0 = Omega t.
    Returns the last of ``n_cycles`` motor revolutions (data: see :func:`periodic_rk4`),
    M = ``steps_per_cycle``; ``max_cycles`` (static) bounds the count one compiled program runs
    (None: ``n_cycles``).
    """
    return _simulate_drive(cam, drive, plant, cam_speed_rad_s, cycles_data(n_cycles), steps_per_cycle,
                           cycle_bound(n_cycles, max_cycles))


@runtime.program_cache(static_argnames=("steps_per_cycle", "max_cycles"))
def _simulate_drive(cam: CamHarmonics, drive: Drive, plant: Plant, cam_speed_rad_s, n_cycles,
                    steps_per_cycle: int, max_cycles: int) -> DriveResponse:
    omega = cam_speed_rad_s
    m = steps_per_cycle
    dt = TWO_PI / (omega * m)
    rhs = _drive_rhs(cam, drive, plant, omega)
    f0 = evaluate_cam(cam, jnp.zeros(()))
    zero = jnp.zeros_like(f0.f)
    y0 = DriveState(zero, zero + omega, f0.f, zero)

    def rhs_cycle(j, t, y, _):
        # motor angle: the step's start (the cam law is 2 pi periodic) plus Omega t
        return rhs(TWO_PI * j / m + omega * t, y, None)

    last = periodic_rk4(rhs_cycle, y0, dt, m, n_cycles, max_cycles=max_cycles)
    motor = cam_grid(m, zero.dtype)
    theta1 = motor + last.cam_lag
    v = evaluate_cam(cam, theta1)
    rate = last.cam_rate
    spring = plant.stiffness * (v.f - last.load)
    accel1 = rhs(motor, last, None).cam_rate  # the drive equation, elementwise over the cycle
    accel2 = v.d2f * rate**2 + v.df * accel1
    torque = v.df * (drive.follower_inertia * accel2 + spring)
    return DriveResponse(theta1, rate, v.f, last.load, torque)
