"""The interior point's exchange rounds (a semi-infinite program's exchange method): a grid problem
of many angles solved a few angles at a time, each round's answer checked on the whole grid, so
that the answer and its certificate are the whole problem's (:func:`solve_in_rounds`); the angles
of a round (:func:`exchange_angles`) and the subproblem of a round's angles (:func:`take_angles`).
Used by :func:`camjax.solvers.newton.minimize`, which hands in its central paths."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.family import Problem, Weights
from camjax.solvers.base import family_of
from camjax.solvers.box import default_start, from_unit
from camjax.solvers.certificate import KKT, dual_scale
from camjax.solvers.epigraph import EpigraphForm, epigraph_form

# Angles of an exchange round where neither the settings nor the family name a number. Measured on
# each type's 100-weighting sweep (360 angles, 2 cores, the same optima and 0 infeasible at 16, 24
# and 32): 16 angles a round against 32 ran the knife edge 2.2x faster (its slowest weighting 25
# steps, not 71), the flat face 1.8x, the curved face and the oscillating flat face 1.3x, the
# oscillating curved face within 2 %, and compiled 8-15 % faster; the roller, the oscillating
# roller and the oscillating curved face, whose answers bind at more angles (more rounds at 16),
# declare EXCHANGE_ANGLES = 32 (the oscillating curved face 49 Newton steps at the median at 16,
# 34.5 at 32).
EXCHANGE_ANGLES = 16




def exchange_angles(problem: Problem, settings) -> int:
    """The angles of an exchange round: the interior point's ``settings.exchange_angles`` where set,
    else the family's ``EXCHANGE_ANGLES`` (an optional family constant), else :data:`EXCHANGE_ANGLES`."""
    if settings.exchange_angles is not None:
        return settings.exchange_angles
    return getattr(family_of(problem), "EXCHANGE_ANGLES", EXCHANGE_ANGLES)


WARM_MU = 1e-3  # a later round's first barrier parameters, x mu0 (it starts from the last answer)
EXCHANGE_ROUNDS = 5  # the most exchange rounds from one start (each one interior-point solve on k angles)


def angle_blocks(fns: EpigraphForm, settings) -> int | None:
    """The number of row blocks with one row per angle (the objective's and every constraint's) when
    the form is a grid problem the exchange rounds can take apart (:func:`solve_in_rounds`), else None."""
    n = fns.n_angles
    blocks = fns.kinds[:-2]
    k = settings.exchange_angles
    if fns.split or k <= 0 or n <= 2 * k or any(count != n for _, count in blocks):
        return None
    return len(blocks)


def take_angles(problem: Problem, index: jax.Array) -> Problem:
    """The problem on the grid angles ``index`` (k,), from the family's one-angle problems
    (``per_angle``, so without what one angle's problem leaves out, such as a model): each grid
    leaf ((n, 1) there) and each leaf that is (n,) in the problem itself (a positive drive's second
    contact's coefficient) taken at ``index``, each scalar kept. Every constraint row and every
    objective row at those angles is the whole problem's (tests/test_newton.py)."""
    return _angle_taker(problem)(index)


def _angle_taker(problem: Problem):
    """:func:`take_angles` as ``index -> problem``, the one-angle problems built once."""
    per = family_of(problem).per_angle(problem)
    shapes = {path: jnp.shape(x) for path, x in jax.tree_util.tree_flatten_with_path(problem)[0]}

    def take(index):
        def leaf(path, x):
            if x.ndim == 2:
                return x[index, 0]
            return x[index] if len(shapes[path]) == 1 else x[0]

        return jax.tree_util.tree_map_with_path(leaf, per)

    return take


