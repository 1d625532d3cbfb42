"""Numerically safe primitives: the one home for everything that can blow up.

Every function here is finite in value *and* gradient for any finite input, using the
double-``where`` trick: the unsafe branch is fed a harmless value where it would misbehave, so
that ``0 * inf`` never appears in a cotangent.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

# Floor on a radius of curvature (mm) used where a stress needs 1/sqrt(rho). Below it the
# profile is treated as a corner: the stress saturates at a huge but finite value and the
# curvature constraint (which has its own penalty) carries the gradient.
RHO_FLOOR_MM = 1e-15


def safe_sqrt(x: jax.Array) -> jax.Array:
    """sqrt(x) for x > 0, 0 otherwise; the gradient is 0 (not inf/nan) for x <= 0."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def safe_divide(num: jax.Array, den: jax.Array, fallback: float = 0.0) -> jax.Array:
    """num / den where den != 0, ``fallback`` elsewhere, with finite gradients."""
    nonzero = den != 0
    return jnp.where(nonzero, num / jnp.where(nonzero, den, 1.0), fallback)


def floor_positive(x: jax.Array, floor: float) -> jax.Array:
    """max(x, floor) whose gradient is 1 above the floor and exactly 0 below it."""
    return jnp.where(x > floor, x, floor)


def smooth_max(x: jax.Array, temperature: jax.Array | float, axis: int | None = None) -> jax.Array:
    """Log-sum-exp upper bound on max(x): max(x) <= smooth_max(x) <= max(x) + T*log(n).

    Use it for gradients only; report ``jnp.max``. ``temperature`` is in the units of ``x``.
    """
    return temperature * jax.nn.logsumexp(x / temperature, axis=axis)


def positive_part(x: jax.Array) -> jax.Array:
    """max(x, 0): the violation of a constraint written as x <= 0."""
    return jnp.maximum(x, 0.0)


def argmax_deg(values: jax.Array, theta_deg: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(max, angle in degrees where it occurs) of a sampled curve."""
    i = jnp.argmax(values)
    return values[i], theta_deg[i]


def argmin_deg(values: jax.Array, theta_deg: jax.Array) -> tuple[jax.Array, jax.Array]:
    """(min, angle in degrees where it occurs) of a sampled curve."""
    i = jnp.argmin(values)
    return values[i], theta_deg[i]
