"""Exact extrema over the cam angle: the grid finds where, a 1-D solve makes the value exact.

Every quantity camjax takes a max or min of (a kinematic curve, a force, a radius of curvature, a
stress) is a function of the cam angle that is analytic inside each segment of the motion
program (SPEC 3, "Extrema"). The sample grid brackets its extremum; :func:`refine_max` then
solves f'(theta) = 0 inside the segment that holds the bracket, by safeguarded Newton on f' with
bisection fallback and derivatives from ``jax.jvp`` through the closed-form laws. At a joint a
jump can put the extremum on the joint itself: each segment's one-sided limits at its two ends
are candidates too.

Candidates. In every segment the ``candidates`` best local maxima of its samples (the segment's
two one-sided end values included) are refined, and the largest refined value wins, so a second
peak just below the grid's best sample is not lost to the grid's error.

Gradients with respect to the design (anything in ``params``) follow the envelope theorem: the
angle is found with the parameters under ``stop_gradient`` and the value is the function at that
fixed angle, so d(max f)/dp = df/dp at the argmax (also at a joint or a segment end, whose
position does not depend on the design).

Everything here works under ``jit``, ``vmap`` and ``grad``: the segment layout and the grid size
are static, the iteration count is fixed (``lax.fori_loop``), and no branch depends on a traced
value. A degenerate segment (a dwell, a constant velocity: f' = 0 throughout) is never bracketed
and keeps its grid value; nothing returns NaN.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import program as program_mod
from camjax.numerics import safe_divide
from camjax.program import Kinematics, MotionProgram

# Safeguarded Newton converges in ~5 steps from the scanned bracket (1/8 of two samples); 20
# steps also let pure bisection (the fallback, e.g. at a kink of f') shrink it ~1e6-fold, where a
# smooth maximum's value is exact to ~1e-15 relative (the error is quadratic in the angle).
ITERATIONS = 20
# Values of the scene's [motion] extrema switch: refined off the grid, or the grid's samples.
EXTREMA_MODES = ("exact", "grid")
# Steps in which a candidate's two-sample bracket is scanned for the sign change of f'.
SCAN_POINTS = 8
# Local maxima refined per segment: the best and the runner-up.
CANDIDATES = 2

# fn(segment, theta_deg, params) -> values: segment is an integer array of shape () (the closed
# form to use; mapped over the segments with vmap, so fn is traced once for all of them:
# camjax.program.segment_motion takes it as it is), theta_deg an array of angles inside that
# segment (deg), values of the same shape; elementwise.
SegmentFunction = Callable[[jax.Array, jax.Array, Any], jax.Array]
# quantity(kin, params) -> values, elementwise over the angles of ``kin``.
Quantity = Callable[[Kinematics, Any], jax.Array]


class Extremum(NamedTuple):
    """A refined max or min over the cam angle (shape () each)."""

    value: jax.Array  # units of the quantity
    angle_deg: jax.Array  # where it occurs, deg in [0, 360)


def segment_sample_ranges(bounds_deg, samples: int) -> tuple[tuple[int, int], ...]:
    """[first, last + 1) indices of the grid samples k 360 / N that lie in each segment.

    The same rule as :func:`camjax.program.motion_at`: a sample on a joint belongs to the
    segment that starts there, and the last segment takes everything from its start on.
    """
    theta = np.arange(samples) * (360.0 / samples)
    out = []
    for j, (lo, hi) in enumerate(bounds_deg):
        inside = theta >= lo if j == len(bounds_deg) - 1 else (theta >= lo) & (theta < hi)
        idx = np.flatnonzero(inside)
        out.append((int(idx[0]), int(idx[-1]) + 1) if idx.size else (0, 0))
    return tuple(out)


def _value_slope_curvature(fn: SegmentFunction, segment: int, theta_deg, params):
    """f(theta), f'(theta) and f''(theta) (per deg, per deg^2) by forward-mode AD through the closed form."""
    ones = jnp.ones_like(theta_deg)

    def value_and_slope(t):
        return jax.jvp(lambda u: fn(segment, u, params), (t,), (ones,))

    (f, g), (_, h) = jax.jvp(value_and_slope, (theta_deg,), (ones,))
    return f, g, h


