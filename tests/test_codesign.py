"""Co-design of the designed laws and the cam's geometry (``camjax design`` on a scene with [design]
and ``design = true`` segments): the affine kinematics against the program, the envelope gradient
against central differences, "co-design never loses to choosing" against the built-in laws each
with its own optimal geometry (re-evaluated through the program, not the search's affine map), and
the command end to end, its designed law fed back reproducing the design."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest
from codesign_fixtures import design_keeping_codesign
from test_codesign_sweep import SAMPLES as SWEEP_SAMPLES

from camjax.cli import main
from camjax.codesign import Codesign, codesign_outcome, fixed_scene
from camjax.codesign.builtin import fitted_coordinates
from camjax.codesign.kkt import nnls
from camjax.evaluate import scene_arrays
from camjax.laws import LAWS
from camjax.pipeline import design_report
from camjax.scene import builtin_scene_text, load_scene, scene_from_dict, with_samples
from camjax.scene.designed import law_from_control
from camjax.solvers.base import problem_from_scene, solve
from camjax.synthesis.problem import build_problem
from camjax.synthesis.segments import builtin_measures
from camjax.synthesis.solve import measures

SAMPLES = 120  # search grid of the roller case (the built-in scenes search on their 360)
# the flat case's grid: tests/test_codesign_sweep.py's, whose first weighting is the scene's own
# (alpha = gamma = 1), so `camjax design codesign --samples 90` here co-designs what that sweep's
# first point does, bit for bit: the same compiled programs (the co-design's pieces, the chosen
# laws' [design] solve and exact maxima), found in the compilation cache by whichever file runs
# second (in one process, in memory)
FLAT_SAMPLES = SWEEP_SAMPLES


def roller_data() -> dict:
    """The built-in roller scene with its rise and return designed (cubic, 12 control values, at
    rest at the dwells) and a stress weight, for the same small jerk term as the codesign scene."""
    data = tomllib.loads(builtin_scene_text("roller"))
    segs = data["motion"]["segments"]
    for i in (0, 2):
        segs[i] = {k: segs[i][k] for k in ("kind", "angle_deg", "lift_mm")} | {
            "law": "bspline", "degree": 3, "control_count": 12, "design": True}
    data["design"]["gamma"] = 0.5
    data["synthesis"] = {"objective": {"l2_jerk": 1e-6}}
    return data


# the built-in scene on its case's grid: the scene `camjax design codesign --samples 90` designs,
# so the command's co-design (flat_command) is the flat case's and shares its compiled programs
SCENES = {"flat": (lambda: with_samples(load_scene("codesign"), FLAT_SAMPLES), FLAT_SAMPLES),
          "roller": (lambda: scene_from_dict(roller_data(), "roller-codesign"), SAMPLES)}


@pytest.fixture(scope="module", params=sorted(SCENES))
def case(request):
    scene_of, samples = SCENES[request.param]
    scene = scene_of()
    return request.param, scene, Codesign(scene, samples)


@pytest.fixture(scope="module")
def flat_command(tmp_path_factory):
    """`camjax design codesign --samples 90` (its folder) and the co-design it computed on the way:
    the flat case's search (codesign_outcome of its Codesign computes the same), run once for the
    command's end-to-end test and "never loses to choosing"."""
    out = tmp_path_factory.mktemp("codesign") / "out"
    outcome, _ = design_keeping_codesign(["codesign", "--out", str(out), "--samples", str(FLAT_SAMPLES)])
    assert outcome.scene.motion.samples == FLAT_SAMPLES
    return out, outcome


# ------------------------------------------------------------------------------ quick


