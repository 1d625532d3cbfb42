"""Roller followers end to end: report figures against closed forms and NumPy, the design block,
`camjax design` / `camjax sweep` on the built-in roller scene, and bad input (exit 2, no files)."""

import dataclasses
import json
import math

import numpy as np
import pytest

import camjax
from camjax import cli, followers
from camjax.scene import builtin_scene_text, parse_scene

ROLLER = builtin_scene_text("roller")


def _variant(old, new, text=ROLLER):
    assert text.count(old) == 1, old
    return text.replace(old, new)


@pytest.mark.slow
def test_min_prime_radius_of_the_harmonic_rise_and_its_rule():
    # rise 8 mm harmonic over 90 deg, e = 0, limit 30 deg (the return over 180 deg is gentler):
    # R_p = sqrt(h^2/4 + A^2 / tan^2 30) - h/2, A = pi h / (2 beta) (tests/test_roller_geometry.py)
    data = camjax.design_report(dataclasses.replace(camjax.load_scene("roller"), design=None))
    a = math.pi * 8 / (2 * math.radians(90))
    closed = math.sqrt(16 + (a / math.tan(math.radians(30))) ** 2) - 4
    # R_p = max_theta f, f = |s'| / tan 30 - s, refined off the grid (exact extrema): the closed
    # form to a few ulps of the Newton solve (1e-12 relative)
    assert data["min_prime_radius_mm"] == pytest.approx(closed, rel=1e-12)
    assert data["min_base_radius_mm"] == pytest.approx(data["min_prime_radius_mm"] - 5.0, rel=1e-15)
    # the limit binds where cos(pi theta / beta) = (h/2) / (R_p + h/2): theta = 36.95 deg; the
    # angle of a smooth max is found to ~sqrt(eps) relative at worst (1e-6 deg)
    x = math.acos(4 / (closed + 4))
    assert data["min_base_radius_deg"] == pytest.approx(math.degrees(x) * 90 / 180, abs=1e-6)
    assert data["min_base_radius_binding"] == "pressure_angle"
    assert f"pressure angle |phi| <= 30 deg binds at {data['min_base_radius_deg']:g} deg" in \
        data["min_base_radius_rule"]
    # on the 1 deg samples (extrema = "grid") the max is below the continuous one by at most
    # max|f''| (dtheta/2)^2 / 2 = (8 * 4 / tan 30) * 7.6e-5 / 2 = 2.1e-3 mm, at the sample 37 deg
    grid_scene = dataclasses.replace(camjax.load_scene("roller"), design=None)
    grid = followers.of(grid_scene).min_base_radius(grid_scene, camjax.scene_arrays(grid_scene, extrema="grid"))
    assert closed - 2.1e-3 <= grid.prime_radius_mm <= closed + 1e-12
    assert grid.angle_deg == round(math.degrees(x) * 90 / 180)
    json.dumps(data, allow_nan=False)


@pytest.mark.slow
def test_min_base_radius_is_the_smallest_cam_for_the_designs_roller_and_offset():
    """With a [design] that moves R_f and the offset, the report's smallest cam is sized for the
    follower the cam is drawn with (the design's), not the [follower] table's, and says so."""
    data = camjax.design_report(camjax.load_scene("roller"))
    rf, e = data["design"]["roller_radius_mm"], data["design"]["offset_mm"]
    assert (rf, e) != (5.0, 0.0) and data["follower_scene"] == {"roller_radius_mm": 5.0, "offset_mm": 0.0}
    # independent sizing on a dense grid (harmonic rise 8 mm / 90 deg, return over 180 deg): the
    # pressure-angle need f = |s' - e| / tan 30 - s (ccw), R_p = hypot(e, max f). 2e6 samples: the
    # grid max is below the continuous one by ~max|f''| (dtheta/2)^2 / 2 < 1e-10 mm. The reported
    # size is the larger of this need and the undercut's, so its equality with this need (1e-8 mm)
    # says the undercut needs no more. At this design the two needs tie: the size-only optimum
    # with R_f and e free sits on both limits (the report's own rows: the pressure angle at its 30
    # deg, the undercut's root at the same R_p), so the name of the binding limit is either,
    # decided by round-off.
    theta = np.linspace(0.0, 2.0 * np.pi, 2_000_001)
    rise, ret = np.radians(90.0), np.radians(180.0)
    t2 = theta - np.radians(135.0)
    s = np.where(theta <= rise, 4.0 * (1 - np.cos(np.pi * theta / rise)),
                 np.where((t2 >= 0) & (t2 <= ret), 4.0 * (1 + np.cos(np.pi * t2 / ret)), 0.0))
    ds = np.where(theta <= rise, 4.0 * np.pi / rise * np.sin(np.pi * theta / rise),
                  np.where((t2 >= 0) & (t2 <= ret), -4.0 * np.pi / ret * np.sin(np.pi * t2 / ret), 0.0))
    need = np.max(np.abs(ds - e) / np.tan(np.radians(30.0)) - s)
    assert data["min_base_radius_binding"] in ("pressure_angle", "undercut")
    assert data["min_prime_radius_mm"] == pytest.approx(math.hypot(e, need), abs=1e-8)
    assert data["min_base_radius_mm"] == pytest.approx(math.hypot(e, need) - rf, abs=1e-8)
    assert f"R_f = {rf:g} mm, offset {e:g} mm" in data["min_base_radius_rule"]


