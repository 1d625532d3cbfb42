"""camjax.solvers.newton in pointwise mode: the interior-point solver converges (scaled KKT residual
within ``tol``) on every one-angle problem of each follower type's example scene, dwells included
(the pointwise solve: one vmapped program per type), each angle's optimum is the gradient
solver's, and the condensed pointwise design is no worse than the gradient solver's."""

import dataclasses

import jax
import numpy as np
import pytest

import camjax
from camjax import followers
from camjax.family import weights_of
from camjax.solvers import newton
from camjax.solvers.base import family_of, problem_from_scene, solve

SAMPLES = 72
# The types whose one-angle problems newton solves on every angle: the roller and the knife edge
# (dwells: the pressure-angle row's kink in the offset), the curved face and the oscillating flat.
# Left out: the flat face (its one-angle problems have no offset; tests/test_newton.py covers its
# global problem) and the two types whose one-angle optimum can lie where the reach row is active
# with an infinite slope (a square root at its limit: no finite multipliers, so no KKT residual
# reaches tol on those angles: oscillating roller 10 of 360 angles, oscillating curved face 12).
TYPES = ("roller", "knife_edge", "curved_face", "oscillating_flat")


@pytest.fixture(scope="module", params=TYPES)
def solved(request):
    """One type's example scene: the pointwise solves of newton (every one-angle problem in one
    vmapped program; the solution's ``converged`` is every angle's, its ``iterations`` the most any
    angle took) and of the gradient solver."""
    name = request.param
    scene = camjax.load_scene(followers.get(name).example_scene)
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=SAMPLES))
    problem = problem_from_scene(scene)
    weighting = (scene.design.alpha, scene.design.gamma)
    w = weights_of(*weighting)  # scalar weights
    by_newton = solve(problem, weighting, mode="pointwise", solver="newton")
    by_gradient = solve(problem, weighting, mode="pointwise", solver="gradient")
    return name, problem, w, by_newton, by_gradient


@pytest.mark.slow
def test_converges_on_every_angle(solved):
    """Every angle's one-angle problem reaches the stopping rule (KKT residual <= tol) well inside
    the iteration safeguard. A dwell's pressure-angle row has a kink in the offset (|e|) at the
    barrier problem's minimizer: its slack never equals the row there and the line search accepts
    no step across the kink, yet the barrier parameter must fall all the same."""
    name, _, _, by_newton, _ = solved
    assert jax.tree.leaves(by_newton.pointwise)[0].shape == (SAMPLES,)
    # converged: the scaled KKT residual within tol on every angle
    assert bool(by_newton.converged), name
    assert int(by_newton.iterations) < newton.DEFAULT_SETTINGS.max_iterations // 4, name


@pytest.mark.slow
def test_each_angle_optimum_is_the_gradient_solvers(solved):
    """Each one-angle problem's objective at newton's answer is the gradient solver's or lower
    (1e-7 relative: the gradient solver stops on its own tolerance, newton's barrier leaves ~1e-9),
    on the angles where both answers are feasible."""
    name, problem, w, by_newton, by_gradient = solved
    fam = family_of(problem)
    # every angle's evaluation in one compiled program per type, for both solvers' answers (op by op,
    # the per-angle split and the vmapped evaluation compile each of their operations)
    evaluate = jax.jit(lambda p, weights, d: jax.vmap(lambda q, x: fam.evaluate(q, weights, x))(fam.per_angle(p), d))
    mine, theirs = evaluate(problem, w, by_newton.pointwise), evaluate(problem, w, by_gradient.pointwise)
    both = np.asarray(mine.feasible) & np.asarray(theirs.feasible)
    assert both.sum() >= SAMPLES // 2, name
    excess = np.asarray(mine.objective) - np.asarray(theirs.objective) * (1.0 + 1e-7)
    assert np.all(excess[both] <= 0.0), (name, np.flatnonzero(both & (excess > 0.0)))


@pytest.mark.slow
def test_condensed_design_no_worse_than_the_gradient_solvers(solved, request):
    """The whole-cam design of the pointwise rule is the gradient solver's or better (1e-7 relative)
    where both are feasible. The knife edge's condensing angle (the first of largest R_b) is a dwell
    whose one-angle optimum leaves the offset free in an interval: newton's barrier takes an interior
    offset, the gradient solver keeps its start's, and the continuous polish then raises R_b by an
    amount that depends on that offset (the same gap before newton converged on every angle)."""
    name, _, _, by_newton, by_gradient = solved
    if name == "knife_edge":  # measured: 0.260615 against 0.255900 (strict: a pass would be news)
        request.applymarker(pytest.mark.xfail(strict=True, reason="a degenerate condensing angle: "
                                              "the offset is the solver's choice"))
    if bool(by_newton.feasible) and bool(by_gradient.feasible):
        assert float(by_newton.objective) <= float(by_gradient.objective) * (1.0 + 1e-7), name
