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
# Floor on cos(pressure angle) in a roller's normal force P = F / cos phi: phi -> 90 deg is a
# jammed follower; the force saturates there (finite) and the pressure-angle constraint carries
# the gradient.
COS_FLOOR = 1e-12


class NonFiniteError(ValueError):
    """A result that came out inf or NaN: the inputs' magnitudes overflow float64."""


def finite_float(x, what: str = "a design result") -> float:
    """A scalar as a Python float; :class:`NonFiniteError` naming ``what`` if it is inf or NaN."""
    import numpy as np

    v = float(np.asarray(x))
    if not np.isfinite(v):
        raise NonFiniteError(f"non-finite value {v} in {what}")
    return v


def safe_sqrt(x: jax.Array) -> jax.Array:
    """sqrt(x) for x > 0, 0 otherwise; the gradient is 0 (not inf/nan) for x <= 0."""
    positive = x > 0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, x, 1.0)), 0.0)


def safe_divide(num: jax.Array, den: jax.Array, fallback: float = 0.0) -> jax.Array:
    """num / den where den != 0, ``fallback`` elsewhere, with finite gradients."""
    nonzero = den != 0
    return jnp.where(nonzero, num / jnp.where(nonzero, den, 1.0), fallback)


def capped_divide(num: jax.Array, den: jax.Array) -> jax.Array:
    """num / den, saturated at +/- the dtype's largest finite value where it would overflow.

    For quantities that legitimately blow up (a radius of curvature at an inflection, a guide
    force at jamming): finite in value and gradient for every input, den = 0 included (+max
    for 0 / 0). Double-where: the division never sees a denominator that would overflow.
    """
    cap = jnp.finfo(jnp.result_type(num, den, float)).max
    over = jnp.abs(den) * cap <= jnp.abs(num)
    sign = jnp.where((num < 0) != (den < 0), -1.0, 1.0)
    return jnp.where(over, sign * cap, num / jnp.where(over, 1.0, den))


def floor_positive(x: jax.Array, floor: float) -> jax.Array:
    """max(x, floor) whose gradient is 1 above the floor and exactly 0 below it."""
    return jnp.where(x > floor, x, floor)


def positive_part(x: jax.Array) -> jax.Array:
    """max(x, 0): the violation of a constraint written as x <= 0."""
    return jnp.maximum(x, 0.0)


# Relative accuracy camjax documents for a contact stress (README "Accuracy and limits").
STRESS_RTOL = {"float64": 1e-9, "float32": 1e-4}


def stress_relative_error_bound(base_radius_mm, s, d2s, rho_mm, dtype) -> jax.Array:
    """Round-off bound on the relative error of sigma = C / sqrt(rho), rho = R_b + s + s''.

    rho is a difference of terms of size R_b + |s| + |s''|; near the curvature limit it cancels
    and its relative error grows like eps (R_b + |s| + |s''|) / rho, halved by the square root.
    A few ulps of the law evaluation itself are covered by the factor 4.
    """
    eps = jnp.finfo(dtype).eps
    scale = jnp.abs(base_radius_mm) + jnp.abs(s) + jnp.abs(d2s)
    return 4.0 * 0.5 * eps * safe_divide(scale, jnp.abs(rho_mm), fallback=jnp.inf)


def precision_warning(base_radius_mm, s, d2s, rho_mm, dtype) -> str | None:
    """A message when the dtype cannot deliver the documented stress accuracy, else None.

    Not traceable (returns a Python string): call it on concrete arrays, after a solve.
    """
    name = jnp.dtype(dtype).name
    bound = float(jnp.max(stress_relative_error_bound(base_radius_mm, s, d2s, rho_mm, dtype)))
    tol = STRESS_RTOL.get(name, STRESS_RTOL["float32"])
    if bound <= tol:
        return None
    return (f"{name}: the contact stress may be off by up to {bound:.1e} (relative) because the "
            f"radius of curvature ({float(jnp.min(rho_mm)):.3g} mm) is a small difference of large "
            f"terms; documented tolerance {tol:g}. Use float64 for designs this close to rho = 0.")


# Longest run of angles reduced in one piece by :func:`max_over_angles`.
ANGLE_TILE = 8192


def max_over_angles(fn, *per_angle: jax.Array, tile: int = ANGLE_TILE, pad_value: float = 0.0) -> jax.Array:
    """max over angles of ``fn(*per_angle)`` (arrays of shape (n,)), computed tile by tile.

    Same value as ``jnp.max(fn(*per_angle))`` (a max is exact in any order). On XLA:CPU a
    reduction whose rows pass ~16k elements leaves its fast path and runs ~15x slower per
    element (benchmarks/, "cost in N"); evaluating ``fn`` and reducing on tiles of <= ``tile``
    angles with ``lax.map`` keeps the cost linear in the number of angles. The last tile is
    padded with ``pad_value`` in every input: ``fn`` of the padding must not exceed the max.
    """
    n = per_angle[0].shape[-1]
    if n <= tile:
        return jnp.max(fn(*per_angle))
    pad = (-n) % tile
    tiles = [jnp.pad(a, (0, pad), constant_values=pad_value).reshape(-1, tile) for a in per_angle]
    return jnp.max(jax.lax.map(lambda ts: jnp.max(fn(*ts)), tuple(tiles)))
