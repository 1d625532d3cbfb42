"""solve / sweep API: reference figures, one compiled program for 100+ weightings, Pareto front, JSON."""

import json

import numpy as np
import pytest
from reference import numpy_reference_optimum

from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import base, hybrid
from camjax.solvers import sweep as S
from camjax.solvers.registry import DEFAULT_SOLVER


@pytest.fixture(scope="module")
def problem(default_scene):
    """The grid problem: the sweeps are checked against references on the same grid."""
    return P.problem_from_scene(default_scene, extrema="grid")


@pytest.fixture(scope="module")
def big_sweep(problem):
    """11 x 11 = 121 weightings, alpha and gamma from 0.01 to 100, global, the default solver, in the
    default chunks (on the CPU 13 of 10, the last padded: the program of any sweep of this problem)."""
    grid = np.logspace(-2, 2, 11)
    base.search_batch.clear_cache()
    base.judge_batch.clear_cache()
    result = S.sweep(problem, grid, grid, progress=False)
    return result


@pytest.mark.slow
def test_sweep_of_121_weightings_is_one_search_and_one_judgement(big_sweep):
    assert big_sweep.results.batch_size == 121
    assert (base.search_batch._cache_size(), base.judge_batch._cache_size()) == (1, 1)  # the search, its judgement
    assert bool(np.all(big_sweep.results.feasible))


def test_a_sweep_of_another_size_runs_the_same_programs_and_designs(problem, big_sweep):
    """6 of the 121 weightings swept alone (one chunk, padded from 6 to the default's size): no
    program compiled again, and each design equal to the big sweep's, to the bit (a weighting's
    lanes compute the same whatever the chunk holds)."""
    grid = np.logspace(-2, 2, 11)
    sizes = (base.search_batch._cache_size(), base.judge_batch._cache_size())
    small = S.sweep(problem, grid[[2, 5]], grid[[3, 7, 9]], progress=False)
    assert (base.search_batch._cache_size(), base.judge_batch._cache_size()) == sizes
    picked = [i * 11 + j for i in (2, 5) for j in (3, 7, 9)]
    for name in ("base_radius_mm", "face_width_mm", "objective"):
        np.testing.assert_array_equal(np.asarray(getattr(small.results, name)),
                                      np.asarray(getattr(big_sweep.results, name))[picked], err_msg=name)


def test_sweep_shows_the_size_stress_trade(problem, big_sweep):
    """Larger alpha / gamma -> smaller cam and higher peak stress (SPEC 7, the source's trade)."""
    r = big_sweep.results
    ratio = np.asarray(r.alpha) / np.asarray(r.gamma)
    order = np.argsort(ratio, kind="stable")
    size = np.asarray(r.base_radius_mm + r.face_width_mm)[order]
    stress = np.asarray(r.stress_max_MPa)[order]
    # the default solver (newton) stops on its scaled KKT residual (1e-9): an active stress row
    # may end inside its limit by up to ~2e-7 of it (measured 1.2e-4 MPa at 1230 MPa), so the
    # stress is monotone to 1e-6 of its size; the size to 1e-6 mm or to what the stopping rule
    # leaves free at the looser of two neighbouring weightings, whichever is larger (a size excess
    # ds costs alpha / (alpha + gamma) ds / N of the normalized objective, as the face width below;
    # measured 2.4e-6 mm at alpha / (alpha + gamma) = 1e-4, 3e-8 mm elsewhere)
    size_weight = (np.asarray(r.alpha) / (np.asarray(r.alpha) + np.asarray(r.gamma)))[order]
    free = np.maximum(1e-6, 1e-9 * float(problem.size_norm_mm) / size_weight)
    assert np.all(np.diff(size) <= np.maximum(free[:-1], free[1:]))
    assert np.all(np.diff(stress) >= -1e-6 * stress[1:])
    assert size[0] - size[-1] > 10.0 and stress[-1] > 5 * stress[0]
    # the face width is the same for every weighting: never below the lift's need (a limit: to
    # 1e-6 mm), and above it by 1e-6 mm or by what the stopping rule leaves free, whichever is
    # larger: an excess dw raises the normalized objective by alpha / (alpha + gamma) dw / N,
    # which newton's KKT tolerance holds to ~1e-9. Measured on two machines: 6.5e-6 mm at a
    # stress-dominated weighting (alpha / (alpha + gamma) = 1e-4: 1e-11 of objective) on one,
    # within 1e-6 mm everywhere on the other.
    excess = np.asarray(r.face_width_mm) - numpy_reference_optimum()[2]
    size_weight = np.asarray(r.alpha) / (np.asarray(r.alpha) + np.asarray(r.gamma))
    assert np.all(excess >= -1e-6)
    assert np.all(excess <= np.maximum(1e-6, 1e-9 * float(problem.size_norm_mm) / size_weight))