def _brackets(ends, angles, samples, m, k):
    """Brackets of the ``k`` best local maxima on one segment's sub-grid ([start] + its samples +
    [end], padded to a common length).

    Args:
      ends: (2,) the segment's one-sided limits at its start and end.
      angles: (M,) the sub-grid's angles (deg); M >= m, the padding repeats the start.
      samples: (M,) the grid's values at its samples, -inf at the two ends and in the padding.
      m: the sub-grid's own length (its samples + 2), shape ().
      k: static number of brackets.

    Returns (a, c, b), each of shape (k,): bracket ends and the sample in between (deg).
    """
    position = jnp.arange(angles.shape[0])
    vals = jnp.where(position == 0, ends[0], jnp.where(position == m - 1, ends[1], samples))
    dtype = vals.dtype
    left = jnp.concatenate([jnp.full((1,), -jnp.inf, dtype), vals[:-1]])
    right = jnp.concatenate([vals[1:], jnp.full((1,), -jnp.inf, dtype)])
    local = (vals >= left) & (vals >= right)
    # rank local maxima first, by value; the rest (masked to -inf) only fill the k slots, lower
    # positions first (top_k's order on ties), so the padding comes after every real point
    _, idx = jax.lax.top_k(jnp.where(local, vals, -jnp.inf), k)
    return angles[jnp.maximum(idx - 1, 0)], angles[idx], angles[jnp.minimum(idx + 1, m - 1)]


def _sub_grids(bounds_deg, ranges, grid_values):
    """The sub-grids of :func:`_brackets` for the given segments, padded to a common length M:
    angles (S, M), samples (S, M) and lengths m (S,)."""
    n, dtype = grid_values.shape[0], grid_values.dtype
    size = max(i1 - i0 + 2 for i0, i1 in ranges)
    angles, samples = [], []
    for (lo, hi), (i0, i1) in zip(bounds_deg, ranges, strict=True):
        pad = size - (i1 - i0 + 2)
        # the grid's own angle expression (program.sample_angles_deg), so samples match bitwise
        at = jnp.arange(i0, i1, dtype=dtype) * (360.0 / n)
        angles.append(jnp.concatenate([jnp.asarray([lo], dtype), at, jnp.asarray([hi], dtype),
                                       jnp.full((pad,), lo, dtype)]))
        samples.append(jnp.concatenate([jnp.full((1,), -jnp.inf, dtype), grid_values[i0:i1],
                                        jnp.full((pad + 1,), -jnp.inf, dtype)]))
    lengths = jnp.asarray([i1 - i0 + 2 for i0, i1 in ranges])
    return jnp.stack(angles), jnp.stack(samples), lengths


def _scan_angles(a0, b0, points):
    """``points`` + 1 equally spaced angles over each bracket [a0, b0] (shape (..., k)): shape
    (..., k, points + 1)."""
    frac = jnp.linspace(0.0, 1.0, points + 1, dtype=a0.dtype)
    return a0[..., None] + (b0 - a0)[..., None] * frac


def _sub_bracket(t, f, g):
    """From f and f' at the scan angles ``t`` (shape (k, points + 1) each): the step where f' turns
    from + to - with the largest f at its ends (shape (k,) each: a, b, bracketed, and the best
    point seen).

    Two samples' bracket can hold a peak and a trough (f' + - + at its ends and middle: a
    cycloid's s'' between a joint and x = 1/2): the ends' slopes alone would miss the peak.
    """
    f = jnp.where(jnp.isnan(f), -jnp.inf, f)
    turns = (g[:, :-1] > 0) & (g[:, 1:] < 0)
    height = jnp.where(turns, jnp.maximum(f[:, :-1], f[:, 1:]), -jnp.inf)
    m = jnp.argmax(height, axis=1)
    rows = jnp.arange(t.shape[0])
    best = t[rows, jnp.argmax(f, axis=1)]
    return t[rows, m], t[rows, m + 1], jnp.any(turns, axis=1), best


def _newton_step(a, b, x, bracketed, g, h):
    """One safeguarded Newton step on f' = 0 inside [a, b] (f'(a) > 0 > f'(b) while bracketed),
    from g = f'(x) and h = f''(x): the new (a, b, x)."""
    rising = g > 0
    a = jnp.where(bracketed & rising, x, a)
    b = jnp.where(bracketed & ~rising, x, b)
    newton = x - safe_divide(g, h)
    # Newton only towards a maximum (h < 0) and inside the shrunk bracket, else bisect; the ends
    # count as inside: once converged, a Newton step lands on x, which is now an end
    take = (h < 0) & (newton >= a) & (newton <= b)
    step = jnp.where(take, newton, 0.5 * (a + b))
    return a, b, jnp.where(bracketed & (g != 0), step, x)


def _finalist(angles, values, valid):
    """The angle of the largest value (NaN and invalid entries lose), shape ()."""
    return angles[jnp.argmax(jnp.where(valid & ~jnp.isnan(values), values, -jnp.inf))]


