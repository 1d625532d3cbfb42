"""Reported values are the computed values: `camjax design` (in-process, through the CLI) for each
follower type, then every dimension in result.json is checked to reproduce the exported
profile.csv, and every extremum it reports to be at least as extreme as the same column's samples.

The geometry is checked from positions alone (no camjax geometry function): the base circle is the
outline where the follower dwells at zero lift; a roller's pitch curve is the outline offset by
R_f; a translating follower's axis at cam angle theta is (sigma sin theta, cos theta) in cam
coordinates (sigma = +1 ccw, -1 cw); a rocker's pivot at distance d and its arm of length l meet
the pitch points by the law of cosines at the CSV's arm angle; a flat face lies at distance f from
the pivot. A [design] that frees the follower's dimensions is solved in each scene, so a report
that gave the scene's [follower] values instead of the solved ones would fail.

Tolerances: the CSV holds 12 decimals (rounding 5e-13 mm) and the JSON full float64, so a
reported dimension reproduces the outline to round-off of a few operations on ~100 mm values
(~1e-13); 1e-9 mm is the brief's machining-irrelevant bound with a wide margin. Extrema: the
report's value must be >= the column's largest sample (<= its smallest) less the CSV's rounding,
taken as 1e-9 plus 1e-14 relative (the %.12f format keeps 17 significant digits up to 1e5).
"""

import json
import math
import tomllib

import numpy as np
import pytest
from test_oscillating_problem import FLAT, SCENE

from camjax import cli, followers
from camjax.scene import builtin_scene_text

pytestmark = pytest.mark.slow  # four `camjax design` runs with a solver each (~10 s apiece)

TOL_MM = 1e-9

OSC_ROLLER = (SCENE.replace("ROT", "cw").replace("pivot_distance_mm = 80.0", "pivot_distance_mm = 100.0")
              .replace("DESIGN", "pivot_distance_mm = [65.0, 110.0]\narm_length_mm = [40.0, 80.0]"))
OSC_FLAT = FLAT.replace("ROT", "ccw").replace("DESIGN", "pivot_distance_mm = [120.0, 180.0]\n"
                                                        "face_offset_mm = [0.0, 20.0]")
# hand-written scenes that free the follower's dimensions; every other registered follower type runs
# its built-in example scene, so a new follower folder is in this matrix without editing it
SCENES = {"flat": builtin_scene_text("default"), "roller": builtin_scene_text("roller"),
          "oscillating_roller": OSC_ROLLER, "oscillating_flat": OSC_FLAT}
SCENES.update({name: builtin_scene_text(followers.get(name).example_scene)
               for name in followers.names() if name not in SCENES})


@pytest.fixture(scope="module", params=list(SCENES))
def run(request, tmp_path_factory):
    """(follower type, result.json, {column: values}) of one `camjax design` run."""
    folder = tmp_path_factory.mktemp(request.param)
    scene = folder / "scene.toml"
    scene.write_text(SCENES[request.param])
    out = folder / "out"
    assert cli.main(["design", str(scene), "--out", str(out), "--dpi", "30"]) == 0
    data = json.loads((out / "result.json").read_text())
    assert data["follower_type"] == request.param
    assert data["evaluated_at"]["source"] == "design"
    with open(out / "profile.csv") as fh:
        header = fh.readline().strip().split(",")
    table = np.loadtxt(out / "profile.csv", delimiter=",", skiprows=1)
    return request.param, data, {name: table[:, i] for i, name in enumerate(header)}