def test_sweep_matches_single_solves(problem, big_sweep):
    records = big_sweep.records()
    for k in (0, 60, 120):
        rec = records[k]
        one = S.solve(problem, rec["alpha"], rec["gamma"])
        assert one.to_json(problem)["base_radius_mm"] == pytest.approx(rec["base_radius_mm"], abs=1e-8)


def test_pareto_mask_against_brute_force():
    rng = np.random.default_rng(0)
    size, stress = rng.random(40), rng.random(40)
    feasible = rng.random(40) > 0.2
    mask = S.pareto_mask(size, stress, feasible)
    for i in range(40):
        dominated = any(feasible[j] and size[j] <= size[i] and stress[j] <= stress[i]
                        and (size[j] < size[i] or stress[j] < stress[i]) for j in range(40))
        assert mask[i] == (feasible[i] and not dominated)


def test_records_json_and_plot(big_sweep, tmp_path):
    data = big_sweep.to_json()
    text = json.dumps(data, allow_nan=False)
    rec = json.loads(text)["records"][0]
    for key in ("alpha", "gamma", "base_radius_mm", "face_width_mm", "stress_max_MPa", "objective", "feasible"):
        assert key in rec
    assert sum(r["pareto"] for r in data["records"]) >= 5
    path = tmp_path / "pareto.png"
    S.plot_pareto(big_sweep, path)
    assert path.stat().st_size > 10_000


@pytest.mark.slow
def test_reference_pointwise_design_json(problem):
    res = S.solve(problem, 1.0, 1.0, mode="pointwise")
    d = res.to_json(problem)
    assert d["mode"] == "pointwise" and d["solver"] == DEFAULT_SOLVER and d["feasible"] and d["converged"]
    ref = numpy_reference_optimum(1.0, 1.0)  # independent NumPy closed form (tests/reference.py)
    assert d["base_radius_mm"] == pytest.approx(ref[0], abs=1e-6) and d["base_radius_deg"] == ref[1]
    assert d["face_width_mm"] == pytest.approx(ref[2], abs=1e-6) and d["face_width_deg"] == ref[3]
    assert len(d["pointwise"]["base_radius_mm"]) == 360
    json.dumps(d, allow_nan=False)


@pytest.mark.slow
def test_chunking_does_not_change_results(problem):
    """GA keys come from the weighting's index: chunk sizes 2 and 3 give the same designs."""
    from camjax.solvers import ga

    small = ga.GASettings(population=12, generations=15)
    a = S.sweep(problem, [1.0, 2.0, 4.0], [1.0], solver="ga", chunk_size=3, ga_settings=small)
    b = S.sweep(problem, [1.0, 2.0, 4.0], [1.0], solver="ga", chunk_size=2, ga_settings=small, progress=False)
    np.testing.assert_array_equal(np.asarray(a.results.base_radius_mm), np.asarray(b.results.base_radius_mm))


@pytest.mark.slow
def test_hybrid_polishes_the_ga(problem):
    res = S.solve(problem, 10.0, 1.0, solver="hybrid")
    ref = optimum.global_optimum(problem, weights_of(10.0, 1.0))
    assert float(res.base_radius_mm) == pytest.approx(float(ref.base_radius_mm), abs=1e-6)
    # the GA stage's generations (hybrid.ga_stage: 100 under the default settings) + Newton steps
    assert bool(res.converged) and int(res.iterations) > hybrid.ga_stage(base.Settings()).generations


