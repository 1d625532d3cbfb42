"""Motion laws: closed forms vs SPEC table, vs autodiff, boundary conditions, families."""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camjax.laws import (
    LAWS,
    THESIS_NOMINAL,
    FourierSeries,
    fourier_law,
    polynomial_coefficients,
    polynomial_law,
    stepped_law,
    summarize,
    summarize_all,
)

PI = math.pi

# (peak |p'|, peak +p'', peak -p'', peak |p'''|) as printed in SPEC section 1, and the number of
# significant digits printed there (the comparison tolerance is half a unit of the last digit).
SPEC_TABLE = {
    "harmonic": ("1.5708", "4.9348", "-4.9348", "15.503"),
    "cycloidal": ("2", "6.2832", "-6.2832", "39.478"),
    "double_harmonic": ("2.0405", "5.5517", "-9.8696", "42.414"),
    "double_cycloidal": ("2.6667", "10.883", "-10.883", "105.28"),
    "poly_3_4": ("1.7778", "4", "-12", "48"),
    "poly_4_5": ("2.1094", "5", "-20", "120"),
    "poly_3_4_5": ("1.875", "5.7735", "-5.7735", "60"),
    "poly_4_5_6": ("2.0736", "5.9745", "-8.1345", "120"),
    "poly_3_4_5_6": ("2.0736", "8.1345", "-5.9745", "120"),
    "poly_4_5_6_7": ("2.1875", "7.5132", "-7.5132", "52.5"),
    "modified_trapezoid": ("2.0", "4.8881", "-4.8881", "61.43"),
    "modified_sine": ("1.76", "5.528", "-5.528", "69.5"),
}

# Exact closed-form peaks where they exist: (|p'|, +p'', -p'', |p'''|).
CLOSED_FORM = {
    "harmonic": (PI / 2, PI**2 / 2, -(PI**2) / 2, PI**3 / 2),
    "cycloidal": (2.0, 2 * PI, -2 * PI, 4 * PI**2),
    "poly_3_4": (16 / 9, 4.0, -12.0, 48.0),  # p' = 12x^2 - 12x^3 peaks at x = 2/3
    "poly_3_4_5": (15 / 8, 10 / math.sqrt(3), -10 / math.sqrt(3), 60.0),
    "poly_4_5_6_7": (35 / 16, None, None, 52.5),
}


@functools.cache
def _summaries(samples: int = 2001, names: tuple[str, ...] = tuple(LAWS)) -> dict:
    """name -> summary of each named law on ``samples`` points, all of them from one compiled
    program (summarize_all) instead of one per law and test; summarize is summarize_all of one law.
    The end values (FLCD) are the laws' at x = 0 and 1 whatever the samples."""
    return dict(zip(names, summarize_all([LAWS[n] for n in names], samples=samples), strict=True))


def _half_ulp_of_print(text: str) -> float:
    digits = text.split(".")[1] if "." in text else ""
    return 0.5 * 10.0 ** (-len(digits)) if digits else 0.5


@pytest.mark.parametrize("name", list(SPEC_TABLE))
def test_peaks_match_spec_table_to_printed_digits(name):
    s = _summaries()[name]
    got = (s.peak_velocity, s.peak_accel_pos, s.peak_accel_neg, s.peak_jerk)
    for g, printed in zip(got, SPEC_TABLE[name], strict=True):
        # peaks refined to ~1e-13 relative (next test): far below print precision
        assert abs(g - float(printed)) <= _half_ulp_of_print(printed) + 1e-9, (name, g, printed)


@pytest.mark.parametrize("samples", [101, 2001])
@pytest.mark.parametrize("name", list(CLOSED_FORM))
def test_peaks_match_closed_forms(name, samples):
    s = _summaries() if samples == 2001 else _summaries(samples, tuple(CLOSED_FORM))
    s = s[name]
    got = (s.peak_velocity, s.peak_accel_pos, s.peak_accel_neg, s.peak_jerk)
    for g, ref in zip(got, CLOSED_FORM[name], strict=True):
        if ref is not None:
            # refined peak of a smooth maximum: final spacing h = 2/(samples-1)/16^3 (2.4e-6 at
            # 101 samples), error <= (h/2)^2 |f''|/2 = 1.5e-10 for the worst peak here (3-4-5's
            # acceleration, where the fourth derivative is -208); the grid of 101 points alone is
            # off by ~1e-3, so this fails if the refinement does not work
            assert g == pytest.approx(ref, rel=0, abs=2e-10), (name, g, ref)


@functools.cache
def _ends():
    """name -> every law at x = 0 and 1, all laws in one compiled program (not op by op per law)."""
    return jax.jit(lambda x: {name: law(x) for name, law in LAWS.items()})(jnp.asarray([0.0, 1.0]))


