"""Gradient-based law shaping (goes beyond source 003): the cam law that minimizes residual
vibration over a speed band, with the lift and the dwells pinned, by L-BFGS through the
steady-state dynamics.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import optax

from camjax import runtime
from camjax.dynamics.harmonics import CamHarmonics, evaluate_cam, mean_square
from camjax.dynamics.plant import Plant, tracking_error_harmonics


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


@runtime.program_cache(static_argnames=("steps",))
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
