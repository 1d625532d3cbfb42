"""camjax.solvers.scipy_family: SciPy on a family's own JAX functions reaches the camjax optimum."""

import dataclasses

import numpy as np
import pytest

import camjax
from camjax.family import weights_of
from camjax.solvers import scipy_family
from camjax.solvers.base import problem_from_scene, solve_batch, weighting_keys

pytest.importorskip("scipy")


@pytest.fixture(scope="module")
def problem():
    """The oscillating-roller scene (free R_b and pivot distance d) on a 90-sample grid, grid extrema."""
    scene = camjax.load_scene("oscillating-roller")
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=90, extrema="grid"))
    return problem_from_scene(scene)


@pytest.fixture(scope="module")
def camjax_optimum(problem):
    """The hybrid solver's design for alpha = 0.99, gamma = 0.01 (size-dominated: the optimum is the
    smallest cam on the pressure-angle limit, a vertex of the feasible set that both must find)."""
    sol = solve_batch(problem, weights_of(np.array([0.99]), np.array([0.01])), weighting_keys(0, 1),
                      "global", "hybrid")
    assert bool(sol.feasible[0])
    return float(sol.objective[0]), np.array([float(v[0]) for v in sol.design])


@pytest.mark.slow
@pytest.mark.parametrize("method", ["slsqp", "differential_evolution"])
def test_scipy_reaches_camjax_optimum(problem, camjax_optimum, method):
    objective, design = camjax_optimum
    result = getattr(scipy_family, method)(problem, 0.99, 0.01)
    assert result.max_violation < 1e-9  # rows are g / N: 1e-9 of N ~ 1e-7 mm, below the 1e-6 mm tolerance
    # Both stop at a KKT point of the same grid problem: SLSQP with ftol 1e-12, DE's trust-constr polish
    # and the hybrid's gradient polish each to ~1e-10 in F; 1e-8 relative leaves two orders of margin.
    assert abs(result.objective / objective - 1.0) < 1e-8
    # F ~ R_p / N (N = 68 mm): 1e-8 in F is ~1e-6 mm in R_b; the pivot distance moves with R_b along
    # the active pressure-angle constraint, so 1e-4 mm bounds both.
    np.testing.assert_allclose(result.design, design, atol=1e-4)
    assert result.design[1] == design[1] and result.design[3] == design[3]  # fixed R_f, l stay fixed


@pytest.mark.slow
def test_fixed_variables_are_not_searched(problem):
    """SLSQP from a start at the box centre moves only the free variables (R_b, d)."""
    lower, upper = problem.lower, problem.upper
    result = scipy_family.slsqp(problem, 0.99, 0.01, maxiter=3)
    assert result.design[1] == float(lower.roller_radius_mm) == float(upper.roller_radius_mm)
    assert result.design[3] == float(lower.arm_length_mm) == float(upper.arm_length_mm)
    assert np.all(result.design >= np.array([float(v) for v in lower]))
    assert np.all(result.design <= np.array([float(v) for v in upper]))
