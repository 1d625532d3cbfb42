"""The flat-face problem's optimum in closed form and its exact polish (SPEC 5).

Pointwise, the best R_b at each angle has a closed form (the stress term against the size term,
:func:`optimal_curvature_radius`, :func:`pointwise_optimum`); globally, the design needs are found by
bisection on R_b (:func:`global_optimum`); L is the smallest admissible face width either way. These
are the independent references the solvers are checked against. With exact extrema,
:func:`polish` and :func:`polish_pointwise` move a solver's design (found on the sample grid) to
the continuous optimum (the problem's protocol hooks of the same names call them).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp

from camjax.contact import stress_from_coefficient
from camjax.family import (
    Weights,
)
from camjax.followers.flat.needs import (
    Design,
    Problem,
    exact_peak_stress,
    face_width_need,
    required_base_radius,
    required_face_width,
    rho_need,
)
from camjax.numerics import safe_divide

POLISH_STEPS = 12  # most refinements of the peak per polish (it stops once the point holds)
STOP_RTOL = 1e-9  # a model step shorter than this (relative) ends the search: its point is the optimum
# Newton steps of the peak refinements inside the polish: the scan leaves 1/8 of two samples,
# which Newton closes in ~5; the final evaluation refines with the full ITERATIONS.
POLISH_ITERATIONS = 8


def polish(problem: Problem, weights: Weights, design: Design) -> Design:
    """The exact optimum near a solver's design, when the problem carries :class:`ExactExtrema`.

    L: the objective grows with L, so the optimum is the smallest feasible L, clip(2 max|s'|,
    L_lo, L_hi), exact. R_b: g(R) = alpha R / N + gamma sigma_peak(R) / sigma_max is convex on
    the feasible [R_need, R_hi] (as in :func:`global_optimum`); its derivative, by the envelope
    theorem at the refined peak, is nondecreasing. Every point evaluated narrows the bracket
    [a, b] with g'(a) < 0 < g'(b) that the solver's R splits off [R_need, R_hi]. The next point
    is the model step: the peak's coefficient C* and curvature radius rho* at the last point give
    g' as alpha / N - gamma C* / (2 sigma_max (R + rho* - R_last)^(3/2)) while the peak stays at
    its angle, whose root is :func:`optimal_curvature_radius` - q* (exact in one step when the
    peak's angle does not move with R; a fast fixed point when it moves a little); bisection
    when that leaves the bracket or the last step did not halve |g'| (the peak jumps between
    two angles: a kink). It stops once a model step is shorter than :data:`STOP_RTOL` (its point
    is the answer) or after :data:`POLISH_STEPS` (the point of least |g'| seen is). An end is kept when g'
    does not change sign there. The ends' peak slopes do not depend on the weighting: under
    ``vmap`` over weightings they are computed once. Without ``problem.exact`` the design is
    returned unchanged. Traceable and vmappable.
    """
    if problem.exact is None:
        return design
    width = jnp.clip(required_face_width(problem), problem.lower.face_width_mm, problem.upper.face_width_mm)
    lo = jnp.minimum(jnp.maximum(problem.lower.base_radius_mm, required_base_radius(problem)),
                     problem.upper.base_radius_mm)
    hi = problem.upper.base_radius_mm

    def peak_stress(r):
        return exact_peak_stress(problem, Design(r, width), POLISH_ITERATIONS).value

    peak = jax.value_and_grad(peak_stress)  # (sigma*, d sigma*/dR), the slope by the envelope theorem

    def slope(peak_slope):
        return weights.alpha / problem.size_norm_mm + weights.gamma * peak_slope / problem.sigma_max_MPa

    def model_step(x, sigma, peak_slope):
        # sigma = C / sqrt(rho) and d sigma / dR = -C / (2 rho^(3/2)) at the peak: rho* and C*
        rho = safe_divide(-sigma, 2.0 * peak_slope, fallback=jnp.inf)
        coefficient = sigma * jnp.sqrt(jnp.where(jnp.isfinite(rho) & (rho > 0), rho, 0.0))
        best_rho = optimal_curvature_radius(weights, coefficient, problem.sigma_max_MPa, problem.size_norm_mm)
        return x + best_rho - rho  # R + rho_best - rho*: inf or nan fall to bisection

    # weighting-independent peaks; mapped, not called twice: the refined peak is traced once here
    g_lo, g_hi = slope(jax.lax.map(peak, jnp.stack([lo, hi]))[1])
    interior = (g_lo < 0) & (g_hi > 0)  # else an end is the optimum: no search

    def settled(x, nxt):  # the next step is shorter than STOP_RTOL
        return jnp.abs(nxt - x) <= STOP_RTOL * (1.0 + jnp.abs(x))

    def cond(state):
        i, a, b, g_last, x, nxt, best, g_best = state
        return interior & (i < POLISH_STEPS) & ((i == 0) | ~settled(x, nxt)) & (g_best != 0)

    def body(state):
        i, a, b, g_last, x, nxt, best, g_best = state
        x = nxt
        sigma, peak_slope = peak(x)
        g = slope(peak_slope)
        a, b = jnp.where(g < 0, x, a), jnp.where(g < 0, b, x)
        closer = jnp.abs(g) < jnp.abs(g_best)
        best, g_best = jnp.where(closer, x, best), jnp.where(closer, g, g_best)
        # the model step, unless it leaves the bracket or the last one did not halve |g'| (the
        # peak jumps between two angles at a kink): then bisection, which halves the bracket
        step = model_step(x, sigma, peak_slope)
        use_model = (step >= a) & (step <= b) & (jnp.abs(g) <= 0.5 * jnp.abs(g_last))
        nxt = jnp.where(use_model, step, 0.5 * (a + b))
        return i + 1, a, b, g, x, nxt, best, g_best

    r0 = jnp.clip(design.base_radius_mm, lo, hi)
    inf = jnp.full_like(lo, jnp.inf)
    state = (jnp.zeros((), jnp.int32), lo, hi, inf, r0, r0, r0, inf)
    i, a, b, g_last, x, nxt, best, g_best = jax.lax.while_loop(cond, body, state)
    # a search that stopped on a short model step ends at that step's point (the model steps
    # contract, so its error is a fraction of that step, already below STOP_RTOL); one stopped
    # by the step count or at a kink, at the point of least |g'| seen
    x = jnp.where(settled(x, nxt) & (nxt >= a) & (nxt <= b), nxt, best)
    radius = jnp.where(g_lo >= 0, lo, jnp.where(g_hi <= 0, hi, x))
    return Design(jax.lax.stop_gradient(radius), width)


def optimal_curvature_radius(weights: Weights, coefficient, sigma_max_MPa, size_norm_mm) -> jax.Array:
    """Unconstrained minimizer rho* of alpha rho / N + gamma C / (sigma_max sqrt(rho)), mm.

    rho* = (gamma N C / (2 alpha sigma_max))^(2/3); +inf when alpha = 0 < gamma C (the stress
    term alone wants an infinite cam), 0 when gamma C = 0 (the size term alone wants the smallest).
    """
    num = weights.gamma * size_norm_mm * coefficient
    den = 2.0 * weights.alpha * sigma_max_MPa
    ratio = safe_divide(num, den, fallback=jnp.inf)
    ratio = jnp.where(num > 0, ratio, 0.0)
    return jnp.where(jnp.isfinite(ratio), jnp.cbrt(jnp.where(jnp.isfinite(ratio), ratio, 0.0)) ** 2, jnp.inf)


def pointwise_optimum(problem: Problem, weights: Weights) -> Design:
    """Closed-form optimum of the problem at each angle separately, arrays of shape (n,).

    Derivation. At one angle F(R, L) = alpha (R + L)/N + gamma C / (sigma_max sqrt(R + q)) is a
    sum of a function of L and a function of R, and every constraint involves only one of them,
    so the problem splits.

    * L: minimize alpha L / N on [max(L_lo, 2|s'|), L_hi]: the lower end. (With alpha = 0 the
      objective does not depend on L; we break the tie the same way, the smallest feasible L.)
    * R: curvature and stress are both lower bounds on rho, so the feasible set is
      [R_need, R_hi] with R_need = max(R_lo, -q + max(rho_min, (C/sigma_max)^2)). On rho > 0,
      f(R) = alpha R / N + gamma C / (sigma_max sqrt(R + q)) is convex (linear + convex), with
      f'(R) = alpha/N - gamma C / (2 sigma_max) rho^(-3/2) = 0 at
      rho* = (gamma N C / (2 alpha sigma_max))^(2/3). A convex 1-D function is minimized on an
      interval at its stationary point projected onto the interval:
      R* = clip(-q + rho*, R_need, R_hi). alpha = 0 gives rho* = inf (R* = R_hi); gamma = 0 or
      C = 0 gives rho* = 0 (R* = R_need).
    * Infeasible angles (R_need > R_hi or 2|s'| > L_hi) get the closest bound, R_hi or L_hi; the
      violation is reported by :func:`violation`, not hidden.

    Per-angle: L* = clip(max(2|s'|, L_lo), -, L_hi); R* = min(max(-q + rho*, R_need), R_hi).
    """
    c = problem.stress_coefficient
    rho_star = optimal_curvature_radius(weights, c, problem.sigma_max_MPa, problem.size_norm_mm)
    r_need = jnp.maximum(problem.lower.base_radius_mm, rho_need(problem) - problem.q_mm)
    r = jnp.minimum(jnp.maximum(rho_star - problem.q_mm, r_need), problem.upper.base_radius_mm)
    l_need = jnp.maximum(problem.lower.face_width_mm, face_width_need(problem))
    length = jnp.minimum(l_need, problem.upper.face_width_mm)
    return Design(r, length)


@functools.partial(jax.jit, static_argnames="bisections")
def global_optimum(problem: Problem, weights: Weights, bisections: int = 200) -> Design:
    """Exact optimum of the global problem (one R_b, L), by bisection on a convex 1-D function.

    A reference that uses the structure of this two-variable problem (it does not extend to new
    design variables; the generic solvers do not rely on it). L splits off exactly as in
    :func:`pointwise_optimum` with 2 max|s'|. For R, g(R) = alpha R / N + gamma max_theta
    sigma_theta(R) / sigma_max is convex (a max of convex functions plus a linear one) on the
    feasible interval [R_need, R_hi]; its right derivative
    g'(R) = alpha/N - gamma C_k / (2 sigma_max rho_k^(3/2)), k = argmax_theta sigma_theta(R),
    is nondecreasing, and bisection on its sign converges to the minimizer (a kink where two
    angles share the max included). ``bisections`` halvings of [R_need, R_hi] (200: to the last
    bit in float64). A problem with :class:`ExactExtrema` gets the continuous optimum
    (:func:`polish` from the grid's). Returns scalars. Compiled once per problem form (its grid's
    shape and, with exact extrema, its laws); the weights and the scene's values are data, so a
    reference over many weightings compiles once.
    """
    lo_r = jnp.maximum(problem.lower.base_radius_mm, required_base_radius(problem))
    hi_r = problem.upper.base_radius_mm
    lo_r = jnp.minimum(lo_r, hi_r)  # infeasible: R_hi, reported as such

    def slope(r):
        rho = r + problem.q_mm
        sigma = stress_from_coefficient(problem.stress_coefficient, rho)
        k = jnp.argmax(sigma)
        rho_k = jnp.maximum(rho[k], problem.rho_min_mm)
        dsigma = -0.5 * problem.stress_coefficient[k] * rho_k ** -1.5
        return weights.alpha / problem.size_norm_mm + weights.gamma * dsigma / problem.sigma_max_MPa

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        up = slope(m) >= 0
        return jnp.where(up, a, m), jnp.where(up, m, b)

    a, b = jax.lax.fori_loop(0, bisections, halve, (lo_r, hi_r))
    r = jnp.where(slope(lo_r) >= 0, lo_r, jnp.where(slope(hi_r) < 0, hi_r, 0.5 * (a + b)))
    l_need = jnp.maximum(problem.lower.face_width_mm, required_face_width(problem))
    # with exact extrema the grid's optimum is the start of the polish to the continuous one
    return polish(problem, weights, Design(r, jnp.minimum(l_need, problem.upper.face_width_mm)))


def polish_pointwise(problem: Problem, weights: Weights, design: Design, extras: dict) -> tuple[Design, dict]:
    """The condensed pointwise design as continuous maxima over the angle (with ``problem.exact``).

    R_b: the largest per-angle optimum R*(theta) of :func:`pointwise_optimum`, a closed form in
    q(theta), C(theta) and s'(theta), refined off the grid from the scene's closed forms (its
    kinks, where a constraint takes over, are handled by the bisection fallback). L: the largest
    per-angle width, clip(2 max|s'|, L_lo, L_hi), exact. Without ``problem.exact``: unchanged.
    """
    if problem.exact is None:
        return design, extras
    from camjax import extrema
    from camjax.evaluate import model_at
    from camjax.program import segment_bounds_deg

    model, plain = problem.exact.model, problem._replace(exact=None)

    def fn(segment, theta_deg, params):
        m, pr, w = params
        p = model_at(m, segment, theta_deg)
        at = pr._replace(theta_deg=theta_deg, q_mm=p.kin.s + p.kin.d2s, ds_mm=p.kin.ds,
                         stress_coefficient=p.stress_coefficient)
        return pointwise_optimum(at, w).base_radius_mm

    grid = pointwise_optimum(plain, weights).base_radius_mm
    e = extrema.refine_max(fn, (model, plain, weights), segment_bounds_deg(model.program), grid,
                           constant=extrema.dwells(model.program))
    width = jnp.clip(problem.exact.face_width_need_mm, problem.lower.face_width_mm,
                     problem.upper.face_width_mm)
    extras = {**extras, "base_radius_deg": e.angle_deg, "face_width_deg": problem.exact.face_width_need_deg}
    return Design(e.value, width), extras