def test_the_scenes_follower_dimensions_stay_visible_under_their_own_name(run):
    # the [follower] table read with tomllib (not camjax's parser); a flat face has none
    kind, data, _ = run
    table = tomllib.loads(SCENES[kind])["follower"]
    # the follower's design variables that its [follower] table also sets (a flat face: none)
    keys = [k for k in followers.get(kind).variables if k != "base_radius_mm" and k in table]
    assert keys or kind in ("flat", "knife_edge"), f"{kind}: the scene sets none of its dimensions"
    if keys:
        assert data["follower_scene"] == {k: float(table[k]) for k in keys}
        # the report gives the dimensions the drawn cam was computed with: where [design] frees one
        # (the hand-written rocker scenes), the solver moved it off the scene's value (else
        # follower_scene and the design could not be told apart) and the follower's block reports it
        block = data.get("oscillating_follower", data.get("roller", {}))
        for key in keys:
            if kind in ("oscillating_roller", "oscillating_flat") and key != "roller_radius_mm":
                assert abs(data["design"][key] - float(table[key])) > 1e-3, key
            if key in data["design"] and key in block:
                assert block[key] == data["design"][key], key
    else:
        assert "follower_scene" not in data


def _turn(x, y, a):
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def _near(values, expected, what):
    err = float(np.max(np.abs(np.asarray(values) - np.asarray(expected))))
    assert err <= TOL_MM, f"{what}: off by {err:.3g} mm"


def _zero_dwell(lift, velocity):
    """Samples where the follower dwells at zero lift (lift = velocity = 0 exactly: a dwell's)."""
    rows = (lift == 0.0) & (velocity == 0.0)
    assert rows.sum() >= 10, "the scene must dwell at zero lift"
    return rows

# ---------------------------------------------------------------------------- dimensions


def test_every_follower_draws_its_base_circle_where_it_dwells_at_zero_lift(run):
    # any follower type: where the follower rests at zero lift (or swing) it touches the base circle
    kind, data, col = run
    rb = data["evaluated_at"]["base_radius_mm"]
    rocking = "swing_deg" in col
    lift, velocity = (col["swing_deg"], col["ds_rad_per_rad"]) if rocking else (col["s_mm"], col["ds_mm_per_rad"])
    dwell = _zero_dwell(lift, velocity)
    _near(np.hypot(col["x_mm"][dwell], col["y_mm"][dwell]), rb, f"{kind}: |outline| at zero lift vs R_b")


