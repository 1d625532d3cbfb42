"""A dense convex QP by a primal-dual interior-point method: one problem, at most a given number of steps.

    minimize 0.5 x^T P x + q^T x   subject to   G x <= h

Mehrotra's predictor-corrector on the slack form G x + s = h, s >= 0, multipliers lam >= 0: each
step solves the reduced Newton system (P + G^T diag(lam/s) G) dx = ... by Cholesky (n is a few
tens), takes the affine-scaling direction, centres it with sigma = (mu_aff / mu)^3 and the
second-order correction, and moves 0.99 of the way to the boundary. The whole solve is one
``lax.while_loop`` that stops once mu is below ``tol`` or after ``iterations`` steps; under vmap
a batch runs until its slowest member has converged, and a step after a member's convergence
leaves its iterate unchanged.

Why an interior-point method and not a first-order one: the synthesis problems are small and
dense (tens of variables, hundreds of constraints), where 20-30 Newton steps reach 1e-9 of the
optimum, while first-order LP/QP methods (PDHG, as in mpax) need thousands of steps for 1e-6.
No maintained JAX library solves dense QPs this way (jaxopt, which did, is unmaintained), and the
method is forty lines. Feasibility is never in question for the synthesis (its equality
constraints are eliminated and every inequality is an epigraph bound that a large t meets), so
the method starts from a strictly feasible point given by the caller.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp


class QPResult(NamedTuple):
    x: jax.Array  # (n,) the solution
    lam: jax.Array  # (m,) the inequality multipliers
    gap: jax.Array  # () duality measure mu = s . lam / m at the end
    residual: jax.Array  # () primal and dual residuals at the end, relative to their terms' sizes


def solve_qp(P, q, G, h, x0, lam0=None, iterations: int = 40, tol: float = 1e-13) -> QPResult:
    """Minimize 0.5 x'Px + q'x subject to Gx <= h from ``x0`` (G x0 < h preferred; the slacks
    start at max(h - G x0, 1e-3)) and ``lam0`` (default ones; a dual-feasible lam0 starts
    the method on the central path's side it converges fastest from). P must be positive
    semidefinite and P + G^T G definite; ``P = None`` is an LP (no quadratic term at all).
    Pure JAX, differentiable in none of its arguments (a solver, not a layer); vmap over any of them.

    Pass None rather than a matrix of zeros: XLA:CPU (jaxlib 0.10.2) compiles a batched
    ``x @ zeros @ x`` into a program that returns garbage (about 1e180) in roughly one compile of
    five, and the interior point's residuals and objective would carry it.
    """
    q, G, h, x0 = (jnp.asarray(a, dtype=jnp.float64) for a in (q, G, h, x0))
    m = G.shape[0]
    lam0 = jnp.ones(m) if lam0 is None else jnp.asarray(lam0, dtype=jnp.float64)
    n = q.shape[0]
    if P is None:
        quadratic, P_abs = (lambda x: 0.0 * x), 0.0  # noqa: E731
        hessian = lambda w: G.T @ (w[:, None] * G)  # noqa: E731
    else:
        P = jnp.asarray(P, dtype=jnp.float64)
        quadratic, P_abs = (lambda x: P @ x), jnp.max(jnp.abs(P))  # noqa: E731
        hessian = lambda w: P + G.T @ (w[:, None] * G)  # noqa: E731
    # rows scaled to unit norm: the same feasible set, multipliers of comparable size (a jerk row of
    # a fine spline is 1e5 times an epigraph column's -1); lam is scaled back at the end
    norms = jnp.sqrt(jnp.sum(G * G, axis=1))
    norms = jnp.where(norms > 0.0, norms, 1.0)
    G, h = G / norms[:, None], h / norms
    scale = 1.0 + P_abs + jnp.max(jnp.abs(G)) ** 2
    reg = 1e-13 * scale * jnp.eye(n)  # keeps the Cholesky defined once lam/s spans 1e30

    def residuals(x, s, lam):
        return quadratic(x) + q + G.T @ lam, G @ x + s - h

    def relative_residual(x, s, lam):
        rd, rp = residuals(x, s, lam)
        dual_size = 1.0 + jnp.maximum(jnp.max(jnp.abs(q)), jnp.max(jnp.abs(G.T @ lam)))
        primal_size = 1.0 + jnp.max(jnp.abs(h), initial=0.0)
        return jnp.maximum(jnp.max(jnp.abs(rd)) / dual_size, jnp.max(jnp.abs(rp), initial=0.0) / primal_size)

    def max_step(v, dv):
        ratio = jnp.where(dv < 0.0, -v / jnp.where(dv < 0.0, dv, -1.0), jnp.inf)
        return jnp.min(ratio, initial=jnp.inf)

    def step(carry):
        x, s, lam, k = carry
        rd, rp = residuals(x, s, lam)
        mu = jnp.dot(s, lam) / m
        w = lam / s
        chol = jnp.linalg.cholesky(hessian(w) + reg)

        def newton(rc):
            rhs = -rd - G.T @ ((-rc + lam * rp) / s)
            dx = jax.scipy.linalg.cho_solve((chol, True), rhs)
            ds = -rp - G @ dx
            dlam = (-rc - lam * ds) / s
            return dx, ds, dlam

        dx_a, ds_a, dlam_a = newton(s * lam)
        a_aff = jnp.minimum(1.0, jnp.minimum(max_step(s, ds_a), max_step(lam, dlam_a)))
        mu_aff = jnp.dot(s + a_aff * ds_a, lam + a_aff * dlam_a) / m
        sigma = jnp.clip(mu_aff / mu, 0.0, 1.0) ** 3
        dx, ds, dlam = newton(s * lam + ds_a * dlam_a - sigma * mu)
        alpha = jnp.minimum(1.0, 0.99 * jnp.minimum(max_step(s, ds), max_step(lam, dlam)))
        # converged: a smaller mu only loses the Newton system's digits (s or lam near 0 divides)
        done = (mu < tol) | ~jnp.all(jnp.isfinite(dx))
        keep = lambda old, new: jnp.where(done, old, new)  # noqa: E731
        return keep(x, x + alpha * dx), keep(s, s + alpha * ds), keep(lam, lam + alpha * dlam), k + 1

    def running(carry):
        _, s, lam, k = carry
        return (k < iterations) & (jnp.dot(s, lam) / m >= tol)

    s0 = jnp.maximum(h - G @ x0, 1e-3)
    x, s, lam, _ = jax.lax.while_loop(running, step, (x0, s0, lam0 * norms, jnp.zeros((), jnp.int32)))
    residual = relative_residual(x, s, lam)
    return QPResult(x, lam / norms, jnp.dot(s, lam) / m, residual)
