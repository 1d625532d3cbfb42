"""B-spline laws: de Boor in JAX vs SciPy and exact rational evaluation, 3-4-5 as a Bezier,
gradients with respect to the control values, scene keys, and a B-spline segment in the design
of every registered follower."""

from __future__ import annotations

import functools
import math
import tomllib
from fractions import Fraction

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import followers
from camjax.followers._design import design_block
from camjax.laws import LAWS
from camjax.laws import bspline as B
from camjax.program import evaluate as program_evaluate
from camjax.scene import SceneError, builtin_scene_text, parse_scene, scene_from_dict


def _random_spline(k, n, seed, repeat=False):
    rng = np.random.default_rng(seed)
    inner = np.sort(rng.uniform(0.05, 0.95, n - k - 1))
    if repeat and inner.size >= 3:
        inner[1] = inner[2] = inner[0]  # a knot of multiplicity 3 (<= k for k >= 3)
    return np.concatenate([np.zeros(k + 1), inner, np.ones(k + 1)]), rng.normal(size=n)


DEGREES = range(1, B.MAX_DEGREE + 1)
DE_BOOR_X = np.linspace(0.0, 1.0, 2001)


@functools.cache
def _de_boor_of_every_degree():
    """degree -> (knots, control values, JAX's values and derivatives at DE_BOOR_X): every degree
    in one compiled program (eagerly each of de Boor's operations compiles alone; one program per
    degree took ~10 % more CPU seconds in all), computed once for the test of each degree."""
    splines = {k: _random_spline(k, k + 9, seed=k, repeat=k >= 3) for k in DEGREES}
    program = jax.jit(lambda cs, xx: {k: B.evaluate_derivatives(splines[k][0], cs[k], k, xx) for k in DEGREES})
    got = program({k: jnp.asarray(c) for k, (_, c) in splines.items()}, jnp.asarray(DE_BOOR_X))
    return {k: (t, c, got[k]) for k, (t, c) in splines.items()}


@pytest.mark.slow
@pytest.mark.parametrize("k", DEGREES)
def test_de_boor_matches_scipy_with_derivatives(k):
    from scipy.interpolate import BSpline  # imported by the tests that use it: not at every collection

    t, c, got = _de_boor_of_every_degree()[k]
    x = DE_BOOR_X
    ref = BSpline(t, c, k)
    for nu, g in enumerate(got):
        want = ref(x, nu=nu)
        scale = max(1.0, float(np.max(np.abs(want))))
        # both are convex-combination recursions in float64: agreement to a few ulps of the
        # largest value (derivatives grow by ~k/knot spacing per order, hence relative)
        np.testing.assert_allclose(np.asarray(g), want, rtol=0, atol=1e-12 * scale, err_msg=f"nu={nu}")


def _exact_de_boor(t, c, k, x):
    """Cox-de Boor in rational arithmetic (exact)."""
    n = len(c)
    i = max(j for j in range(k, n) if t[j] <= x)
    d = [c[j + i - k] for j in range(k + 1)]
    for r in range(1, k + 1):
        for j in range(k, r - 1, -1):
            a = (x - t[j + i - k]) / (t[j + 1 + i - r] - t[j + i - k])
            d[j] = (1 - a) * d[j - 1] + a * d[j]
    return d[k]


@pytest.mark.slow
def test_degree_nine_matches_exact_rational_evaluation():
    k, n = 9, 16
    rng = np.random.default_rng(9)
    inner = sorted(Fraction(int(v), 1000) for v in rng.integers(1, 1000, n - k - 1))
    t = [Fraction(0)] * (k + 1) + inner + [Fraction(1)] * (k + 1)
    c = [Fraction(int(v), 100) for v in rng.integers(-300, 300, n)]
    xs = [Fraction(j, 97) for j in range(98)]
    exact = np.array([float(_exact_de_boor(t, c, k, x)) for x in xs])
    knots = np.array([float(v) for v in t])
    got = jax.jit(lambda cc, xx: B.evaluate(knots, cc, k, xx))(jnp.asarray([float(v) for v in c]),
                                                                jnp.asarray([float(x) for x in xs]))
    # the bar for high degree is 1e-9 of the lift; de Boor holds ~1e-15 here
    np.testing.assert_allclose(np.asarray(got), exact, rtol=0, atol=1e-13)


def _bernstein_coefficients(power: dict[int, Fraction], n: int) -> list[Fraction]:
    """b_i = sum_{j <= i} C(i, j) / C(n, j) a_j: the power form in the degree-n Bernstein basis."""
    return [sum((Fraction(math.comb(i, j), math.comb(n, j)) * power.get(j, 0) for j in range(i + 1)),
                Fraction(0)) for i in range(n + 1)]


