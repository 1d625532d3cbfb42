"""Robust design ([design] robust, camjax.robust.design): the design keeps each limit over the asked
fraction of its samples, measured on fresh samples of another seed by camjax robust's evaluator;
every follower type keeps each of its constraints on fresh samples and, with zero tolerances, gives
its nominal design; the interior-point solver (the default), the gradient solver and the GA run it;
bad keys exit 2 naming the key; camjax sweep refuses a robust [design]."""

from __future__ import annotations

import math
import tomllib
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scene_text import toml_of

from camjax import followers
from camjax.cli import main
from camjax.family import FEASIBILITY_TOL_MM, weights_of
from camjax.robust import design as rd
from camjax.scene import SceneError, builtin_scene_text, scene_from_dict
from camjax.solvers.base import family_of, problem_from_scene, solve

P, S = 0.99, 400  # the tests' robust set: 2 free variables, m = floor(0.01 x 401) - 2 = 2 samples may exceed a row


def robust_scene(probability=P, samples=S, solver="newton", **tolerances):
    """The built-in robust scene on a 72-sample grid (the check is the formulation, not the
    resolution) with its robust set replaced; ``tolerances`` replace the [tolerances] section."""
    d = tomllib.loads(builtin_scene_text("robust"))
    d["motion"]["samples"] = 72
    d["motion"]["extrema"] = "grid"
    d["design"]["robust"] = {"probability": probability, "samples": samples}
    d["design"]["solver"] = solver
    if tolerances:
        d["tolerances"] = tolerances
    return scene_from_dict(d, "robust-test")


def test_rank_and_order_statistic_against_numpy():
    """m = floor((1 - p)(S + 1)) - d, and the row is the (m + 1)-th largest (np.sort)."""
    assert rd.rank_from_top(0.999, 2000, 1) == 1  # (1 + 1) / 2001 <= 0.001
    assert rd.rank_from_top(0.9998, 10000, 2) == 0  # the robust scene: (0 + 2) / 10001 <= 0.0002
    assert rd.rank_from_top(0.99, 400, 3) == 1
    assert rd.rank_from_top(0.99, 400, 2) == 2
    assert rd.rank_from_top(0.9, 9, 1) == 0
    x = np.random.default_rng(0).normal(size=400)
    assert float(rd._order_statistic(x, 3)) == np.sort(x)[-4]


