"""Polynomial laws of any degree, built exactly and evaluated stably in Bernstein form.

A polynomial law is known exactly: its coefficients are fractions (SPEC section 1's system for a
list of exponents, or :mod:`camjax.program.conditions`' solve of a segment's joint conditions).
It is evaluated in the Bernstein basis of its degree n,

    p(x) = sum_i b_i B_{i,n}(x),  B_{i,n}(x) = C(n, i) x^i (1 - x)^(n - i),

and its k-th derivative in the basis of degree n - k with the coefficients [n]_k Delta^k b_i
(forward differences, computed exactly before rounding to float64).

Why Bernstein and not the monomial sum: the monomial coefficients of high-degree laws are huge and
alternate in sign (exponents 50..100: up to 8.5e42), so summing them in float64 cancels every
digit (s = 1.9e28 mm for a 10 mm lift). Horner on the same coefficients cancels just as badly: the
cancellation is in the basis, not in the order of the sum. The Bernstein coefficients of a
rest-to-rest law are small and mostly 0 and 1 (3-4-5: 0, 0, 0, 1, 1, 1; exponents a..n: a zeros,
then ones), every basis function is >= 0 on [0, 1] and they sum to 1, so the rounding error of the
sum is bounded by a small multiple of n * eps * max|b_i| whatever the degree (Farouki and Rajan,
"On the numerical condition of polynomials in Bernstein form", CAGD 4, 1987). At x = 0 and x = 1
the sum is exactly b_0 and b_n, so a law's end values (its joints) carry no rounding at all.

That bound is computed for every law (:attr:`PolynomialLaw.error_bound`); a law whose displacement
cannot be evaluated to :data:`LIFT_TOLERANCE` of its lift is refused.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np

from camjax.laws.base import Law, LawValues

LIFT_TOLERANCE = 1e-9  # a law must evaluate its displacement to this fraction of its lift
MAX_DEGREE = 120  # the exact rational build of 120 exponents takes seconds; C(120, 60) ~ 1e35
_EPS = float(np.finfo(np.float64).eps) / 2  # unit roundoff u


def falling(e: int, j: int) -> int:
    """Falling factorial [e]_j = e (e-1) ... (e-j+1)."""
    out = 1
    for i in range(j):
        out *= e - i
    return out


def polynomial_coefficients(exponents: Sequence[int]) -> tuple[Fraction, ...]:
    """Exact coefficients c_k of f = sum c_k x**e_k with f(1) = 1, f'(1) = ... = f^(n-1)(1) = 0.

    Solves sum_k c_k [e_k]_j = delta_{j0}, j = 0..n-1 (SPEC section 1) in rational arithmetic,
    so the coefficients carry no rounding; only their evaluation does.
    """
    e = [int(v) for v in exponents]
    n = len(e)
    if n == 0:
        raise ValueError("exponents: need at least one exponent")
    if sorted(set(e)) != e or e[0] < 1:
        raise ValueError(f"exponents: {list(exponents)} must be strictly increasing integers >= 1")
    if e[-1] > MAX_DEGREE:
        raise ValueError(f"exponents: the largest exponent {e[-1]} is above the largest degree "
                         f"camjax evaluates, {MAX_DEGREE}")
    a = [[Fraction(falling(ek, j)) for ek in e] + [Fraction(int(j == 0))] for j in range(n)]
    for col in range(n):  # Gauss-Jordan elimination, exact
        piv = next((r for r in range(col, n) if a[r][col] != 0), None)
        if piv is None:
            raise ValueError(f"exponents: {e} give a singular boundary-condition system")
        a[col], a[piv] = a[piv], a[col]
        a[col] = [v / a[col][col] for v in a[col]]
        for r in range(n):
            if r != col and a[r][col] != 0:
                f = a[r][col]
                a[r] = [vr - f * vc for vr, vc in zip(a[r], a[col], strict=True)]
    return tuple(a[j][n] for j in range(n))


def boundary_condition_number(exponents: Sequence[int]) -> float:
    """2-norm condition number of the boundary-condition matrix [e_k]_j (float64)."""
    e = [int(v) for v in exponents]
    m = np.array([[falling(ek, j) for ek in e] for j in range(len(e))], dtype=np.float64)
    return float(np.linalg.cond(m))


def monomial_to_bernstein(coefficients: Sequence[Fraction]) -> tuple[Fraction, ...]:
    """Bernstein coefficients b_0..b_n of sum_j a_j x^j (dense a_0..a_n, exact).

    b_i = sum_{j <= i} C(i, j) / C(n, j) a_j (x^j = sum_{i >= j} C(i, j) / C(n, j) B_{i,n}).
    """
    a = [Fraction(c) for c in coefficients]
    n = len(a) - 1
    return tuple(sum((Fraction(math.comb(i, j), math.comb(n, j)) * a[j] for j in range(i + 1)),
                     Fraction(0)) for i in range(n + 1))


def bernstein_derivative(b: Sequence[Fraction], k: int) -> tuple[Fraction, ...]:
    """Bernstein coefficients (degree n - k) of the k-th derivative: [n]_k Delta^k b (exact)."""
    n = len(b) - 1
    d = list(b)
    for _ in range(k):
        d = [d[i + 1] - d[i] for i in range(len(d) - 1)]
    return tuple(falling(n, k) * v for v in d) if d else (Fraction(0),)


def evaluate_exact(b: Sequence[Fraction], x: Fraction, k: int = 0) -> Fraction:
    """The k-th derivative of the Bernstein polynomial ``b`` at ``x``, in rational arithmetic."""
    d = bernstein_derivative(b, k)
    m = len(d) - 1
    x = Fraction(x)
    return sum((v * math.comb(m, i) * x**i * (1 - x) ** (m - i) for i, v in enumerate(d)), Fraction(0))


def _bernstein_sum(weights: np.ndarray, xp: jax.Array, yp: jax.Array) -> jax.Array:
    """sum_i w_i x^i (1-x)^(m-i) with w_i = d_i C(m, i); xp, yp: powers 0..n of x and 1 - x."""
    m = weights.shape[0] - 1
    if m < 0:
        return jnp.zeros(xp.shape[:-1], xp.dtype)
    terms = xp[..., : m + 1] * yp[..., m::-1]
    return jnp.sum(terms * jnp.asarray(weights, xp.dtype), axis=-1)


@dataclass(frozen=True, eq=False)
class PolynomialLaw(Law):
    """A polynomial law kept exactly (Bernstein coefficients as fractions) and evaluated stably.

    Attributes (besides :class:`Law`'s):
      bernstein: exact Bernstein coefficients b_0..b_n of p (p(0) = b_0, p(1) = b_n).
      error_bound: a bound on the rounding error of p, p', p'', p''' on [0, 1] in float64.
    """

    bernstein: tuple[Fraction, ...] = field(default=(), repr=False)
    error_bound: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)

    @property
    def degree(self) -> int:
        return len(self.bernstein) - 1


def error_bounds(b: Sequence[Fraction]) -> tuple[float, float, float, float]:
    """Rounding-error bound of p^(k), k = 0..3, evaluated in float64 by :func:`bernstein_law`.

    Each term w_i x^i (1-x)^(m-i) of the degree-m sum carries at most m + 4 roundings (the powers
    by repeated products, 1 - x, the weight, two products) and the sum m more, all relative to
    terms >= 0 times |d_i|: |error| <= gamma_(2m+5) sum |d_i| B_i(x) <= gamma_(2m+5) max |d_i|
    with gamma_q = q u / (1 - q u).
    """
    n = len(b) - 1
    out = []
    for k in range(4):
        d = bernstein_derivative(b, k) if k <= n else (Fraction(0),)
        m = len(d) - 1
        q = 2 * m + 5
        gamma = q * _EPS / (1 - q * _EPS)
        out.append(gamma * float(max(abs(v) for v in d)) * (1 + 4 * _EPS))
    return tuple(out)


class BernsteinForm:
    """x -> LawValues of sum_i b_i B_{i,n}(x) and its first three derivatives, in Bernstein form.

    A module-level callable (not a closure) so that a motion program holding the law pickles: its
    tree structure keys the saved programs of :func:`camjax.runtime.program_cache`. Two forms of
    the same coefficients are equal (and hash alike).
    """

    def __init__(self, coefficients: tuple[Fraction, ...], weights: tuple[np.ndarray, ...]):
        self.coefficients = coefficients  # b_0 .. b_n, exact
        self.weights = weights  # per derivative order k: binomial-weighted coefficients of p^(k)

    def __eq__(self, other) -> bool:
        return isinstance(other, BernsteinForm) and self.coefficients == other.coefficients

    def __hash__(self) -> int:
        return hash(self.coefficients)

    def __call__(self, x):
        n = len(self.coefficients) - 1
        x = jnp.asarray(x)
        if not jnp.issubdtype(x.dtype, jnp.floating):
            x = x.astype(float)
        # powers 0..n of x and of 1 - x by repeated products: no pow (whose derivative at x = 0
        # would be 0 * inf), every term a product of factors in [0, 1]
        ones = jnp.ones((*x.shape, 1), x.dtype)
        xp = jnp.cumprod(jnp.concatenate([ones, jnp.repeat(x[..., None], n, axis=-1)], axis=-1), axis=-1)
        y = 1.0 - x
        yp = jnp.cumprod(jnp.concatenate([ones, jnp.repeat(y[..., None], n, axis=-1)], axis=-1), axis=-1)
        return LawValues(*(_bernstein_sum(w, xp, yp) for w in self.weights))


def bernstein_law(b: Sequence[Fraction], name: str, description: str = "") -> PolynomialLaw:
    """The law sum_i b_i B_{i,n}(x), evaluated in Bernstein form (p', p'', p''' likewise).

    Raises ValueError when the rounding-error bound of p exceeds :data:`LIFT_TOLERANCE` (the law
    cannot be evaluated to 1e-9 of its lift in float64) or the degree exceeds :data:`MAX_DEGREE`.
    """
    b = tuple(Fraction(v) for v in b)
    n = len(b) - 1
    if n > MAX_DEGREE:
        raise ValueError(f"degree {n} is above the largest degree camjax evaluates, {MAX_DEGREE}")
    bound = error_bounds(b)
    if not bound[0] <= LIFT_TOLERANCE:
        big = float(max(abs(v) for v in b))
        raise ValueError(f"the degree-{n} polynomial cannot be evaluated to {LIFT_TOLERANCE:g} of "
                         f"its lift in float64 (its Bernstein coefficients reach {big:.3g}; "
                         f"rounding bound {bound[0]:.2g})")
    weights = []
    for k in range(4):
        d = bernstein_derivative(b, k) if k <= n else ()
        m = len(d) - 1
        weights.append(np.array([float(v * math.comb(m, i)) for i, v in enumerate(d)], dtype=np.float64))
    evaluate = BernsteinForm(b, tuple(weights))
    return PolynomialLaw(name, evaluate, description, bernstein=b, error_bound=bound)


def monomial_description(terms: Sequence[tuple[Fraction, int]]) -> str:
    """'+ 10x^3 - 15x^4 + 6x^5' from (coefficient, exponent) pairs (zero terms left out)."""
    return " ".join(f"{'+' if c >= 0 else '-'} {abs(c)}x^{e}" for c, e in terms if c != 0)


@functools.cache
def _polynomial_law(exponents: tuple[int, ...]) -> PolynomialLaw:
    coeffs = polynomial_coefficients(exponents)
    dense = [Fraction(0)] * (exponents[-1] + 1)
    for c, e in zip(coeffs, exponents, strict=True):
        dense[e] = c
    name = "poly_" + "_".join(str(e) for e in exponents)
    desc = monomial_description(list(zip(coeffs, exponents, strict=True)))
    if len(desc) > 200:
        desc = f"degree {exponents[-1]}, exponents {exponents[0]}..{exponents[-1]}"
    return bernstein_law(monomial_to_bernstein(dense), name, f"polynomial {desc}")


def polynomial_law(exponents: Sequence[int]) -> PolynomialLaw:
    """The polynomial law with the given exponents (e.g. (3, 4, 5) -> 10x^3 - 15x^4 + 6x^5).

    Raises ValueError (message starting ``exponents:``) for exponents that are not strictly
    increasing integers >= 1, or whose law cannot be evaluated to 1e-9 of its lift.
    """
    exps = tuple(int(e) for e in exponents)
    try:
        return _polynomial_law(exps)
    except ValueError as exc:
        msg = str(exc)
        raise ValueError(msg if msg.startswith("exponents:") else f"exponents: {msg}") from None