class _Search(NamedTuple):
    """State of the segments' refinement (S segments, k candidates each)."""

    a0: jax.Array  # (S, k) the candidates' two-sample brackets and the sample between (deg)
    c: jax.Array
    b0: jax.Array
    f: jax.Array  # (S, k, points + 1) f and f' at the scan's angles, filled a column per pass
    g: jax.Array
    a: jax.Array  # (S, k) the scanned sub-brackets, shrunk by the Newton steps (deg)
    b: jax.Array
    x: jax.Array  # (S, k) the Newton iterate (deg)
    bracketed: jax.Array  # (S, k) bool: the scan found f' turning from + to -
    best: jax.Array  # (S, k) the scan's best point (deg)
    finals: jax.Array  # (S, 3, k) f at (c, best, x), filled a row per pass
    angle: jax.Array  # (S,) the result: best of (c, best, x) over the candidates (deg)


def _refine_segments(fn, segments, bounds_deg, ranges, grid_values, params, candidates, iterations, points):
    """The angle of the max on each of ``segments`` (deg, shape (S,)): best of (the sample, the
    scan's best point, the refined root) over each segment's ``candidates`` brackets.

    One loop over all the segments, whose every pass evaluates f, f', f'' of each segment at k
    angles (``fn`` mapped over the segment index, so traced once for all the segments, as is the
    search around it); what a pass does with them is switched on its number (only that stage runs). Pass 0:
    the segments' one-sided end values, which pick the brackets; the next ``points`` + 1: the
    scan of the brackets, a column of angles each; then ``iterations`` Newton steps; the last
    three: f at the candidates' samples, the scan's best points and the Newton iterates.
    """
    dtype = grid_values.dtype
    bounds = [bounds_deg[j] for j in segments]
    angles, samples, lengths = _sub_grids(bounds, [ranges[j] for j in segments], grid_values)
    count, k = len(segments), min(candidates, angles.shape[1])
    # a segment with fewer points than k brackets: its extra slots (in the padding) do not count
    valid = jnp.tile(jnp.arange(k)[None, :] < lengths[:, None], (1, 3))
    width = max(2, k)
    first_newton = 2 + points
    first_final = first_newton + iterations
    starts = jnp.asarray([lo for lo, _ in bounds], dtype)[:, None]
    ends = jnp.asarray(bounds, dtype)
    frac = jnp.linspace(0.0, 1.0, points + 1, dtype=dtype)  # as _scan_angles has it
    segment_index = jnp.asarray(segments)

    def pad(t):  # unused lanes hold the segment's start: f stays finite there
        return jnp.concatenate([t, jnp.broadcast_to(starts, (count, width - t.shape[1]))], axis=1)

    def body(i, s: _Search) -> _Search:
        stage = (i >= 1).astype(int) + (i >= first_newton) + (i >= first_final)
        column, row = jnp.clip(i - 1, 0, points), jnp.clip(i - first_final, 0, 2)
        finalists = jnp.stack([s.c, s.best, s.x], axis=1)
        t = jax.lax.switch(stage, [lambda: pad(ends), lambda: pad(s.a0 + (s.b0 - s.a0) * frac[column]),
                                   lambda: pad(s.x), lambda: pad(finalists[:, row])])
        f, g, h = jax.vmap(lambda j, tj: _value_slope_curvature(fn, j, tj, params))(segment_index, t)
        f_ends, f, g, h = f[:, :2], f[:, :k], g[:, :k], h[:, :k]

        def after_ends():
            a0, c, b0 = jax.vmap(_brackets, (0, 0, 0, 0, None))(f_ends, angles, samples, lengths, k)
            return s._replace(a0=a0, c=c, b0=b0)

        def after_scan():
            fs, gs = s.f.at[:, :, column].set(f), s.g.at[:, :, column].set(g)
            a, b, bracketed, best = jax.vmap(_sub_bracket)(_scan_angles(s.a0, s.b0, points), fs, gs)
            return s._replace(f=fs, g=gs, a=a, b=b, x=0.5 * (a + b), bracketed=bracketed, best=best)

        def after_newton():
            a, b, x = _newton_step(s.a, s.b, s.x, s.bracketed, g, h)
            return s._replace(a=a, b=b, x=x)

        def after_final():
            finals = s.finals.at[:, row].set(f)
            angle = jax.vmap(_finalist)(finalists.reshape(count, -1), finals.reshape(count, -1), valid)
            return s._replace(finals=finals, angle=angle)

        return jax.lax.switch(stage, [after_ends, after_scan, after_newton, after_final])

    # the initial values are never read (each stage writes what the next reads); they are
    # selected on a test of the grid values so that under vmap they are batched like the values
    # the passes write, and the loop body is batched once (not again once the carry turns out
    # batched)
    batched = jnp.isnan(samples[:, :1]) | True
    start = jnp.where(batched, starts, 0.0) * jnp.ones((1, k), dtype)
    scan = jnp.where(batched[:, :, None], jnp.zeros((count, k, points + 1), dtype), 0.0)
    finals = jnp.where(batched[:, :, None], jnp.zeros((count, 3, k), dtype), 0.0)
    state = _Search(start, start, start, scan, scan, start, start, start, start > starts, start, finals,
                    start[:, 0])
    return jax.lax.fori_loop(0, first_final + 3, body, state).angle


