"""One solver interface: every registered solver and mode returns a Solution with a status;
the registry is the one list of names and needs no JAX."""

import dataclasses
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.results import Status
from camjax.solvers import base, ga, registry
from camjax.solvers import hybrid as hybrid_solver
from camjax.solvers.base import Solution, family_of, solve

REGISTRY_FILE = Path(base.__file__).with_name("registry.py")
SMALL_GA = ga.GASettings(population=16, generations=60)


def settings_of(solver):
    """A short GA run for the solvers that run the GA; the defaults for the others (a static
    argument of the compiled solve: the gradient solver's global solve of the grid problem is then
    one program for every test here that runs it)."""
    return base.Settings.of_solvers(ga=SMALL_GA) if solver in ("ga", "hybrid") else base.DEFAULT_SETTINGS


@pytest.fixture(scope="module")
def problem(default_scene):
    """The grid problem: the solvers are checked against references on the same grid."""
    return P.problem_from_scene(default_scene, extrema="grid")


@pytest.fixture(scope="module")
def coarse(default_scene):
    """A 24-angle grid: pointwise solves of every solver stay quick."""
    return P.problem_from_scene(default_scene, samples=24, extrema="grid")


@pytest.mark.parametrize("solver", [s if s == registry.DEFAULT_SOLVER else pytest.param(s, marks=pytest.mark.slow)
                                    for s in registry.SOLVERS])  # the quick loop: the default solver
def test_every_solver_returns_a_solution_near_the_exact_global_optimum(problem, solver):
    sol = solve(problem, (1.0, 1.0), solver=solver, settings=settings_of(solver))
    assert isinstance(sol, Solution) and sol.mode == "global" and sol.solver == solver
    w = weights_of(1.0, 1.0)
    exact = optimum.global_optimum(problem, w)  # bisection, independent of the solvers
    # the gradient solver reaches the bisection's optimum to 1e-6 mm (measured ~1e-10); the
    # interior point (newton, and the hybrid's polish) stops on its scaled KKT residual, which fixes
    # the objective to ~1e-10 relative but R_b, along which the objective is flat there (1e-6 mm
    # moves it 1.5e-10), only to ~1e-6 mm (measured 1.6e-7 and 1.2e-6): 1e-5 mm, and the objective
    # within 1e-9 of the optimum's; the short GA run gets within 0.5 mm of it (its mutation scale
    # at the end)
    tol = {"ga": 0.5, "gradient": 1e-6}.get(solver, 1e-5)
    assert abs(float(sol.design.base_radius_mm - exact.base_radius_mm)) < tol
    assert abs(float(sol.design.face_width_mm - exact.face_width_mm)) < tol
    if solver != "ga":
        best = float(family_of(problem).evaluate(problem, w, exact).objective)
        assert float(sol.objective) <= best * (1 + 1e-9), (float(sol.objective), best)
    assert bool(sol.feasible)
    # the GA has no stopping rule but its budget: feasible -> max_steps; gradient -> converged
    expected = Status.MAX_STEPS if solver == "ga" else Status.CONVERGED
    assert int(sol.status) == expected and sol.to_json(problem)["status"] == expected.name.lower()


@pytest.mark.slow
@pytest.mark.parametrize("solver", registry.SOLVERS)
def test_every_solver_in_pointwise_mode_matches_the_closed_form(coarse, solver):
    w = weights_of(1.0, 1.0)
    sol = solve(coarse, (1.0, 1.0), mode="pointwise", solver=solver, settings=settings_of(solver))
    closed = optimum.pointwise_optimum(coarse, w)  # closed form per angle (SPEC 5)
    # the design is the largest R_b over the angles; tolerance as in the global test
    tol = 0.5 if solver == "ga" else 1e-6
    assert abs(float(sol.base_radius_mm) - float(np.max(closed.base_radius_mm))) < tol
    assert sol.pointwise.base_radius_mm.shape == coarse.theta_deg.shape
    assert int(sol.status) in (Status.CONVERGED, Status.MAX_STEPS)


# the quick loop: the gradient and GA solvers; the hybrid (GA + polish) and newton (its own program) are slow
@pytest.mark.parametrize("solver", [s if s in ("gradient", "ga") else pytest.param(s, marks=pytest.mark.slow)
                                    for s in registry.SOLVERS])
