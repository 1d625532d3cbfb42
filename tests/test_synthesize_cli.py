"""``camjax synthesize``: result.json, synthesis.csv and svaj.png of the built-in synthesis scene;
the designed law fed back as a ``law = "bspline"`` segment reproduces it; bad input exits 2 with
one line naming the field and writes nothing."""

from __future__ import annotations

import csv
import json
import tomllib

import numpy as np
import pytest

from camjax.cli import main
from camjax.laws import LAWS
from camjax.scene import builtin_scene_text, scene_from_dict
from camjax.synthesis.segments import builtin_measures


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("syn") / "out"
    assert main(["synthesize", "synthesis", "--out", str(out)]) == 0
    return out, json.loads((out / "result.json").read_text())


@pytest.mark.slow
def test_result_has_the_figures_and_beats_the_built_in_laws(run):
    out, res = run
    segs = res["synthesis"]["segments"]
    assert [s["segment"] for s in segs] == [1, 3] and (out / "svaj.png").stat().st_size > 10_000
    w = res["synthesis"]["objective"]
    for s in segs:
        assert s["status"] == "optimal"
        assert set(s) >= {"peak_velocity", "peak_accel", "peak_jerk", "l2_accel", "l2_jerk", "control", "knots"}
        assert s["objective"] == pytest.approx(sum(v * s[k] for k, v in w.items()), rel=1e-12)
        # the designed law is at least as good as every built-in law of its class (v = a = 0 at both
        # ends: the scene matches dwells), measured independently of the synthesis
        for name, law in LAWS.items():
            ends = law(np.asarray([0.0, 1.0]))
            if np.max(np.abs(np.asarray([ends[1], ends[2]]))) > 1e-9:
                continue
            m = builtin_measures(law, s["kind"])
            assert s["objective"] <= sum(v * m[k] for k, v in w.items()) * (1 + 1e-9), name
        # above the least peak |a| with a = 0 at the ends on any law (4) and near it
        assert 4.0 < s["peak_accel"] < 5.0


@pytest.mark.slow
def test_the_designed_law_fed_back_as_a_bspline_scene_reproduces_it(run):
    out, res = run
    data = tomllib.loads(builtin_scene_text("synthesis"))
    del data["synthesis"]
    for s in res["synthesis"]["segments"]:
        data["motion"]["segments"][s["segment"]] = s["scene_segment"]
    scene = scene_from_dict(data)
    assert not scene.motion.designed
    rows = list(csv.DictReader(open(out / "synthesis.csv")))
    for s in res["synthesis"]["segments"]:
        law = scene.motion.program.laws[s["segment"]]
        mine = [r for r in rows if int(r["segment"]) == s["segment"]]
        x = np.asarray([float(r["x"]) for r in mine])
        # the program plays a return's law backwards: q(x) = 1 - p(1 - x), q' = p'(1 - x), q'' = -p''(...)
        xs = x if s["kind"] == "rise" else 1.0 - x
        p = [np.asarray(v) for v in law(xs)]
        q = p if s["kind"] == "rise" else [1.0 - p[0], p[1], -p[2], p[3]]
        for k, col in enumerate("svaj"):
            want = np.asarray([float(r[col]) for r in mine])
            # 12 significant digits in the CSV; the jerk of a cubic jumps at knots, compare off them
            ok = np.ones_like(x, bool) if k < 3 else np.min(np.abs(x[:, None] - np.asarray(s["knot_vector"])[None, :]),
                                                           axis=1) > 1e-9
            np.testing.assert_allclose(q[k][ok], want[ok], rtol=1e-9, atol=1e-9 * max(1.0, np.abs(want).max()))


BAD = [
    ({"degree": 12}, "motion.segments[1].degree"),
    ({"control_count": 3}, "motion.segments[1].control_count"),
    ({"control_count": 6}, "motion.segments[1].control_count"),  # s, v, a at both ends fix all 6
    ({"degree": 2, "control_count": 4, "start": {"v": 0.0, "a": 0.0, "j": 1.0}}, "motion.segments[1].start.j"),
    ({"design": False}, "motion.segments[1].design"),
]


@pytest.mark.parametrize("change,field", BAD, ids=[b[1].rsplit(".", 1)[-1] + str(i) for i, b in enumerate(BAD)])
def test_bad_designed_segments_exit_2_naming_the_field(tmp_path, capsys, change, field):
    data = tomllib.loads(builtin_scene_text("synthesis"))
    data["motion"]["segments"][1].update(change)
    _check_refused(tmp_path, capsys, data, field)


@pytest.mark.slow
def test_an_unknown_objective_name_exits_2(tmp_path, capsys):
    data = tomllib.loads(builtin_scene_text("synthesis"))
    data["synthesis"]["objective"]["peak_snap"] = 1.0
    _check_refused(tmp_path, capsys, data, "synthesis.objective.peak_snap")


def _check_refused(tmp_path, capsys, data, field):
    from camjax.scene import SceneError

    with pytest.raises(SceneError) as err:
        scene_from_dict(data)
    assert err.value.field == field


def test_the_command_exits_2_with_one_line_and_writes_nothing(tmp_path, capsys):
    text = builtin_scene_text("synthesis").replace("peak_accel = 1.0", "peak_accel = 1.0, peak_snap = 2.0")
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    assert main(["synthesize", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "synthesis.objective.peak_snap" in err and "unknown key" in err
    assert not out.exists()


@pytest.mark.slow
def test_a_linear_law_between_dwells_takes_the_default_conditions(tmp_path):
    """Degree 1 with the default start/end conditions (v and a "match" the dwells): the
    acceleration rows of a piecewise-linear law are zero (dependent on nothing) and the velocity
    rows pin the first and last spans flat. Least peak |v| is then the lift spread evenly over the
    29 middle spans of 31: 31/29 (closed form), reached exactly by the LP (its rows are the
    derivative spline's control values)."""
    from camjax.synthesis.segments import synthesize_segments

    data = tomllib.loads(builtin_scene_text("synthesis"))
    data["motion"]["segments"][1].update({"degree": 1})
    data["motion"]["segments"][1].pop("start", None)
    data["motion"]["segments"][1].pop("end", None)
    data["synthesis"]["objective"] = {"peak_velocity": 1.0}
    scene = scene_from_dict(data)
    result = synthesize_segments(scene.motion.designed[:1], dict(scene.synthesis.objective),
                                 scene.synthesis.samples_per_span)[0]
    assert result.converged
    assert result.objective == pytest.approx(31 / 29, rel=1e-9)
