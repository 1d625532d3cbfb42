"""Polynomial laws of high degree: Bernstein evaluation against exact rational arithmetic.

The reference for every value is the law's exact monomial form (SPEC section 1's coefficients as
fractions) evaluated in fractions at the float64 sample point itself, so the only error measured
is the float64 evaluation's. Tolerances: 1e-9 of the lift (normalized: 1) for p, and 1e-9 of the
derivative's own peak for p', p'', p''' (a derivative scaled to a segment is lift / beta^k times
p^(k), so 1e-9 of its peak is 1e-9 of the lift in that derivative's units).
"""

import functools
import math
from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax.extrema import max_of, min_of
from camjax.laws import LAWS, polynomial_coefficients, polynomial_law
from camjax.laws.polynomial import (
    LIFT_TOLERANCE,
    MAX_DEGREE,
    bernstein_law,
    evaluate_exact,
    falling,
    monomial_to_bernstein,
)
from camjax.program import MotionProgram, Segment, evaluate
from camjax.scene import SceneError, builtin_scene_text, parse_scene

HIGH = {
    "40..89": tuple(range(40, 90)),  # the exponents of the defect report: s = 5.9e23 mm before
    "50..100": tuple(range(50, 101)),  # s = 1.9e28 mm before
    "1,4,..,100": tuple(range(1, 101, 3)),
    "3,50,100": (3, 50, 100),
}


@functools.cache
def _integer_coefficients(exps):
    """(numerators N_e, common denominator L) of the exact coefficients c_e = N_e / L."""
    c = polynomial_coefficients(exps)
    den = math.lcm(*(v.denominator for v in c))
    return tuple(int(v * den) for v in c), den


def _exact_monomial(exps, x: Fraction, k: int) -> Fraction:
    """k-th derivative of sum c_e x^e at x, exact (independent of the Bernstein conversion).

    With x = m / 2^q (every float is) the sum is one integer over L 2^(q D): integer arithmetic
    throughout, no fraction reduced per term.
    """
    x = Fraction(x)
    m, q2 = x.numerator, x.denominator
    nums, den = _integer_coefficients(tuple(exps))
    top = max(exps) - k
    total = sum(n * falling(e, k) * m ** (e - k) * q2 ** (top - (e - k))
                for n, e in zip(nums, exps, strict=True) if e >= k)
    return Fraction(total, den * q2**top) if top >= 0 else Fraction(0)


@pytest.fixture(scope="module")
def xs():
    return np.linspace(0.0, 1.0, 41)


@pytest.mark.parametrize("key", [pytest.param(k, marks=pytest.mark.slow) if k in ("40..89", "50..100") else k
                                 for k in HIGH])
def test_high_degree_matches_exact_rational_evaluation(key, xs):
    exps = HIGH[key]
    law = polynomial_law(exps)
    got = law(jnp.asarray(xs))
    for k in range(4):
        exact = np.array([float(_exact_monomial(exps, Fraction(float(x)), k)) for x in xs])
        err = np.max(np.abs(np.asarray(got[k]) - exact))
        scale = 1.0 if k == 0 else np.max(np.abs(exact))
        assert err <= LIFT_TOLERANCE * scale, (k, err, scale)
        # and the a-priori bound that decides refusal does hold (it is a bound, not an estimate)
        assert err <= law.error_bound[k]


def test_the_monomial_sum_of_the_same_law_fails(xs):
    """The check above can fail: summing the exact coefficients in float64 (the old evaluation)
    misses p by far more than the lift for exponents 50..100."""
    exps = HIGH["50..100"]
    c = [float(v) for v in polynomial_coefficients(exps)]
    naive = np.array([sum(ci * x**e for ci, e in zip(c, exps, strict=True)) for x in xs])
    exact = np.array([float(_exact_monomial(exps, Fraction(float(x)), 0)) for x in xs])
    assert np.max(np.abs(naive - exact)) > 1.0


def test_bernstein_coefficients_of_standard_laws():
    # 3-4-5 is the smoothstep of degree 5: Bernstein coefficients 0, 0, 0, 1, 1, 1 (closed form)
    b = monomial_to_bernstein([0, 0, 0, 10, -15, 6])
    assert b == (0, 0, 0, 1, 1, 1)
    # exponents a..n: the law is P(Binomial(n, x) >= a), so b_i = [i >= a] exactly
    assert polynomial_law(range(40, 90)).bernstein == tuple(Fraction(int(i >= 40)) for i in range(90))