def test_unreachable_bounds_give_status_infeasible(problem, solver):
    # R_b <= 20 mm while curvature and stress need >= 24.1 mm (the scene's min base radius)
    tight = P.with_bounds(problem, base_radius_mm=(5.0, 20.0))
    sol = solve(tight, (1.0, 1.0), solver=solver, settings=settings_of(solver))
    assert int(sol.status) == Status.INFEASIBLE and not bool(sol.feasible)
    assert sol.status_name == "infeasible" and "stress" in sol.violated(tight)


@pytest.mark.slow
def test_solve_batch_is_traceable_and_vmapped(problem):
    w = weights_of([1.0, 10.0], [1.0, 1.0])
    sol = base.solve_batch(problem, w, base.weighting_keys(0, 2))
    assert sol.batch_size == 2 and sol.status.dtype == np.int32
    # a larger alpha / gamma gives a smaller cam (SPEC 7's trade)
    assert float(sol[1].design.base_radius_mm) < float(sol[0].design.base_radius_mm)
    # pytree: the design leaves are the Design's named variables
    assert jax.tree.structure(sol.design) == jax.tree.structure(P.Design(0.0, 0.0))


def test_timings_are_filled_and_a_second_call_does_not_compile(problem):
    first = solve(problem, (2.0, 1.0), seed=3)
    again = solve(problem, (2.0, 1.0), seed=3)
    assert first.timings.run_s > 0 and again.timings.compile_s == 0.0
    assert float(first.objective) == float(again.objective)


def test_bad_choices_name_the_field():
    with pytest.raises(ValueError, match="mode: 'both' is not allowed; use global, pointwise"):
        registry.check_choice("mode", "both", registry.MODES)
    with pytest.raises(ValueError, match="alpha, gamma: a weighting with alpha = gamma = 0"):
        registry.check_weights([0.0], [0.0])
    with pytest.raises(TypeError, match="not the problem of a registered follower"):
        base.family_of((1.0, 2.0))


@pytest.mark.slow
def test_registry_imports_neither_jax_nor_numpy():
    # a fresh interpreter loads the module file on its own (the camjax package itself imports jax)
    code = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('registry', {str(REGISTRY_FILE)!r})\n"
        "m = importlib.util.module_from_spec(spec); spec.loader.exec_module(m)\n"
        "assert m.SOLVERS == ('gradient', 'ga', 'hybrid', 'newton'), m.SOLVERS\n"
        "print(sorted(k for k in ('jax', 'optax', 'numpy') if k in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_weighting_keys_do_not_depend_on_chunking():
    import jax

    from camjax.solvers.base import weighting_keys

    whole = jax.random.key_data(weighting_keys(7, 6))
    # a chunk starting at weighting 2 draws the same keys as rows 2..5 of the whole batch
    np.testing.assert_array_equal(jax.random.key_data(weighting_keys(7, 4, 2)), whole[2:])
    assert len({tuple(k) for k in np.asarray(whole)}) == 6  # distinct keys


def test_the_hybrids_ga_stage_shortens_only_the_default_ga():
    """hybrid.ga_stage: the GA's default settings run HybridSettings.ga_generations generations;
    GA settings of one's own, or ga_generations None, run as given; 0 generations are refused."""
    default = hybrid_solver.ga_stage(base.DEFAULT_SETTINGS)
    generations = hybrid_solver.DEFAULT_SETTINGS.ga_generations
    assert default == dataclasses.replace(ga.DEFAULT_SETTINGS, generations=generations)
    assert generations < ga.DEFAULT_SETTINGS.generations
    own = dataclasses.replace(ga.DEFAULT_SETTINGS, generations=300)
    assert hybrid_solver.ga_stage(base.Settings.of_solvers(ga=own)) == own
    assert hybrid_solver.ga_stage(base.Settings.of_solvers(ga=SMALL_GA)) == SMALL_GA
    whole = base.Settings.of_solvers(hybrid=hybrid_solver.HybridSettings(ga_generations=None))
    assert hybrid_solver.ga_stage(whole) == ga.DEFAULT_SETTINGS
    fifty = base.Settings.of_solvers(hybrid=hybrid_solver.HybridSettings(ga_generations=50))
    assert hybrid_solver.ga_stage(fifty).generations == 50
    with pytest.raises(ValueError, match="ga_generations: 0 must be >= 1"):
        hybrid_solver.HybridSettings(ga_generations=0)