def test_infeasible_design_names_the_constraint(problem):
    # no face in the box is wide enough (10 mm against the 19.1 mm the lift needs at any R_b), while
    # R_b can meet the curvature and the stress: the answer names the face width alone (the
    # default solver, newton, ends such a problem on its least-violation restoration)
    tight = P.with_bounds(problem, face_width_mm=(5.0, 10.0))
    d = S.solve(tight, 1.0, 1.0).to_json(tight)
    assert d["feasible"] is False and d["violated"] == ["face_width"]
    assert d["constraint_violation"]["face_width_mm"] == pytest.approx(numpy_reference_optimum()[2] - 10.0, abs=1e-5)


def test_bad_weights_are_refused(problem):
    with pytest.raises(ValueError, match="nothing to minimize"):
        S.solve(problem, 0.0, 0.0)
    with pytest.raises(ValueError, match=">= 0"):
        S.sweep(problem, [-1.0], [1.0])
    with pytest.raises(ValueError, match="solver"):
        S.solve(problem, 1.0, 1.0, solver="annealing")
    assert S.weight_grid([1, 2], [3, 4, 5])[0].tolist() == [1, 1, 1, 2, 2, 2]


# ------------------------------------------------------------------------------------- CLI


@pytest.mark.slow
def test_cli_sweep_writes_pareto_json_and_png(tmp_path):
    from camjax import cli

    out = tmp_path / "sweep"
    assert cli.main(["sweep", "--alpha", "0.1,1,10", "--gamma", "1,2", "--out", str(out)]) == 0
    data = json.loads((out / "pareto.json").read_text())
    assert len(data["records"]) == 6
    assert [(r["alpha"], r["gamma"]) for r in data["records"][:2]] == [(0.1, 1.0), (0.1, 2.0)]
    assert (out / "pareto.png").stat().st_size > 10_000


@pytest.mark.parametrize("alpha,gamma,message", [
    ("1,abc", "1", "'abc' is not a number"),
    ("1,", "1", "is not a number"),
    ("-1", "1", "negative"),
    ("0,1", "0", "nothing to minimize"),
    ("1", "inf", "finite"),
])
def test_cli_sweep_bad_lists_exit_2_and_write_nothing(tmp_path, capsys, alpha, gamma, message):
    from camjax import cli

    out = tmp_path / "never"
    assert cli.main(["sweep", "--alpha", alpha, "--gamma", gamma, "--out", str(out)]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_cli_design_overrides_are_validated(tmp_path, capsys):
    from camjax import cli

    out = tmp_path / "never"
    assert cli.main(["design", "--out", str(out), "--alpha", "0", "--gamma", "0"]) == 2
    assert "nothing to minimize" in capsys.readouterr().err
    assert cli.main(["design", "--out", str(out), "--gamma", "-2"]) == 2
    assert not out.exists()


def _overlap(a, b) -> bool:
    return not (a[2] <= b[0] or a[0] >= b[2] or a[3] <= b[1] or a[1] >= b[3])


def test_place_labels_never_overlaps():
    rng = np.random.default_rng(0)
    anchors = rng.uniform(0, 300, size=(80, 2))  # crowded: many labels find no place
    sizes = [(40.0, 9.0)] * 80
    markers = [(x - 4, y - 4, x + 4, y + 4) for x, y in anchors]
    spots = S.place_labels(anchors, sizes, markers, bounds_px=(0, 0, 300, 300))
    boxes = [(x, y, x + 40.0, y + 9.0) for x, y in (s for s in spots if s is not None)]
    assert 10 < len(boxes) < 80
    for i, a in enumerate(boxes):
        assert 0 <= a[0] and a[2] <= 300 and 0 <= a[1] and a[3] <= 300
        assert not any(_overlap(a, m) for m in markers)
        assert not any(_overlap(a, b) for b in boxes[i + 1:])


def test_pareto_labels_do_not_overlap_when_drawn(big_sweep):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = S.plot_pareto(big_sweep)
    renderer = FigureCanvasAgg(fig).get_renderer()
    ax = fig.axes[0]
    labels = [t for t in ax.texts if "/" in t.get_text()]
    assert len(labels) >= 3
    # measured by the renderer (not the placement's own size estimate)
    boxes = [t.get_window_extent(renderer).extents for t in labels]
    for i, a in enumerate(boxes):
        assert not any(_overlap(a, b) for b in boxes[i + 1:]), labels[i].get_text()
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("(+n)" in t for t in legend) and any("non-dominated" in t for t in legend)
