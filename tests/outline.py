"""A follower riding on an exported cam outline, found from the outline alone (shared by the geometry tests).

The follower's position at a cam angle is the largest value over the outline's parameter tau of a
per-point function (the roller-centre height or arm angle at which that outline point stops the
follower). :func:`max_over_outline` takes that maximum: a dense grid over tau brackets the
maximizer and golden-section refinement in tau finishes it; the value is stationary there, so a tau
error delta costs ~delta^2 in the value.
"""

import math

import jax
import jax.numpy as jnp


def turn(x, y, angle):
    """(x, y) turned by ``angle`` (rad, counter-clockwise) about the origin; any array shapes."""
    return jnp.cos(angle) * x - jnp.sin(angle) * y, jnp.sin(angle) * x + jnp.cos(angle) * y


def max_over_outline(value, theta_deg, dense=7200, iters=90):
    """max over tau in [0, 360) deg of ``value(tau_deg, theta_rad)`` at each cam angle ``theta_deg``.

    ``value`` maps a tau grid (m,) and one cam angle (rad) to (m,) values (-inf where a point does
    not touch); returns shape ``theta_deg.shape`` (1-D). ``dense`` grid points bracket the maximizer
    to one grid step, ``iters`` golden-section steps shrink the bracket by 0.618 each.
    """
    th = jnp.deg2rad(jnp.asarray(theta_deg))
    grid = jnp.arange(dense) * (360.0 / dense)
    k = jnp.argmax(jax.vmap(lambda t: value(grid, t))(th), axis=1)
    lo, hi = grid[k] - 360.0 / dense, grid[k] + 360.0 / dense
    g = (math.sqrt(5) - 1) / 2
    h = jax.jit(jax.vmap(value))
    for _ in range(iters):
        a, b = hi - g * (hi - lo), lo + g * (hi - lo)
        up = h(a, th) < h(b, th)
        lo, hi = jnp.where(up, a, lo), jnp.where(up, hi, b)
    return h(0.5 * (lo + hi), th)