def test_dimensions_reproduce_the_profile(run):
    kind, data, col = run
    theta = np.radians(col["theta_deg"])
    sigma = 1.0 if data["rotation"] == "ccw" else -1.0
    x, y = col["x_mm"], col["y_mm"]
    if kind not in ("flat", "roller", "oscillating_roller", "oscillating_flat"):
        pytest.skip(f"{kind}: positions checked by its own tests; its base circle and extrema above and below")
    if kind in ("flat", "roller"):
        rb = data["evaluated_at"]["base_radius_mm"]
        assert rb == data["design"]["base_radius_mm"]
        dwell = _zero_dwell(col["s_mm"], col["ds_mm_per_rad"])
        _near(np.hypot(x[dwell], y[dwell]), rb, "base circle |outline| at zero lift vs R_b")
        u = (sigma * np.sin(theta), np.cos(theta))  # follower axis
        w = (sigma * np.cos(theta), -np.sin(theta))  # across it
        s = col["s_mm"]
        if kind == "flat":
            width = data["evaluated_at"]["face_width_mm"]
            assert width == data["design"]["face_width_mm"]
            _near(x * u[0] + y * u[1], rb + s, "face at R_b + s along the axis")
            offset = x * w[0] + y * w[1]  # the contact point along the face
            assert np.max(np.abs(offset)) <= 0.5 * width + TOL_MM, "the contact runs off the face"
            # rho = R_b + s + s'' (SPEC 3): the curvature column is the same R_b's
            _near(col["rho_mm"], rb + s + col["d2s_mm_per_rad2"], "rho column vs R_b + s + s''")
        else:
            r = data["roller"]
            rf, e, rp = r["roller_radius_mm"], r["offset_mm"], r["prime_radius_mm"]
            for key in ("roller_radius_mm", "offset_mm", "base_radius_mm"):
                assert r.get(key, rb) == data["design"][key], key
            assert rp == pytest.approx(rb + rf, rel=1e-15)
            px, py = col["pitch_x_mm"], col["pitch_y_mm"]
            _near(np.hypot(x - px, y - py), rf, "outline to pitch curve vs R_f")
            _near(px * w[0] + py * w[1], e, "roller centre off the axis vs the offset")
            _near(px * u[0] + py * u[1], math.sqrt(rp * rp - e * e) + s, "roller centre along the axis")
        return
    f = data["oscillating_follower"]
    ev = data["evaluated"]
    rb, d = ev["base_radius_mm"], f["pivot_distance_mm"]
    assert rb == data["evaluated_at"]["base_radius_mm"] == data["design"]["base_radius_mm"]
    for key in ("pivot_distance_mm", "arm_length_mm", "roller_radius_mm", "face_offset_mm"):
        if key in data["design"]:
            assert f[key] == data["design"][key], key
    psi = np.radians(col["arm_angle_deg"])
    psi0 = math.radians(ev["arm_start_angle_deg"])
    _near(np.radians(col["arm_angle_deg"] - col["swing_deg"]), psi0, "arm angle - swing vs psi0 (rad)")
    dwell = _zero_dwell(col["swing_deg"], col["ds_rad_per_rad"])
    _near(np.hypot(x[dwell], y[dwell]), rb, "base circle |outline| at zero swing vs R_b")
    if kind == "oscillating_roller":
        arm, rf, rp = f["arm_length_mm"], f["roller_radius_mm"], ev["prime_radius_mm"]
        assert rp == pytest.approx(rb + rf, rel=1e-15)
        px, py = col["pitch_x_mm"], col["pitch_y_mm"]
        _near(np.hypot(x - px, y - py), rf, "outline to pitch curve vs R_f")
        # law of cosines in the triangle cam centre, pivot, roller centre
        _near(np.hypot(px, py), np.sqrt(d * d + arm * arm - 2 * d * arm * np.cos(psi)),
              "|pitch point| vs the law of cosines in d, l and the arm angle")
        # and placed: the pivot on +X of the fixed frame, the roller centre at (d - l cos psi, l sin psi)
        cx, cy = _turn(px, py, sigma * theta)
        _near(cx, d - arm * np.cos(psi), "roller centre x, fixed frame")
        _near(cy, arm * np.sin(psi), "roller centre y, fixed frame")
        _near(np.hypot(px[dwell], py[dwell]), rp, "prime circle at zero swing vs R_p")
        assert math.cos(psi0) == pytest.approx((d * d + arm * arm - rp * rp) / (2 * d * arm), abs=1e-12)
    else:
        off = f["face_offset_mm"]
        xi = col["contact_on_face_mm"]
        # the contact point = pivot - f m + xi u, face normal m = (sin psi, cos psi), along u = (-cos, sin)
        xf, yf = _turn(x, y, sigma * theta)
        _near(xf, d - off * np.sin(psi) - xi * np.cos(psi), "contact x, fixed frame")
        _near(yf, -off * np.cos(psi) + xi * np.sin(psi), "contact y, fixed frame")
        assert math.sin(psi0) == pytest.approx((rb + off) / d, abs=1e-12)


# ------------------------------------------------------------------------------ extrema


def _slack(v):
    return TOL_MM + 1e-14 * abs(v)


def _check(block, values, what, checked):
    """A reported {max, min, max_abs, min_abs} block at least as extreme as ``values``' samples."""
    values = np.asarray(values)
    hi, lo, big, small = values.max(), values.min(), np.abs(values).max(), np.abs(values).min()
    if "max" in block:
        assert block["max"] >= hi - _slack(hi), f"{what}.max {block['max']!r} < sampled {hi!r}"
    if "min" in block:
        assert block["min"] <= lo + _slack(lo), f"{what}.min {block['min']!r} > sampled {lo!r}"
    if "max_abs" in block:
        assert block["max_abs"] >= big - _slack(big), f"{what}.max_abs {block['max_abs']!r} < {big!r}"
    if "min_abs" in block:
        assert block["min_abs"] <= small + _slack(small), f"{what}.min_abs {block['min_abs']!r} > {small!r}"
    checked.append(what)


