"""Gradient solver against the closed form (pointwise), the exact global reference and extremes."""

import dataclasses

import jax
import numpy as np
import pytest
from reference import numpy_reference_optimum

import camjax
from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import gradient as G

# Every weighting the issue names, extremes included.
WEIGHTINGS = [(1.0, 1.0), (10.0, 1.0), (1.0, 10.0), (0.0, 1.0), (1.0, 0.0), (1e-6, 1.0), (1e6, 1.0)]


@pytest.fixture(scope="module")
def problem(default_scene):
    """The grid problem: the solvers are checked against references on the same grid."""
    return P.problem_from_scene(default_scene, extrema="grid")


@pytest.fixture(scope="module")
def pointwise_all(problem):
    """Every weighting's pointwise solve, one compiled vmapped call."""
    a = np.array([w[0] for w in WEIGHTINGS])
    g = np.array([w[1] for w in WEIGHTINGS])
    return G.solve_sweep(problem, weights_of(a, g), "pointwise")


@pytest.mark.parametrize("i", range(len(WEIGHTINGS)))
def test_pointwise_matches_closed_form_at_every_angle(problem, pointwise_all, i):
    alpha, gamma = WEIGHTINGS[i]
    ref = optimum.pointwise_optimum(problem, weights_of(alpha, gamma))
    res = jax.tree.map(lambda x: x[i], pointwise_all)
    assert bool(np.all(res.converged)) and bool(np.all(res.feasible))
    np.testing.assert_allclose(np.asarray(res.design.base_radius_mm), np.asarray(ref.base_radius_mm),
                               rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.asarray(res.design.face_width_mm), np.asarray(ref.face_width_mm),
                               rtol=0, atol=1e-6)
    assert np.all(np.asarray(res.iterations) > 0)


@pytest.mark.slow
def test_global_matches_exact_reference(problem):
    a = np.array([w[0] for w in WEIGHTINGS])
    g = np.array([w[1] for w in WEIGHTINGS])
    res = G.solve_sweep(problem, weights_of(a, g), "global")
    for i, (alpha, gamma) in enumerate(WEIGHTINGS):
        ref = optimum.global_optimum(problem, weights_of(alpha, gamma))
        assert float(res.design.base_radius_mm[i]) == pytest.approx(float(ref.base_radius_mm), abs=1e-6)
        assert float(res.design.face_width_mm[i]) == pytest.approx(float(ref.face_width_mm), abs=1e-6)
        assert bool(res.converged[i]) and bool(res.feasible[i])
        assert float(res.objective[i]) == pytest.approx(
            float(P.objective(problem, weights_of(alpha, gamma), ref)), rel=1e-9)


def test_no_recompilation_on_second_call(problem):
    w = weights_of(2.0, 1.0)
    G.solve_global(problem, w)
    before = G.solve_global._cache_size()
    G.solve_global(problem, weights_of(3.0, 0.5))  # new values, same shapes: no retrace
    assert G.solve_global._cache_size() == before


def test_infeasible_bounds_reported_by_name_without_nan(problem):
    tight = P.with_bounds(problem, base_radius_mm=(5.0, 20.0), face_width_mm=(5.0, 10.0))
    res = G.solve_global(tight, weights_of(1.0, 1.0))
    assert not bool(res.feasible) and not bool(res.converged)
    assert all(np.all(np.isfinite(np.asarray(x))) for x in jax.tree.leaves(res))
    assert float(res.design.base_radius_mm) == pytest.approx(20.0)  # as close as the box allows
    assert float(res.design.face_width_mm) == pytest.approx(10.0)
    assert P.violated_constraints(tight, res.violation) == ["curvature", "stress", "face_width"]


