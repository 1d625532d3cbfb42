"""The synthesis of one law, as a pure JAX function of the conditions' values and the weights.

Objective: sum_k w_k peak_k + sum_l w_l L2_l over the free coordinates z (c = A^+ b + N z,
:mod:`camjax.synthesis.problem`), where L2_l = c^T Q_l c is exact (Gauss-Legendre per span) and
peak_k = max_i |(M_k c)_i| over the rows of :func:`camjax.synthesis.basis.peak_matrix`.

The peaks are not differentiable where two rows tie, which is exactly where their optimum lies
(the bang-bang accelerations and jerks of the known optima). The synthesis uses the **epigraph
form**: one variable t_k per peak term, minimize sum_k w_k t_k + sum_l w_l c^T Q_l c subject to
-t_k <= M_k c <= t_k. That is a convex QP (an LP for peaks alone) whose optimum is the true
minimax, solved to 1e-9 by an interior-point method (:mod:`camjax.synthesis.qp`). A smooth max
(log-sum-exp or a p-norm) would need a continuation in its sharpness and still stop a fraction
of a percent above the minimax at any finite sharpness, with gradients that grow ill-conditioned
as it sharpens; the epigraph form has neither problem and the same cost per step.

:func:`synthesizer` returns ``solve(values, weights) -> SynthesisResult`` for one problem; batch
it with ``jax.vmap`` over values and weights (:func:`batch_synthesizer`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.synthesis.problem import ALL_OBJECTIVES, L2_OBJECTIVES, PEAK_TERMS, SynthesisProblem
from camjax.synthesis.qp import solve_qp

ITERATIONS = 40  # interior-point steps: the known optima converge in 15-25 (tests/test_synthesis.py)


class Measures(NamedTuple):
    """A designed law's figures, normalized (units h / beta^k; l2: integral over x in [0, 1])."""

    peak_velocity: jax.Array
    peak_accel: jax.Array
    peak_jerk: jax.Array
    l2_accel: jax.Array
    l2_jerk: jax.Array
    peak_force: jax.Array  # N (N m): 0 without the train's force rows
    residual_vibration: jax.Array  # RMS over the term's speeds of A / |D|: 0 without the train


class SynthesisResult(NamedTuple):
    control: jax.Array  # (n,) control values of q (q(0) = 0, q(1) = 1)
    objective: jax.Array  # () sum of weight x measure over the objective's terms (true peaks)
    model_objective: jax.Array  # () the same on the synthesis' discretization (its optimum)
    measures: Measures
    gap: jax.Array  # () interior-point duality measure at the end (0 without peak terms)
    residual: jax.Array  # () interior-point residual at the end
    converged: jax.Array  # () bool


def measures(problem: SynthesisProblem, control) -> Measures:
    """Peak |q'|, |q''|, |q'''| (on 65 points per knot span: exact where the derivative is
    piecewise linear or constant) and the integrals of q''^2 and q'''^2 (exact). A derivative of
    an order above the degree is 0 here (the law has jumps there; reports leave it out). With the
    train (:mod:`camjax.synthesis.vibration`): the peak |contact force| on 65 points per span and
    the residual vibration (RMS over the speeds, normalized by the lift); else 0."""
    c = jnp.asarray(control)
    zero = jnp.zeros((), c.dtype)
    peak = {o: jnp.max(jnp.abs(m @ c)) for o, m in problem.dense.items()}
    l2 = {o: c @ (q @ c) for o, q in problem.grams.items()}
    force = residual = zero
    if problem.train is not None:
        if problem.train.force_dense is not None:
            force = jnp.max(jnp.abs(jnp.asarray(problem.train.force_dense) @ c))
        residual = jnp.sqrt(jnp.maximum(c @ (jnp.asarray(problem.train.residual_gram) @ c), 0.0))
    return Measures(peak.get(1, zero), peak.get(2, zero), peak.get(3, zero), l2.get(2, zero), l2.get(3, zero),
                    force, residual)


def objective_value(problem: SynthesisProblem, weights, m: Measures):
    """sum of weight x measure over the problem's objective terms (``weights`` in their order); the
    residual vibration enters squared (the mean square amplitude over the speeds: a quadratic)."""
    return sum(weights[i] * getattr(m, name) ** (2 if name == "residual_vibration" else 1)
               for i, name in enumerate(problem.objective))


def quadratic_of(problem: SynthesisProblem, name: str) -> np.ndarray:
    """The (n, n) matrix Q of a quadratic term c^T Q c: an L2 term's Gram matrix, or the mean square
    residual vibration's."""
    if name == "residual_vibration":
        return np.asarray(problem.train.residual_gram)
    return problem.grams[L2_OBJECTIVES[name]]