def refine_max(fn: SegmentFunction, params: Any, bounds_deg, grid_values: jax.Array, *,
               candidates: int = CANDIDATES, iterations: int = ITERATIONS,
               constant: tuple[bool, ...] | None = None) -> Extremum:
    """The continuous max over the cam angle of a function known in closed form per segment.

    Args:
      fn: ``fn(segment, theta_deg, params)``: the function on segment ``segment`` (an integer
        array of shape (): :data:`SegmentFunction`) at angles ``theta_deg`` (deg, inside that
        segment; its ends give the one-sided limits), elementwise, differentiable in ``theta_deg``
        (twice) and in ``params``.
      params: pytree the function depends on (the design, the program); gradients flow to it.
      bounds_deg: static ((start, end), ...) of the segments, deg, covering [0, 360) in order.
      grid_values: (N,) the function on the grid k 360 / N (N = grid_values.shape[0]), as the
        caller already has it: it only locates the candidates.
      candidates: local maxima refined per segment.
      iterations: Newton/bisection steps per candidate (fixed, so the call vmaps predictably).
      constant: static flags, one per segment, for segments on which ``fn`` is known to be
        constant (a dwell, for a function of the motion alone): only their start is evaluated.

    Returns:
      :class:`Extremum` (value, angle_deg). The value is never below any grid sample's value of
      ``fn`` and never below a one-sided limit at a joint.
    """
    e = refine_max_segments(fn, params, bounds_deg, grid_values, candidates=candidates, iterations=iterations,
                            constant=constant)
    i = jnp.argmax(jnp.where(jnp.isnan(e.value), -jnp.inf, e.value))
    return Extremum(e.value[i], jnp.mod(e.angle_deg[i], 360.0))


def refine_max_segments(fn: SegmentFunction, params: Any, bounds_deg, grid_values: jax.Array, *,
                        candidates: int = CANDIDATES, iterations: int = ITERATIONS,
                        constant: tuple[bool, ...] | None = None) -> Extremum:
    """The continuous max of each segment (shape (S,) each: values, angles in deg): what
    :func:`refine_max` takes the largest of (same arguments). A constraint that must hold at
    every angle is each of these values; a design step that lowers one peak can raise another."""
    frozen = jax.lax.stop_gradient(params)
    n = grid_values.shape[0]
    ranges = segment_sample_ranges(bounds_deg, n)
    constant = constant or (False,) * len(bounds_deg)
    active = [j for j in range(len(bounds_deg)) if not constant[j]]
    if active:
        # the grid values only locate the candidates: nothing in the search is differentiated
        refined = jax.lax.stop_gradient(_refine_segments(fn, active, bounds_deg, ranges,
                                                         jax.lax.stop_gradient(grid_values), frozen,
                                                         candidates, iterations, SCAN_POINTS))
    angles = jnp.stack([jnp.asarray(lo, grid_values.dtype) if constant[j] else refined[active.index(j)]
                        for j, (lo, _) in enumerate(bounds_deg)])
    # envelope theorem: live params, frozen angle; fn traced once for every segment
    values = jax.vmap(lambda j, at: fn(j, at, params))(jnp.arange(len(bounds_deg)), angles)
    return Extremum(values, angles)


def refine_min(fn: SegmentFunction, params: Any, bounds_deg, grid_values: jax.Array, **kwargs) -> Extremum:
    """The continuous min; see :func:`refine_max` (same arguments)."""
    e = refine_max(lambda j, t, p: -fn(j, t, p), params, bounds_deg, -grid_values, **kwargs)
    return Extremum(-e.value, e.angle_deg)


