"""The follower train's residual vibration as a co-design term (``camjax design`` on a scene with
[design], designed segments, [dynamics] and ``residual_vibration`` in [synthesis]): its value
against the law synthesis' (camjax.synthesis: the synthesis problem's own measures), its gradient
in z against central differences of that independent value and of the whole co-design objective,
the issue's residual check against the best built-in combination (each with its own geometry,
its residual recomputed on the train by the built-in laws' own quadrature), "never loses to
choosing" with the term, and the report (the peak terms: tests/test_codesign_peaks.py)."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from camjax.codesign import Codesign, codesign_scene
from camjax.codesign.builtin import fitted_coordinates
from camjax.codesign.problem import train_quadratics
from camjax.dynamics.context import synthesis_train
from camjax.laws import LAWS
from camjax.laws.bspline import evaluate_derivatives
from camjax.scene import builtin_scene_text, scene_from_dict
from camjax.scene.designed import starting_control
from camjax.synthesis.linear import law_quadratics, linear_kinematics
from camjax.synthesis.problem import build_problem
from camjax.synthesis.segments import builtin_measures, builtin_q
from camjax.synthesis.solve import measures, objective_value, weights_vector
from camjax.synthesis.vibration import builtin_train_measures, residual_maps, train_terms

SAMPLES = 120
# a 60 Hz load train (k23 = I3 (2 pi 60)^2, zeta = 0.05) at the scene's 240 rpm: r = 23.6 on the rise
DYNAMICS = {"follower": "translating", "I3": 0.5, "c3": 18.85, "k23": 71061.3}


def vib_data(band: float = 0.0, count: int = 1, **objective) -> dict:
    """The built-in codesign scene made small (cubic laws of 8 control values, 120 samples) with the
    follower train and ``objective`` as [synthesis]'s terms."""
    data = tomllib.loads(builtin_scene_text("codesign"))
    for seg in data["motion"]["segments"]:
        if seg.get("design"):
            seg["control_count"] = 8
    data["motion"]["samples"] = SAMPLES
    data["dynamics"] = dict(DYNAMICS)
    data["synthesis"] = {"objective": objective}
    if band > 0.0:
        data["synthesis"].update(speed_band=band, speed_count=count)
    return data


def synthesis_value(scene, controls) -> float:
    """The [synthesis] objective of normalized control values by the law synthesis (its problem
    with the train's matrices, its measures and objective value: residual_vibration squared)."""
    train = synthesis_train(scene)
    weights = dict(scene.synthesis.objective)
    total = 0.0
    for ds, c in zip(scene.motion.designed, controls, strict=True):
        basis = ds.basis()
        problem = build_problem(basis, ds.conditions, tuple(weights), train=train_terms(basis, train, ds, 8))
        total += float(objective_value(problem, weights_vector(problem, weights), measures(problem, c)))
    return total


def quadratic(scene):
    """(lin, P, q, const) of the co-design's law terms, built as camjax.codesign.problem does."""
    designed = scene.motion.designed
    train = synthesis_train(scene)
    w = dict(scene.synthesis.objective)
    lin = linear_kinematics(scene.motion.program, designed, SAMPLES, [starting_control(ds) for ds in designed])
    P, q, c = law_quadratics(lin, designed, {"l2_jerk": w["l2_jerk"]})
    Pr, qr, cr = train_quadratics(lin, [residual_maps(ds.basis(), train, ds)[1] for ds in designed],
                                  w["residual_vibration"])
    return lin, P + Pr, q + qr, c + cr


# ------------------------------------------------------------------------------ quick

BANDS = [(0.0, 1), (0.1, 5)]


@pytest.mark.parametrize("band, count", BANDS)
def test_the_residual_term_equals_the_law_synthesis_value(band, count):
    # at random laws meeting the conditions: the co-design's quadratic in z against the synthesis
    # problem's measures of c(z) (a separate construction from the same maps); both are exact
    # quadratics of the same control values, so they agree to rounding: 1e-9 relative
    scene = scene_from_dict(vib_data(band, count, l2_jerk=1e-6, residual_vibration=1e3), "vib")
    lin, P, q, c = quadratic(scene)
    rng = np.random.default_rng(7)
    for _ in range(3):
        z = lin.z0 + 0.3 * rng.normal(size=lin.free)
        mine = 0.5 * z @ P @ z + q @ z + c
        assert mine == pytest.approx(synthesis_value(scene, lin.control(z)), rel=1e-9)


