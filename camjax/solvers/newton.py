"""Newton solver: a primal-dual interior-point method on the smooth epigraph form, in one ``lax.while_loop``.

Formulation (one problem, one weighting; every registered problem family, through its protocol
only, :mod:`camjax.solvers.base`). The design is mapped to the unit box, u = (x - lo) / (hi - lo),
each variable over its bounds (not a family's own ``to_unit``/``from_unit``: the roller's keeps a
bound by a clip that a second-order path cannot see, :mod:`camjax.solvers.gradient`), and
an epigraph variable t stands for the max over angles of the objective:

    minimize    t  (+ 1e-9 size_term when alpha = 0, the gradient solver's tie-break)
    subject to  f_i(u) - t  <= 0      one row per angle i: f_i = F of the one-angle problem
                                       (:func:`per_angle`), i.e. (alpha size + gamma sigma_i /
                                       sigma_max) / (alpha + gamma)
                g_k,i(u) / N <= 0     every constraint row of ``family.constraints``
                0 <= u <= u_max       the box (u_max = 0 fixes a variable; it is left out)

which is smooth (the kink of the max over angles is gone) and has the same minimizer as the
family's objective on the grid: min_u max_i f_i(u) = min_u F(u) / (alpha + gamma). Every family's
objective is alpha size + gamma (peak stress) / sigma_max with the peak a max over angles, so
f_i needs nothing but ``per_angle`` and ``objective``: the split is generic. With gamma = 0
every f_i is the same size term; n equal rows would leave the split of the objective's
multiplier among them free (a degenerate path that stalls), so the first row alone holds t and
the others are the constant -1. A constraint block that is not one row per angle (a robust
problem's row per sample, :mod:`camjax.robust.design`, each a max over the grid) is taken from
the n one-angle problems instead: one smooth row per angle and sample, the same feasible set.
Rows below -1e3 (normalized; a discarded sample's -1e30) are floored there, the same feasible
set with slacks of O(1). Such a split problem (up to 1e5 near-parallel rows) takes the
feasible-slack path (:func:`_slacks`) and a linear fall of the barrier parameter.

The form (its objective phi, its rows and their blocks) is built by
:func:`camjax.solvers.epigraph.epigraph_form`.

Method (Nocedal & Wright, Numerical Optimization, 2nd ed., Algorithm 19.2; the barrier update and
the filter line search of IPOPT, Waechter & Biegler 2006). Slacks s > 0 turn every row into
c(z) + s = 0 (z = (u, t)); the barrier KKT conditions grad phi + J^T y = 0, c + s = 0, S y = mu e
are solved by Newton steps on the condensed system (H + J^T S^-1 Y J) dz = ... of size (m + 1)^2
(m free variables), H the exact Hessian of the Lagrangian (with the rows and their Jacobian from one
forward-over-forward pass, :func:`_derivatives`); its inertia is
corrected through its eigenvalues (a non-positive one flipped and floored at 1e-8: the system is
tiny). Steps keep s, y > 0 by the fraction-to-boundary rule (tau = max(0.99, 1 - mu)); the primal
step length is found by a backtracking search (Armijo on the barrier objective once nearly
feasible, else progress in it or in the infeasibility ||c + s||_1, and, on the paths that keep
one, a filter of earlier (infeasibility, barrier objective) pairs that forbids cycling), its 30
trial lengths tried one at a time until one is accepted (``line_search_chunk``: that many at once,
a ``vmap``). The barrier parameter falls
superlinearly, mu <- max(tol / 100, min(0.2 mu, mu^1.5)), each time the barrier problem is solved
to 10 mu (its infeasibility c + s counted on the rows at or beyond their limit: a row strictly
inside is feasible whatever its slack) or when the line search accepts no trial (IPOPT's tiny step:
a row's kink at the barrier problem's minimizer, a dwell's |e|, holds a stationarity ~ mu that
only a lower mu removes). The box rows are linear and start with s = -c, so every iterate stays
strictly inside the box, where the families' physics is defined. Up to four central paths take
turns in one loop (mu0 with the filter first; then mu0 / n, or mu0 *
:data:`SMOOTH_SECOND_MU` for a smooth family's form, and both without the filter; one angle: two):
each path's first turn is :data:`FIRST_SEGMENT` (80) steps and each later one :data:`PATH_SEGMENT`
(40), a path resuming where it stopped, until one converges or each has taken ``max_iterations``
(:func:`_paths`).

Stopping rule: the scaled KKT residual (IPOPT's: stationarity, primal infeasibility and
complementarity, :func:`camjax.solvers.certificate.kkt_residuals`) <= ``tol`` (1e-9), evaluated at
the top of each iteration from the rows, Jacobian and gradient the step uses; ``max_iterations`` is
a safeguard only. Gradients stay finite from infeasible starts: the families' functions are written
with safe square roots and divisions, and a trial step with a non-finite merit is rejected.

Exchange rounds (:mod:`camjax.solvers.exchange`): a grid of more than 2 ``exchange_angles`` angles
(the family's ``EXCHANGE_ANGLES``, else 16: :func:`camjax.solvers.exchange.exchange_angles`) is
solved that many angles at a time and each answer checked on the whole grid; the whole grid's KKT
residual ends the rounds, so the answer and its certificate are the whole problem's.

:func:`run_one` returns with the answer its certificate (:mod:`camjax.solvers.certificate`: the
KKT residuals, the iterations, the multipliers and the sensitivity dF*/d(limit) of the optimal
objective to the limits of the scene), computed in the same program (no second solve).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from camjax.family import Design, Problem, Weights
from camjax.solvers import exchange
from camjax.solvers.base import Raw, family_of
from camjax.solvers.box import default_start, from_unit, to_unit
from camjax.solvers.certificate import (
    KKT,
    TOL,
    Certificate,
    KKTPoint,
    certificate_of,
    dual_scale,
    residuals,
    rows_and_jacobian,
)
from camjax.solvers.certificate import certificate_json as certificate_json  # in result.json
from camjax.solvers.epigraph import EpigraphForm, epigraph_form
from camjax.solvers.exchange import take_angles as take_angles  # the exchange rounds' subproblem


@dataclass(frozen=True)
class NewtonSettings:
    """Static configuration of the interior-point solver (hashable: a ``jit`` static argument).

    The objective is normalized to O(1) (F / (alpha + gamma)), the rows to O(1) (g / N), the
    variables to the unit box: the tolerances are dimensionless.
    """

    tol: float = TOL  # scaled KKT residual ending the solve
    max_iterations: int = 200  # a safeguard only (steps of one central path): the solve stops on ``tol``
    mu0: float = 0.1  # first barrier parameter
    kappa_mu: float = 0.2  # mu <- min(kappa_mu mu, mu^theta_mu) ...
    theta_mu: float = 1.5
    kappa_eps: float = 10.0  # ... once the barrier problem is solved to kappa_eps mu
    interior: float = 1e-2  # the start's distance from the box's faces (unit box) and least slack
    line_search_trials: int = 30  # step lengths alpha_max 2^-k, k < trials ...
    line_search_chunk: int = 1  # ... tried this many at once, until one is accepted (the same
    # steps whatever the number; one at a time ran the seven types' 100-weighting sweeps, searched
    # 10 weightings at a time on the CPU, in 0.75 to 1.13 of the time of six at a time, median
    # 0.88, in benchmarks/results/line_search.json; 0.73 to 1.09 in a run before it)
    armijo: float = 1e-4
    exchange_angles: int | None = None  # a grid of more angles than twice this is solved in exchange
    # rounds of this many angles (:mod:`camjax.solvers.exchange`); 0: every grid whole; None: the
    # family's (:func:`camjax.solvers.exchange.exchange_angles`)
    free_variables: int | None = None  # the design variables the problem's box leaves free, where
    # known when the program is traced (:func:`for_problem`; solve_batch sets it): the derivatives
    # then take that many directions (and t's), not one per variable; None: one per variable


DEFAULT_SETTINGS = NewtonSettings()


def for_problem(problem: Problem, settings: NewtonSettings) -> NewtonSettings:
    """``settings`` with ``free_variables`` counted from the problem's box (the variables with upper
    > lower, as :func:`camjax.solvers.box.u_max_of`) where its bounds are concrete numbers; under
    a trace (the box unknown until the program runs), or where already set, ``settings`` as given."""
    if settings.free_variables is not None:
        return settings
    lower, upper = family_of(problem).bounds(problem)
    leaves = jax.tree.leaves((lower, upper))
    if any(isinstance(x, jax.core.Tracer) for x in leaves):
        return settings
    free = jax.tree.map(lambda lo, hi: np.asarray(hi) > np.asarray(lo), lower, upper)
    return replace(settings, free_variables=int(sum(np.sum(x) for x in jax.tree.leaves(free))))


FILTER = 32  # entries of the line search's filter (a ring: the oldest is replaced)
SMOOTH_SECOND_MU = 1e-3
"""A smooth form's second paths start at mu0 x this (roller co-design steps at 1e-2/1e-3/1e-4: 90/23/27)."""
FIRST_SEGMENT = 80  # steps of a central path's first turn before the next path's (:func:`_paths`) ...
PATH_SEGMENT = 40  # ... and of each later turn, the path resuming where it stopped


