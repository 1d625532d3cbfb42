"""Robust design ([design] robust, camjax.robust.design): the design keeps each limit over the asked
fraction of its samples, measured on fresh samples of another seed by camjax robust's evaluator;
with zero tolerances it is the nominal design; the gradient solver, the GA and the interior-point
solver run it; bad keys exit 2 naming the key."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from scene_text import toml_of

from camjax.cli import main
from camjax.robust import design as rd
from camjax.scene import SceneError, builtin_scene_text, scene_from_dict
from camjax.solvers.base import problem_from_scene, solve

P, S = 0.99, 400  # the tests' robust set: 3 free variables, m = floor(0.01 x 401) - 3 = 1 sample may exceed a row


def robust_scene(probability=P, samples=S, solver="gradient", **tolerances):
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
    assert rd.rank_from_top(0.9995, 8000, 3) == 1  # the robust scene: (1 + 3) / 8001 <= 0.0005
    assert rd.rank_from_top(0.99, 400, 3) == 1
    assert rd.rank_from_top(0.9, 9, 1) == 0
    x = np.random.default_rng(0).normal(size=400)
    assert float(rd._order_statistic(x, 3)) == np.sort(x)[-4]


@pytest.mark.parametrize("entry, field", [
    ({"probability": 1.0, "samples": 400}, "design.robust.probability"),
    ({"probability": 0.0, "samples": 400}, "design.robust.probability"),
    ({"probability": 0.999, "samples": 400}, "design.robust.samples"),  # < d / (1 - p) - 1 = 2999
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


@pytest.mark.slow
def test_zero_tolerances_give_the_nominal_design():
    """Every spread 0: each sample is the nominal scene, the robust rows are the nominal rows, and
    the gradient solver takes the same path (to 1e-9 mm: the same operations, a sort of equal
    values in between)."""
    scene = robust_scene(samples=300, rpm={"sd": 0.0}, offset_mm={"sd": 0.0}, spring_N_per_m={"sd": 0.0},
                         profile_error_mm={"amplitude": 0.0, "harmonics": [3]})
    base = problem_from_scene(scene)
    nominal = solve(base, (1.0, 0.0))
    robust, _ = rd.solve_robust(rd.robust_problem(scene, base), (1.0, 0.0), mode="global",
                                solver="gradient", seed=0)
    for name in nominal.design._fields:
        assert float(getattr(robust.design, name)) == pytest.approx(float(getattr(nominal.design, name)),
                                                                    abs=1e-9), name
    assert bool(robust.feasible)


@pytest.fixture(scope="module")
def gradient_block():
    """The robust design block of the test scene (gradient solver), as camjax design writes it."""
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
def test_robust_design_keeps_the_probability_on_fresh_samples(gradient_block):
    """Each limit kept by the robust design on 20000 fresh samples (seed + 1) >= p - margin
    (3 sd: 0.99 - 0.0150), where the nominal optimum breaks the pressure angle in most samples; the
    robust design is larger, feasible, and its rows are <= 0."""
    _, out = gradient_block
    block = out["robust"]
    fresh = block["check"]["samples"]
    assert fresh == 20000 and block["check"]["seed"] == 1
    assert block["free_variables"] == 3 and block["samples_allowed_over"] == 1
    margin = _margin(P, S, 3, fresh)
    assert margin < 0.016
    robust, nominal = block["robust"], block["nominal"]
    for lim, kept in robust["probability_kept"]["limits"].items():
        assert kept >= P - margin, (lim, kept)
    assert nominal["probability_kept"]["limits"]["pressure_angle"] < 0.5
    assert robust["feasible"] and out["feasible"] and out["violated"] == []
    assert all(v <= 1e-6 for v in robust["robust_rows_mm"].values())
    assert nominal["robust_rows_mm"]["pressure_angle"] > 0  # the nominal optimum is not robust
    assert robust["size_mm"] > nominal["size_mm"]
    assert block["size_increase_percent"] == pytest.approx(
        100 * (robust["size_mm"] / nominal["size_mm"] - 1), rel=1e-12)
    assert out["base_radius_mm"] == robust["design"]["base_radius_mm"]


@pytest.mark.slow
def test_the_ga_runs_the_robust_problem(gradient_block):
    """The GA on the same robust set: a design that keeps every robust row (feasible) and is no
    smaller than the gradient solver's optimum (less 1e-6 mm), within 2 % of it (a GA's result)."""
    scene, out = gradient_block
    base = problem_from_scene(scene)
    problem = rd.robust_problem(scene, base)
    ga, _ = rd.solve_robust(problem, (1.0, 0.0), mode="global", solver="ga", seed=0)
    size = float(ga.evaluation.nominal.size_mm)
    best = out["robust"]["robust"]["size_mm"]
    assert bool(ga.feasible)
    assert best - 1e-6 <= size <= 1.02 * best


@pytest.mark.slow
def test_a_rocking_follower_with_the_interior_point_solver():
    """An oscillating roller (its example scene, rpm and the roller's radius toleranced) solved by
    the newton solver: converged, feasible, robust rows <= 0 on the full set, an objective no better
    than the nominal optimum's (the robust problem's feasible set is inside the nominal's), and the
    gradient solver's robust optimum on the same robust rows: the objective within 1e-7 relative
    (the solvers' accuracy target; each stops far tighter, newton on a scaled KKT residual of 1e-9,
    measured apart by 5e-10) and the base radius within 1e-6 mm (measured 2e-8 mm)."""
    from camjax import followers

    kind = followers.get("oscillating_roller")
    d = tomllib.loads(builtin_scene_text(kind.example_scene))
    d["motion"]["samples"] = 90
    d["motion"]["extrema"] = "grid"
    d["design"]["solver"] = "newton"
    d["design"]["robust"] = {"probability": 0.95, "samples": 100}
    d["tolerances"] = {"rpm": {"sd_percent": 3}, "roller_radius_mm": {"sd": 0.05}}
    try:
        scene = scene_from_dict(d, "rocker")
    except SceneError as exc:  # a coarser grid than the scene's shortest segment allows
        pytest.skip(str(exc))
    base = problem_from_scene(scene)
    weights = (scene.design.alpha, scene.design.gamma)
    nominal = solve(base, weights, solver="newton")
    problem = rd.robust_problem(scene, base)
    robust, _ = rd.solve_robust(problem, weights, mode="global", solver="newton", seed=0)
    assert robust.status_name == "converged"
    assert bool(robust.feasible), robust.violation
    assert all(float(v) <= 1e-6 for v in robust.evaluation.rows)
    assert float(robust.objective) >= float(nominal.objective) - 1e-9
    reference, _ = rd.solve_robust(problem, weights, mode="global", solver="gradient", seed=0)
    assert bool(reference.feasible)
    assert float(robust.objective) == pytest.approx(float(reference.objective), rel=1e-7)
    assert float(robust.design.base_radius_mm) == pytest.approx(float(reference.design.base_radius_mm), abs=1e-6)
