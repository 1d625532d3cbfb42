"""A scene's designed segments synthesized together, and the best built-in law of each one's class.

Segments of the same structure (basis and the positions and orders of their conditions) form one
batch: one problem, one ``jit(vmap(solve))`` over their conditions' values. Each result is compared
with the built-in laws (:data:`camjax.laws.LAWS`) that meet the same conditions (the same joint
class: what the designed law must do at its ends, a built-in law does too), measured the same way.

The segments are read by duck typing (the attributes of :class:`camjax.scene.designed.DesignedSegment`),
so this model-layer module imports nothing of the scene layer.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.laws import LAWS
from camjax.synthesis.basis import make_basis
from camjax.synthesis.problem import (
    ALL_OBJECTIVES,
    L2_OBJECTIVES,
    OBJECTIVES,
    PEAK_OBJECTIVES,
    build_problem,
    kept_values,
)
from camjax.synthesis.solve import batch_synthesizer
from camjax.synthesis.vibration import builtin_train_measures, residual_figures, train_terms

ORDERS = {**PEAK_OBJECTIVES, **L2_OBJECTIVES}
BUILTIN_TOL = 1e-6  # a built-in law meets a condition when its normalized value is this close


class SegmentSynthesis(NamedTuple):
    """One designed segment's result (floats and NumPy; q is the normalized motion, q(0) = 0)."""

    segment: object  # the DesignedSegment
    knots: np.ndarray  # full clamped knot vector
    control: np.ndarray  # control values of q
    measures: dict  # name -> value (None where the order exceeds the degree)
    objective: float
    model_objective: float
    converged: bool
    residual: float
    best_builtin: tuple[str, float, dict] | None  # (law name, objective, measures) or None


def builtin_q(law, kind: str, x: np.ndarray) -> tuple[np.ndarray, ...]:
    """q, q', q'', q''' of a built-in law played as the segment's normalized motion (a return
    runs the law backwards: q(x) = 1 - p(1 - x)); NumPy arrays of the shape of ``x``."""
    if kind == "rise":
        return _law_values(law, x)
    p = _law_values(law, 1.0 - np.asarray(x))
    return (1.0 - p[0], p[1], -p[2], p[3])


def _law_values(law, x) -> tuple[np.ndarray, ...]:
    """``law`` at the points ``x`` (NumPy in and out) through one compiled program per law and
    size class: ``x`` is padded with zeros to the next power of two (64 at least), so that the few
    sizes a co-design asks for (a segment's samples, the conditions, the measures' grids) share a
    program. Op by op, each of a law's tens of operations compiled for every new shape: 0.3-0.7 s
    a law and shape, against ~0.1 s for the whole law compiled."""
    x = np.asarray(x)
    flat = x.reshape(-1)
    size = max(64, 1 << max(flat.size - 1, 0).bit_length())
    padded = np.zeros(size, dtype=flat.dtype)
    padded[: flat.size] = flat
    values = _compiled_law(law, jnp.asarray(padded))
    return tuple(np.asarray(v)[: flat.size].reshape(x.shape) for v in values)


@functools.partial(jax.jit, static_argnums=0)
def _compiled_law(law, x: jax.Array) -> tuple[jax.Array, ...]:
    return tuple(law(x))


def builtin_measures(law, kind: str) -> dict:
    """Peaks on 20001 points and integrals by 6-point Gauss-Legendre on 400 spans (the laws are
    smooth or piecewise smooth with breaks at simple fractions: 1e-9 relative)."""
    x = np.linspace(0.0, 1.0, 20001)
    _, v, a, j = builtin_q(law, kind, x)
    nodes, w = np.polynomial.legendre.leggauss(6)
    edges = np.linspace(0.0, 1.0, 401)
    half = 0.5 * np.diff(edges)
    xg = ((edges[:-1] + half)[:, None] + half[:, None] * nodes[None, :]).ravel()
    wg = (half[:, None] * w[None, :]).ravel()
    _, _, ag, jg = builtin_q(law, kind, xg)
    return {"peak_velocity": float(np.max(np.abs(v))), "peak_accel": float(np.max(np.abs(a))),
            "peak_jerk": float(np.max(np.abs(j))), "l2_accel": float(wg @ ag**2),
            "l2_jerk": float(wg @ jg**2)}