@pytest.mark.parametrize("entry, field", [
    ({"probability": 1.0, "samples": 400}, "design.robust.probability"),
    ({"probability": 0.0, "samples": 400}, "design.robust.probability"),
    ({"probability": 0.999, "samples": 400}, "design.robust.samples"),  # < d / (1 - p) - 1 = 1999
    ({"probability": 0.99, "samples": 10**5}, "design.robust.samples"),
    ({"probability": 0.99, "samples": 400.5}, "design.robust.samples"),
    ({"probability": 0.99}, "design.robust.samples"),
    ({"probability": 0.99, "samples": 400, "sead": 1}, "design.robust.sead"),
])
def test_bad_robust_keys_exit_2_naming_the_key(tmp_path, capsys, entry, field):
    d = tomllib.loads(builtin_scene_text("robust"))
    d["design"]["robust"] = entry
    path = tmp_path / "bad.toml"
    path.write_text(toml_of(d))
    assert main(["design", str(path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert field in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_robust_needs_tolerances():
    d = tomllib.loads(builtin_scene_text("robust"))
    d.pop("tolerances")
    with pytest.raises(SceneError) as err:
        scene_from_dict(d, "bad")
    assert err.value.field == "design.robust" and "tolerances" in str(err.value)


def test_the_robust_key_round_trips_through_scene_overrides():
    """with_design (the CLI's overrides) re-reads [design] by the same rules: the robust set is kept,
    and an override that leaves too few samples for its free variables is refused."""
    from camjax.scene import with_design

    scene = robust_scene()
    assert with_design(scene, alpha=2.0).design.robust == scene.design.robust
    with pytest.raises(SceneError) as err:
        with_design(scene, robust={"probability": 0.999, "samples": 1000})
    assert err.value.field == "design.robust.samples"


@pytest.fixture(scope="module")
def robust_block():
    """The robust design block of the test scene (the interior-point solver), as camjax design writes it."""
    scene = robust_scene()
    return scene, rd.design_json(scene, problem_from_scene(scene))


def _margin(p: float, samples: int, free: int, fresh: int) -> float:
    """3 standard deviations of the fraction kept measured on ``fresh`` samples: the design's
    probability of breaking a limit is at most Beta(m + d, S - m - d + 1) distributed (the scenario
    approach with m samples discarded and d free variables; mean (m + d) / (S + 1) <= 1 - p),
    plus the binomial spread of the fresh count."""
    m = rd.rank_from_top(p, samples, free)
    a, b = m + free, samples - m - free + 1
    beta_var = a * b / ((a + b) ** 2 * (a + b + 1))
    return 3.0 * math.sqrt(beta_var + (1 - p) * p / fresh)


@pytest.mark.slow
def test_robust_design_keeps_the_probability_on_fresh_samples(robust_block):
    """Each limit kept by the robust design on 20000 fresh samples (seed + 1) >= p - margin
    (3 sd: 0.99 - 0.0150), where the nominal optimum, on its stress limit, breaks it in more than 5 %
    of them; the robust design is larger, feasible, and its rows are <= 0."""
    _, out = robust_block
    block = out["robust"]
    fresh = block["check"]["samples"]
    assert fresh == 20000 and block["check"]["seed"] == 1
    assert block["free_variables"] == 2 and block["samples_allowed_over"] == 2
    margin = _margin(P, S, 2, fresh)
    assert margin < 0.016
    robust, nominal = block["robust"], block["nominal"]
    for lim, kept in robust["probability_kept"]["limits"].items():
        assert kept >= P - margin, (lim, kept)
    assert nominal["probability_kept"]["limits"]["stress"] < 0.95
    assert robust["feasible"] and out["feasible"] and out["violated"] == []
    assert all(v <= 1e-6 for v in robust["robust_rows_mm"].values())
    assert nominal["robust_rows_mm"]["stress"] > 0  # the nominal optimum is not robust
    assert robust["size_mm"] > nominal["size_mm"]
    assert block["size_increase_percent"] == pytest.approx(
        100 * (robust["size_mm"] / nominal["size_mm"] - 1), rel=1e-12)
    assert out["base_radius_mm"] == robust["design"]["base_radius_mm"]


@pytest.mark.slow
def test_the_ga_runs_the_robust_problem(robust_block):
    """The GA on the same robust set: a design that keeps every robust row (feasible) and is no
    smaller than the interior-point solver's optimum (less 1e-6 mm), within 2 % of it (a GA's result)."""
    scene, out = robust_block
    base = problem_from_scene(scene)
    problem = rd.robust_problem(scene, base)
    ga, _ = rd.solve_robust(problem, (1.0, 0.0), mode="global", solver="ga", seed=0)
    size = float(ga.evaluation.nominal.size_mm)
    best = out["robust"]["robust"]["size_mm"]
    assert bool(ga.feasible)
    assert best - 1e-6 <= size <= 1.02 * best


def test_sweep_refuses_a_robust_design(tmp_path, capsys):
    """camjax sweep solves the nominal problem per weighting: a scene with [design] robust exits 2
    naming design.robust and writes nothing (camjax design solves it, one weighting at a time)."""
    out = tmp_path / "o"
    assert main(["sweep", "robust", "--alpha", "1", "--gamma", "0,1", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "design.robust" in err and "camjax design" in err and "Traceback" not in err
    assert not out.exists()


PF, SF = 0.9, 100  # every follower's robust set: m = floor(0.1 x 101) - d = 10 - d samples may exceed a row
# (the solves' rows grow with SF: 100 samples, not 200, halve the file's robust solves; the fresh sets
# below are doubled to keep their count, and the margin grows from 0.069 to 0.093)
FRESH_SETS = 10  # fresh sets of SF samples each (seeds 1..10): the same shapes, so nothing compiles again
FOLLOWER_SPREAD_MM = 0.05  # sd of every toleranced design variable but the base radius


def follower_scene(name: str, scale: float = 1.0):
    """The follower type's example scene on a 72-sample grid, size only (gamma = 0: the optimum on
    a limit), the interior-point solver, the robust set (PF, SF), and its tolerances times ``scale``: the
    speed (3 %), every design variable but the base radius (0.05 mm) and, for a translating
    follower, a form error (0.01 mm, harmonics 2 and 3)."""
    kind = followers.get(name)
    d = tomllib.loads(builtin_scene_text(kind.example_scene))
    d["motion"]["samples"] = 72
    d["motion"]["extrema"] = "grid"
    d["design"].update(solver="newton", gamma=0.0, robust={"probability": PF, "samples": SF})
    tol = {"rpm": {"sd_percent": 3.0 * scale}}
    tol.update({v: {"sd": FOLLOWER_SPREAD_MM * scale} for v in kind.variables if v != "base_radius_mm"})
    if not kind.rocking:
        tol["profile_error_mm"] = {"amplitude": 0.01 * scale, "harmonics": [2, 3]}
    d["tolerances"] = tol
    return scene_from_dict(d, f"robust-{name}")


@pytest.fixture(scope="module")
def follower_designs():
    """Each follower type's :func:`follower_scene`, its problem and weights, the nominal optimum
    and the robust problem around it with its robust design (the interior-point solver: ~30 Newton
    steps where the gradient solver takes 1,000-2,000, 8 s against 20 s for the oscillating curved
    face's robust solve on 2 cores), solved once per type for the tests of this module (``get(name)``)."""
    solved = {}

    def get(name: str) -> SimpleNamespace:
        if name not in solved:
            scene = follower_scene(name)
            base = problem_from_scene(scene)
            w = (scene.design.alpha, scene.design.gamma)
            nominal = solve(base, w, solver="newton")
            problem = rd.robust_problem(scene, base, origin=nominal.design)
            robust, _ = rd.solve_robust(problem, w, mode="global", solver="newton", seed=0)
            solved[name] = SimpleNamespace(scene=scene, base=base, weights=w, nominal=nominal,
                                           problem=problem, robust=robust)
        return solved[name]

    return get


@pytest.mark.slow
def test_a_rocking_follower_with_the_gradient_solver(follower_designs):
    """An oscillating roller (its example scene with the robust set and tolerances of
    :func:`follower_scene`: rpm, the roller's radius, the pivot distance and the arm length
    toleranced) solved by the gradient solver on the robust problem the interior-point solver solved
    in :func:`follower_designs` (the design that
    test_every_follower_type_keeps_each_constraint_on_fresh_samples checks on fresh samples):
    converged, feasible, robust rows <= 0 on the full set, an objective no better than the nominal
    optimum's (the robust problem's feasible set is inside the nominal's), and the two robust
    optima agree: the objective within 1e-7 relative (the solvers' accuracy target; each stops far
    tighter, newton on a scaled KKT residual of 1e-9; measured 1.2e-9 apart) and the base radius
    within 1e-6 mm (6e-8 mm apart when the gradient solver's problem was the shared one). Sharing the problem and design
    with the follower test compiles one robust solve here (the gradient solver's), not three."""
    d = follower_designs("oscillating_roller")
    robust, _ = rd.solve_robust(d.problem, d.weights, mode="global", solver="gradient", seed=0)
    assert robust.status_name == "converged"
    assert bool(robust.feasible), robust.violation
    assert all(float(v) <= 1e-6 for v in robust.evaluation.rows)
    assert float(robust.objective) >= float(d.nominal.objective) - 1e-9
    reference = d.robust
    assert bool(reference.feasible)
    assert float(robust.objective) == pytest.approx(float(reference.objective), rel=1e-7)
    assert float(robust.design.base_radius_mm) == pytest.approx(float(reference.design.base_radius_mm), abs=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize("name", followers.names())
def test_every_follower_type_keeps_each_constraint_on_fresh_samples(name, follower_designs):
    """Every registered follower type through its family protocol.

    - The robust design is feasible and no smaller than the nominal optimum, and each of its
      constraint rows is kept on 10 x 100 fresh samples (seeds 1..10, the same models) in at least
      p minus the margin of :func:`_margin` (3 sd of the scenario approach's Beta and of the fresh
      count's binomial: 0.9 - 0.093).
    - With every spread 0, each sample is the nominal scene: the robust rows equal the nominal's
      maxima over the grid (1e-9 mm: the same models, built batched) at the nominal optimum and at
      the zero-spread robust optimum, both designs keep them, and the robust optimum's objective is
      the nominal optimum's to 1e-6 relative: the interior point stops when every row's scaled
      complementarity is <= 1e-9, so its duality gap, their sum, grows with the rows; a round's 16
      identical samples carry 16 copies of each nominal row (measured 1.4e-7 for the roller,
      1.1e-7 for the oscillating curved face, whose size-only optimum is also a ridge, R_b + R_c).
    """
    d = follower_designs(name)
    scene, base, w, nominal, robust = d.scene, d.base, d.weights, d.nominal, d.robust
    zero = follower_scene(name, 0.0)
    fam = family_of(base)
    flat_problem = rd.robust_problem(zero, base, origin=nominal.design)
    same, _ = rd.solve_robust(flat_problem, w, mode="global", solver="newton", seed=0)
    assert float(same.objective) == pytest.approx(float(nominal.objective), rel=1e-6)
    for design in (nominal.design, same.design):
        # the robust rows (rd.constraint_maxima, in the evaluation the solve judges its result by) and
        # the family's own maxima over the nominal grid (fam.constraint_maxima, in the program a round
        # judges the samples by): both compiled by solve_robust for this problem's form, not again
        rows = rd._evaluate(flat_problem, weights_of(*w), jax.tree.map(jnp.asarray, design)).rows
        ref = dict(zip(rd._row_names(flat_problem), np.asarray(rd._maxima(flat_problem, design)[0]),
                       strict=True))
        for k in fam.Constraints._fields:
            assert float(getattr(rows, k)) == pytest.approx(float(ref[k]), abs=1e-9), k
            assert float(getattr(rows, k)) <= FEASIBILITY_TOL_MM, k
    assert bool(same.feasible) and bool(robust.feasible), robust.violation
    assert float(robust.evaluation.nominal.size_mm) >= float(nominal.evaluation.size_mm) - 1e-6
    free = rd.free_variables(scene.design.variables)
    fresh = FRESH_SETS * SF
    margin = _margin(PF, SF, free, fresh)
    assert margin < 0.095
    over: dict[str, int] = {}
    for seed in range(1, FRESH_SETS + 1):
        # each sample's max over the grid of each row (rd.sample_maxima, stacked by rd._maxima: the
        # program the solve's rounds compiled for a problem of this form, origin included)
        sampled = rd.robust_problem(scene, base, seed=seed, origin=nominal.design)
        g = np.asarray(rd._maxima(sampled, robust.design)[1])
        for row, gk in zip(rd._row_names(sampled), g, strict=True):
            over[row] = over.get(row, 0) + int(np.sum(gk > FEASIBILITY_TOL_MM))
    for row, count in over.items():
        assert 1.0 - count / fresh >= PF - margin, (row, count, fresh)
