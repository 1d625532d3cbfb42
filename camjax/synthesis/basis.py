"""The B-spline basis of a designed law as matrices: every quantity the synthesis needs is linear
(or quadratic) in the control values, so it is a matrix computed once per basis.

A designed law is q(x) = sum_i c_i N_i,k(x) on a clamped knot vector over x in [0, 1]
(:mod:`camjax.laws.bspline`). Its r-th derivative is again a B-spline, of degree k - r, whose
control values are a fixed linear map of c (differences divided by knot widths); so

- q^(r)(x) at any points is ``E c`` with E = :func:`evaluation_matrix`;
- the derivative spline's own control values are ``D c`` with D = :func:`derivative_matrix`; for
  a derivative of degree 0 or 1 (the jerk of a cubic, the acceleration of a cubic) its peak |.|
  is exactly max |D c| (a piecewise-linear function peaks at a knot, where it equals a control
  value; a piecewise constant one is its control values);
- the integral of (q^(r))^2 over [0, 1] is ``c^T Q c`` with Q = :func:`gram_matrix`, computed by
  Gauss-Legendre quadrature with k - r + 1 points on each knot span: exact, the integrand being a
  polynomial of degree 2 (k - r) there.

The matrices are de Boor's recursion and the derivative's differences of
:mod:`camjax.laws.bspline` run in NumPy on the identity matrix of control values (the spline is
linear in them), so they agree with the law the program evaluates to rounding
(tests/test_synthesis.py checks it). They are NumPy arrays: static data of a synthesis problem,
built in milliseconds without tracing anything.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from camjax.laws.bspline import clamped_knots, derivative_coefficients_numpy, evaluate_numpy


class Basis(NamedTuple):
    """A clamped B-spline basis on [0, 1]: degree, full knot vector (NumPy), number of controls."""

    degree: int
    knots: np.ndarray  # (n + degree + 1,) float64, first/last degree + 1 knots at 0 and 1
    n: int

    @property
    def interior(self) -> tuple[float, ...]:
        """The interior knots (the scene's ``knots`` key)."""
        return tuple(float(v) for v in self.knots[self.degree + 1: self.n])

    @property
    def breaks(self) -> np.ndarray:
        """The distinct knots 0 = b_0 < ... < b_m = 1: the ends of the polynomial pieces."""
        return np.unique(self.knots)


def make_basis(degree: int, n_control: int, interior=None) -> Basis:
    """The clamped basis of ``degree`` with ``n_control`` control values and the given interior
    knots (None: equally spaced). Raises ValueError naming ``degree``, ``control`` or ``knots``."""
    return Basis(int(degree), clamped_knots(int(degree), int(n_control), interior), int(n_control))


def _derivative_basis(basis: Basis, order: int):
    t, C, k = basis.knots, np.eye(basis.n), basis.degree
    for _ in range(order):
        t, C, k = derivative_coefficients_numpy(t, C, k)
    return t, C, k


def evaluation_matrix(basis: Basis, x, order: int) -> np.ndarray:
    """(len(x), n): row i maps the control values to q^(order)(x_i)."""
    t, C, k = _derivative_basis(basis, order)
    return evaluate_numpy(t, C, k, x)


def derivative_matrix(basis: Basis, order: int) -> np.ndarray:
    """(n - order, n): the control values of the derivative spline of ``order`` (degree k - order)."""
    return _derivative_basis(basis, order)[1]


def span_points(basis: Basis, per_span: int) -> np.ndarray:
    """``per_span`` + 1 equally spaced points on every polynomial piece (ends shared, sorted)."""
    b = basis.breaks
    f = np.linspace(0.0, 1.0, int(per_span) + 1)
    pts = (b[:-1, None] + (b[1:] - b[:-1])[:, None] * f[None, :]).ravel()
    return np.unique(pts)


def gram_matrix(basis: Basis, order: int) -> np.ndarray:
    """(n, n): c^T Q c = integral_0^1 (q^(order))^2 dx, exactly (Gauss-Legendre per knot span)."""
    if order > basis.degree:
        return np.zeros((basis.n, basis.n))
    g = basis.degree - order + 1  # exact for polynomials of degree 2 g - 1 >= 2 (k - order)
    nodes, weights = np.polynomial.legendre.leggauss(g)
    b = basis.breaks
    half = 0.5 * (b[1:] - b[:-1])
    mid = 0.5 * (b[1:] + b[:-1])
    x = (mid[:, None] + half[:, None] * nodes[None, :]).ravel()
    w = (half[:, None] * weights[None, :]).ravel()
    e = evaluation_matrix(basis, x, order)
    q = e.T @ (w[:, None] * e)
    return 0.5 * (q + q.T)


def peak_matrix(basis: Basis, order: int, per_span: int) -> tuple[np.ndarray, bool]:
    """The rows whose largest |row . c| is the peak |q^(order)| used by the synthesis, and whether
    that peak is exact: the derivative's control values when it has degree 0 or 1 (exact), else
    its values at ``per_span`` + 1 points on every piece (a lower bound, within O(per_span^-2))."""
    if basis.degree - order <= 1:
        return derivative_matrix(basis, order), True
    return evaluation_matrix(basis, span_points(basis, per_span), order), False