def _convex_radii(scene, prime_radius_mm, samples=None):
    """SPEC 3's zero-offset pitch radius in NumPy on the scene's grid (or ``samples`` of them):
    rho_p on the convex samples and their angles (deg)."""
    if samples is not None:
        scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=samples, extrema="grid"))
    arrays = camjax.scene_arrays(scene)
    s, v, a = (np.asarray(x) for x in (arrays.kin.s, arrays.kin.ds, arrays.kin.d2s))
    w = prime_radius_mm + s
    rho_p = (w**2 + v**2) ** 1.5 / (w**2 + 2 * v**2 - a * w)
    convex = rho_p > 0
    return rho_p[convex], np.asarray(arrays.theta_deg)[convex]


@pytest.mark.slow  # > 2 s (a compile of its own)
def test_undercut_binds_for_a_large_roller():
    text = _variant("roller_radius_mm = 5.0 ", "roller_radius_mm = 12.0 ")
    scene = dataclasses.replace(parse_scene(text, "big-roller"), design=None)
    grid = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema="grid"))
    for case in (grid, scene):
        data = camjax.design_report(case)
        assert data["min_base_radius_binding"] == "undercut"
        assert "undercut" in data["min_base_radius_rule"] and f"{data['min_base_radius_deg']:g} deg" in \
            data["min_base_radius_rule"]
    # grid extrema: at that prime radius the smallest convex cam-surface radius on the samples is the
    # scene's 1 mm (rho_c = rho_p - R_f), by bisection to the last bit: the limit to round-off
    data = camjax.design_report(grid)
    rho_p, theta = _convex_radii(grid, data["min_prime_radius_mm"])
    assert np.min(rho_p - 12.0) == pytest.approx(1.0, abs=1e-9)
    assert theta[int(np.argmin(rho_p))] == pytest.approx(data["min_base_radius_deg"])
    # exact extrema (the default): the limit holds between the samples too, so the prime radius is
    # larger than the grid's, its samples keep more than 1 mm, and on 10^6 samples (grid error
    # ~(360/10^6)^2 of the 360-sample grid's 2e-3 mm, ~1e-9 mm) the smallest radius is 1 mm, at
    # the angle the report names (to the dense grid's spacing, 3.6e-4 deg)
    exact = camjax.design_report(scene)
    assert exact["min_prime_radius_mm"] > data["min_prime_radius_mm"]
    assert np.min(_convex_radii(scene, exact["min_prime_radius_mm"])[0] - 12.0) > 1.0
    rho_p, theta = _convex_radii(scene, exact["min_prime_radius_mm"], samples=1_000_000)
    assert np.min(rho_p - 12.0) == pytest.approx(1.0, abs=1e-8)
    assert theta[int(np.argmin(rho_p))] == pytest.approx(exact["min_base_radius_deg"], abs=1e-3)


@pytest.mark.slow
def test_roller_stress_curve_against_spec_formula_in_numpy():
    # offset fixed at 0 so SPEC 3's zero-offset formulas apply as printed
    text = _variant("offset_mm = [-4.0, 4.0]", "offset_mm = 0.0")
    scene = parse_scene(text, "roller-centred")
    report = camjax.analyse(scene)
    d, a = report.data["design"], report.arrays
    rb, rf = d["base_radius_mm"], d["roller_radius_mm"]
    assert d["offset_mm"] == 0.0 and d["prime_radius_mm"] == pytest.approx(rb + rf, rel=1e-15)
    s, v, acc = (np.asarray(x) for x in (a.kin.s, a.kin.ds, a.kin.d2s))
    w = rb + rf + s
    rho_p = (w**2 + v**2) ** 1.5 / (w**2 + 2 * v**2 - acc * w)
    phi = np.arctan(v / w)
    k = 2 * (1 - 0.3**2) / 2.1e5
    sigma = 0.564 * np.sqrt(np.asarray(a.force_N) / np.cos(phi) / 8.0 * (1 / (rho_p - rf) + 1 / rf) / k)
    # same formula evaluated in another order: float64 round-off ~1e-15 relative (1e-12 with the
    # cancellation in 1/(rho_p - R_f) + 1/R_f near concave stretches)
    np.testing.assert_allclose(report.curves.stress_MPa, sigma, rtol=1e-12)
    # the report's peak is the continuous one (exact extrema): at or above every sample, and above
    # the 1 deg samples' by less than |sigma''| (0.5 deg)^2 / 2, below 1e-3 relative while
    # |sigma''| / sigma < 26 per rad^2 (measured: 4e-6 relative above the samples)
    assert sigma.max() <= report.data["stress_MPa"]["max"] <= sigma.max() * (1 + 1e-3)
    assert d["peak_stress_MPa"] == pytest.approx(sigma.max(), rel=1e-12)
    assert report.data["roller"]["prime_radius_mm"] == pytest.approx(rb + rf, rel=1e-15)