@pytest.mark.slow
def test_single_angle_grid(default_scene):
    scene = dataclasses.replace(default_scene, motion=dataclasses.replace(default_scene.motion, samples=1))
    prob = P.problem_from_scene(scene, extrema="grid")  # the problem at the one angle itself
    assert prob.q_mm.shape == (1,)
    w = weights_of(1.0, 1.0)
    ref = optimum.pointwise_optimum(prob, w)
    for res in (G.solve_global(prob, w), G.solve_pointwise(prob, w)):
        assert np.asarray(res.design.base_radius_mm).ravel()[0] == pytest.approx(float(ref.base_radius_mm[0]),
                                                                                 abs=1e-6)
        assert bool(np.all(res.feasible))


@pytest.mark.slow
def test_float32_problem_runs(default_scene):
    """float32 trades digits for speed: still close to the float64 closed form (1e-3 mm)."""
    prob = P.problem_from_scene(default_scene, camjax.scene_arrays(default_scene, dtype=np.float32))
    res = G.solve_global(prob, weights_of(np.float32(1.0), np.float32(1.0)))
    assert res.design.base_radius_mm.dtype == np.float32
    assert float(res.design.base_radius_mm) == pytest.approx(numpy_reference_optimum()[0], abs=1e-3)


@pytest.mark.slow  # full suite only: the variant's own compile (1.2-1.4 s)
def test_plain_rprop_variant_agrees(problem):
    """secant=False is the plain iRprop- rule (camjax's own, not optax's): slower, same optimum."""
    w = weights_of(1.0, 1.0)
    plain = G.solve_global(problem, w, settings=G.GradientSettings(secant=False))
    fast = G.solve_global(problem, w)
    ref = optimum.global_optimum(problem, w)
    assert float(plain.design.base_radius_mm) == pytest.approx(float(ref.base_radius_mm), abs=1e-6)
    assert bool(plain.converged) and int(plain.iterations) > int(fast.iterations)


def test_transform_without_secant_is_irprop_minus():
    """secant=False is iRprop- as torch.optim.Rprop computes it. (optax 0.2.8's scale_by_rprop
    emits each update one step late, optax PR #1725, so it is not the reference here.)"""
    import jax.numpy as jnp

    tx = G.scale_by_secant_rprop(0.1, secant=False)
    update = jax.jit(tx.update)  # one compiled step per shape, not op by op
    x = jnp.zeros(1)
    state = tx.init(x)
    out = []
    for g in [1.0, 1.0, 1.0, -1.0, 1.0]:
        u, state = update(jnp.array([g]), state, x)
        out.append(float(u[0]))
    np.testing.assert_allclose(out, [-0.1, -0.12, -0.144, 0.0, -0.072], rtol=1e-14)

    # and against a NumPy iRprop- on a random gradient sequence
    rng = np.random.default_rng(0)
    step, prev = np.full(5, 0.1), np.zeros(5)
    x = jnp.zeros(5)
    state = tx.init(x)
    for _ in range(40):
        g = rng.normal(size=5) * (rng.random(5) > 0.2)
        flip = g * prev
        step = np.clip(np.where(flip > 0, step * 1.2, np.where(flip < 0, step * 0.5, step)), 1e-15, 0.25)
        expect = np.where(flip < 0, 0.0, -np.sign(g) * step)
        prev = np.where(flip < 0, 0.0, g)
        u, state = update(jnp.asarray(g), state, x)
        np.testing.assert_allclose(np.asarray(u), expect, rtol=1e-15, atol=0)
        x = x + u


@pytest.mark.slow  # full suite only: the variant's own compile (1.2-1.4 s)
def test_per_angle_multipliers_agree(problem):
    """aggregate_constraints=False (one multiplier per angle and constraint): same optimum."""
    w = weights_of(10.0, 1.0)
    res = G.solve_global(problem, w, settings=G.GradientSettings(aggregate_constraints=False))
    assert res.multipliers.face_width.shape == problem.q_mm.shape
    ref = optimum.global_optimum(problem, w)
    assert float(res.design.base_radius_mm) == pytest.approx(float(ref.base_radius_mm), abs=1e-6)
    assert float(res.design.face_width_mm) == pytest.approx(float(ref.face_width_mm), abs=1e-6)
    assert bool(res.converged)