@pytest.mark.parametrize("name", list(LAWS))
def test_boundary_values(name):
    v = _ends()[name]
    np.testing.assert_allclose(v.p, [0.0, 1.0], atol=1e-14)
    # rest-to-rest laws start and end at rest; the uniform law moves at p' = 1 throughout
    end_v = 1.0 if name == "uniform" else 0.0
    np.testing.assert_allclose(v.dp, [end_v, end_v], atol=1e-12)
    assert LAWS[name].end_velocity == end_v


@pytest.mark.slow
@pytest.mark.parametrize("name", list(LAWS))
def test_closed_form_derivatives_equal_autodiff(name):
    law = LAWS[name]
    # interior points away from the piecewise breaks of the modified laws (1/8, 3/8, ...)
    x = jnp.linspace(0.0, 1.0, 97)[1:-1] + 1e-3

    @jax.jit  # the law and its three derivatives in one program (not op by op)
    def closed_and_autodiff(x):
        v = law(x)
        return (v.dp, v.d2p, v.d3p), [jax.vmap(jax.grad(lambda t, k=k: law(t)[k]))(x) for k in range(3)]

    closed_forms, autodiff = closed_and_autodiff(x)
    for k, (closed, ad) in enumerate(zip(closed_forms, autodiff, strict=True)):
        scale = max(1.0, float(jnp.max(jnp.abs(closed))))
        np.testing.assert_allclose(closed, ad, rtol=0, atol=1e-10 * scale, err_msg=f"{name} order {k + 1}")


# SPEC: harmonic violates FLCD against dwells; double harmonic violates it at its end; cycloidal
# has a perturbation at both ends; double cycloidal and 4-5-6-7 have neither.
FLCD_EXPECTED = {
    "harmonic": (False, None),
    "double_harmonic": (False, None),
    "cycloidal": (True, True),
    "double_cycloidal": (True, False),
    "poly_4_5_6_7": (True, False),
    "poly_3_4_5": (True, True),
}


@pytest.mark.parametrize("name", list(FLCD_EXPECTED))
def test_flcd_statements_of_the_spec(name):
    s = _summaries()[name]
    flcd, pert = FLCD_EXPECTED[name]
    assert s.flcd_against_dwells is flcd
    if pert is not None:
        assert s.perturbation_against_dwells is pert
    if name == "double_harmonic":  # starts smoothly, the acceleration jumps at its end only
        assert abs(s.end_accel[0]) < 1e-12 and s.end_accel[1] == pytest.approx(-(PI**2))


def test_polynomial_closed_forms_from_spec():
    # A-B-C: f = (bc/2)x^a - ac x^b + (ab/2)x^c ; A-B-C-D likewise (SPEC section 1)
    a, b, c = 3, 4, 5
    assert polynomial_coefficients((a, b, c)) == (b * c / 2, -a * c, a * b / 2)
    a, b, c, d = 4, 5, 6, 7
    ref = (b * c * d / 6, -a * c * d / 2, a * b * d / 2, -a * b * c / 6)
    assert polynomial_coefficients((a, b, c, d)) == ref
    # worked example 4-5-7: (35x^4 - 42x^5 + 10x^7)/3, peak p'' ~ -8.697
    from fractions import Fraction

    assert polynomial_coefficients((4, 5, 7)) == (Fraction(35, 3), Fraction(-14), Fraction(10, 3))
    assert summarize(polynomial_law((4, 5, 7))).peak_accel_neg == pytest.approx(-8.697, abs=5e-4)


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(1, 12), min_size=1, max_size=6, unique=True))
def test_general_polynomial_boundary_conditions(exps):
    exps = sorted(exps)
    law = polynomial_law(exps)
    end = law(jnp.asarray(1.0))
    n = len(exps)
    # f(1) = 1 and the first n-1 derivatives vanish at 1 (up to order 3 available here)
    # the coefficients are exact rationals; what is left is the round-off of summing terms of size
    # |c_k| [e_k]_j in float64: 64 eps sum|c_k| max(e)^3 bounds it (the extremes matrix's bound)
    tol = 64 * np.finfo(float).eps * sum(abs(float(c)) for c in polynomial_coefficients(exps)) * max(exps) ** 3
    assert abs(float(end.p) - 1.0) <= tol
    for k, val in enumerate((end.dp, end.d2p, end.d3p), start=1):
        if k < n:
            assert abs(float(val)) <= tol
    assert float(law(jnp.asarray(0.0)).p) == 0.0