@pytest.mark.slow
def test_cw_scene_mirrors_the_ccw_design():
    ccw = camjax.analyse(camjax.load_scene("roller"))
    text = _variant('rotation = "ccw"', 'rotation = "cw"')
    cw = camjax.analyse(parse_scene(text, "roller-cw"))
    a, b = ccw.data["design"], cw.data["design"]
    # the mirror image of the optimum is the optimum of the mirrored problem: e -> -e, same R_p
    assert b["prime_radius_mm"] == pytest.approx(a["prime_radius_mm"], abs=1e-6)
    assert b["offset_mm"] == pytest.approx(-a["offset_mm"], abs=1e-5)
    assert cw.data["rotation"] == "cw"


@pytest.mark.slow
def test_design_and_sweep_cli_on_the_roller_scene(tmp_path, capsys):
    out = tmp_path / "design"
    assert cli.main(["design", "roller", "--out", str(out), "--dpi", "40"]) == 0
    data = json.loads((out / "result.json").read_text())
    d = data["design"]
    assert {"roller_radius_mm", "offset_mm", "prime_radius_mm", "base_radius_mm"} <= set(d)
    assert (out / "stress.png").exists() and data["design"]["feasible"] is True
    assert "R_p =" in capsys.readouterr().out
    sweep = tmp_path / "sweep"
    assert cli.main(["sweep", "roller", "--alpha", "1,0.5", "--gamma", "0,1", "--out", str(sweep),
                     "--dpi", "40"]) == 0
    records = json.loads((sweep / "pareto.json").read_text())["records"]
    assert len(records) == 4
    for r in records:
        assert r["prime_radius_mm"] == pytest.approx(r["base_radius_mm"] + r["roller_radius_mm"], rel=1e-15)
        assert -4.0 <= r["offset_mm"] <= 4.0 and r["size_mm"] == r["prime_radius_mm"]


BAD_ROLLER = {
    "limit_out_of_range": (_variant("max_pressure_angle_deg = 30.0", "max_pressure_angle_deg = 95.0"),
                           "follower.max_pressure_angle_deg"),
    "roller_radius_zero": (_variant("roller_radius_mm = [3.0, 12.0]", "roller_radius_mm = [0.0, 12.0]"),
                           "design.roller_radius_mm"),
    "roller_radius_negative": (_variant("roller_radius_mm = 5.0 ", "roller_radius_mm = -5.0 "),
                               "follower.roller_radius_mm"),
    "offset_reaches_prime_circle": (_variant("offset_mm = [-4.0, 4.0]", "offset_mm = [-60.0, -53.0]"),
                                    "design.offset_mm"),
    "free_low_above_high": (_variant("offset_mm = [-4.0, 4.0]", "offset_mm = [3.0, -3.0]"),
                            "design.offset_mm"),
    "base_low_above_high": (_variant("base_radius_mm = [2.0, 40.0]", "base_radius_mm = [40.0, 2.0]"),
                            "design.base_radius_mm"),
    "face_width_for_roller": (_variant("sigma_max_MPa = 1000.0", "sigma_max_MPa = 1000.0\nface_width_mm = [5, 25]"),
                              "design.face_width_mm"),
    "roller_variable_for_flat": (_variant("face_width_mm = [5.0, 25.0]",
                                          "face_width_mm = [5.0, 25.0]\noffset_mm = [-1, 1]",
                                          builtin_scene_text("default")), "design.offset_mm"),
}


@pytest.mark.parametrize("case", sorted(BAD_ROLLER))
def test_bad_roller_input_exits_2_naming_the_field_and_writes_nothing(case, tmp_path, capsys):
    text, field = BAD_ROLLER[case]
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["design", str(scene), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == "" and "Traceback" not in captured.err
    assert f" {field}" in lines[0], lines[0]
    assert [p.name for p in tmp_path.iterdir()] == ["bad.toml"]
