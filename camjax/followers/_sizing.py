"""Exact sizing: the smallest admissible design variable with the limits held at every cam angle.

A follower's sizing rule finds the smallest x (an arm's start angle psi0, a prime radius R_p) at
which its per-angle limits g(theta; x) <= 0 (pressure angle, undercut, smallest radius of
curvature) hold. On the grid that is a search over x with the limits checked at the samples;
between two samples a limit can still be broken by ~N^-2 relative, so the grid's x is too small
by about that much. :func:`exact_boundary` starts from the grid's x and moves it to the root of

    G(x) = max over the cam angle of max_r g_r(theta; x),

with the max over the angle refined off the grid (:func:`camjax.extrema.refine_max`, every
candidate bracket of every segment checked). Since the refined max is never below the samples'
max, G(x) >= 0 at the grid's boundary and the exact boundary lies above it: the result is never
smaller than the grid's (never less safe), and G <= 0 holds there. The root is bracketed (the
bracket's upper end grows from a Newton estimate, envelope theorem, until G <= 0) and closed by
the Illinois variant of regula falsi (until it is a few ulps wide); the result is the bracket's
admissible end.

The limits must be functions of the motion (s and its derivatives) and of x: on a dwell they are
constant. Module-level and decorated with :func:`camjax.runtime.program_cache`, so that a compiled
(and a saved) program serves every call of the same limits, program layout and grid size.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from camjax import extrema as extrema_mod
from camjax import program as program_mod
from camjax import runtime
from camjax.program import Kinematics

# Newton steps towards the root before the bracket is closed (each a little past the Newton point).
EXPANSIONS = 40
NEWTON_OVERSHOOT = 1.01
# Points scanned between the last two Newton points when a step passed the admissible x.
SCAN = 32
# Illinois steps: superlinear, so a bracket of ~1e-3 relative closes to float64 in ~10; the rest
# are a margin for limits whose binding row switches inside the bracket (a kink of G).
ITERATIONS = 40

# limits(kin, x, params) -> (R, *kin.s.shape): the per-angle limits, <= 0 where admissible.
Limits = Callable[[Kinematics, jax.Array, Any], jax.Array]


class Boundary(NamedTuple):
    """The exact boundary (shape () each)."""

    x: jax.Array  # the smallest admissible x (the grid's where nothing had to move)
    angle_deg: jax.Array  # cam angle of the binding limit's peak at x, deg in [0, 360)
    row: jax.Array  # int: which limit binds there
    peak: jax.Array  # G(x) (<= 0 when refined)
    refined: jax.Array  # bool: False where no admissible x was found below ``hi`` (x is the grid's)


def peak(limits: Limits, prog, kin: Kinematics, x, params):
    """G(x): the largest limit over the cam angle, refined off the grid ``kin``; (value, angle in
    deg, row). Traceable."""
    bounds, constant = program_mod.segment_bounds_deg(prog), extrema_mod.dwells(prog)
    grid = limits(kin, x, params)
    rows = jnp.eye(grid.shape[0], dtype=grid.dtype)

    def fn(segment, theta_deg, both):
        xx, p, w = both
        return jnp.tensordot(w, limits(program_mod.segment_motion(prog, segment, theta_deg), xx, p), axes=1)

    e = jax.lax.map(lambda w: extrema_mod.refine_max(fn, (x, params, w), bounds, w @ grid, constant=constant),
                    rows)
    i = jnp.argmax(jnp.where(jnp.isnan(e.value), -jnp.inf, e.value))
    return e.value[i], e.angle_deg[i], i


@runtime.program_cache(static_argnames=("limits",))
def exact_boundary(prog, kin: Kinematics, x0, hi, params, limits: Limits) -> Boundary:
    """The smallest x in [x0, hi] with G(x) <= 0 (see the module docstring), from the grid's
    boundary ``x0`` (admissible at the samples); ``hi`` the end of the domain of x.

    Args:
      prog: the :class:`camjax.program.MotionProgram` behind the grid.
      kin: the grid's motion (N samples).
      x0, hi: shape () each.
      params: pytree of the limits' other arguments (arrays).
      limits: static, a module-level function ``limits(kin, x, params)``.
    """
    dtype = kin.s.dtype
    x0, hi = jnp.asarray(x0, dtype), jnp.asarray(hi, dtype)

    def g(x):
        return peak(limits, prog, kin, x, params)[0]

    value_and_slope = jax.value_and_grad(g)  # the slope by the envelope theorem

    # Newton steps from x0 while G > 0 and falls (a little past the root each: from a convex G's
    # infeasible side plain Newton would only creep up to it). The admissible x can form a narrow
    # window (a rocker's pressure angle limits the arm from both sides), so no blind growth: a
    # step that lands where G > 0 and rises has passed the root or found none
    def newton_cond(c):
        k, a, b, gb, sb = c
        return (gb > 0) & (sb < 0) & (k < EXPANSIONS) & (b < hi)

    def newton(c):
        k, a, b, gb, sb = c
        nb = jnp.minimum(b - NEWTON_OVERSHOOT * gb / sb, hi)
        gn, sn = value_and_slope(nb)
        return k + 1, b, nb, gn, sn

    g0, s0 = value_and_slope(x0)
    _, a, b, gb, sb = jax.lax.while_loop(newton_cond, newton, (0, x0, x0, g0, s0))
    inside = g0 > 0
    # passed it (G > 0 and rising at b): the first admissible point of a scan of [a, b], if any
    def scan(bracket):
        a, b, gb = bracket
        ts = a + (b - a) * jnp.linspace(0.0, 1.0, SCAN + 1, dtype=dtype)[1:]
        gs = jax.lax.map(g, ts)
        j = jnp.argmax(gs <= 0)
        hit = gs[j] <= 0
        return (jnp.where(hit & (j > 0), ts[jnp.maximum(j - 1, 0)], a), jnp.where(hit, ts[j], b),
                jnp.where(hit, gs[j], gb))

    a, b, gb = jax.lax.cond(gb > 0, scan, lambda bracket: bracket, (a, b, gb))
    found = ~inside | (gb <= 0)

    def illinois(c):
        k, a, fa, b, fb, side = c
        m = jnp.where(fa != fb, b - fb * (b - a) / (fa - fb), 0.5 * (a + b))
        m = jnp.where((m > a) & (m < b), m, 0.5 * (a + b))
        fm = g(m)
        bad = fm > 0
        # Illinois: halve the value at the end that stays twice in a row
        a2, fa2 = jnp.where(bad, m, a), jnp.where(bad, fm, jnp.where(side == 1, 0.5 * fa, fa))
        b2, fb2 = jnp.where(bad, b, m), jnp.where(bad, jnp.where(side == -1, 0.5 * fb, fb), fm)
        return k + 1, a2, fa2, b2, fb2, jnp.where(bad, -1, 1)

    def open_(c):  # the bracket is wider than a few ulps of x
        k, a, _, b, _, _ = c
        return (k < ITERATIONS) & (b - a > 4.0 * jnp.finfo(dtype).eps * jnp.abs(b))

    run = inside & found
    start = (0, jnp.where(run, a, x0), jnp.where(run, g(a), 1.0), jnp.where(run, b, x0),
             jnp.where(run, gb, 0.0), jnp.asarray(0))
    _, a, _, b, _, _ = jax.lax.while_loop(lambda c: run & open_(c), illinois, start)
    x = jnp.where(run, b, x0)
    value, angle, row = peak(limits, prog, kin, x, params)
    return Boundary(x, angle, row, value, found)


__all__ = ["EXPANSIONS", "ITERATIONS", "Boundary", "Limits", "exact_boundary", "peak"]