@pytest.mark.slow
def test_the_residual_of_a_bspline_agrees_with_the_built_in_laws_quadrature():
    # the same B-spline played as a "built-in" law through builtin_train_measures (a uniform grid
    # of 64 subintervals per unit, the law evaluated by de Boor, not the basis matrices): cubic of
    # 11 control values has its knots at multiples of 1/8, on that grid, so both quadratures are
    # exact to ~1e-15 on each piece; 1e-9 relative on the amplitude leaves room for rounding.
    data = vib_data(0.1, 5, l2_jerk=1e-6, residual_vibration=1e3)
    data["motion"]["segments"][1]["control_count"] = 11
    scene = scene_from_dict(data, "vib")
    ds = scene.motion.designed[0]
    train = synthesis_train(scene)._replace(spring_rate=None)
    c = starting_control(ds)
    basis = ds.basis()
    rows, Q = residual_maps(basis, train, ds)

    def q_of(x):
        return tuple(np.asarray(v) for v in evaluate_derivatives(basis.knots, c, ds.degree, x, 3))

    ref = builtin_train_measures(q_of, train, ds)
    assert np.sqrt(c @ Q @ c) == pytest.approx(ref["residual_vibration"], rel=1e-9)
    np.testing.assert_allclose(np.linalg.norm(rows @ c, axis=1), ref["residual_vibration_by_speed"], rtol=1e-9)


@pytest.mark.parametrize("band, count", BANDS)
def test_the_residual_terms_gradient_matches_central_differences(band, count):
    # the co-design's gradient of its law terms, P z + q, against central differences of the law
    # synthesis' value of c(z) (h = 1e-3; the value is an exact quadratic, so the differences are
    # exact but for rounding, ~1e-16 |F| / h ~ 1e-13 relative): 1e-8 relative (2-norm)
    scene = scene_from_dict(vib_data(band, count, l2_jerk=1e-6, residual_vibration=1e3), "vib")
    lin, P, q, _ = quadratic(scene)
    z = lin.z0 + 0.2 * np.random.default_rng(3).normal(size=lin.free)
    h = 1e-3
    fd = np.zeros(lin.free)
    for i in range(lin.free):
        e = np.zeros(lin.free)
        e[i] = h
        fd[i] = (synthesis_value(scene, lin.control(z + e)) - synthesis_value(scene, lin.control(z - e))) / (2 * h)
    assert np.linalg.norm(P @ z + q - fd) <= 1e-8 * np.linalg.norm(fd)


# ------------------------------------------------------------------------------ slow


@pytest.fixture(scope="module")
def heavy():
    """The scene with a heavy residual weight (1e6 per (A/h)^2: the cam's objective is ~0.5) and its
    co-design (the joint program's: quadratic law terms alone)."""
    scene = scene_from_dict(vib_data(l2_jerk=1e-6, residual_vibration=1e6), "vib")
    outcome = codesign_scene(scene, SAMPLES)
    assert outcome.method == "joint"
    return scene, outcome


@pytest.mark.slow
def test_the_codesign_law_value_and_gradient_with_the_residual():
    # Codesign's own law value (the quadratic it adds to F) against the synthesis' value (1e-9, as
    # above) over a band, and its envelope gradient of the whole F against central differences of F
    # at the modified sine fit (h = 1e-5, as tests/test_codesign.py: truncation ~1e-10, the inner
    # solve repeats to ~1e-12; 1e-6 relative).
    scene = scene_from_dict(vib_data(0.1, 5, l2_jerk=1e-6, residual_vibration=1e3), "vib")
    cd = Codesign(scene, SAMPLES)
    z = fitted_coordinates(cd, ["modified_sine"] * len(cd.designed))
    assert cd.law_value(z) == pytest.approx(synthesis_value(scene, cd.lin.control(z)), rel=1e-9)
    f, inner = cd.value(z)
    assert np.isfinite(f) and inner.feasible
    g = cd.gradient(z, inner)
    fd = cd.gradient_fd(z, 1e-5)
    assert np.linalg.norm(g - fd) <= 1e-6 * np.linalg.norm(fd)


