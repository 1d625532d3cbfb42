"""Gradient solver: augmented Lagrangian over a secant-accelerated Rprop (an optax transform), in one jit.

The problem (:mod:`camjax.followers.flat.problem`) is solved for one weighting on its angle grid; batch it with
``vmap`` (weightings, pointwise angles, or both, see :func:`solve_pointwise`, :func:`solve_sweep`).

Formulation. Each design variable is mapped to the unit box, u = (x - lo) / (hi - lo), so every
variable has the same scale whatever its bounds. The objective is normalized by alpha + gamma (same
minimizer; every weighting from 1e-6 to 1e6 gives an O(1) function). The constraints g <= 0
(mm, one per angle) are divided by N = R_b,max + L_max and enter an augmented Lagrangian

    L_A(u; lam) = F / (alpha + gamma) + sum_i mu/2 [max(0, g_i + lam_i/mu)^2 - (lam_i/mu)^2],

minimized over the box by projected Rprop: sign-based steps with per-variable step sizes that
grow on agreement and halve on a sign change. Rprop suits this problem: it is invariant to the
scale of the gradient (the stress term varies as rho^-3/2), it converges to a kink as well as to
a smooth minimum (global mode uses the true max over angles, whose gradient is that of the argmax
angle), and a box is kept by projection. Plain Rprop only halves its way to the optimum (about
20 steps per decimal digit), so :func:`scale_by_secant_rprop` (an optax ``GradientTransformation``)
takes a secant-Newton step inside the Rprop step size wherever the curvature along a variable is
positive: superlinear near a smooth optimum, Rprop elsewhere (``secant=False`` gives plain
iRprop-, ~8x more steps; optax 0.2.8's own ``scale_by_rprop`` emits each update one step late,
optax PR #1725, so it is not used). The gradient fed to it is the
*projected* gradient (zero for a variable held at a bound by a gradient pointing outward), so a
step size never grows against a bound.

Multipliers are updated, lam <- clip(lam + mu g, 0, LAM_MAX), whenever the inner problem has
converged (or after ``inner_steps`` steps); the transform's memory is then cleared. Stopping rule:
the projected-gradient norm ||pg||_inf <= ``gtol`` (or every moving variable's step below
``xtol``: Rprop cannot move further), together with the AL residual max_i |min(-g_i, lam_i/mu)|
<= ``ctol`` (feasibility and complementarity). The whole loop is one ``lax.while_loop`` capped at
``max_steps``, after which the BFGS refinement (:func:`refine_bfgs`) takes over; an infeasible
problem runs to both caps and is reported infeasible by name.

When alpha = 0 the objective does not depend on the size; a tie-break 1e-9 (R_b + L)/N then
picks the smallest such design, as :func:`camjax.followers.flat.optimum.pointwise_optimum` does.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import optax
from jax.flatten_util import ravel_pytree

from camjax.family import Constraints, Design, Problem, Violation, Weights
from camjax.solvers import quasi_newton as qn
from camjax.solvers.base import Raw, family_of, in_mode
from camjax.solvers.box import (
    clip_unit,
    default_start,
    from_unit,
    midpoint,
    problem_dtype,
    solver_objective,
    to_unit,
    u_max_of,
)

LAM_MAX = 1e12  # cap on the multipliers (an infeasible problem would let them grow without end)


@dataclass(frozen=True)
class GradientSettings:
    """Static configuration of the gradient solver (hashable: a ``jit`` static argument).

    Lengths are in units of the box (u in [0, 1]); the objective is normalized to O(1).
    """

    # cap on Rprop's steps; with the BFGS refinement on (the default) it is where Rprop hands over:
    # the refinement finishes what Rprop has not in 1000 steps (the oscillating roller: 2,347 steps
    # with a cap of 2000, 1,140 with 1000, the same optimum). A cap of 300 was tried: 753 steps
    # there, but 10 of the oscillating flat's 100 sweep weightings ended infeasible (1 with 1000)
    max_steps: int = 1000
    inner_steps: int = 300  # cap on steps between multiplier updates
    initial_step: float = 0.05  # first Rprop step
    reset_step: float = 1e-2  # cap on the step size a multiplier update restarts from
    min_step: float = 1e-15
    max_step: float = 0.25
    penalty: float = 1e3  # mu, on constraints divided by N
    gtol: float = 1e-10  # projected-gradient norm (inf-norm, unit box)
    xtol: float = 1e-12  # Rprop step size below which a variable has stopped
    ctol: float = 1e-12  # AL residual (constraints / N)
    inner_rtol: float = 0.1  # inexact inner solves: stop when steps <= inner_rtol * AL residual
    secant: bool = True  # secant-Newton steps inside Rprop's trust region (False: plain Rprop)
    # one multiplier per constraint (its max over angles; exact here), where the problem's family
    # allows it (:func:`_aggregate`); False: one per angle and constraint
    aggregate_constraints: bool = True
    # the BFGS refinement after an Rprop stall (:func:`refine_bfgs`): cap on its rounds (multiplier
    # updates); 0 turns it off (Rprop alone)
    refine_rounds: int = 30
    refine_steps: int = 200  # cap on BFGS evaluations per round
    refine_gtol: float = 1e-11  # gradient norm (2-norm, box angle coordinates) ending a round
    refine_penalty_growth: float = 4.0  # the penalty grows by this factor each round ...
    refine_penalty_max: float = 1e6  # ... up to this


DEFAULT_SETTINGS = GradientSettings()
# Rprop alone, without the refinement after a stall (speed studies)
RPROP_SETTINGS = GradientSettings(refine_rounds=0, max_steps=2000)


class GradientState(NamedTuple):
    """Loop state (shapes for one problem; a vmapped solve adds leading axes)."""

    u: Design  # () each: position in the unit box
    rprop: ScaleBySecantRpropState  # step sizes, previous gradient and point, like ``u``
    multipliers: Constraints  # (n,) each, or () with aggregate_constraints; >= 0
    step: jax.Array  # () int: steps taken
    inner_step: jax.Array  # () int: steps since the last multiplier update
    pg_norm: jax.Array  # () inf-norm of the projected gradient at ``u``
    residual: jax.Array  # () AL residual at ``u``
    done: jax.Array  # () bool


class GradientResult(NamedTuple):
    """Outcome of one gradient solve (shape () each for one problem; vmapped: leading axes)."""

    design: Design  # mm
    objective: jax.Array  # F with the true max over angles
    violation: Violation  # worst violation per constraint, mm / MPa
    feasible: jax.Array  # bool
    iterations: jax.Array  # int, Rprop steps
    converged: jax.Array  # bool, stopping rule met before max_steps
    projected_gradient_norm: jax.Array  # final ||pg||_inf (unit box, normalized objective)
    multipliers: Constraints  # final multipliers, (n,) or () each


# ------------------------------------------------------------------ secant-Rprop transform


class ScaleBySecantRpropState(NamedTuple):
    """Per-variable state (pytrees like the parameters)."""

    step_sizes: optax.Updates  # trust-region radius (Rprop step size)
    prev_grads: optax.Updates  # gradient at the previous point (0: none)
    prev_params: optax.Params  # the previous point


def scale_by_secant_rprop(initial_step: float, eta_minus: float = 0.5, eta_plus: float = 1.2,
                          min_step: float = 1e-15, max_step: float = 0.25,
                          secant: bool = True) -> optax.GradientTransformation:
    """Rprop whose step is a secant-Newton step when the curvature along a variable is known.

    Per variable: the step size adapts as in Rprop (x eta_plus when the gradient keeps its sign,
    x eta_minus when it flips). The curvature h = (g - g_prev) / (x - x_prev) is estimated from
    the last two points; where h > 0 the step is -g / h clipped to the step size (a trust
    region), else Rprop's -sign(g) step (and no move on a sign flip, iRprop-). Far from the
    optimum this is Rprop (scale-free, robust to a stress that varies as rho^-3/2); close to a
    smooth optimum the secant steps converge superlinearly instead of Rprop's halving, and at a
    kink the flips shrink the trust region as in Rprop. Returns the *update* (to be added);
    needs ``params``. With ``secant=False`` it is plain iRprop- (as ``torch.optim.Rprop``; tested).
    """

    def init_fn(params):
        return ScaleBySecantRpropState(optax.tree.full_like(params, initial_step),
                                       optax.tree.zeros_like(params), params)

    def update_fn(grads, state, params=None):
        if params is None:
            raise ValueError("scale_by_secant_rprop needs params")

        def leaf(g, g0, x, x0, step):
            flip = g * g0
            step = jnp.where(flip > 0, step * eta_plus, jnp.where(flip < 0, step * eta_minus, step))
            step = jnp.clip(step, min_step, max_step)
            dx, dg = x - x0, g - g0
            known = (dx != 0) & (g0 != 0)
            h = jnp.where(known, dg / jnp.where(known, dx, 1.0), 0.0)
            newton = (h > 0) if secant else jnp.zeros_like(h, dtype=bool)
            newton_step = jnp.clip(-g / jnp.where(newton, h, 1.0), -step, step)
            update = jnp.where(newton, newton_step, jnp.where(flip < 0, 0.0, -jnp.sign(g) * step))
            # after a flip without a secant step, iRprop- forgets the gradient (no double halving)
            g = jnp.where(newton | (flip >= 0), g, 0.0)
            return update, step, g

        args = (grads, state.prev_grads, params, state.prev_params, state.step_sizes)
        updates = jax.tree.map(lambda *a: leaf(*a)[0], *args)
        steps = jax.tree.map(lambda *a: leaf(*a)[1], *args)  # same ops: XLA computes them once
        memory = jax.tree.map(lambda *a: leaf(*a)[2], *args)
        return updates, ScaleBySecantRpropState(steps, memory, params)

    return optax.GradientTransformation(init_fn, update_fn)


# ------------------------------------------------------------------------- Lagrangian


def scaled_constraints(problem: Problem, design: Design, aggregate: bool = False) -> Constraints:
    """g / N, dimensionless: (n,) each, or their maxima over angles, () each, with ``aggregate``.

    Every constraint is a design-independent per-angle term minus one design variable, so its max
    over angles (the family's ``constraint_maxima``) is exact and as smooth as the
    constraint itself: one multiplier per constraint instead of one per angle, same optimum.
    """
    family = family_of(problem)
    c = family.constraint_maxima(problem, design) if aggregate else family.constraints(problem, design)
    norm = family.size_norm(problem)
    return jax.tree.map(lambda g: g / norm, c)


def _aggregate(problem: Problem, settings: GradientSettings) -> bool:
    """One multiplier per constraint: the setting, unless the problem's family declares
    ``ONE_MULTIPLIER_PER_CONSTRAINT = False`` (its rows' max is not one design variable minus a
    fixed term, e.g. a robust problem's max over samples: :mod:`camjax.robust.design`)."""
    declared = getattr(family_of(problem), "ONE_MULTIPLIER_PER_CONSTRAINT", True)
    return settings.aggregate_constraints and declared


def augmented_lagrangian(u: Design, problem: Problem, weights: Weights, multipliers: Constraints,
                         penalty: float, aggregate: bool = False) -> tuple[jax.Array, Constraints]:
    """L_A at unit-box point ``u``, and the scaled constraints there (aux).

    ``multipliers`` match :func:`scaled_constraints` (per angle, or per constraint with
    ``aggregate``).
    """
    design = from_unit(problem, u)
    g = scaled_constraints(problem, design, aggregate)
    terms = jax.tree.map(
        lambda gi, lam: jnp.sum(jnp.maximum(gi + lam / penalty, 0.0) ** 2 - (lam / penalty) ** 2),
        g, multipliers)
    return solver_objective(problem, weights, design) + 0.5 * penalty * sum(jax.tree.leaves(terms)), g


def _projected_gradient(problem: Problem, u: Design, grad: Design) -> Design:
    """Zero the components that would push a variable at a bound out of the box."""
    return jax.tree.map(
        lambda v, gr, top: jnp.where(((v <= 0) & (gr > 0)) | ((v >= top) & (gr < 0)), 0.0, gr),
        u, grad, u_max_of(problem))


def _tree_max_abs(tree) -> jax.Array:
    return jnp.max(jnp.stack([jnp.max(jnp.abs(x)) for x in jax.tree.leaves(tree)]))


# --------------------------------------------------------------------------- init/step


def init(problem: Problem, design: Design | None = None,
         settings: GradientSettings = DEFAULT_SETTINGS) -> GradientState:
    """Start at ``design`` (mm; default: the family's ``start(problem)`` where it has one, else the
    centre of the box), multipliers 0."""
    if design is None:
        design = default_start(problem)
    dtype = problem_dtype(problem)
    u = clip_unit(problem, jax.tree.map(lambda x: jnp.asarray(x, dtype), to_unit(problem, design)))
    rprop = _transform(settings).init(u)
    shapes = jax.eval_shape(
        lambda v: scaled_constraints(problem, from_unit(problem, v), _aggregate(problem, settings)), u)
    zeros = jax.tree.map(lambda a: jnp.zeros(a.shape, a.dtype), shapes)
    inf = jnp.asarray(jnp.inf, dtype)
    return GradientState(u, rprop, zeros, jnp.asarray(0), jnp.asarray(0), inf, inf, jnp.asarray(False))


def step(state: GradientState, problem: Problem, weights: Weights,
         settings: GradientSettings = DEFAULT_SETTINGS) -> GradientState:
    """One projected Rprop step on L_A, a multiplier update when the inner problem has converged."""
    mu = settings.penalty
    (_, g), grad = jax.value_and_grad(augmented_lagrangian, has_aux=True)(
        state.u, problem, weights, state.multipliers, mu, _aggregate(problem, settings))
    pg = _projected_gradient(problem, state.u, grad)
    pg_norm = _tree_max_abs(pg)
    residual = _tree_max_abs(jax.tree.map(lambda gi, lam: jnp.minimum(-gi, lam / mu), g, state.multipliers))

    updates, rprop = _transform(settings).update(pg, state.rprop, state.u)
    u_next = clip_unit(problem, jax.tree.map(lambda v, d: v + d, state.u, updates))
    moving = jax.tree.map(lambda gr, s: jnp.where(gr != 0, s, 0.0), pg, rprop.step_sizes)

    # inexact inner solves while the multipliers are far off (steps to a fraction of the residual)
    inner_xtol = jnp.maximum(settings.xtol, settings.inner_rtol * residual)
    stalled = (_tree_max_abs(moving) <= inner_xtol) & (state.inner_step >= 2)
    inner_converged = (pg_norm <= settings.gtol) | stalled
    done = inner_converged & (residual <= settings.ctol)
    update = ~done & (inner_converged | (state.inner_step + 1 >= settings.inner_steps))

    multipliers = jax.tree.map(
        lambda lam, gi: jnp.where(update, jnp.clip(lam + mu * gi, 0.0, LAM_MAX), lam),
        state.multipliers, g)
    restarted = ScaleBySecantRpropState(
        # the minimizer moves by about the residual when the multipliers change: restart the
        # step sizes at that length (within [xtol, reset_step]) and forget the old curvature
        jax.tree.map(lambda s: jnp.maximum(s, jnp.clip(residual, 10 * settings.xtol, settings.reset_step)),
                     rprop.step_sizes),
        jax.tree.map(jnp.zeros_like, rprop.prev_grads), rprop.prev_params)
    rprop = jax.tree.map(lambda a, b: jnp.where(update, a, b), restarted, rprop)
    u = jax.tree.map(lambda a, b: jnp.where(done, a, b), state.u, u_next)
    return GradientState(
        u, rprop, multipliers,
        state.step + jnp.where(done, 0, 1),
        jnp.where(update, 0, state.inner_step + 1),
        pg_norm, residual, done)


def _transform(settings: GradientSettings) -> optax.GradientTransformation:
    return scale_by_secant_rprop(settings.initial_step, min_step=settings.min_step,
                                 max_step=settings.max_step, secant=settings.secant)


def postprocess(state: GradientState, problem: Problem, weights: Weights,
                settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Design in mm, judged with the true max over angles (after the BFGS refinement, if any)."""
    design = from_unit(problem, state.u)
    family = family_of(problem)
    steps, done = state.step, state.done
    if settings.refine_rounds > 0:
        # Rprop's own stopping rule on the gradient is a KKT point; a stall (steps shrunk by sign
        # flips, at a kink of a max over angles or in a curved valley) need not be, and is refined
        needed = ~(state.done & (state.pg_norm <= settings.gtol))
        refined, refine_steps, finished = refine_bfgs(problem, weights, state.u, settings, needed)
        # both designs judged in one (vmapped) evaluation: one trace of the family's physics
        both = jax.vmap(lambda d: family.evaluate(problem, weights, d))(
            jax.tree.map(lambda a, b: jnp.stack([a, b]), design, refined))
        ev, ev_r = jax.tree.map(lambda x: x[0], both), jax.tree.map(lambda x: x[1], both)
        # kept only when no worse: feasible, and a smaller objective or a feasibility repaired
        better = needed & ev_r.feasible & (~ev.feasible | (ev_r.objective <= ev.objective))
        design = jax.tree.map(lambda a, b: jnp.where(better, a, b), refined, design)
        ev = jax.tree.map(lambda a, b: jnp.where(better, a, b), ev_r, ev)
        # converged: Rprop's stopping rule, or the refinement's (its point no better: Rprop's kept)
        steps, done = steps + refine_steps, done | better | (needed & finished)
    else:
        ev = family.evaluate(problem, weights, design)
    return GradientResult(design, ev.objective, ev.violation, ev.feasible, steps, done,
                          state.pg_norm, state.multipliers)


def _to_angle(problem: Problem, u: Design) -> Design:
    """Unit box -> unbounded angles z, u = u_max (1 - cos z) / 2 (the inverse on [0, pi])."""
    return jax.tree.map(
        lambda v, top: jnp.arccos(jnp.clip(1.0 - 2.0 * v / jnp.where(top > 0, top, 1.0), -1.0, 1.0)),
        u, u_max_of(problem))


def _from_angle(problem: Problem, z: Design) -> Design:
    return jax.tree.map(lambda v, top: top * (0.5 - 0.5 * jnp.cos(v)), z, u_max_of(problem))


class _BfgsState(NamedTuple):
    x: jax.Array  # (m,) accepted point, box angle coordinates
    f: jax.Array  # () L_A there
    grad: jax.Array  # (m,) its gradient
    g: Constraints  # scaled constraints there, per angle
    h: jax.Array  # (m, m) inverse-Hessian estimate
    p: jax.Array  # (m,) search direction
    t: jax.Array  # () step length being tried
    lam: Constraints  # multipliers, per angle
    rnd: jax.Array  # () int: rounds (multiplier updates) so far
    k: jax.Array  # () int: evaluations in this round
    steps: jax.Array  # () int: evaluations in all
    fresh: jax.Array  # () bool: the next evaluation restarts a round at x
    done: jax.Array  # () bool


def refine_bfgs(problem: Problem, weights: Weights, u: Design,
                settings: GradientSettings = DEFAULT_SETTINGS, needed: jax.Array | bool = True
                ) -> tuple[Design, jax.Array, jax.Array]:
    """Augmented-Lagrangian rounds of BFGS with an Armijo line search, from unit-box point ``u``.

    Rprop moves each variable by the sign of its own derivative. Where the optimum sits on a
    kink of a max over angles (two angles' constraints active at once, e.g. the pressure angle
    on the rise and on the return, or the face width each needs) or in a curved valley that
    couples the variables (pivot distance, arm length and prime radius of a rocker), its steps
    flip sign and shrink until it stalls short of the optimum. Here every angle's constraint
    has its own multiplier (the aggregated max is a kink there), which makes L_A smooth, and a
    quasi-Newton step follows the valley. The box is kept by the map u = (1 - cos z) / 2 (z
    unbounded); with at most a handful of variables the inverse Hessian is kept dense.

    Each round minimizes L_A for fixed multipliers (to ``refine_gtol``, ``refine_steps``
    evaluations, or a line search that cannot decrease it any more: a kink), then updates the
    multipliers as :func:`step` does, the penalty growing from round to round
    (``refine_penalty_growth`` up to ``refine_penalty_max``) so that the last rounds end feasible
    to the families' tolerances. The rounds stop once a round ended on its gradient or line-search
    test with the AL residual within ``ctol``. Every loop iteration is one evaluation of L_A and
    its gradient (one trace: the compile cost of one more Rprop loop), the line search's trials
    included; none is run where ``needed`` is false (a vmapped batch runs until its last member
    is done). Returns the design (mm), the evaluations made and whether the rounds stopped on
    their rule (not on ``refine_rounds``).
    """
    x0, unravel = ravel_pytree(_to_angle(problem, u))
    dtype, m = x0.dtype, x0.shape[0]
    eye = jnp.eye(m, dtype=dtype)
    mu_max = max(settings.refine_penalty_max, settings.penalty)

    def penalty(rnd):
        return jnp.minimum(settings.penalty * settings.refine_penalty_growth ** rnd.astype(dtype), mu_max)

    def lagrangian(x, lam, mu):
        return augmented_lagrangian(_from_angle(problem, unravel(x)), problem, weights, lam, mu, False)

    value_and_grad = jax.value_and_grad(lagrangian, has_aux=True)
    # per-angle multipliers, 0 (their shapes only: nothing is traced)
    shapes = jax.eval_shape(lambda v: scaled_constraints(problem, from_unit(problem, v), False), u)
    lam0 = jax.tree.map(lambda a: jnp.zeros(a.shape, a.dtype), shapes)

    def body(s: _BfgsState) -> _BfgsState:
        mu = penalty(s.rnd)
        x_try = jnp.where(s.fresh, s.x, s.x + s.t * s.p)
        (f_try, g_try), grad_try = value_and_grad(x_try, s.lam, mu)
        f_try = f_try.astype(dtype)  # (the weights may be wider than the problem)
        slope = s.grad @ s.p
        ok = s.fresh | (jnp.isfinite(f_try) & (f_try <= s.f + qn.ARMIJO * s.t * slope))
        # BFGS update of the inverse Hessian on an accepted step with positive curvature
        dx, dg = x_try - s.x, grad_try - s.grad
        sy = dx @ dg
        curved = ok & ~s.fresh & qn.curvature_ok(sy, jnp.linalg.norm(dx), jnp.linalg.norm(dg))
        first = jnp.all(s.h == eye)  # the first update starts from the scaled identity
        h = jnp.where(first, qn.first_scaling(sy, jnp.where(curved, dg @ dg, 1.0), eye), s.h)
        h = jnp.where(curved, qn.inverse_hessian_update(h, dx, dg, jnp.where(curved, sy, 1.0), eye, jnp),
                      jnp.where(s.fresh, eye, s.h))
        x = jnp.where(ok, x_try, s.x)
        f = jnp.where(ok, f_try, s.f)
        grad = jnp.where(ok, grad_try, s.grad)
        g = jax.tree.map(lambda a, b: jnp.where(ok, a, b), g_try, s.g)
        p = -h @ grad
        p = jnp.where(p @ grad < 0, p, -grad)  # a descent direction (h reset if it is not)
        # first step of a round: 0.1 in the largest angle; else the full quasi-Newton step
        t_new = jnp.where(s.fresh, 0.1 / jnp.maximum(jnp.max(jnp.abs(p)), 1e-300), 1.0)
        # a rejected trial: the minimizer of the quadratic through f, the slope and f_try,
        # within [0.1, 0.5] of the step (a tenth of it where that quadratic has no minimum)
        t_back = qn.backtrack(s.t, slope, s.f, f_try, 0.1, jnp)
        t = jnp.where(ok, t_new, t_back).astype(dtype)
        p = jnp.where(ok, p, s.p)
        # end of a round: gradient small, line search exhausted (a kink: no decrease along p
        # above rounding) or the step cap
        gnorm = jnp.linalg.norm(grad)
        stuck = ~ok & (t * jnp.max(jnp.abs(p)) <= settings.xtol)
        solved = ok & (gnorm <= settings.refine_gtol)
        ends = solved | stuck | (s.k + 1 >= settings.refine_steps)
        residual = _tree_max_abs(jax.tree.map(lambda gi, lam: jnp.minimum(-gi, lam / mu), g, s.lam))
        finished = ends & (solved | stuck) & (residual <= settings.ctol)
        update = ends & ~finished
        lam = jax.tree.map(lambda lm, gi: jnp.where(update, jnp.clip(lm + mu * gi, 0.0, LAM_MAX), lm),
                           s.lam, g)
        rnd = s.rnd + jnp.where(update, 1, 0)
        done = finished | (rnd >= settings.refine_rounds)
        return _BfgsState(x, f, grad, g, jnp.where(update, eye, h), p, t, lam, rnd,
                          jnp.where(update, 0, s.k + 1), s.steps + 1, update, done)

    zero = jnp.asarray(0)
    start = _BfgsState(x0, jnp.asarray(jnp.inf, dtype), jnp.zeros_like(x0), lam0, eye, jnp.zeros_like(x0),
                       jnp.asarray(0.0, dtype), lam0, zero, zero, zero, jnp.asarray(True),
                       ~jnp.asarray(needed) | (settings.refine_rounds <= 0))
    end = jax.lax.while_loop(lambda s: ~s.done, body, start)
    design = from_unit(problem, _from_angle(problem, unravel(end.x)))
    return design, end.steps, end.rnd < settings.refine_rounds


# ------------------------------------------------------------------------------ solves


def minimize(problem: Problem, weights: Weights, init_design: Design | None = None,
             settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Solve one problem (global over its angle grid) for one weighting; traceable, vmappable.

    Args:
      problem: the problem, grid arrays of shape (n,).
      weights: scalar alpha, gamma.
      init_design: start (mm); default the centre of the box, and for a family with its own
        ``start(problem)`` both (the better result kept).
      settings: static configuration.
    """
    start = getattr(family_of(problem), "start", None)
    if init_design is not None or start is None:
        return _minimize_from(problem, weights, init_design, settings)
    # a family with its own start: solved from it and from the box's centre (one vmapped solve),
    # the better kept (feasible first, then the smaller objective); iterations are the sum
    both = jax.vmap(lambda d: _minimize_from(problem, weights, d, settings))(
        jax.tree.map(lambda a, b: jnp.stack([a, b]), start(problem), midpoint(problem)))
    first, second = jax.tree.map(lambda x: x[0], both), jax.tree.map(lambda x: x[1], both)
    take_second = (second.feasible & ~first.feasible) | (
        (second.feasible == first.feasible) & (second.objective < first.objective))
    best = jax.tree.map(lambda a, b: jnp.where(take_second, b, a), first, second)
    return best._replace(iterations=first.iterations + second.iterations)


def _minimize_from(problem: Problem, weights: Weights, init_design: Design | None,
                   settings: GradientSettings) -> GradientResult:
    def cond(state):
        return ~state.done & (state.step < settings.max_steps)

    state = init(problem, init_design, settings)
    state = jax.lax.while_loop(cond, partial(step, problem=problem, weights=weights, settings=settings),
                               state)
    return postprocess(state, problem, weights, settings)


@partial(jax.jit, static_argnames="settings")
def solve_global(problem: Problem, weights: Weights, init_design: Design | None = None,
                 settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Global mode, one weighting: one R_b and L for the whole cam (jitted :func:`minimize`)."""
    return minimize(problem, weights, init_design, settings)


def minimize_pointwise(problem: Problem, weights: Weights, init_design: Design | None = None,
                       settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Pointwise mode, one weighting: the n one-angle problems at once (vmap), leaves of shape (n,).

    ``init_design`` (optional) holds one start per angle, shape (n,) each. Traceable.
    """
    run = in_mode(lambda p, w, _key, init=None: minimize(p, w, init, settings), "pointwise")
    return run(problem, weights, jax.random.key(0), init_design)


@partial(jax.jit, static_argnames="settings")
def solve_pointwise(problem: Problem, weights: Weights, init_design: Design | None = None,
                    settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Jitted :func:`minimize_pointwise`."""
    return minimize_pointwise(problem, weights, init_design, settings)


@partial(jax.jit, static_argnames=("mode", "settings"))
def solve_sweep(problem: Problem, weights: Weights, mode: str = "global", init_design: Design | None = None,
                settings: GradientSettings = DEFAULT_SETTINGS) -> GradientResult:
    """Many weightings at once: ``weights`` leaves of shape (w,); results get a leading axis w.

    mode "global": leaves (w,); "pointwise": leaves (w, n) (one solve per weighting and angle;
    the mode is applied by :func:`camjax.solvers.base.in_mode`). ``init_design`` (optional) has
    the same leading axes as the result. The solver's raw results; :func:`camjax.solvers.base.solve_batch`
    gives :class:`~camjax.solvers.base.Solution` s.
    """
    inner = in_mode(lambda p, w, _key, init=None: minimize(p, w, init, settings), mode)
    key = jax.random.key(0)  # unused: the gradient solver is deterministic
    if init_design is None:
        return jax.vmap(lambda w: inner(problem, w, key))(weights)
    return jax.vmap(lambda w, d: inner(problem, w, key, d))(weights, init_design)


def run_one(problem: Problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """The solver protocol of :mod:`camjax.solvers.base`: :func:`minimize` with ``settings.of("gradient")``.

    ``key`` is unused (deterministic). Converged when the stopping rule was met before max_steps.
    """
    res = minimize(problem, weights, init, settings.of("gradient"))
    return Raw(res.design, res.iterations, res.converged)
