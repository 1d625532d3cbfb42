"""The pieces every problem family shares (camjax.family), on a small stand-in family whose values are
known by construction: box distances by hand, per-angle slices against the grid, tolerances."""

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import family
from camjax.family import Weights
from camjax.numerics import NonFiniteError


class Design(NamedTuple):
    a_mm: jax.Array
    b_mm: jax.Array


class Problem(NamedTuple):
    theta_deg: jax.Array
    q_mm: jax.Array
    lower: Design
    upper: Design
    sigma_max_MPa: jax.Array


class Violation(NamedTuple):
    curvature: jax.Array
    stress: jax.Array


def _problem(n=6):
    theta = jnp.arange(n) * (360.0 / n)
    return Problem(theta, jnp.sin(jnp.deg2rad(theta)), Design(jnp.asarray(10.0), jnp.asarray(2.0)),
                   Design(jnp.asarray(20.0), jnp.asarray(2.0)), jnp.asarray(500.0))


@pytest.mark.parametrize("design, distance", [((15.0, 2.0), 0.0), ((7.5, 2.0), 2.5), ((15.0, 2.25), 0.25),
                                              ((23.0, 1.0), 3.0)])
def test_bounds_violation_is_the_largest_distance_outside_the_box(design, distance):
    # the box is [10, 20] x [2, 2]: the distances are read off by hand; exact in binary
    v = jax.jit(family.bounds_violation)(_problem(), Design(*map(jnp.asarray, design)))
    assert float(v) == distance


def test_bounds_violation_gradient_is_finite_inside_and_outside():
    for a in (15.0, 5.0, 25.0):
        g = jax.grad(lambda x: family.bounds_violation(_problem(), Design(x, jnp.asarray(2.0))))(a)
        assert np.isfinite(float(g))


def test_per_angle_gives_one_angle_each_and_broadcasts_the_rest():
    p = _problem(6)
    per = family.per_angle(p, {"theta_deg", "q_mm"})
    assert per.theta_deg.shape == (6, 1) and per.q_mm.shape == (6, 1)
    assert per.lower.a_mm.shape == (6,) and per.sigma_max_MPa.shape == (6,)
    for k in range(6):
        one = jax.tree.map(lambda x, k=k: x[k], per)
        assert float(one.theta_deg[0]) == float(p.theta_deg[k]) and float(one.q_mm[0]) == float(p.q_mm[k])
        assert float(one.upper.a_mm) == 20.0


def test_weighted_objective_and_bounds():
    w = Weights(jnp.asarray(0.5), jnp.asarray(2.0))
    # 0.5 * 0.25 + 2 * 250 / 500 = 1.125, exact in binary
    assert float(family.weighted_objective(w, 0.25, 250.0, 500.0)) == 1.125
    lo, hi = family.bounds(_problem())
    assert (float(lo.a_mm), float(hi.a_mm)) == (10.0, 20.0)


def test_condense_at_largest_takes_the_design_of_the_largest_size():
    p = _problem(6)
    per = Design(jnp.array([1.0, 4.0, 3.0, 4.0, 0.0, 2.0]), jnp.arange(6.0))
    design, extras = family.condense_at_largest(p, per, per.a_mm + 0.0, "a_deg")
    assert (float(design.a_mm), float(design.b_mm)) == (4.0, 1.0)  # the first of the tie
    assert float(extras["a_deg"]) == 60.0 and extras["theta_deg"] is p.theta_deg


def test_tolerances_decide_feasibility_and_the_names_of_violations():
    tol = {"curvature": 1e-6, "stress": 1e-6 * 500.0}
    assert bool(family.all_within(Violation(jnp.asarray(1e-6), jnp.asarray(5e-4)), tol))
    assert not bool(family.all_within(Violation(jnp.asarray(2e-6), jnp.asarray(0.0)), tol))
    assert family.violated(("curvature", "stress"), Violation(2e-6, 6e-4), tol) == ["curvature", "stress"]
    assert family.violated(("curvature", "stress"), Violation(0.0, 6e-4), tol) == ["stress"]