@pytest.mark.slow
@pytest.mark.parametrize("key", ["50..100", "3,50,100"])
def test_ends_are_exact_and_autodiff_agrees(key):
    law = polynomial_law(HIGH[key])
    ends = law(jnp.asarray([0.0, 1.0]))
    assert np.asarray(ends.p).tolist() == [0.0, 1.0]  # b_0 and b_n, no rounding
    for k in (1, 2):  # rest to rest (the exponents' conditions give p'(1) = p''(1) = 0 too)
        assert np.asarray(ends[k]).tolist() == [0.0, 0.0]
    # the derivatives are the closed form's: jvp of p, p', p'' in x reproduces p', p'', p'''
    x = jnp.linspace(0.0, 1.0, 41)
    for k in range(3):
        _, tangent = jax.jvp(lambda t, k=k: law(t)[k], (x,), (jnp.ones_like(x),))
        ref = np.asarray(law(x)[k + 1])
        assert np.all(np.isfinite(np.asarray(tangent)))
        np.testing.assert_allclose(np.asarray(tangent), ref, rtol=0, atol=1e-9 * np.max(np.abs(ref)))


def test_exact_evaluation_of_bernstein_form_matches_monomials():
    exps = (3, 4, 5)
    law = polynomial_law(exps)
    for x in (Fraction(1, 3), Fraction(7, 10)):
        for k in range(4):
            assert evaluate_exact(law.bernstein, x, k) == _exact_monomial(exps, x, k)


def test_a_law_that_cannot_be_evaluated_is_refused():
    # alternating Bernstein coefficients of size 1e8 over degree 100: rounding alone reaches 1e-6
    b = [Fraction(0)] + [Fraction((-1) ** i * 10**8) for i in range(1, 100)] + [Fraction(1)]
    with pytest.raises(ValueError, match="cannot be evaluated to 1e-09 of its lift"):
        bernstein_law(b, "wild")
    with pytest.raises(ValueError, match=rf"^exponents: .*above the largest degree .* {MAX_DEGREE}"):
        polynomial_law((3, MAX_DEGREE + 1))


def test_scene_names_the_segment_of_a_refused_law():
    text = builtin_scene_text("default").replace(
        'law = "cycloidal", lift_mm = 5.0 },\n  { kind = "dwell",  angle_deg = 120 }',
        f'law = "polynomial", exponents = [3, {MAX_DEGREE + 5}], lift_mm = 5.0 }},\n'
        '  { kind = "dwell",  angle_deg = 120 }')
    with pytest.raises(SceneError, match=r"motion\.segments\[1\]\.exponents = .*largest degree"):
        parse_scene(text, "x")


@pytest.mark.slow
def test_program_extrema_and_samples_agree_at_degree_100():
    """The defect: the report's extrema (refined) said 10 mm while the samples held 1.9e28 mm."""
    lift = 10.0
    prog = MotionProgram.from_segments([
        Segment("dwell", 100.0), Segment("rise", 80.0, polynomial_law(HIGH["50..100"]), lift),
        Segment("dwell", 120.0), Segment("return", 60.0, LAWS["cycloidal"], lift)])
    kin = evaluate(prog, 720)
    s = np.asarray(kin.s)
    assert np.all(s <= lift * (1 + LIFT_TOLERANCE)) and np.all(s >= -lift * LIFT_TOLERANCE)
    hi = max_of(prog, lambda k, _: k.s, kin.s)
    lo = min_of(prog, lambda k, _: k.s, kin.s)
    assert abs(float(hi.value) - lift) <= lift * LIFT_TOLERANCE
    assert abs(float(lo.value)) <= lift * LIFT_TOLERANCE
    # velocity: the refined peak is at least the sampled one and close to it (720 samples)
    vmax = max_of(prog, lambda k, _: k.ds, kin.ds)
    assert float(vmax.value) >= float(jnp.max(kin.ds)) * (1 - 1e-12)
