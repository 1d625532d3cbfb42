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


class _Search(NamedTuple):
    """State of :func:`exact_boundary`'s one loop (shape () each, ``gs``/``ts`` (SCAN,))."""

    stage: jax.Array  # int: NEWTON, SCAN or ILLINOIS_START, ILLINOIS, FINAL, DONE
    point: jax.Array  # the x the next pass evaluates G at
    g0: jax.Array  # G(x0)
    k: jax.Array  # int: Newton steps taken, then Illinois steps
    a: jax.Array  # the bracket [a, b] and G, G' or G at its ends (Newton: G and G' at b)
    b: jax.Array
    fa: jax.Array
    fb: jax.Array
    sb: jax.Array
    side: jax.Array  # int: Illinois, the end that moved last (-1 a, 1 b)
    run: jax.Array  # bool: the root is bracketed inside, closed by Illinois
    ts: jax.Array  # the scan's points and G there
    gs: jax.Array
    boundary: Boundary


# stages of exact_boundary's loop, each pass one evaluation of G (and G') at ``point``
_NEWTON, _SCAN, _ILLINOIS_START, _ILLINOIS, _FINAL, _DONE = range(6)


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

    The search's stages (Newton steps, a scan, Illinois steps, the boundary's peak) run as one
    loop whose every pass evaluates G and its slope once, switched on the stage (as
    :mod:`camjax.extrema` refines): the refined peak is traced once, not once per stage.
    """
    dtype = kin.s.dtype
    x0, hi = jnp.asarray(x0, dtype), jnp.asarray(hi, dtype)

    def full(x):
        value, angle, row = peak(limits, prog, kin, x, params)
        return value, (angle, row)

    value_and_slope = jax.value_and_grad(full, has_aux=True)  # the slope by the envelope theorem

    # Newton steps from x0 while G > 0 and falls (a little past the root each: from a convex G's
    # infeasible side plain Newton would only creep up to it). The admissible x can form a narrow
    # window (a rocker's pressure angle limits the arm from both sides), so no blind growth: a
    # step that lands where G > 0 and rises has passed the root or found none
    def newton_cond(k, b, gb, sb):
        return (gb > 0) & (sb < 0) & (k < EXPANSIONS) & (b < hi)

    def illinois_point(a, fa, b, fb):
        m = jnp.where(fa != fb, b - fb * (b - a) / (fa - fb), 0.5 * (a + b))
        return jnp.where((m > a) & (m < b), m, 0.5 * (a + b))

    def open_(k, a, b):  # the bracket is wider than a few ulps of x
        return (k < ITERATIONS) & (b - a > 4.0 * jnp.finfo(dtype).eps * jnp.abs(b))

    def after_illinois(s: _Search) -> _Search:  # the next Illinois step, or the boundary's peak
        more = s.run & open_(s.k, s.a, s.b)
        x = jnp.where(s.run, s.b, x0)
        return s._replace(stage=jnp.where(more, _ILLINOIS, _FINAL),
                          point=jnp.where(more, illinois_point(s.a, s.fa, s.b, s.fb), x))

    def newton(s: _Search, g, slope, _aux) -> _Search:
        first = s.k < 0  # the pass at x0
        g0 = jnp.where(first, g, s.g0)
        k, a, b = jnp.where(first, 0, s.k + 1), jnp.where(first, x0, s.b), s.point
        s = s._replace(g0=g0, k=k, a=a, b=b, fb=g, sb=slope)
        more = newton_cond(k, b, g, slope)
        nb = jnp.minimum(b - NEWTON_OVERSHOOT * g / slope, hi)
        # passed it (G > 0 and rising at b): a scan of [a, b] for its first admissible point
        scan = g > 0
        ts = a + (b - a) * jnp.linspace(0.0, 1.0, SCAN + 1, dtype=dtype)[1:]
        return s._replace(stage=jnp.where(more, _NEWTON, jnp.where(scan, _SCAN, _ILLINOIS_START)),
                          point=jnp.where(more, nb, jnp.where(scan, ts[0], a)), k=jnp.where(more, k, 0), ts=ts)

    def scan(s: _Search, g, _slope, _aux) -> _Search:
        gs = s.gs.at[s.k].set(g)
        k = s.k + 1
        done = k >= SCAN
        j = jnp.argmax(gs <= 0)
        hit = gs[j] <= 0
        a = jnp.where(hit & (j > 0), s.ts[jnp.maximum(j - 1, 0)], s.a)
        b, gb = jnp.where(hit, s.ts[j], s.b), jnp.where(hit, gs[j], s.fb)
        return s._replace(stage=jnp.where(done, _ILLINOIS_START, _SCAN), gs=gs, k=jnp.where(done, 0, k),
                          point=jnp.where(done, a, s.ts[jnp.minimum(k, SCAN - 1)]),
                          a=jnp.where(done, a, s.a), b=jnp.where(done, b, s.b), fb=jnp.where(done, gb, s.fb))

    def illinois_start(s: _Search, g, _slope, _aux) -> _Search:
        found = ~(s.g0 > 0) | (s.fb <= 0)
        run = (s.g0 > 0) & found
        s = s._replace(run=run, a=jnp.where(run, s.a, x0), fa=jnp.where(run, g, 1.0), b=jnp.where(run, s.b, x0),
                       fb=jnp.where(run, s.fb, 0.0), side=jnp.asarray(0), k=jnp.asarray(0),
                       boundary=s.boundary._replace(refined=found))
        return after_illinois(s)

    def illinois(s: _Search, fm, _slope, _aux) -> _Search:
        a, fa, b, fb, side, m = s.a, s.fa, s.b, s.fb, s.side, s.point
        bad = fm > 0
        # Illinois: halve the value at the end that stays twice in a row
        a2, fa2 = jnp.where(bad, m, a), jnp.where(bad, fm, jnp.where(side == 1, 0.5 * fa, fa))
        b2, fb2 = jnp.where(bad, b, m), jnp.where(bad, jnp.where(side == -1, 0.5 * fb, fb), fm)
        return after_illinois(s._replace(k=s.k + 1, a=a2, fa=fa2, b=b2, fb=fb2, side=jnp.where(bad, -1, 1)))

    def final(s: _Search, value, _slope, aux) -> _Search:
        angle, row = aux
        return s._replace(stage=jnp.asarray(_DONE), boundary=s.boundary._replace(
            x=s.point, angle_deg=angle, row=row, peak=value))

    def body(s: _Search) -> _Search:
        (value, aux), slope = value_and_slope(s.point)
        branches = [lambda *a, f=f: _typed(f(*a), s) for f in (newton, scan, illinois_start, illinois, final)]
        return jax.lax.switch(s.stage, branches, s, value, slope, aux)

    zero, int0 = jnp.zeros((), dtype), jnp.zeros((), jnp.int32)
    row0 = jnp.zeros((), int)  # jnp.argmax's
    start = _Search(int0 + _NEWTON, x0, zero, int0 - 1, x0, x0, zero, zero, zero, int0,
                    jnp.zeros((), bool), jnp.zeros((SCAN,), dtype), jnp.zeros((SCAN,), dtype),
                    Boundary(x0, zero, row0, zero, jnp.zeros((), bool)))
    return jax.lax.while_loop(lambda s: s.stage != _DONE, body, start).boundary


def _typed(new, like):
    """``new`` with the dtypes of ``like`` (a loop carry keeps its types)."""
    return jax.tree.map(lambda x, y: jax.lax.convert_element_type(x, y.dtype), new, like)


__all__ = ["EXPANSIONS", "ITERATIONS", "Boundary", "Limits", "exact_boundary", "peak"]