class NewtonState(NamedTuple):
    """Loop state (one problem; vmapped: leading axes)."""

    z: jax.Array  # (m + 1,) unit-box variables and t
    s: jax.Array  # (M,) slacks > 0
    y: jax.Array  # (M,) multipliers > 0
    mu: jax.Array  # () barrier parameter
    iteration: jax.Array  # () int
    kkt: KKT  # scaled KKT residuals at (z, y) (mu = 0), evaluated at the top of each step
    done: jax.Array  # () bool
    filter: jax.Array  # (FILTER, 2) (theta, psi) pairs no trial may be worse than in both; inf: empty
    filter_count: jax.Array  # () int: entries added since mu last changed (the oldest replaced)
    use_filter: jax.Array  # () bool: this path's line search keeps the filter (else memoryless)


class _Derivatives(NamedTuple):
    c: jax.Array  # (M,) the rows
    jac: jax.Array  # (M, m + 1) their Jacobian
    grad: jax.Array  # (m + 1,) the objective's gradient
    hess: jax.Array  # (m + 1, m + 1) the Lagrangian's Hessian, phi + y . c


def _derivatives(fns: EpigraphForm, z, y, free_variables: int | None = None) -> _Derivatives:
    """The rows, their Jacobian, the objective's gradient and the Hessian of the Lagrangian
    phi + y . c at z, from one forward-over-forward pass: the Hessian is the forward derivative of
    grad phi + J^T y, J itself a forward pass (no reverse pass), and the rows, J and grad phi are
    its primal values.

    phi and every row are affine in the epigraph variable t (:class:`EpigraphForm`: t enters as
    f_i - t and as phi = t + ...), so t's column of J is the form's ``t_column``, its entry of
    grad phi is 1, and its row and column of the Hessian are 0: the second-order directions are
    the design variables' only, k^2 instead of (k + 1)^2 (the oscillating roller's sweep, 2 free
    variables: 4 instead of 9).

    ``free_variables`` (k < m, static): the derivatives along the k free variables only (the
    columns of a fixed variable are 0, as the step takes them: it moves no fixed variable); None:
    along every variable."""
    m1 = z.shape[0]
    m = m1 - 1
    if free_variables is None or free_variables >= m:
        index = jnp.arange(m)
    else:  # the free variables' unit vectors, picked by the data (at least one direction)
        index = jnp.nonzero(fns.free[:m] > 0, size=max(free_variables, 1), fill_value=0)[0]
    basis = jnp.eye(m1, dtype=z.dtype)[:, index]  # (m + 1, k)

    def point(w):
        return z + basis @ w

    def lagrangian_gradient(w):
        c, jac = rows_and_jacobian(fns, w, point)
        grad = jax.jacfwd(lambda v: fns.phi(point(v)))(w)
        return grad + jac.T @ y, (c, jac, grad)

    hess, (c, jac, grad) = jax.jacfwd(lagrangian_gradient, has_aux=True)(jnp.zeros(basis.shape[1], z.dtype))
    along_t = jnp.zeros(m1, z.dtype).at[m].set(1.0)
    # back to every variable's coordinates, t's column added
    jac = jac @ basis.T + fns.t_column[:, None] * along_t
    grad = grad @ basis.T + along_t
    return _Derivatives(c, jac, grad, basis @ hess @ basis.T)