def solve_in_rounds(problem: Problem, weights: Weights, fns: EpigraphForm, blocks: int, init_design,
                    settings, paths, start):
    """A grid problem solved by exchange rounds (a semi-infinite program's exchange method, e.g.
    Reemtsen & Goerner 1998): each round solves the interior point on ``exchange_angles`` angles of
    the grid (:func:`take_angles`), then checks the answer on the whole grid with the multipliers of the
    angles left out set to 0. The whole grid's scaled KKT residual <= ``tol`` ends the rounds: the
    answer is then the whole problem's, certified on its every row. Else the next round's angles are
    up to half of them that the last answer held active (the largest multipliers > 1e-8),
    then those whose largest row (the epigraph rows f_i - t, the constraints g / N) is largest at
    the answer, so a violated angle comes in. The first round takes them evenly spaced (a coarse
    grid) from the default start, or half of them evenly spaced and half where the rows are largest
    from a given start (``init_design``); a later round starts from the last answer, its barrier at
    :data:`WARM_MU` x mu0. Rounds from a given start that end unconverged after
    :data:`EXCHANGE_ROUNDS` start again from the default start (as many rounds more, in the same
    loop: no second program). The knife edge's hybrid polished one weighting of its 100-weighting
    sweep (alpha 0.0226) from its GA answer, R_b 12.716 mm: the first round's interior point
    converged on its 16 angles at a worse point (R_b 25.3 mm) and the rounds ended unconverged
    after 41 steps; started again, they reach the optimum (57 steps in all; tests/test_newton.py).
    Measured on the oscillating roller's 100-weighting sweep (360 angles):
    30 Newton steps in all at the median (36 on the whole grid), each ~1/11 of the cost of a whole
    grid's step.

    ``paths(problem, fns, start_design, settings, mu_factor)``: the interior point's solve of a
    round's problem (its state: z, y, iteration, kkt); ``start(problem, fns, design, settings, mu0)``:
    its first iterate (z first). Returns (z, y, iterations summed over the rounds, converged, KKT)
    on the whole grid."""
    n, k = fns.n_angles, settings.exchange_angles
    dtype = fns.u_max.dtype
    m = fns.u_max.shape[0]
    total = sum(count for _, count in fns.kinds)
    take = _angle_taker(problem)  # the one-angle problems built once, outside the rounds

    def largest_rows(c):  # (n,) the largest of each angle's rows c
        return jnp.max(c[: blocks * n].reshape(blocks, n), axis=0)

    def full_multipliers(index, y_sub):
        y = jnp.zeros(total, dtype)
        per_angle = y_sub[: blocks * k].reshape(blocks, k)
        y = y.at[(jnp.arange(blocks)[:, None] * n + index[None, :]).ravel()].set(per_angle.ravel())
        # gamma = 0: the first objective row alone holds t, in the subset and on the grid
        first_alone = jnp.zeros(n, dtype).at[0].set(per_angle[0].sum())
        y = y.at[:n].set(jnp.where(weights.gamma != 0, y[:n], first_alone))
        return y.at[total - 2 * m:].set(y_sub[-2 * m:])

    def round_(st):
        r, z, y, keep, score, iterations, _, _, again = st
        held = jnp.zeros(n, bool).at[jax.lax.top_k(keep, k // 2)[1]].set(True) & (keep > 0)
        index = jnp.sort(jax.lax.top_k(jnp.where(held, jnp.inf, score), k)[1])
        sub = take(index)
        warm = r > 0
        last = from_unit(problem, fns.unravel(z[:m]), own=False)
        first = jax.tree.map(lambda a, b: jnp.where(again, a, b), default_design, design0)
        start = jax.tree.map(lambda a, b: jnp.where(warm, a, b), last, first)
        end = paths(sub, epigraph_form(sub, weights), start, settings, jnp.where(warm, WARM_MU, 1.0))
        y = full_multipliers(index, end.y)
        # the whole grid's KKT residuals (:func:`camjax.solvers.certificate.residuals`) from the
        # subset's: the rows left out carry no multiplier, so stationarity and complementarity are
        # the subset's but for the dual scale (its mean multiplier over every row); the primal
        # infeasibility is every row's
        c = fns.rows(end.z)
        ratio = dual_scale(end.y, end.y.shape[0]) / dual_scale(y, total)
        stat, comp = end.kkt.stationarity * ratio, end.kkt.complementarity * ratio
        primal = jnp.maximum(jnp.max(c), 0.0)
        kkt = KKT(stat, primal, comp, jnp.maximum(jnp.maximum(stat, primal), comp))
        held = largest_rows(y)
        done = kkt.error <= settings.tol
        # rounds from a given start that end unconverged: the rounds again from the default start
        restart = may_restart & ~again & ~done & (r + 1 >= EXCHANGE_ROUNDS)
        keep = jnp.where(restart, keep_default, jnp.where(held > 1e-8, held, 0.0))
        score = jnp.where(restart, score_default, largest_rows(c))
        return (jnp.where(restart, 0, r + 1), end.z, y, keep, score, iterations + end.iteration, done, kkt,
                again | restart)

    inf = jnp.asarray(jnp.inf, dtype)
    # the first round from the default start: the coarse grid of k evenly spaced angles (scored
    # 1, every other 0; no angle held); the state's z is read from the second round on
    default_design = default_start(problem)
    keep_default = jnp.zeros(n, dtype)
    score_default = jnp.zeros(n, dtype).at[jnp.round(jnp.linspace(0, n - 1, k)).astype(int)].set(1.0)
    may_restart = init_design is not None
    if init_design is None:
        design0, keep0, score0 = default_design, keep_default, score_default
    else:
        # from a given start (the hybrid's polish from the GA's answer, near an optimum): k / 2
        # evenly spaced angles (held) and the k / 2 whose largest row is largest there, the rows
        # that start near their limits; the flat face's 100-weighting polish took up to 152 steps
        # with k evenly spaced, its angles where the GA's design binds found only in a later round
        design0 = init_design
        z0 = start(problem, fns, design0, settings, settings.mu0)[0]
        c0 = fns.rows(z0.at[-1].set(0.0))  # t = 0: the epigraph rows are f_i; scored at t = max f_i
        t0 = jnp.max(jnp.where(fns.epigraph, c0[:n], -jnp.inf))
        keep0 = jnp.zeros(n, dtype).at[jnp.round(jnp.linspace(0, n - 1, k // 2)).astype(int)].set(1.0)
        score0 = largest_rows(c0.at[:n].add(-t0))
    st = (jnp.asarray(0), jnp.zeros(m + 1, dtype), jnp.zeros(total, dtype), keep0, score0,
          jnp.asarray(0), jnp.asarray(False), KKT(inf, inf, inf, inf), jnp.asarray(False))
    _, z, y, _, _, iterations, converged, kkt, _ = jax.lax.while_loop(
        lambda st: ~st[6] & (st[0] < EXCHANGE_ROUNDS), round_, st)
    return z, y, iterations, converged, kkt
