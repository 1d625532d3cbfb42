"""A law-synthesis problem: the basis, the conditions the law must meet, the objective's terms.

The variables are the control values c of a clamped B-spline q(x) on x in [0, 1], the segment's
motion normalized (s = s0 + D q(x), D the signed lift, x = (theta - theta0) / beta), so q(0) = 0,
q(1) = 1, and a condition s^(r) = value at an end or an interior point is the linear equation
q^(r)(x) = value beta^r / D: one row of ``A c = b``.

Conditions are met by construction, not penalized: with A of full row rank r (rows that repeat
earlier ones are dropped and checked for consistency, :func:`inconsistent_condition`), every c
with A c = b is c = A^+ b + N z, N an orthonormal basis of A's null space (SVD, once per basis),
and the synthesis runs over the free coordinates z. At a clamped end, q^(r) depends only on the
r + 1 control values nearest it (:mod:`camjax.laws.bspline`), so the end conditions pin those;
the null-space form is the same thing written for any set of rows (interior points included).

The structure (basis, which conditions, which objective terms) is static NumPy data; the
conditions' values and the objective's weights are the data a synthesis is batched over.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from camjax.synthesis.basis import Basis, evaluation_matrix, gram_matrix, peak_matrix, span_points

PEAK_OBJECTIVES = {"peak_velocity": 1, "peak_accel": 2, "peak_jerk": 3}  # name -> derivative order
L2_OBJECTIVES = {"l2_accel": 2, "l2_jerk": 3}
OBJECTIVES = (*PEAK_OBJECTIVES, *L2_OBJECTIVES)  # the law's own terms (dimensionless)
# the follower train's terms (camjax.synthesis.vibration): they need the scene's [dynamics]
TRAIN_OBJECTIVES = ("peak_force", "residual_vibration")
ALL_OBJECTIVES = (*OBJECTIVES, *TRAIN_OBJECTIVES)
PEAK_TERMS = (*PEAK_OBJECTIVES, "peak_force")  # the terms taken in epigraph form
ORDER_NAMES = {0: "s", 1: "v", 2: "a", 3: "j"}
PER_SPAN = 8  # points per knot span where a peak of a derivative of degree >= 2 is sampled
MEASURE_PER_SPAN = 64  # points per span for the reported peaks (exact for degree <= 1)
MAX_CONTROL = 256


class Condition(NamedTuple):
    """One equality: q^(order)(x) = value (normalized). ``label``: where it came from, for messages
    (e.g. ``end.a``)."""

    x: float
    order: int
    label: str


class SynthesisProblem(NamedTuple):
    """Static data of one synthesis (NumPy arrays; see the module docstring)."""

    basis: Basis
    conditions: tuple[Condition, ...]  # all of them, in the order given
    kept: tuple[int, ...]  # indices of the independent conditions (rows of A)
    dependent: tuple[tuple[int, tuple[int, ...], np.ndarray], ...]  # (index, rows kept before it, coefficients over them)
    A: np.ndarray  # (r, n) rows of the kept conditions
    A_pinv: np.ndarray  # (n, r)
    null: np.ndarray  # (n, n - r) orthonormal
    objective: tuple[str, ...]  # the objective's terms, in OBJECTIVES order
    peak_rows: tuple[np.ndarray, ...]  # per peak term of the objective: (rows, n)
    peak_exact: tuple[bool, ...]
    grams: dict  # order -> (n, n) Gram matrix of q^(order), orders 1..3
    dense: dict  # order -> (points, n) evaluation matrix for the reported peaks, orders 1..3
    train: object = None  # camjax.synthesis.vibration.TrainTerms of the segment, or None

    @property
    def free(self) -> int:
        """The number of free coordinates z."""
        return self.null.shape[1]


def condition_rows(basis: Basis, conditions) -> np.ndarray:
    """(len(conditions), n): the row of each condition."""
    rows = np.zeros((len(conditions), basis.n))
    for i, c in enumerate(conditions):
        rows[i] = evaluation_matrix(basis, np.asarray([c.x]), c.order)[0]
    return rows


def build_problem(basis: Basis, conditions, objective, per_span: int = PER_SPAN,
                  train=None) -> SynthesisProblem:
    """The synthesis problem of ``basis`` under ``conditions`` (a sequence of :class:`Condition`)
    for the objective terms ``objective`` (names from :data:`ALL_OBJECTIVES`; the train's terms
    need ``train``, the segment's :class:`camjax.synthesis.vibration.TrainTerms`).

    Raises ValueError ``"<name>: ..."`` for an unknown term, one whose derivative the basis does
    not have (order above the degree), or a train term without the train (or its spring).
    """
    conditions = tuple(conditions)
    names = tuple(objective)
    for name in names:
        if name not in ALL_OBJECTIVES:
            raise ValueError(f"{name}: unknown objective term (allowed: {', '.join(ALL_OBJECTIVES)})")
        if name in TRAIN_OBJECTIVES:
            if train is None or (name == "peak_force" and train.force_rows is None):
                extra = " with a spring, on a law of degree >= 2" if name == "peak_force" else ""
                raise ValueError(f"{name}: needs the follower train (a [dynamics] section{extra})")
            continue
        order = {**PEAK_OBJECTIVES, **L2_OBJECTIVES}[name]
        if order > basis.degree:
            raise ValueError(f"{name}: needs a law of degree >= {order} (its {ORDER_NAMES[order]} is "
                             f"not a function for degree {basis.degree})")
    names = tuple(n for n in ALL_OBJECTIVES if n in names)
    rows = condition_rows(basis, conditions)
    kept: list[int] = []
    dependent = []
    for i, row in enumerate(rows):
        trial = rows[[*kept, i]]
        scale = max(1.0, float(np.abs(trial).max()))
        if np.linalg.matrix_rank(trial, tol=1e-10 * scale * basis.n) > len(kept):
            kept.append(i)
        else:  # row = coeffs . rows[kept], the rows kept so far (more may be kept later)
            coeffs = np.linalg.lstsq(rows[kept].T, row, rcond=None)[0] if kept else np.zeros(0)
            dependent.append((i, tuple(kept), coeffs))
    A = rows[kept] if kept else np.zeros((0, basis.n))
    u, sv, vt = np.linalg.svd(A, full_matrices=True)
    r = len(kept)
    A_pinv = vt[:r].T @ np.diag(1.0 / sv[:r]) @ u[:, :r].T if r else np.zeros((basis.n, 0))
    null = vt[r:].T
    peak_rows, exact = [], []
    for name in names:
        if name in PEAK_OBJECTIVES:
            m, ex = peak_matrix(basis, PEAK_OBJECTIVES[name], per_span)
            peak_rows.append(m)
            exact.append(ex)
        elif name == "peak_force":
            peak_rows.append(train.force_rows)
            exact.append(False)
    orders = [o for o in (1, 2, 3) if o <= basis.degree]
    grams = {o: gram_matrix(basis, o) for o in orders}
    pts = span_points(basis, MEASURE_PER_SPAN)
    dense = {o: evaluation_matrix(basis, pts, o) for o in orders}
    return SynthesisProblem(basis, conditions, tuple(kept), tuple(dependent), A, A_pinv, null, names,
                            tuple(peak_rows), tuple(exact), grams, dense, train)


def inconsistent_condition(problem: SynthesisProblem, values, rtol: float = 1e-9) -> tuple[int, float] | None:
    """The first condition that repeats earlier ones with a different value, as (index, the
    difference), or None. ``values``: one per condition, in the problem's order."""
    values = np.asarray(values, dtype=np.float64)
    for i, before, coeffs in problem.dependent:
        implied = float(coeffs @ values[list(before)]) if before else 0.0
        if abs(values[i] - implied) > rtol * max(1.0, abs(values[i]), abs(implied)):
            return i, values[i] - implied
    return None


def kept_values(problem: SynthesisProblem, values):
    """The right-hand sides of the kept rows (``values`` in the order of ``problem.conditions``;
    NumPy or JAX, the last axis is the conditions')."""
    return values[..., list(problem.kept)]