def test_json_helpers_name_every_variable_and_refuse_non_finite_values():
    p = _problem(3)
    assert family.design_json(Design(1.5, 2.5), ("a_mm", "b_mm")) == {"a_mm": 1.5, "b_mm": 2.5}
    assert family.bounds_json(p, ("a_mm",)) == {"a_bounds_mm": [10.0, 20.0]}

    class Solution(NamedTuple):
        extras: dict
        pointwise: Design

    s = Solution({"theta_deg": p.theta_deg}, Design(jnp.array([1.0, 2.0, 3.0]), jnp.zeros(3)))
    assert family.pointwise_json(s, ("a_mm",)) == {"theta_deg": [0.0, 120.0, 240.0], "a_mm": [1.0, 2.0, 3.0]}

    class Evaluation(NamedTuple):
        stress_max_MPa: float
        stress_max_deg: float

    class Solved(NamedTuple):
        design: Design
        evaluation: Evaluation

    row = family.record_json(Solved(Design(1.0, 2.0), Evaluation(400.0, 90.0)), 3.0, prime_radius_mm=3.5)
    assert row == {"a_mm": 1.0, "b_mm": 2.0, "prime_radius_mm": 3.5, "size_mm": 3.0, "stress_max_MPa": 400.0,
                   "stress_max_deg": 90.0}
    with pytest.raises(NonFiniteError, match="non-finite value nan"):
        family.record_json(Solved(Design(1.0, 2.0), Evaluation(400.0, 90.0)), float("nan"))


def test_solution_keys_keep_the_order_every_family_writes_and_add_the_pointwise_block():
    p = _problem(3)

    class Solution(NamedTuple):
        mode: str
        extras: dict
        pointwise: Design
        design: Design
        violation: Violation

    s = Solution("pointwise", {"theta_deg": p.theta_deg, "a_deg": 120.0},
                 Design(jnp.array([1.0, 2.0, 3.0]), jnp.zeros(3)), Design(3.0, 2.0), Violation(0.0, 1.5))
    out = family.solution_keys(p, s, ("a_mm",), size_mm=3.0, figures={"stress_max_MPa": 400.0},
                               pointwise_angles=("a_deg",), prime_radius_mm=5.0)
    assert list(out) == ["a_mm", "prime_radius_mm", "size_mm", "constraint_violation", "stress_max_MPa",
                         "sigma_max_MPa", "a_bounds_mm", "a_deg", "pointwise"]
    assert out["constraint_violation"] == {"curvature_mm": 0.0, "stress_MPa": 1.5}
    assert out["sigma_max_MPa"] == 500.0 and out["a_deg"] == 120.0 and out["pointwise"]["a_mm"] == [1.0, 2.0, 3.0]
    assert "pointwise" not in family.solution_keys(p, s._replace(mode="global"), ("a_mm",), size_mm=3.0,
                                                   figures={})


def test_violation_json_names_each_field_with_its_unit_in_field_order():
    class Circle(NamedTuple):
        reach: float
        pressure_angle: float
        stress: float
        bounds: float

    # pi/36 rad = 5 deg (to a rounding of pi); the other fields pass through unchanged
    out = family.violation_json(Circle(0.25, np.pi / 36.0, 3.0, 0.0))
    assert list(out) == ["reach_mm", "pressure_angle_deg", "stress_MPa", "bounds_mm"]
    assert out["pressure_angle_deg"] == pytest.approx(5.0, rel=1e-15)
    assert (out["reach_mm"], out["stress_MPa"], out["bounds_mm"]) == (0.25, 3.0, 0.0)


class ContactProblem(NamedTuple):
    theta_deg: jax.Array
    lower: Design
    upper: Design
    sigma_max_MPa: jax.Array
    min_curvature_radius_mm: jax.Array


class ContactViolation(NamedTuple):
    pressure_angle: jax.Array
    undercut: jax.Array
    stress: jax.Array
    bounds: jax.Array


class ContactEvaluation(NamedTuple):
    objective: jax.Array
    size_mm: jax.Array
    stress_max_MPa: jax.Array
    stress_max_deg: jax.Array
    pressure_angle_max_deg: jax.Array
    pressure_angle_max_at_deg: jax.Array
    cam_rho_min_mm: jax.Array
    violation: ContactViolation
    feasible: jax.Array


