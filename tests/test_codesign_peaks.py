"""The peak terms of a co-design (``peak_velocity``, ``peak_accel``, ``peak_jerk``, ``peak_force`` in
[synthesis] of a scene with [design] and designed segments; camjax.codesign.peaks): the smooth
maximum's bounds and gradient, the continuation's result against the law synthesis' exact LP
optimum (a bound that follows from optimality), "never loses to choosing", and the reported peaks
against an independent evaluation of the written law."""

from __future__ import annotations

import numpy as np
import pytest
from test_codesign_vibration import SAMPLES, vib_data

import camjax.codesign.peaks as peaks_mod
from camjax.codesign import Codesign, CodesignError, codesign_scene
from camjax.dynamics.context import synthesis_train
from camjax.scene import scene_from_dict
from camjax.scene.designed import starting_control
from camjax.synthesis.linear import linear_kinematics
from camjax.synthesis.segments import synthesize_segments
from camjax.synthesis.vibration import builtin_train_measures


def terms_of(scene):
    designed = scene.motion.designed
    lin = linear_kinematics(scene.motion.program, designed, SAMPLES, [starting_control(d) for d in designed])
    return lin, peaks_mod.peak_terms(lin, designed, dict(scene.synthesis.objective), 8, synthesis_train(scene))


@pytest.fixture(scope="module")
def peak_scene():
    """The small co-design scene with the follower train, peak |a| and peak contact force terms, and
    laws of 16 control values (8 leave each law 2 free coordinates: too few to beat the built-ins)."""
    data = vib_data(l2_jerk=1e-6, peak_accel=1e-3, peak_force=1e-5)
    for seg in data["motion"]["segments"]:
        if seg.get("design"):
            seg["control_count"] = 16
    return scene_from_dict(data, "peaks")


@pytest.mark.slow
def test_the_smooth_peak_bounds_the_exact_one_within_its_stated_gap(peak_scene):
    """max|v| <= M_tau(v) <= max|v| + tau log(2P) on the search's rows, at random z and every
    stage's tau."""
    lin, terms = terms_of(peak_scene)
    assert len(terms.labels) == 4  # two terms on two segments
    rng = np.random.default_rng(0)
    for _ in range(3):
        z = lin.z0 + 0.3 * rng.normal(size=lin.free)
        exact = float(terms.weights @ peaks_mod.peaks(terms, z, dense=False))
        for taus in peaks_mod.schedule(terms, z):
            smooth = peaks_mod.smooth_value(terms, z, taus)[0]
            # (the lower bound to rounding: at the last stage's tau the sum is the max's own term)
            assert exact * (1 - 1e-14) <= smooth <= exact + peaks_mod.smoothing_bound(terms, taus) * (1 + 1e-12)


def test_the_smooth_peaks_gradient_matches_central_differences(peak_scene):
    """The jitted gradient of sum w M_tau against central differences (h = 1e-6 of a smooth function
    with curvature ~ w/tau: truncation ~ h^2 w / tau^2, rounding ~ 1e-16 w peak / h; 1e-6 relative)."""
    lin, terms = terms_of(peak_scene)
    z = lin.z0 + 0.2 * np.random.default_rng(1).normal(size=lin.free)
    taus = peaks_mod.schedule(terms, z)[1]
    g = peaks_mod.smooth_value(terms, z, taus)[1]
    h = 1e-6
    fd = np.zeros(lin.free)
    for i in range(lin.free):
        e = np.zeros(lin.free)
        e[i] = h
        fd[i] = (peaks_mod.smooth_value(terms, z + e, taus)[0] - peaks_mod.smooth_value(terms, z - e, taus)[0]) / (2 * h)
    assert np.linalg.norm(g - fd) <= 1e-6 * np.linalg.norm(fd)


def test_peak_force_with_a_designed_spring_is_refused_naming_it():
    data = vib_data(l2_jerk=1e-6, peak_force=1e-5)
    data["synthesis"]["spring_N_per_m"] = [1000.0, 5000.0]
    with pytest.raises(CodesignError) as err:
        Codesign(scene_from_dict(data, "spring"), SAMPLES)
    assert err.value.field == "synthesis.objective.peak_force"


# ------------------------------------------------------------------------------ slow


@pytest.fixture(scope="module")
def peak_outcome(peak_scene):
    return codesign_scene(peak_scene, SAMPLES)


@pytest.mark.slow
def test_the_codesign_with_peak_terms_never_loses_to_choosing(peak_outcome):
    """The written objective (exact maxima) is <= the best built-in combination's, each with its own
    geometry; the co-designed laws win here (the built-ins are not optimal for this objective)."""
    out = peak_outcome
    assert out.best_builtin is not None
    assert out.objective <= out.best_builtin[1] * (1 + 1e-12)
    assert out.chosen == "codesign" and out.codesign_objective < out.best_builtin[1]


@pytest.mark.slow
def test_the_reported_peaks_are_those_of_the_written_law(peak_scene, peak_outcome):
    """Each designed segment's peak |a| (normalized) from the written B-spline evaluated by SciPy
    (its knots and control values, independent of the project's de Boor code and compiling no
    program) on 20001 points and the knots (the cubic's a is piecewise linear: its peak is at a
    knot, exact to 1e-9), and its peak contact force from the built-in laws' quadrature of the train
    (:func:`builtin_train_measures` on 4097 points against the report's 65 per span: 1e-4)."""
    interpolate = pytest.importorskip("scipy.interpolate")
    train = synthesis_train(peak_scene)
    for seg in peak_outcome.segments:
        ds = seg.segment
        x = np.union1d(np.linspace(0.0, 1.0, 20001), seg.knots)
        spline = interpolate.BSpline(np.asarray(seg.knots), np.asarray(seg.control), ds.degree)

        def law(t, spline=spline):
            return tuple(spline(np.asarray(t), nu) for nu in range(4))

        a = law(x)[2]
        assert abs(np.max(np.abs(a)) - seg.measures["peak_accel"]) <= 1e-9 * seg.measures["peak_accel"]
        force = builtin_train_measures(law, train, ds)["peak_force"]
        assert abs(force - seg.measures["peak_force"]) <= 1e-4 * force


@pytest.mark.slow
def test_a_dominant_peak_weight_reaches_the_law_synthesis_optimum():
    """With peak_jerk weighted w = 1e3 (the geometry's part G ~ 0.5), optimality bounds the co-design's
    peak: w (p - p_LP) <= G(z_LP) - G(z*) + (the smoothing bound) with G >= 0, so p_LP <= p <=
    p_LP + (G(z_LP) + smoothing) / w, p_LP the exact LP optimum of camjax synthesize on the same rows;
    and p, as written, is within 1e-9 of the peak jerk the LP's law has (the cubic's j is
    piecewise constant: its control values are its values)."""
    w = 1e3
    scene = scene_from_dict(vib_data(peak_jerk=w), "jerk")
    out = codesign_scene(scene, SAMPLES)
    law_only = synthesize_segments(scene.motion.designed, {"peak_jerk": w}, 8)
    cd = Codesign(scene, SAMPLES)
    g_lp = cd.value(cd.lin.coordinates([r.control for r in law_only]))[0] - w * sum(
        r.measures["peak_jerk"] for r in law_only)
    p_lp = sum(r.measures["peak_jerk"] for r in law_only)
    p = sum(s.measures["peak_jerk"] for s in out.segments)
    assert out.chosen == "codesign"
    assert p_lp * (1 - 1e-9) <= p <= p_lp + (g_lp + 1e-3) / w