def _extremum_blocks(tree, path=""):
    """(dotted key, block) of every {max, min, ...} block in a result.json tree."""
    if isinstance(tree, dict):
        if "max" in tree or "min" in tree:
            yield path, tree
        for key, value in tree.items():
            yield from _extremum_blocks(value, f"{path}.{key}" if path else key)


# result.json's names of the motion's extrema -> profile.csv's columns, translating and rocking
KINEMATIC_COLUMNS = {"displacement_mm": "s_mm", "velocity_mm_per_rad": "ds_mm_per_rad",
                     "accel_mm_per_rad2": "d2s_mm_per_rad2", "velocity_rad_per_rad": "ds_rad_per_rad",
                     "accel_rad_per_rad2": "d2s_rad_per_rad2"}


def test_every_reported_extremum_named_as_a_column_is_at_least_its_samples(run):
    # any follower type: each extremum block whose key names a profile.csv column (or a motion
    # column, KINEMATIC_COLUMNS) is at least as extreme as that column's samples
    kind, data, col = run
    checked: list[str] = []
    for path, block in _extremum_blocks(data):
        name = path.rsplit(".", 1)[-1]
        column = KINEMATIC_COLUMNS.get(name, name)
        if column in col:
            _check(block, col[column], f"{kind}: {path}", checked)
    # the motion, the loads and the follower's own curves: at least the six motion blocks and two more
    assert len(checked) >= 8, checked


