"""SciPy baseline: an independent solver that agrees with the closed form and the JAX solvers."""

import numpy as np
import pytest

from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import gradient as G

pytest.importorskip("scipy")
from camjax.solvers import scipy_baseline as SB  # noqa: E402


@pytest.fixture(scope="module")
def problem(default_scene):
    # the SciPy baseline solves the problem on the samples: compare it with the grid problem
    return P.problem_from_scene(default_scene, extrema="grid")


@pytest.mark.parametrize("alpha,gamma", [(1.0, 1.0), (10.0, 1.0), (1.0, 0.0)])
def test_slsqp_pointwise_matches_closed_form(problem, alpha, gamma):
    angles = np.arange(0, 360, 9)
    res = SB.slsqp_pointwise(problem, alpha, gamma, angles)
    ref = optimum.pointwise_optimum(problem, weights_of(alpha, gamma))
    np.testing.assert_allclose(res.base_radius_mm, np.asarray(ref.base_radius_mm)[angles], atol=1e-5)
    np.testing.assert_allclose(res.face_width_mm, np.asarray(ref.face_width_mm)[angles], atol=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("alpha,gamma", [(1.0, 1.0), (10.0, 1.0)])
def test_global_gradient_agrees_with_slsqp_and_differential_evolution(problem, alpha, gamma):
    ours = G.solve_global(problem, weights_of(alpha, gamma))
    slsqp = SB.slsqp_global(problem, alpha, gamma)
    assert float(ours.design.base_radius_mm) == pytest.approx(float(slsqp.base_radius_mm), abs=1e-5)
    assert float(ours.design.face_width_mm) == pytest.approx(float(slsqp.face_width_mm), abs=1e-5)
    de = SB.differential_evolution_global(problem, alpha, gamma, seed=1)
    assert float(ours.design.base_radius_mm) == pytest.approx(float(de.base_radius_mm), abs=1e-3)
    assert float(ours.design.face_width_mm) == pytest.approx(float(de.face_width_mm), abs=1e-3)
    assert float(ours.objective) <= float(de.objective) + 1e-9


@pytest.mark.slow
def test_differential_evolution_pointwise_at_the_binding_angles(problem):
    res = SB.differential_evolution_pointwise(problem, 1.0, 1.0, [315], seed=0, popsize=10)
    ref = optimum.pointwise_optimum(problem, weights_of(1.0, 1.0))
    np.testing.assert_allclose(res.base_radius_mm, np.asarray(ref.base_radius_mm)[[315]], atol=1e-3)
    np.testing.assert_allclose(res.face_width_mm, np.asarray(ref.face_width_mm)[[315]], atol=1e-3)