def test_nnls_matches_scipy():
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(3)
    for _ in range(20):
        A, b = rng.normal(size=(4, 9)), rng.normal(size=4)
        x = nnls(A, b)
        ref = optimize.nnls(A, b)[0]
        assert np.all(x >= 0.0)
        # the residual is unique (the solution need not be, with more columns than rows)
        assert np.linalg.norm(A @ x - b) == pytest.approx(np.linalg.norm(A @ ref - b), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("edit, field", [
    (("l2_jerk = 1e-6", "peak_force = 1.0"), "dynamics"),  # the train's force needs the train
    (('mode = "global"', 'mode = "pointwise"'), "design.mode"),
])
@pytest.mark.slow
def test_what_the_codesign_does_not_take_exits_2_naming_the_field(tmp_path, capsys, edit, field):
    text = builtin_scene_text("codesign").replace(*edit)
    assert edit[1] in text
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    assert main(["design", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err, err
    assert not out.exists()


# ------------------------------------------------------------------------------ slow


@pytest.mark.slow
def test_the_affine_kinematics_are_the_programs(case):
    # kinematics(z) = kin0 + J (z - z0) against the program built from the control values c(z):
    # the same de Boor evaluation, so equal to rounding (1e-12 of each row's scale)
    _, scene, cd = case
    z = cd.lin.z0 + 0.05 * np.random.default_rng(0).normal(size=cd.lin.free)
    laws = [law_from_control(ds, c)[0] for ds, c in zip(cd.designed, cd.lin.control(z), strict=True)]
    kin = scene_arrays(fixed_scene(scene, laws, [{}] * len(laws)), samples=cd.samples, extrema="grid").kin
    mine = np.asarray(cd.kinematics(z))
    for r, ref in enumerate((kin.s, kin.ds, kin.d2s, kin.d3s)):
        ref = np.asarray(ref)
        np.testing.assert_allclose(mine[r], ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))


@pytest.mark.slow
def test_the_envelope_gradient_matches_central_differences(case):
    # at the modified sine law fitted onto the B-splines (a feasible, generic point: the flat
    # face's face width and the roller's pressure angle (at two angles, balanced by the offset)
    # are active there). Central differences with h = 1e-5: truncation ~h^2 F''' ~ 1e-10
    # relative, and the inner solve repeats its optimum to ~1e-12; measured agreement 2e-10 to
    # 4e-10. 1e-6 leaves margin, while a missing multiplier (one angle of a tie) is off by ~30 %.
    _, _, cd = case
    z = fitted_coordinates(cd, ["modified_sine"] * len(cd.designed))
    f, inner = cd.value(z)
    assert np.isfinite(f) and inner.feasible
    g = cd.gradient(z, inner)
    fd = cd.gradient_fd(z, 1e-5)
    assert np.linalg.norm(g - fd) <= 1e-6 * np.linalg.norm(fd)


def _program_objective(cd, laws, law_terms: float) -> float:
    """F of fixed laws in the co-design's scene through the program (scene arrays on its grid, the
    registered solver)."""
    scene = cd.scene
    fixed = fixed_scene(scene, laws, [{}] * len(laws))
    problem = problem_from_scene(fixed, scene_arrays(fixed, samples=cd.samples, extrema="grid"))
    sol = solve(problem, (scene.design.alpha, scene.design.gamma))
    assert bool(sol.feasible)
    return float(sol.objective) + law_terms


@pytest.mark.slow
def test_codesign_never_loses_to_choosing(case, request):
    # the search on the module's Codesign of the scene (codesign_scene builds the same one): its
    # compiled inner solve and gradient are the ones the tests above ran, not traced and compiled
    # again; the flat scene's search is the command's (flat_command: the same scene and grid)
    name, scene, cd = case
    out = request.getfixturevalue("flat_command")[1] if name == "flat" else codesign_outcome(cd)
    weights = dict(scene.synthesis.objective)
    designed = scene.motion.designed
    # the co-designed laws, re-evaluated through the program: the search's F to 1e-8 (the same
    # solver on the same grid, a separate solve; the affine map equals the program to rounding).
    # Two solves agree to the solver's stopping rule, not to rounding: measured 4e-10 on one CPU and
    # 1.04e-9 on an AMD EPYC (the same code), so 1e-8; still 6 orders below the >= 1 % win below.
    laws = [law_from_control(ds, c)[0] for ds, c in zip(designed, out.controls, strict=True)]
    law_terms = sum(w * float(getattr(measures(build_problem(ds.basis(), ds.conditions, ()), c), n))
                    for ds, c in zip(designed, out.controls, strict=True) for n, w in weights.items())
    mine = _program_objective(cd, laws, law_terms)
    assert mine == pytest.approx(out.codesign_objective, rel=1e-8)
    # built-in laws (one for both segments, each with its own optimal geometry, exact law figures)
    best = out.best_builtin[1]
    for law in ("cycloidal", "poly_3_4_5", "modified_sine", "modified_trapezoid"):
        terms = sum(w * builtin_measures(LAWS[law], ds.kind)[n] for ds in designed for n, w in weights.items())
        assert _program_objective(cd, [LAWS[law]] * len(designed), terms) >= best * (1 - 1e-9), law
    combo = out.best_builtin[0]
    terms = sum(w * builtin_measures(LAWS[n_], ds.kind)[n] for ds, n_ in zip(designed, combo, strict=True)
                for n, w in weights.items())
    assert _program_objective(cd, [LAWS[n_] for n_ in combo], terms) == pytest.approx(best, rel=1e-9)
    # never loses; on both scenes it wins by more than 1 % (measured: flat 18 % on its 90 samples,
    # roller 6 %)
    assert out.chosen == "codesign" and out.objective == out.codesign_objective
    assert out.codesign_objective <= best * (1 - 0.01), (name, out.codesign_objective, best)


@pytest.mark.slow
def test_design_codesign_end_to_end_and_fed_back(flat_command):
    out = flat_command[0]
    res = json.loads((out / "result.json").read_text())
    assert (out / "synthesis.png").stat().st_size > 10_000
    rows = (out / "synthesis.csv").read_text().splitlines()
    assert rows[0] == "segment,x,s,v,a,j" and len(rows) == 1 + 2 * 401
    syn = res["synthesis"]
    c = syn["codesign"]
    assert set(c) >= {"objective", "objective_exact", "design_objective", "law_objective", "chosen",
                      "best_builtin", "iterations", "inner_solves"}
    assert c["chosen"] == "codesign" and c["objective"] <= c["best_builtin"]["objective"]
    assert c["design_objective"] == pytest.approx(res["design"]["objective"], rel=1e-15)
    segs = syn["segments"]
    assert [s["segment"] for s in segs] == [1, 3]
    for s in segs:
        assert set(s) >= {"peak_velocity", "peak_accel", "peak_jerk", "l2_accel", "l2_jerk", "control",
                          "knots", "best_builtin", "scene_segment", "status"}
    # the law terms are the segments' own figures times the weights
    w = syn["objective"]
    assert c["law_objective"] == pytest.approx(sum(v * s[k] for s in segs for k, v in w.items()), rel=1e-9)
    # the designed laws fed back as fixed B-spline segments: the same design to 1e-9
    data = tomllib.loads(builtin_scene_text("codesign"))
    del data["synthesis"]
    data["motion"]["samples"] = FLAT_SAMPLES
    for s in segs:
        data["motion"]["segments"][s["segment"]] = s["scene_segment"]
    scene = scene_from_dict(data)
    assert not scene.motion.designed
    again = design_report(scene)["design"]["objective"]
    assert again == pytest.approx(res["design"]["objective"], rel=1e-9)


def test_commands_that_do_not_design_laws_warn_that_they_run_the_starting_laws(capsys):
    """A scene with design = true segments: dynamics moves them by their starting laws and says so
    on stderr, naming the segments (nothing designed is silently replaced; camjax sweep co-designs
    them, tests/test_codesign_sweep.py)."""
    from camjax.cli.common import warn_starting_laws

    warn_starting_laws(load_scene("codesign"), "dynamics")
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "camjax dynamics: warning:" in err
    assert "motion.segments[1], motion.segments[3] have design = true" in err
    warn_starting_laws(load_scene("default"), "dynamics")  # nothing designed: nothing said
    assert capsys.readouterr().err == ""