@pytest.mark.slow
def test_the_hybrid_is_never_worse_than_the_ga_it_starts_from():
    """The oscillating flat face's example scene, alpha 1 and gamma from 1 to 50 (seed 0): at
    gamma 10 the gradient polish from the GA's best design stalled above it (objective 1.6027
    against the GA's 1.5571, measured before the hybrid kept the better of the two). The GA here
    runs the hybrid's GA stage (same keys, :func:`camjax.solvers.hybrid.ga_stage`'s settings), so the
    hybrid's answer is feasible wherever the GA's is and its objective no larger (to rounding:
    1e-12 relative)."""
    import jax.numpy as jnp

    from camjax.scene import load_scene

    problem = base.problem_from_scene(load_scene("oscillating-flat"))
    gammas = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0]
    weights = weights_of(jnp.ones(len(gammas)), jnp.asarray(gammas))
    keys = base.weighting_keys(0, len(gammas))
    stage = base.Settings.of_solvers(ga=hybrid_solver.ga_stage(base.DEFAULT_SETTINGS))
    found = base.solve_batch(problem, weights, keys, "global", "ga", stage)
    hybrid = base.solve_batch(problem, weights, keys, "global", "hybrid")
    assert np.all(np.asarray(found.feasible)) and np.all(np.asarray(hybrid.feasible))
    np.testing.assert_array_less(np.asarray(hybrid.objective), np.asarray(found.objective) * (1 + 1e-12))


@pytest.mark.slow
@pytest.mark.parametrize("mode", registry.MODES)
def test_every_solvers_search_hands_the_judgement_one_form(coarse, mode):
    """The judgement program (polish and evaluation) is shared by the solvers of a problem only if
    each search gives it arguments of one form: the design's tree, shapes and dtypes, int32
    iterations and a bool ``done`` (False for the GA's fixed budget). Each solver's search, traced
    for shapes alone (no compile), against the form :func:`solve` compiles the judgement for
    before any search has run."""
    w, keys = weights_of([1.0, 2.0], [1.0, 0.5]), base.weighting_keys(0, 2)
    expected = base._judge_specs(coarse, mode, 2)
    for solver in registry.SOLVERS:
        raw, done = jax.eval_shape(lambda p, w, k, s=solver: base.search_batch(p, w, k, mode, s, settings_of(s)),
                                   coarse, w, keys)
        got = (raw.design, raw.iterations, done)
        assert jax.tree.structure(got) == jax.tree.structure(expected), solver
        assert [(x.shape, x.dtype) for x in jax.tree.leaves(got)] == \
            [(x.shape, x.dtype) for x in jax.tree.leaves(expected)], solver


@pytest.mark.slow
def test_a_batch_searched_in_chunks_is_the_batch_searched_at_once(coarse):
    """search_batch in chunks (a lax.map of vmaps, the batch padded with its last weighting to equal
    chunks, cut back) gives each weighting what one vmap of the whole batch gives: 13 weightings in
    chunks of 5 (3 chunks of 5, 2 padded) and 13 at once, the same iterations and designs to 1e-12
    relative (the same steps; XLA's code for a vmap of 5 and of 13 may round differently). On the
    CPU solve_batch searches in chunks of SEARCH_CHUNK."""
    assert base.search_chunk(weights_of(np.ones(13), np.ones(13))) == (
        base.SEARCH_CHUNK if jax.default_backend() == "cpu" else 0)
    alpha = np.linspace(0.05, 1.0, 13)
    w = weights_of(alpha, 1.0 - alpha + 0.05)
    keys = base.weighting_keys(0, 13)
    args = (coarse, w, keys, "global", registry.DEFAULT_SOLVER, base.DEFAULT_SETTINGS)
    (chunked, done_c), (whole, done_w) = base.search_batch(*args, 5), base.search_batch(*args, 0)
    assert np.asarray(chunked.iterations).shape == (13,)
    np.testing.assert_array_equal(np.asarray(chunked.iterations), np.asarray(whole.iterations))
    np.testing.assert_array_equal(np.asarray(done_c), np.asarray(done_w))
    assert np.all(np.asarray(done_w))
    for got, want in zip(jax.tree.leaves(chunked.design), jax.tree.leaves(whole.design), strict=True):
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-12)
    assert len(set(np.asarray(whole.iterations).tolist())) > 1  # weightings of unequal paths