def refine_curves(curves: SegmentFunction, params: Any, bounds_deg, grid: jax.Array, *,
                  constant: tuple[bool, ...] | None = None):
    """Max and min over the cam angle of each of Q curves, refined off their grid values.

    ``curves(segment, theta_deg, params)`` gives the Q curves stacked (shape (Q, *theta.shape));
    ``grid`` (Q, N) their values on the grid. One refinement per (curve, sense): the function
    refined is w . curves with w = +-e_q, mapped over the rows w one at a time (``lax.map``, not
    ``vmap``: the refinement is traced once and not batched again, which costs far more time than
    the rows' sequential run saves). A row sees its own curve only: another curve that is not
    finite somewhere (say one taken at a base radius where it has no meaning) does not reach it.
    Returns (max, max_deg, min, min_deg), each of shape (Q,).
    """
    count = grid.shape[0]

    def fn(segment, theta_deg, both):
        p, w = both
        c = curves(segment, theta_deg, p)
        mine = (w != 0).reshape(w.shape + (1,) * (c.ndim - 1))
        return jnp.tensordot(w, jnp.where(mine, c, 0.0), axes=1)

    weights = jnp.concatenate([jnp.eye(count, dtype=grid.dtype), -jnp.eye(count, dtype=grid.dtype)])
    e = jax.lax.map(lambda w: refine_max(fn, (params, w), bounds_deg, w @ grid, constant=constant), weights)
    return e.value[:count], e.angle_deg[:count], -e.value[count:], e.angle_deg[count:]


def sampled_extremes(grid, theta_deg):
    """(max, max_deg, min, min_deg) of each row of ``grid`` (Q, N) over its samples at ``theta_deg``
    (N,) (NumPy; the first sample wins on ties): the ``extrema = "grid"`` counterpart of
    :func:`refine_curves`."""
    g, t = np.asarray(grid), np.asarray(theta_deg)
    i, j = np.argmax(g, axis=1), np.argmin(g, axis=1)
    rows = np.arange(g.shape[0])
    return g[rows, i], t[i], g[rows, j], t[j]


# ------------------------------------------------------------------ quantities of the motion


def _program_function(quantity: Quantity) -> SegmentFunction:
    """fn(segment, theta, (program, params)) = quantity(kinematics of that segment at theta, params)."""
    def fn(segment, theta_deg, both):
        prog, params = both
        return quantity(program_mod.segment_motion(prog, segment, theta_deg), params)

    return fn


def max_of(program: MotionProgram, quantity: Quantity, grid_values: jax.Array, params: Any = None,
           **kwargs) -> Extremum:
    """Continuous max over the cam angle of ``quantity(kin, params)``, a function of the motion.

    ``grid_values`` is the quantity on the program's N-sample grid (``quantity(evaluate(program,
    N), params)``); gradients flow to the program's lifts and to ``params``. The quantity must
    depend on the motion (s and its derivatives), not on ``kin.theta`` itself: dwells are taken
    as constant. Keyword arguments as :func:`refine_max`.
    """
    return refine_max(_program_function(quantity), (program, params), program_mod.segment_bounds_deg(program),
                      grid_values, constant=dwells(program), **kwargs)


def min_of(program: MotionProgram, quantity: Quantity, grid_values: jax.Array, params: Any = None,
           **kwargs) -> Extremum:
    """Continuous min over the cam angle of ``quantity(kin, params)``; see :func:`max_of`."""
    return refine_min(_program_function(quantity), (program, params), program_mod.segment_bounds_deg(program),
                      grid_values, constant=dwells(program), **kwargs)


def dwells(program: MotionProgram) -> tuple[bool, ...]:
    """Which segments are dwells (static): every function of the motion is constant on them."""
    return tuple(kind == "dwell" for kind in program.kinds)


def grid_max(grid_values: jax.Array) -> Extremum:
    """The grid's own max and its sample angle (the ``extrema = "grid"`` path), shape () each."""
    i = jnp.argmax(grid_values)
    return Extremum(grid_values[i], i * (360.0 / grid_values.shape[0]))


def grid_min(grid_values: jax.Array) -> Extremum:
    """The grid's own min and its sample angle."""
    i = jnp.argmin(grid_values)
    return Extremum(grid_values[i], i * (360.0 / grid_values.shape[0]))


__all__ = ["CANDIDATES", "EXTREMA_MODES", "ITERATIONS", "Extremum", "dwells", "grid_max", "grid_min",
           "max_of", "min_of", "refine_curves", "refine_max", "refine_max_segments", "refine_min",
           "sampled_extremes", "segment_sample_ranges"]