def _start(problem, fns: EpigraphForm, design, settings: NewtonSettings, mu0):
    if design is None:
        design = default_start(problem)
    dtype = fns.u_max.dtype
    u = ravel_pytree(jax.tree.map(lambda x: jnp.asarray(x, dtype), to_unit(problem, design, own=False)))[0]
    a = settings.interior
    u = jnp.where(fns.u_max > 0, jnp.clip(u, a * fns.u_max, (1.0 - a) * fns.u_max), 0.0)
    z0 = jnp.concatenate([u, jnp.zeros(1, dtype)])
    n = fns.n_angles
    rows0 = fns.rows(z0)  # t = 0: the epigraph rows are f_i
    f_max = jnp.max(jnp.where(fns.epigraph, rows0[:n], -jnp.inf))
    t0 = f_max + 0.1 * (1.0 + jnp.abs(f_max))  # epigraph rows strictly feasible
    z0 = z0.at[-1].set(t0)
    epigraph = jnp.zeros(rows0.shape[0], bool).at[:n].set(fns.epigraph)
    c0 = rows0 - t0 * epigraph  # t enters the epigraph rows linearly
    s0 = jnp.maximum(-c0, a)
    m = u.shape[0]
    # the box rows are linear: their slack is their distance to the face, exactly
    box = jnp.arange(c0.shape[0]) >= c0.shape[0] - 2 * m
    s0 = jnp.where(box, -c0, s0)
    mu0 = jnp.asarray(mu0, dtype)
    # multipliers: the epigraph rows share the objective's unit weight (sum y = 1 where t is
    # stationary), every other row mu / s
    y0 = jnp.where(epigraph, 1.0 / jnp.sum(fns.epigraph), mu0 / s0)
    return z0, s0, y0, mu0


