"""The peak terms of a co-design (``peak_velocity``, ``peak_accel``, ``peak_jerk``, ``peak_force``):
a smooth maximum, sharpened by a continuation.

Each designed segment's peak term is w max_i |v_i(z)| with v(z) = R c(z) affine in the laws'
coordinates z (c = cp + N z, :mod:`camjax.synthesis.linear`): R the rows ``camjax synthesize``
takes for that term (:func:`camjax.synthesis.basis.peak_matrix`: the derivative's control values,
exact, or its values at ``samples_per_span`` + 1 points per knot span; the follower train's
contact force at those points for ``peak_force``, :func:`camjax.synthesis.vibration.force_matrix`).

**Why a smooth maximum.** F(z) = (the geometry's optimum on the kinematics of z) + (the law terms)
is a bilevel value function searched by BFGS (:mod:`camjax.codesign.search`): an epigraph form
(t >= |v_i|, minimize t) needs a constrained outer solver, and the exact LP of ``camjax
synthesize`` does not apply because the geometry's part of F is not linear in z. So the search
minimizes F_tau, each peak replaced by

    M_tau(v) = tau log sum_i (e^{v_i / tau} + e^{-v_i / tau}),
    max|v| <= M_tau(v) <= max|v| + tau log(2 P)          (P the rows),

smooth in z, with a continuation tau_k = TAU_START 10^-k x (the term's peak at the start), each
stage's BFGS started from the last stage's answer, down to TAU_END: the last stage's smoothing
costs at most w tau log(2 P) on the objective (:func:`smoothing_bound`), 7e-7 of the peak with
P ~ 500. The reported objective and figures take the exact maximum on the dense rows
(``MEASURE_PER_SPAN`` points per span, as ``camjax synthesize`` reports its peaks).

NumPy data built once (:func:`peak_terms`); the smooth value and its gradient are one jitted pure
JAX function of z and tau.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.synthesis.basis import evaluation_matrix, peak_matrix, span_points
from camjax.synthesis.problem import MEASURE_PER_SPAN, PEAK_OBJECTIVES, PEAK_TERMS
from camjax.synthesis.vibration import force_matrix

TAU_START = 1e-1  # the first stage's tau, relative to each term's peak at the start
TAU_END = 1e-7  # the last stage's tau, relative (the smoothing bound: TAU_END log(2 P) of the peak)


class PeakTerms(NamedTuple):
    """The co-design's peak terms, one per (term, designed segment): |R z + r0| (NumPy)."""

    labels: tuple[str, ...]  # e.g. "peak_accel of motion.segments[1]"
    weights: np.ndarray  # (terms,)
    rows: tuple[np.ndarray, ...]  # per term (points, nz): the search's rows in z
    offsets: tuple[np.ndarray, ...]  # per term (points,)
    dense_rows: tuple[np.ndarray, ...]  # per term (dense points, nz): the reported peak's
    dense_offsets: tuple[np.ndarray, ...]


def peak_terms(lin, designed, weights: dict, samples_per_span: int, train=None) -> PeakTerms | None:
    """The peak terms of ``weights`` ({name: weight}; the names of :data:`PEAK_TERMS` are taken, the
    others ignored) on every designed segment, in the coordinates of ``lin``; ``train``: the
    follower train (:class:`camjax.synthesis.vibration.Train`, with its spring) for ``peak_force``.
    None when there is no peak term."""
    names = [n for n in PEAK_TERMS if weights.get(n, 0.0) > 0.0]
    if not names:
        return None
    labels, ws, rows, offsets, drows, doffsets = [], [], [], [], [], []
    for seg, ds in zip(lin.segments, designed, strict=True):
        basis = ds.basis()
        sl = slice(seg.offset, seg.offset + seg.null.shape[1])
        for name in names:
            if name == "peak_force":
                search = force_matrix(basis, train, ds, span_points(basis, samples_per_span))
                dense = force_matrix(basis, train, ds, span_points(basis, MEASURE_PER_SPAN))
            else:
                order = PEAK_OBJECTIVES[name]
                search = peak_matrix(basis, order, samples_per_span)[0]
                dense = evaluation_matrix(basis, span_points(basis, MEASURE_PER_SPAN), order)
            for R, out_rows, out_offsets in ((search, rows, offsets), (dense, drows, doffsets)):
                full = np.zeros((R.shape[0], lin.free))
                full[:, sl] = R @ seg.null
                out_rows.append(full)
                out_offsets.append(R @ seg.cp)
            labels.append(f"{name} of motion.segments[{ds.index}]")
            ws.append(float(weights[name]))
    return PeakTerms(tuple(labels), np.asarray(ws), tuple(rows), tuple(offsets), tuple(drows),
                     tuple(doffsets))


def soft_peak(v, tau):
    """M_tau(v) = tau log sum (e^{v/tau} + e^{-v/tau}) >= max|v| (pure JAX; finite for every tau > 0)."""
    return tau * jax.nn.logsumexp(jnp.concatenate([v, -v]) / tau)


def _smooth(z, taus, rows, offsets, weights):
    total = 0.0
    for k, (R, r0) in enumerate(zip(rows, offsets, strict=True)):
        total = total + weights[k] * soft_peak(R @ z + r0, taus[k])
    return total


_smooth_value_and_grad = jax.jit(jax.value_and_grad(_smooth))


def smooth_value(terms: PeakTerms, z, taus) -> tuple[float, np.ndarray]:
    """sum_k w_k M_tau_k(R_k z + r0_k) and its gradient in z (NumPy floats)."""
    f, g = _smooth_value_and_grad(jnp.asarray(z, dtype=jnp.float64), jnp.asarray(taus), terms.rows,
                                  terms.offsets, jnp.asarray(terms.weights))
    return float(f), np.asarray(g)


def peaks(terms: PeakTerms, z, dense: bool = True) -> np.ndarray:
    """Each term's exact max|v| (NumPy) on the dense rows (default) or the search's rows."""
    z = np.asarray(z, dtype=np.float64)
    rows, offsets = (terms.dense_rows, terms.dense_offsets) if dense else (terms.rows, terms.offsets)
    return np.asarray([float(np.max(np.abs(R @ z + r0))) for R, r0 in zip(rows, offsets, strict=True)])


def exact_value(terms: PeakTerms, z) -> float:
    """sum_k w_k max|v_k| on the dense rows (what the report gives)."""
    return float(terms.weights @ peaks(terms, z))


def schedule(terms: PeakTerms, z0) -> list[np.ndarray]:
    """The continuation's taus per stage (each (terms,)): TAU_START down to TAU_END by factors of
    10, relative to each term's peak at ``z0`` (a term at 0 there takes 1e-12)."""
    scale = np.maximum(peaks(terms, z0, dense=False), 1e-12)
    stages = int(round(np.log10(TAU_START / TAU_END))) + 1
    return [scale * TAU_START * 10.0 ** (-k) for k in range(stages)]


def smoothing_bound(terms: PeakTerms, taus) -> float:
    """The most the smooth terms exceed the exact ones on the search's rows: sum w tau log(2 P)."""
    return float(sum(w * t * np.log(2.0 * R.shape[0])
                     for w, t, R in zip(terms.weights, taus, terms.rows, strict=True)))