def test_polynomial_rejects_bad_exponents():
    with pytest.raises(ValueError, match="strictly increasing"):
        polynomial_law((4, 3))
    with pytest.raises(ValueError, match="strictly increasing"):
        polynomial_law((0, 3))


def test_stepped_law_matches_spec_example():
    law = stepped_law(lambda x: x - 4 * x**3, "spec_example")
    x = jnp.linspace(0.0, 0.5, 51)
    v = law(x)
    np.testing.assert_allclose(v.p, 8 / 7 * (5 * x**3 - 6 * x**5), atol=1e-14)
    np.testing.assert_allclose(v.dp, 120 / 7 * (x**2 - 2 * x**4), atol=1e-13)
    np.testing.assert_allclose(v.d2p, 240 / 7 * (x - 4 * x**3), atol=1e-12)
    np.testing.assert_allclose(v.d3p, 240 / 7 * (1 - 12 * x**2), atol=1e-12)
    # second half by symmetry: p_B(x) = 1 - p_A(1 - x), p''_B(x) = -p''_A(1 - x)
    xb = 1.0 - x
    vb = law(xb)
    np.testing.assert_allclose(vb.p, 1.0 - v.p, atol=1e-14)
    np.testing.assert_allclose(vb.d2p, -v.d2p, atol=1e-12)


def test_fourier_preset_and_law():
    s = THESIS_NOMINAL.evaluate(jnp.asarray([0.0, PI]))
    # S(0) = sum of all amplitudes (cos 0 = 1), S(pi) = h0 - h1 - h3 - ... (odd harmonics)
    amps = [h for _, h, _ in THESIS_NOMINAL.harmonics]
    assert float(s.p[0]) == pytest.approx(0.2417 + sum(amps), abs=1e-15)
    assert float(s.p[1]) == pytest.approx(0.2417 - sum(amps), abs=1e-15)
    law = fourier_law(THESIS_NOMINAL)
    x = jnp.linspace(0, 1, 11)
    # odd-harmonic cosine series: the rising half is antisymmetric about x = 1/2
    np.testing.assert_allclose(law(x).p + law(1 - x).p, 1.0, atol=1e-14)
    series = FourierSeries.from_mapping({"h0": 1.0, "h2": 0.5}, {"phi2": 0.3})
    assert series.harmonics == ((2, 0.5, 0.3),)
    with pytest.raises(ValueError, match="phases"):
        FourierSeries.from_mapping({"h1": 1.0}, {"phi3": 0.1})


def test_uniform_law_is_constant_velocity():
    x = jnp.linspace(0.0, 1.0, 101)
    v = LAWS["uniform"](x)
    # closed form p = x: p' = 1, p'' = p''' = 0 exactly (no rounding in the formula)
    np.testing.assert_array_equal(v.p, x)
    np.testing.assert_array_equal(v.dp, np.ones(101))
    np.testing.assert_array_equal(v.d2p, np.zeros(101))
    np.testing.assert_array_equal(v.d3p, np.zeros(101))
    # the slope from differences of the positions alone (exact for a line up to rounding)
    np.testing.assert_allclose(np.diff(np.asarray(v.p)) / np.diff(np.asarray(x)), 1.0, rtol=1e-12)
    s = _summaries()["uniform"]
    assert s.flcd_against_dwells is False and s.perturbation_against_dwells is False
    assert (s.peak_velocity, s.peak_accel_pos, s.peak_accel_neg, s.peak_jerk) == (1.0, 0.0, 0.0, 0.0)


def test_uniform_joints_against_dwells_are_shocks():
    from camjax.program import MotionProgram, Segment, joints

    uni = LAWS["uniform"]
    lift, rise_deg, ret_deg = 8.0, 90.0, 120.0
    prog = MotionProgram.from_segments([
        Segment("dwell", 60.0), Segment("rise", rise_deg, uni, lift),
        Segment("dwell", 90.0), Segment("return", ret_deg, uni, lift),
    ])
    js = joints(prog)
    # every joint of a uniform segment with a dwell is a velocity jump of lift / beta (mm/rad)
    assert [j.flcd_class for j in js] == ["shock"] * 4
    by_angle = {round(j.joint_deg): j for j in js}
    assert by_angle[60].jump_v == pytest.approx(lift / math.radians(rise_deg), rel=1e-12)
    assert by_angle[150].jump_v == pytest.approx(-lift / math.radians(rise_deg), rel=1e-12)
    assert by_angle[240].jump_v == pytest.approx(-lift / math.radians(ret_deg), rel=1e-12)
    assert by_angle[0].jump_v == pytest.approx(lift / math.radians(ret_deg), rel=1e-12)
    assert all(j.jump_s == pytest.approx(0.0, abs=1e-12) for j in js)
