"""B-spline laws: p(x) = sum_i c_i N_i,k(x) on a clamped knot vector over x in [0, 1].

A clamped B-spline (the first and last knots repeated k + 1 times) takes its first and last
control values at the ends, and its r-th derivative at an end depends only on the r + 1 control
values nearest that end; so c_0 = 0 and c_{n-1} = 1 make a rise law, and c_0 = c_1 = c_2 (c_{n-3}
= c_{n-2} = c_{n-1}) make it start (end) at rest, velocity and acceleration zero. Without interior
knots the basis is Bernstein's: a degree-5 clamped B-spline is a Bezier curve, and the 3-4-5
polynomial is the one with control values (0, 0, 0, 1, 1, 1).

Evaluation is de Boor's algorithm, vectorized over any array of x: each x finds its knot span
(``searchsorted`` on the knots, which are static) and runs the k-step triangular recursion on the
k + 1 control values of that span, all x at once. Why de Boor and not a basis matrix: x is not a
fixed grid (the exact extrema solve at arbitrary angles and differentiate in the angle with
``jax.jvp``), the work per point is O(k^2) whatever the number of knots (a table law has hundreds),
and every step is a convex combination, so it is stable at high degree (no power basis, no
cancellation). Derivatives are the same evaluation on the derivative spline, whose control values
are differences of the c_i (linear in c): values and derivatives are differentiable with respect
to the control values (``jax.grad``) and to x.

The knots are static (NumPy, part of the law's identity); the control values are data to the
functions :func:`evaluate` and :func:`derivative_coefficients`, and constants of a built
:class:`~camjax.laws.Law`.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from camjax.laws import Law, LawValues

MAX_DEGREE = 9  # checked against exact rational evaluation to 1e-12 (tests/test_bspline.py)


def clamped_knots(degree: int, n_control: int, interior: Sequence[float] | None = None) -> np.ndarray:
    """The clamped knot vector on [0, 1]: 0 and 1 repeated ``degree + 1`` times around the interior.

    ``interior``: the interior knots, strictly inside (0, 1), nondecreasing, each repeated at most
    ``degree`` times; None: ``n_control - degree - 1`` equally spaced ones. Raises ValueError.
    """
    k = int(degree)
    if not 1 <= k <= MAX_DEGREE:
        raise ValueError(f"degree: {degree} must be an integer 1..{MAX_DEGREE}")
    if n_control < k + 1:
        raise ValueError(f"control: {n_control} values are too few for degree {k}; need at least {k + 1}")
    if interior is None:
        m = n_control - k - 1
        inner = np.arange(1, m + 1, dtype=np.float64) / (m + 1)
    else:
        inner = np.asarray([float(v) for v in interior], dtype=np.float64)
        if inner.size != n_control - k - 1:
            raise ValueError(f"knots: {inner.size} interior knots with {n_control} control values of degree "
                             f"{k}; need {n_control - k - 1} (control values - degree - 1)")
        if inner.size and not (np.all(np.isfinite(inner)) and inner[0] > 0.0 and inner[-1] < 1.0):
            raise ValueError("knots: interior knots must lie strictly inside (0, 1)")
        if np.any(np.diff(inner) < 0.0):
            raise ValueError("knots: interior knots must be nondecreasing")
        _, counts = np.unique(inner, return_counts=True)
        if inner.size and counts.max() > k:
            raise ValueError(f"knots: a knot repeated {counts.max()} times; at most the degree ({k})")
    return np.concatenate([np.zeros(k + 1), inner, np.ones(k + 1)])


def _check(knots: np.ndarray, degree: int, n_coeffs: int) -> None:
    if knots.ndim != 1 or knots.size != n_coeffs + degree + 1:
        raise ValueError(f"knots: {knots.size} knots for {n_coeffs} coefficients of degree {degree}; "
                         f"need {n_coeffs + degree + 1}")


def evaluate(knots: np.ndarray, coeffs: jax.Array, degree: int, x: jax.Array) -> jax.Array:
    """The spline sum_i coeffs[i] N_i,degree(x) at every x (any shape), by de Boor's algorithm.

    ``knots`` (NumPy, static): nondecreasing, ``len(coeffs) + degree + 1`` of them; the spline's
    base interval is [knots[degree], knots[-degree-1]]. Outside it the end polynomial pieces are
    continued. ``coeffs``: shape (n,), any JAX array (differentiable). Pure JAX in coeffs and x.
    """
    t = np.asarray(knots, dtype=np.float64)
    k = int(degree)
    coeffs = jnp.asarray(coeffs)
    n = coeffs.shape[0]
    _check(t, k, n)
    x = jnp.asarray(x, dtype=coeffs.dtype)
    if k == 0:
        span = jnp.clip(jnp.searchsorted(jnp.asarray(t), x, side="right") - 1, 0, n - 1)
        return coeffs[span]
    tj = jnp.asarray(t, dtype=coeffs.dtype)
    # knot span: t[span] <= x < t[span + 1], kept inside the base interval (k <= span <= n - 1)
    span = jnp.clip(jnp.searchsorted(tj, x, side="right") - 1, k, n - 1)
    offsets = jnp.arange(k + 1)
    d = coeffs[span[..., None] - k + offsets]  # (..., k + 1): the span's control values
    for r in range(1, k + 1):
        j = offsets[r:]  # j = r..k, updated from d[j - 1] and d[j]
        left = tj[span[..., None] - k + j]
        right = tj[span[..., None] + 1 + j - r]
        # right > left for every span inside the base interval (no knot repeated more than k times)
        alpha = (x[..., None] - left) / (right - left)
        new = (1.0 - alpha) * d[..., r - 1:k] + alpha * d[..., r:]
        d = jnp.concatenate([d[..., :r], new], axis=-1)
    return d[..., k]


def derivative_coefficients(knots: np.ndarray, coeffs: jax.Array, degree: int
                            ) -> tuple[np.ndarray, jax.Array, int]:
    """(knots, coeffs, degree) of the derivative spline: c'_i = k (c_{i+1} - c_i) / (t_{i+k+1} - t_{i+1}).

    Linear in ``coeffs``. A degree-0 spline's derivative is the zero spline of degree 0.
    """
    t = np.asarray(knots, dtype=np.float64)
    k = int(degree)
    coeffs = jnp.asarray(coeffs)
    if k == 0:
        return t, jnp.zeros_like(coeffs), 0
    width = t[k + 1: k + coeffs.shape[0]] - t[1: coeffs.shape[0]]
    # width is 0 only across a knot repeated k + 1 times (a clamped end), where the difference of
    # the coefficients multiplies a basis function that vanishes: give it a zero coefficient
    scale = np.where(width > 0.0, k / np.where(width > 0.0, width, 1.0), 0.0)
    return t[1:-1], jnp.asarray(scale, dtype=coeffs.dtype) * jnp.diff(coeffs), k - 1


def evaluate_derivatives(knots: np.ndarray, coeffs: jax.Array, degree: int, x: jax.Array,
                         orders: int = 3) -> tuple[jax.Array, ...]:
    """The spline and its first ``orders`` derivatives at x (a tuple of ``orders + 1`` arrays)."""
    out = []
    t, c, k = np.asarray(knots, dtype=np.float64), jnp.asarray(coeffs), int(degree)
    for _ in range(orders + 1):
        out.append(evaluate(t, c, k, x))
        t, c, k = derivative_coefficients(t, c, k)
    return tuple(out)


def evaluate_numpy(knots: np.ndarray, coeffs: np.ndarray, degree: int, x) -> np.ndarray:
    """The NumPy twin of :func:`evaluate` (same spans, same recursion) on a matrix of coefficients
    at once: sum_i coeffs[i, :] N_i,degree(x) for every x, shape (len(x), coeffs.shape[1]); with
    ``coeffs`` the identity it is the basis matrix. For static data (a scene's laws as it is read,
    the synthesis' basis matrices): no program is compiled."""
    t, C, k = np.asarray(knots, dtype=np.float64), np.asarray(coeffs, dtype=np.float64), int(degree)
    x = np.atleast_1d(np.asarray(x, dtype=np.float64))
    n = C.shape[0]
    if k == 0:
        span = np.clip(np.searchsorted(t, x, side="right") - 1, 0, n - 1)
        return C[span]
    span = np.clip(np.searchsorted(t, x, side="right") - 1, k, n - 1)
    offsets = np.arange(k + 1)
    d = C[span[:, None] - k + offsets]  # (X, k + 1, cols)
    for r in range(1, k + 1):
        j = offsets[r:]
        left = t[span[:, None] - k + j]
        right = t[span[:, None] + 1 + j - r]
        alpha = ((x[:, None] - left) / (right - left))[..., None]
        new = (1.0 - alpha) * d[:, r - 1:k] + alpha * d[:, r:]
        d = np.concatenate([d[:, :r], new], axis=1)
    return d[:, k]


def derivative_coefficients_numpy(knots: np.ndarray, coeffs: np.ndarray, degree: int
                                  ) -> tuple[np.ndarray, np.ndarray, int]:
    """The NumPy twin of :func:`derivative_coefficients` on a matrix of coefficients (one column
    per spline)."""
    t, C, k = np.asarray(knots, dtype=np.float64), np.asarray(coeffs, dtype=np.float64), int(degree)
    if k == 0:
        return t, np.zeros_like(C), 0
    n = C.shape[0]
    width = t[k + 1: k + n] - t[1:n]
    scale = np.where(width > 0.0, k / np.where(width > 0.0, width, 1.0), 0.0)
    return t[1:-1], scale[:, None] * np.diff(C, axis=0), k - 1


def evaluate_derivatives_numpy(knots: np.ndarray, coeffs: np.ndarray, degree: int, x,
                               orders: int = 3) -> tuple[np.ndarray, ...]:
    """The NumPy twin of :func:`evaluate_derivatives` for one spline (``coeffs`` shape (n,)): the
    spline and its first ``orders`` derivatives at x (1-D), for static data."""
    t, c, k = np.asarray(knots, dtype=np.float64), np.asarray(coeffs, dtype=np.float64)[:, None], int(degree)
    out = []
    for _ in range(orders + 1):
        out.append(evaluate_numpy(t, c, k, x)[:, 0])
        t, c, k = derivative_coefficients_numpy(t, c, k)
    return tuple(out)


def reversed_spline(knots: np.ndarray, coeffs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Knots and coefficients of q(x) = f(1 - x) for a spline f on [0, 1]: mirrored knots,
    reversed coefficients (the basis is mirrored with them)."""
    return (1.0 - np.asarray(knots, dtype=np.float64))[::-1].copy(), np.asarray(coeffs)[::-1].copy()


def spline_law(knots: np.ndarray, coeffs: Sequence[float], degree: int, name: str, description: str,
               cls=Law, **extra) -> Law:
    """A :class:`~camjax.laws.Law` from a spline on [0, 1] with p(0) = 0, p(1) = 1 (not checked here).

    The knots and coefficients become constants of every program that uses the law; the law is
    compared by identity like every other (build it once per scene). ``cls``/``extra``: a Law
    subclass and its further fields (the table law's fit report).
    """
    t = np.asarray(knots, dtype=np.float64)
    c = np.asarray(coeffs, dtype=np.float64)
    k = int(degree)
    _check(t, k, c.size)

    def evaluate_law(x):
        return LawValues(*evaluate_derivatives(t, jnp.asarray(c, dtype=jnp.result_type(x, float)), k, x))

    v0, v1 = (float(v) for v in evaluate_derivatives_numpy(t, c, k, [0.0, 1.0], 1)[1])
    # the uniform law's field: p' at the ends; a shaped law with equal ends records it, else 0 (the
    # program's joint analysis reads the exact one-sided limits, not this field)
    end_velocity = v0 if math.isclose(v0, v1, rel_tol=1e-12, abs_tol=1e-12) else 0.0
    return cls(name, evaluate_law, description, end_velocity=end_velocity, **extra)


def bspline_law(degree: int, control: Sequence[float], knots: Sequence[float] | None = None,
                falling: bool = False) -> Law:
    """The B-spline rise law of ``degree`` with normalized ``control`` values and optional
    ``knots`` (interior knots in (0, 1); None: equally spaced).

    ``falling`` = False: the control values describe a rise, first 0 and last 1. True: they describe
    a return along the cam angle, first 1 and last 0; the law returned is the rise it runs
    backwards (a program plays a return's law from x = 1 to 0). Raises ValueError naming
    ``control``, ``knots`` or ``degree``.
    """
    if isinstance(degree, bool) or not isinstance(degree, int | np.integer):
        raise ValueError(f"degree: {degree!r} must be an integer 1..{MAX_DEGREE}")
    return _bspline_law(int(degree), tuple(float(v) for v in control),
                        None if knots is None else tuple(float(v) for v in knots), bool(falling))


# One law object per (degree, control, knots, direction): a program holds its laws as static values,
# compared by identity, so a scene read again (a design fed back, a sweep's next weighting, a test
# that parses the scene twice) reuses the programs compiled for the first reading.
@functools.lru_cache(maxsize=256)
def _bspline_law(degree: int, control: tuple[float, ...], knots: tuple[float, ...] | None,
                 falling: bool) -> Law:
    c = np.asarray(control, dtype=np.float64)
    if not np.all(np.isfinite(c)):
        raise ValueError("control: values must be finite numbers")
    t = clamped_knots(int(degree), c.size, knots)
    first, last = (1.0, 0.0) if falling else (0.0, 1.0)
    if c[0] != first or c[-1] != last:
        raise ValueError(f"control: a {'return' if falling else 'rise'} starts at {first:g} and ends at "
                         f"{last:g} (normalized to the lift); got {c[0]:g} and {c[-1]:g}")
    if falling:
        t, c = reversed_spline(t, c)
    shown = ", ".join(f"{v:g}" for v in (c[::-1] if falling else c))
    return spline_law(t, c, int(degree), f"bspline_{int(degree)}",
                      f"B-spline of degree {int(degree)}, control ({shown})")