def test_worst_contact_and_judged_read_the_worst_angle_off_the_curves():
    # four angles, the curves written so that each worst value and its angle are known by hand
    p = ContactProblem(jnp.array([0.0, 90.0, 180.0, 270.0]), Design(10.0, 2.0), Design(20.0, 2.0),
                       jnp.asarray(500.0), jnp.asarray(3.0))
    sigma = jnp.array([100.0, 620.0, 620.0, 300.0])  # peak 620 first at 90 deg: 120 MPa over
    phi = jnp.array([0.1, 0.2, 0.6, 0.5])  # 0.6 rad at 180 deg: 0.1 rad over a 0.5 rad limit
    margin = jnp.array([9.0, 2.0, 7.0, 5.0])  # rho_c 2 mm at 90 deg: 1 mm short of 3 mm
    design = Design(jnp.asarray(25.0), jnp.asarray(2.0))  # 5 mm above the box
    figures, violations = family.worst_contact(p, design, sigma, phi, margin, 0.5)
    assert {k: float(v) for k, v in figures.items()} == {
        "stress_max_MPa": 620.0, "stress_max_deg": 90.0, "pressure_angle_max_deg": pytest.approx(np.degrees(0.6)),
        "pressure_angle_max_at_deg": 180.0, "cam_rho_min_mm": 2.0}
    assert float(violations["pressure_angle"]) == pytest.approx(0.1, abs=1e-15)
    assert (float(violations["undercut"]), float(violations["stress"]), float(violations["bounds"])) == (1.0, 120.0, 5.0)
    ev = family.judged(ContactEvaluation, ContactViolation, p, objective=jnp.asarray(0.7), size_mm=27.0,
                       figures=figures, violations=violations)
    assert isinstance(ev.violation, ContactViolation) and float(ev.violation.stress) == 120.0
    assert float(ev.objective) == 0.7 and ev.size_mm == 27.0 and not bool(ev.feasible)
    inside = family.worst_contact(p, Design(jnp.asarray(15.0), jnp.asarray(2.0)), sigma * 0.5, phi * 0.5,
                                  margin + 1.0, 0.5)
    assert bool(family.judged(ContactEvaluation, ContactViolation, p, objective=0.0, size_mm=17.0,
                              figures=inside[0], violations=inside[1]).feasible)


def test_sized_objective_is_the_weighted_size_and_stress():
    w = Weights(jnp.asarray(0.5), jnp.asarray(2.0))
    p = _problem()
    # 0.5 * 0.25 + 2 * 250 / 500 = 1.125, exact in binary
    f = family.sized_objective(lambda p, d: 0.25 * d.a_mm, lambda p, d: 250.0 * d.b_mm, p, w, Design(1.0, 1.0))
    assert float(f) == 1.125


def test_twin_type_keeps_the_twins_fields_and_defaults_and_is_its_own_type():
    class Twin(NamedTuple):
        a: float
        b: float
        c: float = 1.0
        d: float = 2.0

    T = family.twin_type("T", Twin, "A twin without d, with x before c.", __name__, drop=("d",), add=("x",),
                         before="c")
    assert T._fields == ("a", "b", "x", "c") and T(1, 2, 3) == (1, 2, 3, 1.0)
    assert T is not Twin and T.__doc__.startswith("A twin") and T.__module__ == __name__
    assert jax.tree.leaves(T(1.0, 2.0, 3.0)) == [1.0, 2.0, 3.0, 1.0]
    with pytest.raises(ValueError, match="defaults must come last"):
        family.twin_type("U", Twin, "", __name__, add=("y",))


def test_the_smooth_excess_keeps_the_rows_sign_and_its_value_and_gradient_where_it_binds():
    """family.excess(lean, reach, smooth=True) against |lean| - reach (independent: written here):
    the same sign on a grid of lean and reach through 0 (both signs of reach), and where the row
    binds (|lean| = reach > 0) the same value (0) and the same gradient (sign(lean), -1) by
    reverse mode; smooth across lean = 0 inside the limit: its second derivative in lean there is
    1 / reach (finite differences, where |lean| - reach has a kink); finite gradients at 0, 0."""
    lean, reach = np.meshgrid(np.linspace(-3.0, 3.0, 61), np.linspace(-2.0, 2.0, 41))
    smooth = np.asarray(family.excess(jnp.asarray(lean), jnp.asarray(reach), smooth=True))
    plain = np.abs(lean) - reach
    assert np.all(np.sign(smooth) == np.sign(plain))
    for r in (0.5, 1.7, 12.0):
        for sign in (1.0, -1.0):
            grad = jax.grad(lambda a, b: family.excess(a, b, smooth=True), argnums=(0, 1))(sign * r, r)
            assert float(family.excess(sign * r, r, smooth=True)) == pytest.approx(0.0, abs=1e-15)
            np.testing.assert_allclose(np.asarray(grad), [sign, -1.0], rtol=1e-12)
        h = 1e-4
        second = (float(family.excess(h, r, True)) - 2 * float(family.excess(0.0, r, True))
                  + float(family.excess(-h, r, True))) / h**2
        assert second == pytest.approx(1.0 / r, rel=1e-6)
    grad = jax.grad(lambda a, b: family.excess(a, b, smooth=True), argnums=(0, 1))(0.0, 0.0)
    assert np.all(np.isfinite(np.asarray(grad)))
    assert float(family.excess(-1.5, 1.0)) == pytest.approx(0.5)