def meets_conditions(law, segment) -> bool:
    """Whether a built-in law played as the segment meets every one of its conditions (the same
    joint class)."""
    q = builtin_q(law, segment.kind, np.asarray([c.x for c in segment.conditions]))  # one call
    for k, (c, value) in enumerate(zip(segment.conditions, segment.values, strict=True)):
        if abs(float(q[c.order][k]) - value) > BUILTIN_TOL * max(1.0, abs(value)):
            return False
    return True


def term_value(name: str, measure: float) -> float:
    """A term's contribution per unit weight: the measure, squared for the residual vibration."""
    return measure**2 if name == "residual_vibration" else measure


def best_builtin(segment, weights: dict, train=None) -> tuple[str, float, dict] | None:
    """The built-in law meeting the segment's conditions with the least objective, or None. With
    ``train`` (:class:`camjax.synthesis.vibration.Train`) its figures include the train's."""
    best = None
    for name, law in LAWS.items():
        if not meets_conditions(law, segment):
            continue
        m = builtin_measures(law, segment.kind)
        if train is not None:
            m.update(builtin_train_measures(lambda x, law=law: builtin_q(law, segment.kind, x), train,
                                            segment))
        obj = sum(w * term_value(n, m[n]) for n, w in weights.items())
        if best is None or obj < best[1]:
            best = (name, float(obj), m)
    return best


def synthesize_segments(segments, weights: dict, samples_per_span: int = 8,
                        train=None) -> list[SegmentSynthesis]:
    """Synthesize every designed segment for the objective ``weights`` ({name: weight > 0}).
    ``train``: the follower train (:class:`camjax.synthesis.vibration.Train`) for the terms
    ``peak_force`` and ``residual_vibration`` and their figures (None: the law's terms only).

    Raises ValueError for a term whose order exceeds a segment's degree or a train term without
    the train (the scene checks both first).
    """
    names = tuple(n for n in ALL_OBJECTIVES if n in weights)
    groups: dict[tuple, list] = {}
    for seg in segments:
        key = (seg.degree, seg.control_count, seg.knots, tuple((c.x, c.order) for c in seg.conditions))
        if train is not None:  # the train's matrices depend on the segment's duration, level and lift
            key = (*key, seg.index)
        groups.setdefault(key, []).append(seg)
    results = {}
    for (degree, count, knots, *_), members in groups.items():
        basis = make_basis(degree, count, knots)
        terms = None if train is None else train_terms(basis, train, members[0], samples_per_span)
        problem = build_problem(basis, members[0].conditions, names, samples_per_span, terms)
        values = kept_values(problem, np.asarray([m.values for m in members], dtype=np.float64))
        w = np.tile(np.asarray([weights[n] for n in problem.objective]), (len(members), 1))
        out = batch_synthesizer(problem)(values, w)
        for b, seg in enumerate(members):
            meas = {n: (float(getattr(out.measures, n)[b]) if ORDERS[n] <= degree else None)
                    for n in OBJECTIVES}
            if terms is not None:
                c = np.asarray(out.control[b])
                meas.update(residual_figures(np.linalg.norm(terms.residual_rows @ c, axis=1)))
                if terms.force_dense is not None:
                    meas["peak_force"] = float(out.measures.peak_force[b])
            results[seg.index] = SegmentSynthesis(
                seg, basis.knots, np.asarray(out.control[b]), meas, float(out.objective[b]),
                float(out.model_objective[b]), bool(out.converged[b]), float(out.residual[b]),
                best_builtin(seg, {n: weights[n] for n in names}, train))
    return [results[seg.index] for seg in segments]
