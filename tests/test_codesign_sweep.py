"""``camjax sweep`` of a scene with designed laws: the laws co-designed with the geometry at every
weighting. Each sweep point against ``camjax design`` at that weighting (the same co-design and the
same written geometry), against the plain sweep of the best built-in combination at the same
weighting (co-design never loses to choosing), and the options it refuses (exit 2, one line naming
the option, nothing written)."""

from __future__ import annotations

import json

import pytest

from camjax.cli import main
from camjax.codesign import fixed_scene
from camjax.laws import LAWS
from camjax.pipeline import sweep_scene
from camjax.scene import builtin_scene_text, load_scene, with_samples
from camjax.synthesis.segments import builtin_measures, term_value

SAMPLES = 90  # the search grid and the design's (the built-in scene has 360)
ALPHAS, GAMMAS = (1.0, 3.0), (1.0,)  # 2 x 1 weightings


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """pareto.json of ``camjax sweep codesign`` over 2 x 1 weightings on 90 samples, and its folder."""
    out = tmp_path_factory.mktemp("codesign-sweep") / "out"
    assert main(["sweep", "codesign", "--samples", str(SAMPLES), "--alpha", ",".join(map(str, ALPHAS)),
                 "--gamma", ",".join(map(str, GAMMAS)), "--out", str(out)]) == 0
    return json.loads((out / "pareto.json").read_text()), out


@pytest.mark.slow
def test_the_sweep_writes_each_weightings_chosen_laws_and_no_starting_law_warning(swept, capsys):
    data, out = swept
    assert (out / "pareto.png").stat().st_size > 0
    assert data["codesign"]["laws"] == ["motion.segments[1]", "motion.segments[3]"]
    assert [(r["alpha"], r["gamma"]) for r in data["records"]] == [(a, g) for a in ALPHAS for g in GAMMAS]
    for rec in data["records"]:
        c = rec["codesign"]
        assert c["chosen"] in ("codesign", "best_builtin")
        tables = c["scene_segments"]
        assert c["laws"] == [t["law"] for t in tables]
        if c["chosen"] == "codesign":
            assert c["laws"] == ["bspline", "bspline"] and all(len(t["control"]) == 16 for t in tables)
        else:
            assert c["laws"] == c["best_builtin"]["law"]
        # the exact objective: the written geometry's plus the [synthesis] terms
        assert c["objective_exact"] == pytest.approx(rec["objective"] + c["law_objective"], rel=1e-15)
    assert "starting laws" not in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("index", [len(ALPHAS) * len(GAMMAS) - 1])
def test_each_point_is_camjax_designs_codesign_at_its_weighting(swept, tmp_path, index):
    """The point of weighting (alpha, gamma) is what ``camjax design --alpha --gamma`` writes for the
    scene: the same laws chosen, the same co-design objective, the same geometry. Both run the same
    search and the same [design] solve on the same grid, so they agree to rounding: 1e-12 relative
    (measured: bit for bit).

    The last weighting: the one whose co-design runs with the built-in laws' cache the earlier
    weightings filled and with another weighting than the scene's own, where the sweep's path
    differs from the command's (a weighting ignored, a cache entry that holds one weighting's
    figures, a row of another point would show here); the first weighting runs the command's path
    (an empty cache), and every row's weighting and order are the test above's."""
    rec = swept[0]["records"][index]
    out = tmp_path / "design"
    assert main(["design", "codesign", "--samples", str(SAMPLES), "--alpha", repr(rec["alpha"]),
                 "--gamma", repr(rec["gamma"]), "--out", str(out)]) == 0
    res = json.loads((out / "result.json").read_text())
    c, ref = rec["codesign"], res["synthesis"]["codesign"]
    assert c["chosen"] == ref["chosen"]
    assert c["objective"] == pytest.approx(ref["objective"], rel=1e-12)
    assert c["objective_exact"] == pytest.approx(ref["objective_exact"], rel=1e-12)
    assert c["best_builtin"]["law"] == ref["best_builtin"]["law"]
    assert c["best_builtin"]["objective"] == pytest.approx(ref["best_builtin"]["objective"], rel=1e-12)
    assert c["scene_segments"] == [s["scene_segment"] for s in res["synthesis"]["segments"]]
    for key in ("objective", "base_radius_mm", "face_width_mm"):
        assert rec[key] == pytest.approx(res["design"][key], rel=1e-12), key


@pytest.mark.slow
def test_no_point_loses_to_the_sweep_of_the_best_builtin_combination(swept):
    """At each weighting, the plain sweep of the scene with the best built-in combination's laws
    fixed (exact extrema, its own optimal geometry) plus those laws' [synthesis] terms (their exact
    figures) is no better than the co-design point's exact objective. And it is no better than the
    same combination on the search's grid either: every maximum over the angle refined off the grid
    is at least the grid's, so the exact optimum is at least the grid optimum (to the solver's
    convergence, 1e-6 relative)."""
    scene = with_samples(load_scene("codesign"), SAMPLES)
    weights = dict(scene.synthesis.objective)
    records = swept[0]["records"]
    for names in {tuple(r["codesign"]["best_builtin"]["law"]) for r in records}:
        tables = [{"kind": ds.kind, "angle_deg": ds.angle_deg, "lift_mm": ds.lift, "law": n}
                  for ds, n in zip(scene.motion.designed, names, strict=True)]
        fixed = fixed_scene(scene, [LAWS[n] for n in names], tables)
        law_terms = sum(w * term_value(t, builtin_measures(LAWS[n], ds.kind)[t])
                        for ds, n in zip(scene.motion.designed, names, strict=True) for t, w in weights.items())
        plain = sweep_scene(fixed, ALPHAS, GAMMAS, mode="global", solver="gradient").records()
        for rec, brec in zip(records, plain, strict=True):
            if tuple(rec["codesign"]["best_builtin"]["law"]) != names:
                continue
            assert (brec["alpha"], brec["gamma"]) == (rec["alpha"], rec["gamma"])
            builtin_exact = brec["objective"] + law_terms
            assert rec["codesign"]["objective_exact"] <= builtin_exact * (1 + 1e-9)
            assert builtin_exact >= rec["codesign"]["best_builtin"]["objective"] * (1 - 1e-6)


# ------------------------------------------------------------------------------ bad options


def _bad_scene(tmp_path, edit) -> str:
    text = builtin_scene_text("codesign").replace(*edit)
    assert edit[1] in text
    path = tmp_path / "bad.toml"
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("extra, named", [
    (["--mode", "pointwise"], "--mode = 'pointwise'"),
    (["--chunk-size", "4"], "--chunk-size = 4"),
    (["--backend", "sequential"], "--backend"),
    (["--workers", "2"], "--workers"),
    (["--block-size", "8"], "--block-size"),
    (["--resume"], "--resume"),
    ((("l2_jerk = 1e-6", "peak_force = 1.0"),), "dynamics"),
    ((('mode = "global"', 'mode = "pointwise"'),), "design.mode = 'pointwise'"),
])
def test_what_a_codesign_sweep_refuses_exits_2_naming_it_and_writes_nothing(tmp_path, capsys, extra, named):
    """A pointwise mode (from the option or the scene), the scale-out options, --chunk-size, and
    what the co-design refuses in the scene: one line naming it, exit 2, nothing written."""
    out = tmp_path / "out"
    scene = "codesign"
    if extra and isinstance(extra[0], tuple):
        scene, extra = _bad_scene(tmp_path, extra[0]), []
    assert main(["sweep", scene, "--alpha", "1", "--gamma", "1,2", "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("camjax sweep: error: ") and named in err, err
    assert not out.exists()