# 3-4-5 on one grid: one compiled program for the two tests that compare a B-spline with it
POLY_345 = jax.jit(LAWS["poly_3_4_5"])
LAW_X = jnp.linspace(0.0, 1.0, 1001)


@pytest.mark.slow
def test_degree_five_bspline_is_the_345_polynomial():
    control = _bernstein_coefficients({3: Fraction(10), 4: Fraction(-15), 5: Fraction(6)}, 5)
    law = B.bspline_law(5, [float(v) for v in control])
    got, ref = jax.jit(law)(LAW_X), POLY_345(LAW_X)
    for g, r in zip(got, ref, strict=True):
        # exact control values (0,0,0,1,1,1); p''' peaks at 60: 1e-12 absolute on every derivative
        np.testing.assert_allclose(np.asarray(g), np.asarray(r), rtol=0, atol=1e-12)


@pytest.mark.slow
def test_gradient_with_respect_to_control_values_matches_finite_differences():
    t, c = _random_spline(5, 12, seed=3)
    x = jnp.linspace(0.0, 1.0, 301)

    def scalar(cc):  # a smooth scalar of values and derivatives, like a peak acceleration
        v = B.evaluate_derivatives(t, cc, 5, x)
        return jnp.sum(v[0] ** 2) + 1e-3 * jnp.sum(v[2] ** 2) + 1e-6 * jnp.sum(jnp.sin(v[3] * 1e-2))

    # one program for the gradient and the 24 differences' values (eagerly, every operation
    # compiles alone; a second program for the values alone would compile the scalar again)
    value_and_grad = jax.jit(jax.value_and_grad(scalar))

    def objective(cc):
        return value_and_grad(cc)[0]

    g = value_and_grad(jnp.asarray(c))[1]
    h = 1e-5
    fd = np.array([(objective(jnp.asarray(c + h * e)) - objective(jnp.asarray(c - h * e))) / (2 * h)
                   for e in np.eye(c.size)])
    # central differences: error ~ h^2 f''' (f is nearly quadratic in c) plus rounding ~ 1e-16 f / h
    np.testing.assert_allclose(np.asarray(g), fd, rtol=1e-7, atol=1e-7 * float(np.max(np.abs(fd))))


@pytest.mark.slow
def test_derivative_in_x_by_jvp_is_the_derivative_spline():
    from scipy.interpolate import BSpline

    t, c = _random_spline(5, 10, seed=4)
    x = jnp.linspace(0.01, 0.99, 57)
    _, tangent = jax.jit(lambda xx: jax.jvp(lambda u: B.evaluate(t, jnp.asarray(c), 5, u), (xx,),
                                            (jnp.ones_like(xx),)))(x)
    np.testing.assert_allclose(np.asarray(tangent), BSpline(t, c, 5)(np.asarray(x), nu=1), rtol=1e-12,
                               atol=1e-12)


@pytest.mark.slow
def test_return_control_runs_backwards():
    law = B.bspline_law(5, [1, 1, 1, 0, 0, 0], falling=True)
    for g, r in zip(jax.jit(law)(LAW_X), POLY_345(LAW_X), strict=True):
        np.testing.assert_allclose(np.asarray(g), np.asarray(r), atol=1e-12)


SCENE = """
[motion]
rpm = 240
segments = [
  {{kind = "dwell", angle_deg = 100}},
  {{kind = "rise", angle_deg = 80, {rise}}},
  {{kind = "dwell", angle_deg = 120}},
  {{kind = "return", angle_deg = 60, {ret}}},
]
[follower]
type = "flat"
"""
POLY_RISE = 'law = "polynomial", exponents = [3, 4, 5], lift_mm = 5'
POLY_RET = 'law = "polynomial", exponents = [3, 4, 5], lift_mm = 5'


