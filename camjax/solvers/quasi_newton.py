"""The quasi-Newton arithmetic shared by camjax's two BFGS loops.

- :func:`camjax.solvers.gradient.refine_bfgs`, the gradient solver's augmented-Lagrangian BFGS, is
  traced: one ``lax.while_loop`` of ``jax.numpy`` arrays, branches as ``where``.
- :func:`camjax.codesign.search.bfgs`, the co-design's outer search on F(z), runs in Python on NumPy
  arrays: each of its trials is an inner design solve warm-started from the last one, which a
  traced loop cannot hold.

Both take their Armijo constant, their test for a usable step, the inverse-Hessian update with
its first scaling, and the backtracking step from here. The functions use only what NumPy and
``jax.numpy`` share, with the namespace passed as ``xp``: one formula, in the order of its
operations, for either loop. They work under ``jit``, ``vmap`` and ``grad`` with ``xp=jax.numpy``.
"""

from __future__ import annotations

from typing import Any

ARMIJO = 1e-4  # sufficient decrease: f(x + t p) <= f(x) + ARMIJO t (grad f . p)


def curvature_ok(sy, s_norm, y_norm):
    """Whether a step s with gradient change y keeps the update positive definite:
    s.y > 1e-12 |s| |y| (both loops skip the update otherwise)."""
    return sy > 1e-12 * s_norm * y_norm


def first_scaling(sy, yy, eye):
    """The inverse Hessian before the first update, (s.y / y.y) I (Shanno's scaling: the
    curvature seen along the first step, in every direction)."""
    return sy / yy * eye


def inverse_hessian_update(h, s, y, sy, eye, xp: Any):
    """BFGS update of the inverse Hessian ``h`` with the step ``s`` and the change of gradient
    ``y`` (``sy`` = s.y > 0, passed in so a traced caller can guard it):

        h+ = (I - rho s y^T) h (I - rho y s^T) + rho s s^T,   rho = 1 / s.y.

    ``eye`` is the identity of h's size and dtype, ``xp`` ``numpy`` or ``jax.numpy``.
    """
    rho = 1.0 / sy
    v = eye - rho * xp.outer(s, y)
    return v @ h @ v.T + rho * xp.outer(s, s)


def backtrack(step, slope, f, f_step, fallback: float, xp: Any):
    """The next step length after ``step`` failed the Armijo test: the minimizer of the quadratic
    through f (``f``), the slope along the direction (``slope`` < 0) and f at the step (``f_step``),
    kept within [0.1, 0.5] x ``step``; ``fallback`` x ``step`` where f at the step is not finite
    (an infeasible inner problem, an overflow) or the quadratic has no minimum. Where a step
    overshoots by far (a kink), the step shrinks by 10 at once instead of by 2 per trial."""
    curvature = f_step - f - step * slope
    quadratic = xp.isfinite(f_step) & (curvature > 0)
    t_quad = -slope * step**2 / (2.0 * xp.where(curvature > 0, curvature, 1.0))
    return xp.where(quadratic, xp.clip(t_quad, 0.1 * step, 0.5 * step), fallback * step)
