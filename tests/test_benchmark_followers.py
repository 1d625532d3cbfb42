"""The per-follower benchmarks' bookkeeping (benchmarks/extrema_samples.py, benchmarks/follower_sweep.py)
and their tables in the docs (docs/gen_tables.py): what is picked, how errors and goals are judged."""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # benchmarks/ is not installed

from benchmarks import extrema_samples, follower_sweep  # noqa: E402


def _gen_tables():
    spec = importlib.util.spec_from_file_location("gen_tables", ROOT / "docs" / "gen_tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_figures_pick_extrema_not_their_angles_or_inputs():
    report = {"samples": 360, "min_base_radius_mm": 24.1, "min_base_radius_deg": 315.0,
              "loads": {"force_N": {"max": 68.4, "max_deg": 120.0, "min": 1.0, "min_deg": 3.0},
                        "contact": {"min_force_N": 2.0, "lost": False}},
              "evaluated": {"pressure_angle_deg": {"max_abs": 28.3}, "face": {"contact_max_mm": 9.0}},
              "rpm": 300.0, "bad": {"max": math.inf}}
    assert extrema_samples.figures(report) == {
        "min_base_radius_mm": 24.1, "loads.force_N.max": 68.4, "loads.force_N.min": 1.0,
        "loads.contact.min_force_N": 2.0, "evaluated.pressure_angle_deg.max_abs": 28.3,
        "evaluated.face.contact_max_mm": 9.0}


def test_errors_are_relative_except_near_zero():
    err = extrema_samples.errors({"a": 101.0, "b": 1e-12, "c": 5.0}, {"a": 100.0, "b": 0.0})
    assert err["a"] == abs(101.0 - 100.0) / 100.0 and err["b"] == 1e-12 and "c" not in err


def test_sweep_weightings_sum_to_one_and_span_the_ratio_range():
    alpha, gamma = follower_sweep.weightings(100)
    np.testing.assert_allclose(alpha + gamma, 1.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(gamma[[0, -1]] / alpha[[0, -1]], [1e-2, 1e2], rtol=1e-12)


def test_every_sweep_scene_is_a_built_in_scene_of_its_follower():
    import camjax

    for follower, (scene, baseline) in follower_sweep.SCENES.items():
        assert camjax.load_scene(scene).follower.type == follower
        assert importlib.util.find_spec(baseline) is not None


def test_speed_table_has_a_row_per_follower_and_shows_misses():
    gen = _gen_tables()
    followers = {"oscillating_flat": {"gradient_speedup": 1.5, "ga_speedup": 45.0, "ga_speedup_method": "camjax_ga",
                                      "gradient_accuracy_matched": False, "ga_accuracy_matched": True,
                                      "methods": {"camjax_gradient": {"iterations_max": 2000}}}}
    table = gen.follower_speed(followers)
    rows = [line for line in table.splitlines()[2:]]
    names = sorted(p.name for p in (ROOT / "camjax" / "followers").iterdir()
                   if (p / "follower.py").exists())
    assert [r.split("|")[1].strip().strip("`") for r in rows] == names
    row = next(r for r in rows if "`oscillating_flat`" in r)
    assert "1.5× (**miss**)" in row and "45.0× (pass)" in row and "2000" in row


def test_a_speed_up_without_matched_accuracy_is_a_miss():
    gen = _gen_tables()
    assert gen._ratio_cell(61.5, 20.0, matched=False) == "61.5× (**miss**: accuracy not matched)"
    assert gen._ratio_cell(61.5, 20.0, matched=True) == "61.5× (pass)"
    assert gen._ratio_cell(1.9, 2.0, at_least=False) == "1.9× (pass)"
