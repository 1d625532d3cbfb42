"""camjax.solvers.newton in pointwise mode: the interior-point solver converges (scaled KKT residual
within ``tol``) on every one-angle problem of each follower type's example scene, dwells included
(one vmapped program per type), and the condensed pointwise design is no worse than the gradient
solver's pointwise design."""

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


def _scene(name):
    scene = camjax.load_scene(followers.get(name).example_scene)
    return dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=SAMPLES))


@pytest.mark.slow
@pytest.mark.parametrize("name", followers.names())
def test_pointwise_converges_on_every_angle(name):
    """Every angle's one-angle problem reaches the stopping rule (KKT residual <= tol) well inside
    the iteration safeguard: a dwell's pressure-angle row has a kink in the offset where the barrier
    problem's minimizer sits, so its slack never equals the row there; the barrier parameter must
    fall all the same. The condensed design's objective is the gradient solver's or lower: both
    solve the same one-angle problems (degenerate ones may pick another point of the optimal set),
    the gradient solver to its own tolerance, so 1e-7 relative (the newton solve's barrier leaves
    ~1e-9) is the margin."""
    scene = _scene(name)
    problem = problem_from_scene(scene)
    alpha, gamma = scene.design.alpha, scene.design.gamma
    w = jax.tree.map(lambda x: x[0], weights_of([alpha], [gamma]))
    per = family_of(problem).per_angle(problem)
    res = jax.jit(jax.vmap(lambda q: newton.minimize(q, w)))(per)
    converged = np.asarray(res.converged)
    assert converged.shape == (SAMPLES,)
    assert converged.all(), (name, np.flatnonzero(~converged))
    assert float(np.max(np.asarray(res.kkt.error))) <= newton.DEFAULT_SETTINGS.tol
    assert int(np.max(np.asarray(res.iterations))) < newton.DEFAULT_SETTINGS.max_iterations // 2

    by_newton = solve(problem, (alpha, gamma), mode="pointwise", solver="newton")
    by_gradient = solve(problem, (alpha, gamma), mode="pointwise", solver="gradient")
    assert bool(by_newton.converged), name
    if bool(by_newton.feasible) and bool(by_gradient.feasible):
        assert float(by_newton.objective) <= float(by_gradient.objective) * (1.0 + 1e-7), name