def _slacks(fns: EpigraphForm, s, c):
    """The slacks after a step to rows c: at least -c (a row more feasible than its slack says). On
    a split problem's path every row inside its limit takes s = -c exactly (so c + s = 0 there: the
    infeasibility measure counts violated rows only), and the line search keeps such a row inside.
    Its 1e5 rows' second-order errors c(z + dz) - c - J dz summed to an infeasibility of 3 to 300 that
    no step could lower by the filter's margin: the path stalled at the iteration cap."""
    if fns.split:
        return jnp.where(c < 0, -c, s)
    return jnp.maximum(s, -c)


def _next_mu(mu, fns: EpigraphForm, settings: NewtonSettings):
    """The barrier parameter after mu: superlinear, max(tol / 100, min(kappa_mu mu, mu^theta_mu)).

    A split problem's mu falls linearly: a superlinear fall (x 480 from 4e-6) moved its many
    near-parallel rows' slacks so far that the Newton step crossed them (see ``_slacks``)."""
    fall = settings.kappa_mu * mu if fns.split else jnp.minimum(settings.kappa_mu * mu, mu**settings.theta_mu)
    return jnp.maximum(settings.tol / 100.0, fall)


def _step(state: NewtonState, fns: EpigraphForm, settings: NewtonSettings) -> NewtonState:
    """One iteration: the rows, their Jacobian, the gradient and the Lagrangian's Hessian at z (one
    forward-over-forward pass, :func:`_derivatives`, whose rows the line search reuses); the
    KKT residual there ends the loop (no step from a converged point); else the barrier update
    (the barrier problem solved to ``kappa_eps`` mu) and one Newton step with its line search."""
    z, s, y, mu = state.z, state.s, state.y, state.mu
    dtype = z.dtype
    free = fns.free
    c, jac, grad, hess = _derivatives(fns, z, y, settings.free_variables)
    kkt = residuals(grad, c, jac, y, free)
    done = kkt.error <= settings.tol
    # barrier update (IPOPT's E_mu of the barrier problem: c + s = 0, S y = mu)
    sd = dual_scale(y, y.shape[0])
    # Its infeasibility counts the rows at or beyond their limit only (a row inside with s > -c is
    # feasible): counted, such a gap on a row's kink (|e| / r at a dwell) held a one-angle problem at
    # mu ~ 1e-4, c + s ~ 2e-2, each step across the kink widening it. The stopping rule takes c, not s.
    infeasibility = jnp.max(jnp.where(c < 0, 0.0, jnp.abs(c + s)))
    e_mu = jnp.maximum(jnp.maximum(kkt.stationarity, infeasibility), jnp.max(jnp.abs(s * y - mu)) / sd)
    lower_mu = (e_mu <= settings.kappa_eps * mu) & (state.iteration > 0)
    mu = jnp.where(lower_mu, _next_mu(mu, fns, settings), mu)
    # the filter holds (theta, psi) of the barrier problem at one mu: emptied when mu changes
    filt = jnp.where(lower_mu, jnp.inf, state.filter)
    count = jnp.where(lower_mu, 0, state.filter_count)
    jac = jac * free  # fixed variables take no step
    sigma = y / s
    rd = (grad + jac.T @ y) * free
    rp = c + s
    rc_s = y - mu / s  # S^-1 (S y - mu)
    a = hess * jnp.outer(free, free) + (jac.T * sigma) @ jac
    a = a + jnp.diag(1.0 - free)  # a fixed variable's row: dz_j = 0
    a = 0.5 * (a + a.T)
    # inertia correction by the eigenvalues (the matrix is (m + 1)^2): a non-positive curvature is
    # flipped and floored at 1e-8 (the unit box and the normalized objective: absolute scales).
    # A shift of the whole matrix instead would be relative to its largest eigenvalue, which
    # grows as y / s ~ 1 / mu on the active rows: it would damp the steps along the active
    # constraints' surface to a first-order method's near the optimum.
    w, v = jnp.linalg.eigh(a)
    w = jnp.maximum(jnp.abs(w), 1e-8)
    rhs = -rd - jac.T @ (sigma * rp - rc_s)
    dz = (v @ ((v.T @ rhs) / w)) * free
    dy = sigma * (jac @ dz + rp) - rc_s
    ds = -rp - jac @ dz
    # fraction to the boundary
    tau = jnp.maximum(0.99, 1.0 - mu)

    def max_step(v, dv):
        ratio = jnp.where(dv < 0, -tau * v / jnp.where(dv < 0, dv, -1.0), jnp.inf)
        return jnp.minimum(1.0, jnp.min(ratio))

    alpha_s, alpha_y = max_step(s, ds), max_step(y, dy)
    # filter line search (Waechter & Biegler 2006: the switching rule, a filter of earlier
    # (theta, psi) against cycling): psi = phi - mu sum log s, theta = ||c + s||_1, s reset to >= -c
    # (an l1 merit stalled on the rows' kinks, |s' - e| at a dwell).

    def measures(zv, sv, cv):
        sv = _slacks(fns, sv, cv)
        return fns.phi(zv) - mu * jnp.sum(jnp.log(sv)), jnp.sum(jnp.abs(cv + sv)), cv

    psi0, theta0, _ = measures(z, s, c)  # the rows at z are the derivatives' primal
    slope = grad @ dz - mu * jnp.sum(ds / s)
    theta_max = 1e4 * jnp.maximum(1.0, theta0)
    switching = (slope < 0) & (theta0 <= 1e-4)
    rounding = 10.0 * jnp.finfo(dtype).eps * jnp.abs(psi0)
    trials, chunk = settings.line_search_trials, min(settings.line_search_chunk, settings.line_search_trials)

    def judge(j):
        """Chunk j: any accepted; the first accepted's (else the last's) Armijo, length, rows."""
        k = j * chunk + jnp.arange(chunk)
        lengths = alpha_s * 0.5 ** k.astype(dtype)
        psi_t, theta_t, c_t = jax.vmap(
            lambda al: measures(z + al * dz, s + al * ds, fns.rows(z + al * dz)))(lengths)
        # Armijo's decrease, relaxed by the rounding of psi (IPOPT's 10 eps |psi|)
        armijo = psi_t <= psi0 + settings.armijo * lengths * slope + rounding
        progress = (theta_t <= (1.0 - 1e-5) * theta0) | (psi_t <= psi0 - 1e-5 * theta0)
        in_filter = jnp.all((theta_t[:, None] <= (1.0 - 1e-5) * filt[None, :, 0])
                            | (psi_t[:, None] <= filt[None, :, 1] - 1e-5 * filt[None, :, 0]), axis=1)
        ok = (k < trials) & jnp.isfinite(psi_t) & jnp.isfinite(theta_t) & (theta_t <= theta_max) & jnp.where(
            state.use_filter, in_filter & jnp.where(switching, armijo, progress),
            jnp.where(switching, armijo, progress | armijo))
        if fns.split:  # the feasible-slack path: a row inside its limit stays inside (see ``_slacks``)
            ok = ok & jnp.all((c_t < 0) | (c[None, :] >= 0), axis=1)
        i = jnp.where(jnp.any(ok), jnp.argmax(ok), jnp.minimum(trials - 1 - j * chunk, chunk - 1))
        return jnp.any(ok), armijo[i], lengths[i], c_t[i]

    # chunks until one is accepted: the first accepted trial of all, in order (usually in chunk 0)
    found, armijo_first, length, c_new = jax.lax.while_loop(
        lambda st: ~st[1] & (st[0] < -(-trials // chunk)),
        lambda st: (st[0] + 1, *judge(st[0])),
        (jnp.asarray(0), jnp.asarray(False), jnp.asarray(False), jnp.zeros((), dtype), c))[1:]
    # no trial accepted (IPOPT's tiny step): mu falls. At a row's kink (|e| at a dwell) the
    # stationarity is y_i ~ mu / s_i times the slope's jump: it falls with mu only.
    stalled = ~found & ~done
    # a step that is not Armijo's on psi (an h-type step) adds the current pair to the filter
    add = ~(switching & armijo_first) & ~done
    entry = jnp.stack([(1.0 - 1e-5) * theta0, psi0 - 1e-5 * theta0])
    filt = jnp.where(add, filt.at[count % FILTER].set(entry), filt)
    count = jnp.where(stalled, 0, count + add)
    filt = jnp.where(stalled, jnp.inf, filt)
    z_new = z + length * dz
    s_new = _slacks(fns, s + length * ds, c_new)
    y_new = y + alpha_y * dy
    # IPOPT's safeguard: y_i within [mu / (k s_i), k mu / s_i], k = 1e10
    y_new = jnp.clip(y_new, mu / (1e10 * s_new), 1e10 * mu / s_new)
    mu_new = jnp.where(stalled, _next_mu(mu, fns, settings), mu)
    pick = lambda a_, b_: jnp.where(done, a_, b_)  # noqa: E731
    return NewtonState(pick(z, z_new), pick(s, s_new), pick(y, y_new), pick(state.mu, mu_new),
                       state.iteration + jnp.where(done, 0, 1), kkt, done, pick(state.filter, filt),
                       pick(state.filter_count, count), state.use_filter)


RESTORATION_STEPS = 200  # compass-search steps of :func:`_restore` (an infeasible end only)


def _restore(fns: EpigraphForm, z, active):
    """An end that did not converge and breaks a limit: the design moved to a minimizer of its
    constraint rows' squared violations, 1/2 sum_i max(g_i / N, 0)^2, in the box (t is kept), by
    a compass search: each free variable moved by +-h (the 2m trials at once), the best trial
    taken where it lowers the violation and h doubled, else h halved, from h = 1/4 of the unit box
    down to 1e-12 or RESTORATION_STEPS steps. Unreachable bounds (a face width no face in the box
    can have) leave the interior point's path where the barrier of the other rows had put it: the
    default scene with its face width bounded at 10 mm ended at R_b 23.1 mm, below the smallest
    admissible 24.1 mm, breaking the curvature and the stress (1.1e10 MPa) limits too. Here those
    are met again, and the answer names the limit no design can meet. The rows alone, traced once
    (no derivatives): the smallest program that does it.

    Runs no step where ``active`` is False (a converged or feasible end: z is returned as it is;
    one ``lax.while_loop``, so that under ``vmap`` such weightings run no step either)."""
    m = fns.u_max.shape[0]
    count = sum(k for _, k in fns.kinds)
    constraint = (jnp.arange(count) >= fns.kinds[0][1]) & (jnp.arange(count) < count - 2 * m)
    free = fns.free[:m] > 0
    # the point itself (its violation at the first step), then +-h along each free variable
    moves = jnp.concatenate([jnp.zeros((1, m)), jnp.eye(m), -jnp.eye(m)])
    moves = moves * jnp.concatenate([jnp.ones(1, bool), free, free])[:, None]

    def violation(u):
        c = fns.rows(jnp.concatenate([u, z[m:]]))
        r = jnp.where(constraint & (c > 0), c, 0.0)
        return 0.5 * r @ r

    def body(st):
        k, u, v, h = st
        trials = jnp.clip(u + h * moves * fns.u_max, 0.0, fns.u_max)
        values = jax.vmap(violation)(trials)
        values = jnp.where(jnp.isfinite(values), values, jnp.inf)
        best = jnp.argmin(values)
        better = values[best] < v
        return (k + 1, jnp.where(better, trials[best], u), jnp.where(better, values[best], v),
                jnp.where(better, jnp.minimum(2.0 * h, 0.5), 0.5 * h))

    dtype = z.dtype
    st = (jnp.asarray(0), z[:m], jnp.asarray(jnp.inf, dtype), jnp.asarray(0.25, dtype))
    u = jax.lax.while_loop(
        lambda st: active & (st[0] < RESTORATION_STEPS) & (st[2] > 0.0) & (st[3] > 1e-12), body, st)[1]
    return jnp.where(active, jnp.concatenate([u, z[m:]]), z)


def _paths(problem: Problem, fns: EpigraphForm, init_design, settings: NewtonSettings,
           mu_factor=1.0) -> NewtonState:
    """The central paths of one solve, taking turns in one loop, their first barrier parameters
    times ``mu_factor``: the first converged end, else the end of least KKT residual."""

    def start(mu0, use_filter):
        z0, s0, y0, mu0 = _start(problem, fns, init_design, settings, mu0)
        inf = jnp.asarray(jnp.inf, z0.dtype)
        return NewtonState(z0, s0, y0, mu0, jnp.asarray(0), KKT(inf, inf, inf, inf), jnp.asarray(False),
                           jnp.full((FILTER, 2), jnp.inf, z0.dtype), jnp.asarray(0), use_filter)

    # Central paths: mu0 and mu0 / n (t - f_i ~ n mu on the n epigraph rows: far above the
    # objective, and close to it), each with the filter (no cycling) and without (it crosses the
    # rows' kinks, |s' - e| at a dwell, that can hold a filter's iterates). The first (mu0, filter)
    # converged on all but one weighting of every type's 100-weighting sweep (in up to 87 steps)
    # and on the knife edge's whole 360-angle grid (in 135 steps, where the others stalled). One
    # path steps at a time (a step costs a quarter of four paths stepped side by side), in turns:
    # FIRST_SEGMENT steps on a path's first turn, PATH_SEGMENT on each later one (resuming where it
    # stopped), until one converges or each has taken ``max_iterations``. Measured on
    # the oscillating curved face's sweep: the weighting whose first path had not converged in 200
    # steps ended after 111 in all (231 when each path ran its 200 before the next started).
    smooth = getattr(family_of(problem), "SMOOTH_OBJECTIVE", False)
    first = [settings.mu0, settings.mu0 * (SMOOTH_SECOND_MU if smooth else 1.0 / fns.n_angles)]
    first = first[:1] if fns.n_angles == 1 and not smooth else first
    mu0s = jnp.asarray(first * 2) * fns.mu_scale * mu_factor
    filters = jnp.asarray([True] * len(first) + [False] * len(first))
    states = jax.vmap(start)(mu0s, filters)
    n_paths = len(first) * 2

    def left(states):  # (n_paths,) bool: the paths with steps left
        return states.iteration < settings.max_iterations

    def turn(carry):
        # one path's turn, then the next path with steps left; the paths are gathered and stored
        # once a turn, so a step costs what one path's step costs
        states, path, steps = carry
        state = jax.tree.map(lambda x: x[path], states)
        stop_at = jnp.minimum(jnp.where(state.iteration < FIRST_SEGMENT, FIRST_SEGMENT,
                                        state.iteration + PATH_SEGMENT), settings.max_iterations)

        def stepping(c):
            return ~c[0].done & (c[0].iteration < stop_at)

        def step(c):
            state, steps = c
            state = _step(state, fns, settings)
            return state, steps + jnp.where(state.done, 0, 1)

        state, steps = jax.lax.while_loop(stepping, step, (state, steps))
        states = jax.tree.map(lambda xs, x: xs.at[path].set(x), states, state)
        order = (path + 1 + jnp.arange(n_paths)) % n_paths
        nxt = order[jnp.argmax(left(states)[order])]
        return states, jnp.where(state.done, path, nxt), steps

    def going(carry):
        states, path, _ = carry
        return ~states.done[path] & jnp.any(left(states))

    states, path, steps = jax.lax.while_loop(going, turn, (states, jnp.asarray(0), jnp.asarray(0)))
    pick = jnp.where(states.done[path], path, jnp.argmin(states.kkt.error))
    return jax.tree.map(lambda x: x[pick], states)._replace(iteration=steps)


def minimize(problem: Problem, weights: Weights, init_design: Design | None = None,
             settings: NewtonSettings = DEFAULT_SETTINGS) -> KKTPoint:
    """Solve one problem (global over its angle grid) for one weighting; traceable, vmappable.

    ``init_design``: the start (mm); default the family's ``start(problem)`` where it has one,
    else the centre of the box (pulled ``settings.interior`` inside the box's faces). A grid of more
    than 2 :func:`camjax.solvers.exchange.exchange_angles` angles is solved in exchange rounds
    (:func:`camjax.solvers.exchange.solve_in_rounds`).
    """
    settings = replace(settings, exchange_angles=exchange.exchange_angles(problem, settings))
    fns = epigraph_form(problem, weights)
    blocks = exchange.angle_blocks(fns, settings)
    if blocks is None:
        end = _paths(problem, fns, init_design, settings)
        z, y, iterations, converged, kkt = end.z, end.y, end.iteration, end.done, end.kkt
    else:
        z, y, iterations, converged, kkt = exchange.solve_in_rounds(
            problem, weights, fns, blocks, init_design, settings, _paths, _start)
    m = fns.u_max.shape[0]
    # an end that breaks a limit without converging: its design moved to the least violation
    infeasible = ~converged & (kkt.primal > settings.tol)
    z = _restore(fns, z, infeasible)
    design = from_unit(problem, fns.unravel(z[:m]), own=False)
    return KKTPoint(design, iterations, converged, z, y, kkt)


def run_one(problem: Problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """The solver protocol of :mod:`camjax.solvers.base`: :func:`minimize` with ``settings.of("newton")``.

    ``key`` is unused (deterministic). Converged when the scaled KKT residual reached ``tol``.
    """
    res = minimize(problem, weights, init, settings.of("newton"))
    return Raw(res.design, res.iterations, res.converged, certificate_of(problem, weights, res))


def certify(problem: Problem, weights: Weights, init_design: Design | None = None,
            settings: NewtonSettings = DEFAULT_SETTINGS) -> Certificate:
    """Solve (:func:`minimize`) and certify the answer
    (:func:`camjax.solvers.certificate.certificate_of`); traceable, vmappable."""
    return certificate_of(problem, weights, minimize(problem, weights, init_design, settings))