@pytest.mark.parametrize("rise, ret", [
    ('law = "bspline", control = [0, 0, 0, 1, 1, 1], lift_mm = 5',
     'law = "bspline", degree = 5, control = [1, 1, 1, 0, 0, 0], lift_mm = 5'),
    ('law = "bspline", control_mm = [0, 0, 0, 5, 5, 5]', 'law = "bspline", control_mm = [5, 5, 5, 0, 0, 0]'),
])
@pytest.mark.slow
def test_bspline_segments_in_a_scene_give_the_polynomial_program(rise, ret):
    got = program_evaluate(parse_scene(SCENE.format(rise=rise, ret=ret)).motion.program, 360)
    ref = program_evaluate(parse_scene(SCENE.format(rise=POLY_RISE, ret=POLY_RET)).motion.program, 360)
    for g, r in zip(got, ref, strict=True):
        scale = max(1.0, float(jnp.max(jnp.abs(r))))
        np.testing.assert_allclose(np.asarray(g), np.asarray(r), rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("rise, field", [
    ('law = "bspline", control = [0, 0, 0, 1, 1, 0.9], lift_mm = 5', "segments[1].control"),
    ('law = "bspline", control = [0, 1], control_mm = [0, 5]', "segments[1].control"),
    ('law = "bspline", control = [0, 0, 1, 1], lift_mm = 5, degree = 10', "segments[1].degree"),
    ('law = "bspline", control = [0, 0, 0, 1, 1, 1], knots = [0.5], lift_mm = 5', "segments[1].knots"),
    ('law = "bspline", control = [0, 0, 0, 1, 1, 1, 1], knots = [1.5], lift_mm = 5', "segments[1].knots"),
    ('law = "bspline", control_mm = [0, 0, 4], lift_mm = 5', "segments[1].control_mm"),
    ('law = "bspline", control = [0, "a", 1], lift_mm = 5', "segments[1].control"),
    ('law = "bspline", control = [0, 0.5, 1], lift_mm = 5, exponents = [3]', "segments[1].exponents"),
])
def test_bad_bspline_keys_name_the_field(rise, field):
    with pytest.raises(SceneError) as err:
        parse_scene(SCENE.format(rise=rise, ret=POLY_RET))
    assert err.value.field == f"motion.{field}", str(err.value)
    assert "\n" not in str(err.value)


def _with_law(name: str, law: dict) -> tuple[dict, bool]:
    data = tomllib.loads(builtin_scene_text(followers.get(name).example_scene))
    for seg in data["motion"]["segments"]:
        if seg.get("kind") == "rise":
            for key in ("law", "exponents", "coefficients", "phases"):
                seg.pop(key, None)
            seg.update(law)
            return data, True
    return data, False


def _design(data: dict, name: str) -> dict:
    """The solver's JSON of the scene's [design]: the design block a run of the scene solves first
    (:func:`camjax.followers._design.design_block`, as both follower families' ``run`` call it) and
    the source of its objective and base radius, without the run's drawing at the design (its
    smallest cam, refined report curves and outline: compiled programs of their own, none of them
    checked here)."""
    scene = scene_from_dict(data, name)
    return design_block(scene, camjax.problem_from_scene(scene))[0]


# the translating and the rocking follower whose exact-extrema designs compile fastest (each of
# the two scenes' designs compiles its own program here: in exact mode the laws are the program's
# static structure; measured 11 and 17 CPU s for the pair, 18 and 21 for the flat face and the
# oscillating roller). The knife edge is the roller's problem with R_f = 0: its exact extrema are
# the roller's and the curved face's code; the flat face's exact extrema with B-spline segments
# are tests/test_codesign.py's (the designed laws fed back as fixed segments).
EXACT_BSPLINE_FOLLOWERS = ("knife_edge", "oscillating_flat")


@pytest.mark.slow
@pytest.mark.parametrize("name", followers.names())
def test_a_bspline_rise_designs_as_its_polynomial_with_every_follower(name):
    """The Bezier form of 3-4-5 in the example scene of every follower gives the design of 3-4-5
    (the solver's objective and base radius; a whole run with B-spline segments, drawing included,
    is tests/test_codesign.py's designed laws fed back as fixed segments).

    The exact extrema (the laws evaluated between the samples, inside the design's program) for one
    translating and one rocking follower, which share that code with their kind; the others on
    the grid (the laws' samples only), where the two scenes' designs share one compiled program."""
    spline, found = _with_law(name, {"law": "bspline", "degree": 5, "control": [0, 0, 0, 1, 1, 1]})
    assert found, "the example scene has a rise"
    poly, _ = _with_law(name, {"law": "polynomial", "exponents": [3, 4, 5]})
    for data in (spline, poly):  # a GA's path can split on the laws' last bits: the deterministic solver
        if "design" in data:
            data["design"]["solver"] = "gradient"
        if name not in EXACT_BSPLINE_FOLLOWERS:
            data["motion"]["extrema"] = "grid"
    got, ref = _design(spline, name), _design(poly, name)
    # the laws agree to 1e-15, so both designs solve the same problem: the same optimum to the
    # solver's stopping rule (objective within 1e-9 relative; measured 4e-11 on the oscillating
    # curved face, whose BFGS refinement takes other line-search steps on the other last bits), and
    # where the objective is flat the same design to 1e-4 mm (measured 2e-5 mm there, 3e-10 mm on
    # the oscillating roller, 0 elsewhere)
    assert got["objective"] == pytest.approx(ref["objective"], rel=1e-9)
    assert got["base_radius_mm"] == pytest.approx(ref["base_radius_mm"], rel=0, abs=1e-4)