def synthesizer(problem: SynthesisProblem, iterations: int = ITERATIONS) -> Callable:
    """``solve(values, weights) -> SynthesisResult`` for ``problem``: ``values`` (r,) the kept
    conditions' right-hand sides (:func:`camjax.synthesis.problem.kept_values`), ``weights``
    (len(problem.objective),) >= 0. Pure JAX; jit and vmap it (the structure is in the closure)."""
    pinv = jnp.asarray(problem.A_pinv)
    null = jnp.asarray(problem.null)
    names = problem.objective
    peaks = [jnp.asarray(m) for m in problem.peak_rows]
    peak_at = [i for i, n in enumerate(names) if n in PEAK_TERMS]
    grams = {i: quadratic_of(problem, n) for i, n in enumerate(names) if n not in PEAK_TERMS}
    l2 = [(i, jnp.asarray(null.T @ q @ null), jnp.asarray(null.T @ q), jnp.asarray(q))
          for i, q in grams.items()]
    nz, k = problem.free, len(peaks)
    peak_null = [m @ null for m in peaks]

    def solve(values, weights):
        values = jnp.asarray(values, dtype=jnp.float64)
        weights = jnp.asarray(weights, dtype=jnp.float64)
        cp = pinv @ values if values.shape[0] else jnp.zeros(problem.basis.n)
        # the L2 terms as 0.5 z'Pz z + qz'z + const; None without any (no matrix of zeros: see
        # camjax.synthesis.qp.solve_qp on XLA's batched x @ zeros @ x)
        Pz = qz = None
        const = jnp.zeros(())
        for i, NQN, NQ, Q in l2:
            Pz = 2.0 * weights[i] * NQN if Pz is None else Pz + 2.0 * weights[i] * NQN
            qz = 2.0 * weights[i] * (NQ @ cp) if qz is None else qz + 2.0 * weights[i] * (NQ @ cp)
            const = const + weights[i] * (cp @ Q @ cp)

        def l2_part(z):
            return const if Pz is None else 0.5 * z @ Pz @ z + qz @ z + const

        if k == 0:
            z = jnp.linalg.solve(Pz + 1e-14 * jnp.eye(nz), -qz)
            gap = residual = jnp.zeros(())
            model = l2_part(z)
        else:
            P = None if Pz is None else jnp.zeros((nz + k, nz + k)).at[:nz, :nz].set(Pz)
            q = jnp.concatenate([jnp.zeros(nz) if qz is None else qz, weights[jnp.asarray(peak_at)]])
            blocks, rhs, start_t, lam0 = [], [], [], []
            for j, (mn, m) in enumerate(zip(peak_null, peaks, strict=True)):
                e = -jnp.zeros((mn.shape[0], k)).at[:, j].set(1.0)
                blocks += [jnp.concatenate([mn, e], 1), jnp.concatenate([-mn, e], 1)]
                rhs += [-(m @ cp), m @ cp]
                start_t.append(jnp.max(jnp.abs(m @ cp)) + 1.0)
                # dual feasible for t_k (its multipliers sum to w_k) and, without L2 terms, for z
                share = jnp.maximum(weights[peak_at[j]], 1e-8) / (2.0 * m.shape[0])
                lam0.append(jnp.full(2 * m.shape[0], share))
            G, h = jnp.concatenate(blocks, 0), jnp.concatenate(rhs)
            x0 = jnp.concatenate([jnp.zeros(nz), jnp.stack(start_t)])
            res = solve_qp(P, q, G, h, x0, jnp.concatenate(lam0), iterations)
            z = res.x[:nz]
            # the model's objective with t at its least value for this z (t_k = max |M_k c|)
            c = cp + null @ z
            t = jnp.stack([jnp.max(jnp.abs(m @ c)) for m in peaks])
            model = l2_part(z) + q[nz:] @ t
            gap, residual = res.gap, res.residual
        c = cp + null @ z
        meas = measures(problem, c)
        obj = objective_value(problem, weights, meas)
        ok = jnp.all(jnp.isfinite(c)) & (gap < 1e-8 * (1.0 + jnp.abs(model))) & (residual < 1e-6)
        return SynthesisResult(c, obj, model, meas, gap, residual, ok)

    return solve


def batch_synthesizer(problem: SynthesisProblem, iterations: int = ITERATIONS) -> Callable:
    """``jit(vmap(solve))``: values (B, r) and weights (B, terms) -> a SynthesisResult of arrays
    with a leading batch axis."""
    return jax.jit(jax.vmap(synthesizer(problem, iterations)))


def weights_vector(problem: SynthesisProblem, weights: dict) -> np.ndarray:
    """The weights of a {name: weight} mapping in the problem's term order (0 for names absent)."""
    unknown = [n for n in weights if n not in ALL_OBJECTIVES]
    if unknown:
        raise ValueError(f"{unknown[0]}: unknown objective term (allowed: {', '.join(ALL_OBJECTIVES)})")
    return np.asarray([float(weights.get(n, 0.0)) for n in problem.objective], dtype=np.float64)