@pytest.mark.slow
def test_a_heavy_residual_weight_beats_the_best_built_in_combination_tenfold(heavy):
    # the issue's check in the co-design: at the design speed the co-designed laws' residual is at
    # least 10x below that of the best built-in combination (each with its own optimal geometry),
    # both measured on the train by builtin_train_measures (the designed B-spline played as a law)
    scene, out = heavy
    assert out.chosen == "codesign" and out.best_builtin is not None
    train = synthesis_train(scene)._replace(spring_rate=None)
    for ds, c, name in zip(scene.motion.designed, out.controls, out.best_builtin[0], strict=True):
        basis = ds.basis()

        def q_of(x, basis=basis, c=c, ds=ds):
            return tuple(np.asarray(v) for v in evaluate_derivatives(basis.knots, c, ds.degree, x, 3))

        mine = builtin_train_measures(q_of, train, ds)["residual_vibration"]
        theirs = builtin_train_measures(lambda x, n=name, k=ds.kind: builtin_q(LAWS[n], k, x), train,
                                        ds)["residual_vibration"]
        assert mine <= theirs / 10.0, (ds.index, mine, theirs, name)


@pytest.mark.slow
def test_codesign_never_loses_to_choosing_with_the_residual(heavy):
    # F of the co-designed laws <= F of the best built-in combination (with its own geometry and
    # its residual from the built-in law itself); and that combination's law terms are its exact
    # figures on the train (l2_jerk by builtin_measures, the residual by builtin_train_measures)
    scene, out = heavy
    assert out.objective == out.codesign_objective <= out.best_builtin[1]
    w = dict(scene.synthesis.objective)
    train = synthesis_train(scene)._replace(spring_rate=None)
    law = 0.0
    for ds, name in zip(scene.motion.designed, out.best_builtin[0], strict=True):
        res = builtin_train_measures(lambda x, n=name, k=ds.kind: builtin_q(LAWS[n], k, x), train, ds)
        law += w["residual_vibration"] * res["residual_vibration"] ** 2
        law += w["l2_jerk"] * builtin_measures(LAWS[name], ds.kind)["l2_jerk"]
    assert out.best_builtin[1] > law  # plus the geometry's objective (> 0)


@pytest.mark.slow
def test_design_reports_the_residual_per_segment(heavy):
    # result.json's synthesis block of `camjax design` (camjax.output.synthesis.codesign_report, what
    # the command writes) of the heavy co-design, without the command's design run, figures and
    # files: the command's writing of this block is tests/test_codesign.py's end-to-end test (the
    # same joint co-design, no train); the design's objective enters objective_exact alone,
    # not checked here
    from camjax.output.synthesis import codesign_report

    scene, outcome = heavy
    syn = json.loads(json.dumps(codesign_report(scene, outcome, {"design": {"objective": 0.0}}), allow_nan=False))
    assert syn["train"]["speed_factors"] == [1.0]
    assert syn["train"]["natural_frequency_hz"] == pytest.approx(60.0, rel=1e-5)
    w = syn["objective"]
    for s in syn["segments"]:
        assert s["residual_vibration_by_speed"] == [s["residual_vibration"]]
        assert s["best_builtin"]["residual_vibration"] > 10.0 * s["residual_vibration"]
    # the law terms: the segments' figures with the residual squared, as camjax synthesize counts it
    law = sum(w["l2_jerk"] * s["l2_jerk"] + w["residual_vibration"] * s["residual_vibration"] ** 2
              for s in syn["segments"])
    assert syn["codesign"]["law_objective"] == pytest.approx(law, rel=1e-9)
    assert syn["codesign"]["chosen"] == "codesign"