def test_reported_extrema_are_at_least_the_sampled_ones(run):
    kind, data, col = run
    if kind not in ("flat", "roller", "oscillating_roller", "oscillating_flat"):
        pytest.skip(f"{kind}: the blocks named as columns are checked above")
    checked: list[str] = []
    k, loads, design = data["kinematics"], data["loads"], data["design"]
    if kind in ("flat", "roller"):
        for key, name in (("displacement_mm", "s_mm"), ("velocity_m_s", "velocity_m_s"),
                          ("accel_m_s2", "accel_m_s2"), ("jerk_m_s3", "jerk_m_s3"),
                          ("velocity_mm_per_rad", "ds_mm_per_rad"), ("accel_mm_per_rad2", "d2s_mm_per_rad2")):
            _check(k[key], col[name], f"kinematics.{key}", checked)
        _check(loads["force_N"], col["force_N"], "loads.force_N", checked)
        _check(loads["torque_Nm"], col["torque_Nm"], "loads.torque_Nm", checked)
        _check({"min": loads["contact"]["min_force_N"]}, col["force_N"], "loads.contact.min_force_N", checked)
        _check(data["stress_MPa"], col["stress_MPa"], "stress_MPa", checked)
        _check({"max": design["stress_max_MPa"]}, col["stress_MPa"], "design.stress_max_MPa", checked)
        _check({"max": design["peak_stress_MPa"]}, col["stress_MPa"], "design.peak_stress_MPa", checked)
        if kind == "flat":
            ds = col["ds_mm_per_rad"]
            _check(data["contact_offset_mm"], ds, "contact_offset_mm", checked)
            _check({"max": data["min_face_width_mm"]}, 2 * np.abs(ds), "min_face_width_mm", checked)
            _check({"max": data["min_face_width_asymmetric_mm"]}, [np.ptp(ds)], "min_face_width_asym", checked)
            _check(data["rho_mm"], col["rho_mm"], "rho_mm", checked)
            _check({"min": design["rho_min_mm"]}, col["rho_mm"], "design.rho_min_mm", checked)
            # the smallest admissible R_b keeps rho = R_b + s + s'' >= rho_min at every sample
            rho_min = 1e-3  # the flat face's default follower.min_curvature_radius_mm (the scene sets none)
            _check({"max": data["min_base_radius_mm"]}, rho_min - (col["s_mm"] + col["d2s_mm_per_rad2"]),
                   "min_base_radius_mm", checked)
        else:
            r = data["roller"]
            _check(r["pressure_angle_deg"], col["pressure_angle_deg"], "roller.pressure_angle_deg", checked)
            _check({"max_abs": design["pressure_angle_max_deg"]}, col["pressure_angle_deg"],
                   "design.pressure_angle_max_deg", checked)
            _check(r["pitch_rho_mm"], col["pitch_rho_mm"], "roller.pitch_rho_mm", checked)
            convex = col["pitch_rho_mm"] > 0
            rho_min = 1.0  # the roller scene's follower.min_curvature_radius_mm
            margin = col["pitch_rho_mm"][convex] - r["roller_radius_mm"] - rho_min
            _check(r["undercut_margin_mm"], margin, "roller.undercut_margin_mm", checked)
            _check({"min": design["cam_rho_min_mm"]}, col["pitch_rho_mm"][convex] - r["roller_radius_mm"],
                   "design.cam_rho_min_mm", checked)
        assert len(checked) >= 12
        return
    for key, name in (("swing_deg", "swing_deg"), ("angular_velocity_rad_s", "angular_velocity_rad_s"),
                      ("angular_accel_rad_s2", "angular_accel_rad_s2"),
                      ("angular_jerk_rad_s3", "angular_jerk_rad_s3"),
                      ("velocity_rad_per_rad", "ds_rad_per_rad"), ("accel_rad_per_rad2", "d2s_rad_per_rad2")):
        _check(k[key], col[name], f"kinematics.{key}", checked)
    ev = data["evaluated"]
    _check(ev["arm_angle_deg"], col["arm_angle_deg"], "evaluated.arm_angle_deg", checked)
    _check(ev["pressure_angle_deg"], col["pressure_angle_deg"], "evaluated.pressure_angle_deg", checked)
    _check(ev["rho_mm"], col["rho_mm"], "evaluated.rho_mm", checked)
    for key, name in (("pivot_torque_Nm", "pivot_torque_Nm"), ("contact_force_N", "contact_force_N"),
                      ("torque_Nm", "torque_Nm")):
        _check(loads[key], col[name], f"loads.{key}", checked)
    _check({"min": loads["contact"]["min_pivot_torque_Nm"]}, col["pivot_torque_Nm"],
           "loads.contact.min_pivot_torque_Nm", checked)
    _check(data["stress_MPa"], col["stress_MPa"], "stress_MPa", checked)
    _check({"max": design["stress_max_MPa"]}, col["stress_MPa"], "design.stress_max_MPa", checked)
    if kind == "oscillating_roller":
        _check(ev["pitch_rho_mm"], col["pitch_rho_mm"], "evaluated.pitch_rho_mm", checked)
        convex = col["pitch_rho_mm"] > 0
        rf = data["oscillating_follower"]["roller_radius_mm"]
        rho_min = data["oscillating_follower"]["min_curvature_radius_mm"]
        _check(ev["undercut_margin_mm"], col["pitch_rho_mm"][convex] - rf - rho_min,
               "evaluated.undercut_margin_mm", checked)
        _check({"max_abs": design["pressure_angle_max_deg"]}, col["pressure_angle_deg"],
               "design.pressure_angle_max_deg", checked)
    else:
        xi = col["contact_on_face_mm"]
        face = ev["face"]
        _check({"min": face["contact_min_mm"], "max": face["contact_max_mm"]}, xi, "evaluated.face", checked)
        _check({"max": face["min_length_mm"]}, [np.ptp(xi)], "evaluated.face.min_length_mm", checked)
    assert len(checked) >= 15
