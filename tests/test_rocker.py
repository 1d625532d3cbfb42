"""Rocker (oscillating-follower) loads, scenes and `camjax design`: the lever relations checked against
the moments of the contact force computed from positions, Hertz stress on a dwell in closed form,
scene refusals naming the field, and the design files."""

import json
import math

import numpy as np
import pytest

from camjax import cli, contact, followers, loads
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.laws import get_law
from camjax.loads import RockerTrain
from camjax.program import MotionProgram, Segment, evaluate
from camjax.scene import SceneError, parse_scene, with_samples

LIFT = math.radians(20.0)
PROGRAM = MotionProgram.from_segments([Segment("rise", 120, get_law("poly_3_4_5"), LIFT), Segment("dwell", 60),
                                       Segment("return", 100, get_law("cycloidal"), LIFT), Segment("dwell", 80)])
TRAIN = RockerTrain(inertia_kg_m2=0.002, spring_N_m_per_rad=20.0, preload_rad=0.3, damping_N_m_s_per_rad=0.01)
OMEGA = 30.0  # rad/s


def _turn(x, y, a):
    return np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y


def test_rocker_torque_is_the_kinetostatic_balance_about_the_pivot():
    kin = evaluate(PROGRAM, 720)
    s, ds, d2s = (np.asarray(v) for v in (kin.s, kin.ds, kin.d2s))
    # time derivatives by the chain rule at constant speed: psi' = s' w, psi'' = s'' w^2
    ref = 0.002 * d2s * OMEGA**2 + 0.01 * ds * OMEGA + 20.0 * (s + 0.3)
    np.testing.assert_allclose(loads.rocker_torque(TRAIN, kin, OMEGA), ref, rtol=1e-14, atol=1e-13)


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_roller_contact_force_and_cam_torque_from_the_moments_of_the_contact_force(rotation):
    sigma = 1.0 if rotation == "ccw" else -1.0
    n = 36_000
    kin = evaluate(PROGRAM, n)
    th, s = np.asarray(kin.theta), np.asarray(kin.s)
    d, l, rf, rp = 80.0, 60.0, 8.0, 45.0
    psi0 = math.acos((d * d + l * l - rp * rp) / (2 * d * l))
    cx, cy = d - l * np.cos(s + psi0), l * np.sin(s + psi0)  # roller centre, fixed frame
    x, y = _turn(cx, cy, -sigma * th)  # pitch curve seen from the cam
    h = 2 * np.pi / n
    tx, ty = _turn((np.roll(x, -1) - np.roll(x, 1)) / (2 * h), (np.roll(y, -1) - np.roll(y, 1)) / (2 * h),
                   sigma * th)
    # contact normal from positions: perpendicular to the pitch tangent, away from the cam centre
    nx, ny = -ty / np.hypot(tx, ty), tx / np.hypot(tx, ty)
    flip = np.sign(nx * cx + ny * cy)
    nx, ny = nx * flip, ny * flip
    m = np.asarray(loads.rocker_torque(TRAIN, kin, OMEGA))
    phi = rocker_roller_geo.oscillating_roller_pressure_angle(d, l, psi0, kin, rotation)
    p = np.asarray(loads.rocker_roller_contact_force(m, l, phi))
    # P n at the roller centre turns the arm towards larger psi (clockwise) by M: the lever relation
    moment = -((cx - d) * p * ny - cy * p * nx) * 1e-3
    # central differences at 0.01 deg: tangent direction to ~1e-9, forces ~200 N: measured 8e-8 N m
    np.testing.assert_allclose(moment, m, rtol=0, atol=1e-6)
    # the cam feels -P n at the contact point; the drive balances its moment about the cam centre
    qx, qy = cx - rf * nx, cy - rf * ny
    drive = -sigma * (qx * (-p * ny) - qy * (-p * nx)) * 1e-3
    np.testing.assert_allclose(loads.rocker_cam_torque(m, kin.ds), drive, rtol=0, atol=1e-6)


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_contact_force_and_cam_torque_from_the_moments_of_the_contact_force(rotation):
    sigma = 1.0 if rotation == "ccw" else -1.0
    kin = evaluate(PROGRAM, 720)
    th = np.asarray(kin.theta)
    d, f, rb = 120.0, 10.0, 95.0
    g = rocker_flat_geo.oscillating_flat_geometry(d, f, rb, kin, rotation)
    psi = np.asarray(g.arm_angle)
    x, y = rocker_flat_geo.oscillating_flat_profile(d, f, rb, kin, rotation)
    xf, yf = _turn(np.asarray(x), np.asarray(y), sigma * th)  # contact point, fixed frame
    mx, my = np.sin(psi), np.cos(psi)  # face normal, away from the cam
    m = np.asarray(loads.rocker_torque(TRAIN, kin, OMEGA))
    p = np.asarray(loads.rocker_flat_contact_force(m, g.contact_distance))
    moment = -((xf - d) * p * my - yf * p * mx) * 1e-3
    np.testing.assert_allclose(moment, m, rtol=1e-12, atol=1e-12)  # exact geometry: round-off only
    drive = -sigma * (xf * (-p * my) - yf * (-p * mx)) * 1e-3
    np.testing.assert_allclose(loads.rocker_cam_torque(m, kin.ds), drive, rtol=1e-12, atol=1e-12)


def test_hertz_stress_on_a_dwell_in_closed_form():
    # on a dwell the roller sits on the base circle R_p - R_f: two cylinders, P = M / (l cos phi)
    # with cos phi from the triangle O-A-C (angle between OC and the path, perpendicular to AC)
    d, l, rf, rp = 80.0, 60.0, 8.0, 45.0
    kin = evaluate(MotionProgram.from_segments([Segment("dwell", 360)]), 8)
    m = np.asarray(loads.rocker_torque(TRAIN, kin, OMEGA))  # = k x0 = 6 N m
    psi0 = math.acos((d * d + l * l - rp * rp) / (2 * d * l))
    c = np.array([d - l * math.cos(psi0), l * math.sin(psi0)])
    path = np.array([l * math.sin(psi0), l * math.cos(psi0)]) / l
    cos_phi = abs(c @ path) / np.linalg.norm(c)
    cam, fol = contact.Material(2.1e5, 0.3), contact.Material(1.15e5, 0.26)
    k = (1 - 0.3**2) / 2.1e5 + (1 - 0.26**2) / 1.15e5
    p = 6.0 / (l * 1e-3 * cos_phi)
    ref = 0.564 * math.sqrt(p / 8.0 * (1 / (rp - rf) + 1 / rf) / k)
    g = rocker_roller_geo.oscillating_roller_geometry(d, l, rf, rp, kin)
    np.testing.assert_allclose(loads.rocker_roller_contact_force(m, l, g.pressure_angle), p, rtol=1e-13)
    coeff = contact.stress_coefficient(m / (l * 1e-3), 8.0, cam, fol)
    sigma = contact.roller_stress(coeff, g.pressure_angle, roller_geo.roller_equivalent_radius(g.pitch_curvature, rf))
    np.testing.assert_allclose(sigma, ref, rtol=1e-12)


# ---------------------------------------------------------------------------------- scenes

ROLLER_SCENE = """
[motion]
rpm = 300.0
samples = 360
rotation = "ROT"
segments = [
  { kind = "rise",   angle_deg = 120, law = "cycloidal", lift_deg = 20.0 },
  { kind = "dwell",  angle_deg = 60 },
  { kind = "return", angle_deg = 120, law = "cycloidal", lift_deg = 20.0 },
  { kind = "dwell",  angle_deg = 60 },
]

[follower]
type = "oscillating_roller"
pivot_distance_mm = 80.0
arm_length_mm = 60.0
roller_radius_mm = 8.0
inertia_kg_m2 = 0.002
spring_N_m_per_rad = 20.0
preload_rad = 0.3
damping_N_m_s_per_rad = 0.01

[contact]
cam_width_mm = 8.0
cam = { E_MPa = 2.1e5, poisson = 0.3 }
follower = { E_MPa = 2.1e5, poisson = 0.3 }
"""

FLAT_SCENE = ROLLER_SCENE.replace('type = "oscillating_roller"', 'type = "oscillating_flat"').replace(
    "arm_length_mm = 60.0\nroller_radius_mm = 8.0", "face_offset_mm = 10.0").replace(
    "pivot_distance_mm = 80.0", "pivot_distance_mm = 150.0")


def test_oscillating_scene_reads_lift_deg_as_rad():
    scene = parse_scene(ROLLER_SCENE.replace("ROT", "ccw"))
    assert followers.of(scene).rocking and scene.follower.arm_length_mm == 60.0
    np.testing.assert_allclose(np.asarray(scene.motion.program.lifts), [LIFT, 0.0, LIFT, 0.0], rtol=1e-15)
    assert scene.follower.train == TRAIN
    flat = parse_scene(FLAT_SCENE.replace("ROT", "cw"))
    assert flat.follower.type == "oscillating_flat" and flat.follower.face_offset_mm == 10.0


@pytest.mark.parametrize("edit,field,words", [
    (("lift_deg = 20.0 },\n  { kind = \"dwell\",  angle_deg = 60 },\n  { kind = \"return\"",
      "lift_mm = 5.0 },\n  { kind = \"dwell\",  angle_deg = 60 },\n  { kind = \"return\""),
     "motion.segments[0].lift_mm", "lift_deg"),
    (("arm_length_mm = 60.0\n", ""), "follower.arm_length_mm", "required"),
    (("pivot_distance_mm = 80.0\n", ""), "follower.pivot_distance_mm", "required"),
    (("roller_radius_mm = 8.0\n", ""), "follower.roller_radius_mm", "required"),
    (("lift_deg = 20.0", "lift_deg = 190.0"), "motion.segments[0].lift_deg", "line of centres"),
    (("inertia_kg_m2 = 0.002", "mass_kg = 0.1"), "follower.mass_kg", "oscillating_roller"),
    (("arm_length_mm = 60.0", "arm_length_mm = 60.0\noffset_mm = 2.0"), "follower.offset_mm", "oscillating"),
    (("arm_length_mm = 60.0", "arm_length_mm = -60.0"), "follower.arm_length_mm", "range"),
])
def test_bad_oscillating_scenes_name_the_field(edit, field, words):
    text = ROLLER_SCENE.replace("ROT", "ccw")
    assert edit[0] in text
    with pytest.raises(SceneError) as err:
        parse_scene(text.replace(edit[0], edit[1], 1))
    assert err.value.field == field, str(err.value)
    assert words in str(err.value)


def test_translating_follower_refuses_lift_deg():
    text = ROLLER_SCENE.replace("ROT", "ccw").replace('type = "oscillating_roller"', 'type = "roller"')
    with pytest.raises(SceneError) as err:
        parse_scene(text)
    assert err.value.field == "motion.segments[0].lift_deg" and "lift_mm" in str(err.value)


def _design(tmp_path, text, *extra):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    out = tmp_path / "out"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
        rc = cli.main(["design", str(path), "--out", str(out), "--dpi", "30", *extra])
    return rc, out


@pytest.mark.slow
@pytest.mark.parametrize("scene,rotation", [(ROLLER_SCENE, "ccw"), (FLAT_SCENE, "cw")])
def test_design_writes_the_rocker_files(tmp_path, scene, rotation):
    rc, out = _design(tmp_path, scene.replace("ROT", rotation))
    assert rc == 0
    assert {p.name for p in out.iterdir()} == {"result.json", "svaj.png", "profile.png", "geometry.png",
                                               "loads.png", "profile.csv", "profile.dxf"}
    data = json.loads((out / "result.json").read_text(), parse_constant=lambda c: pytest.fail(c))
    ev = data["evaluated"]
    assert ev["base_radius_mm"] == math.ceil(data["min_base_radius_mm"] + 1.0)
    # the CSV is the outline the report describes: on the dwell at theta = 0 it lies on the base circle
    table = np.loadtxt(out / "profile.csv", delimiter=",", skiprows=1)
    assert math.hypot(table[0, 1], table[0, 2]) == pytest.approx(ev["base_radius_mm"], rel=1e-12)
    assert data["loads"]["contact"]["lost"] is False
    if "prime_radius_mm" in ev:  # the drawn cam is bigger than the smallest, so within the limit
        assert ev["pressure_angle_ok"] and ev["pressure_angle_deg"]["max_abs"] <= 30.0
    else:
        assert ev["curvature_ok"] and ev["face"]["min_length_mm"] > 0


@pytest.mark.parametrize("radius,words", [("5", "cannot reach the prime circle"),
                                          ("135", "cannot reach the prime circle")])  # R_p < |d - l|, > d + l
@pytest.mark.slow
def test_design_refuses_a_base_radius_the_rocker_cannot_close(tmp_path, capsys, radius, words):
    rc, out = _design(tmp_path, ROLLER_SCENE.replace("ROT", "ccw"), "--base-radius", radius)
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--base-radius" in err[0] and words in err[0]


@pytest.mark.slow  # > 2 s (a compile of its own)
def test_design_refuses_an_arm_swung_through_the_line_of_centres(tmp_path, capsys):
    # psi0 for R_p = 139 mm (d + l = 140) is ~173 deg: a 20 deg swing crosses the line of centres
    rc, out = _design(tmp_path, ROLLER_SCENE.replace("ROT", "ccw"), "--base-radius", "131")
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "line of centres" in err[0]


def test_thesis_bench_keeps_its_lifts_in_rad_exactly():
    # the dynamics of the bench read the program's lifts: lift_deg must convert back to the
    # series' 0.48337882 rad to the last bit for `camjax dynamics thesis-bench` to stay unchanged
    from camjax.scene import load_scene

    scene = load_scene("thesis-bench")
    assert scene.follower.type == "oscillating_roller" and scene.dynamics.follower == "oscillating"
    assert [float(x) for x in scene.motion.program.lifts] == [0.48337882, 0.48337882]


@pytest.mark.slow
def test_design_thesis_bench(tmp_path):
    out = tmp_path / "tb"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
        assert cli.main(["design", "thesis-bench", "--out", str(out), "--dpi", "30"]) == 0
    data = json.loads((out / "result.json").read_text())
    assert data["follower_type"] == "oscillating_roller"
    assert data["kinematics"]["swing_deg"]["max"] == pytest.approx(math.degrees(0.48337882), rel=1e-15)
    # sized by the 30 deg rule: at the smallest prime radius |phi| peaks on the limit, so the drawn
    # (1 mm larger) cam stays below it
    assert data["min_base_radius_binding"] == "pressure_angle"
    assert data["evaluated"]["pressure_angle_deg"]["max_abs"] < 30.0


@pytest.mark.slow
def test_design_refuses_a_rocker_no_cam_can_carry(tmp_path, capsys):
    # a face 10 mm from a pivot only 10 mm from the cam centre: R_b + f < d leaves no base circle
    text = FLAT_SCENE.replace("ROT", "ccw").replace("pivot_distance_mm = 150.0", "pivot_distance_mm = 10.0")
    rc, out = _design(tmp_path, text)
    assert rc == 2 and not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "follower.pivot_distance_mm" in err[0]


# A [design] that frees the pivot (and the arm or the face offset): result.json reports the solved
# dimensions and keeps the scene's under follower_scene (tests/test_reported_values.py, every type).


# --------------------------------------------------------------------------------- figures


@pytest.fixture(scope="module")
def rocker_report():
    from camjax.pipeline import analyse

    return analyse(parse_scene(ROLLER_SCENE.replace("ROT", "cw"), "rocker"))


@pytest.mark.slow
def test_rocker_figures_carry_the_title_block_with_the_pivot_and_arm(rocker_report):
    from camjax.followers import drawing
    from camjax.output.titles import title_block

    data = rocker_report.data
    title = title_block(data)
    lines = title.splitlines()
    assert len(lines) == 3 and "scene rocker" in lines[0] and "clockwise" in lines[0]
    assert "oscillating_roller follower" in lines[0]
    assert lines[1] == "rise 120° cycloidal 20° · dwell 60° · return 120° cycloidal 20° · dwell 60°"
    f = data["oscillating_follower"]
    assert f"R_b = {data['evaluated_at']['base_radius_mm']:.3f} mm" in lines[2]
    assert f"d = {f['pivot_distance_mm']:g} mm, l = {f['arm_length_mm']:g} mm, R_f = 8 mm" in lines[2]
    curves = rocker_report.curves
    figures = {name: build(curves, title) for name, build in drawing(curves.follower_type).figure_builders(curves).items()}
    assert set(figures) == {"svaj.png", "profile.png", "geometry.png", "loads.png"}
    for name, fig in figures.items():
        assert fig._suptitle is not None and title in fig._suptitle.get_text(), name


def _spiky_curves():
    # the cam of a solved design (pivot 78.49 mm, arm 67.75 mm): its pitch curve has inflections,
    # where the cam-surface radius rho_c = rho_pitch - R_f runs off to +-infinity between samples
    import dataclasses

    from camjax import followers
    from camjax.evaluate import scene_arrays

    scene = parse_scene(ROLLER_SCENE.replace("ROT", "ccw").replace("samples = 360", "samples = 180").replace(
        '{ kind = "return", angle_deg = 120, law = "cycloidal", lift_deg = 20.0 },\n  { kind = "dwell",  angle_deg = 60 },',
        '{ kind = "return", angle_deg = 100, law = "poly_3_4_5", lift_deg = 20.0 },\n  { kind = "dwell",  angle_deg = 80 },'))
    scene = dataclasses.replace(scene, follower=dataclasses.replace(
        scene.follower, pivot_distance_mm=78.48648745161735, arm_length_mm=67.74966987155759))
    a = scene_arrays(scene)
    return followers.of(scene).evaluate(scene, a.kin, a.cam_speed_rad_s, 24.66442332838182)


def test_rho_panel_is_clipped_to_the_cams_size_and_marks_what_it_clips():
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from camjax.followers._rocking_drawing import geometry_figure

    c = _spiky_curves()
    limit = 4.0 * float(np.max(np.hypot(c.profile_x_mm, c.profile_y_mm)))  # 4 x the cam's largest radius
    over, under = c.rho_mm > limit, c.rho_mm < -limit
    assert over.any()  # the spike the panel used to scale itself to (7874 mm here, R_max = 48 mm)
    fig = geometry_figure(c, "title")
    FigureCanvasAgg(fig).draw()
    ax = fig.axes[1]
    low, high = ax.get_ylim()
    assert -limit <= low and high <= limit  # the axis spans at most +-4 R_max
    assert low <= float(np.min(c.rho_mm[~under])) and float(np.max(c.rho_mm[~over])) <= high
    # every clipped run carries a marker on the edge it leaves by; the largest value is written
    edge = [ln for ln in ax.get_lines() if ln.get_marker() in ("^", "v")]
    ups = sum(len(ln.get_xdata()) for ln in edge if ln.get_marker() == "^")
    runs = np.count_nonzero(np.diff(np.concatenate([[0], over.astype(int), [0]])) == 1)
    assert ups == runs
    texts = " ".join(t.get_text() for t in ax.texts)
    assert f"{float(np.max(c.rho_mm)):.4g} mm" in texts and "clipped" in ax.get_title(loc="right")
    # no dot calls an in-range value the maximum while larger ones run off the top
    assert not any(t.get_text().startswith(f"{float(np.max(c.rho_mm[~over])):.4g} @") for t in ax.texts)


@pytest.mark.slow
def test_rho_panel_keeps_its_whole_range_when_nothing_is_clipped(rocker_report):
    from camjax.followers._rocking_drawing import geometry_figure

    c = rocker_report.curves
    assert np.max(np.abs(c.rho_mm)) < 4.0 * float(np.max(np.hypot(c.profile_x_mm, c.profile_y_mm)))
    ax = geometry_figure(c, "title").axes[1]
    low, high = ax.get_ylim()
    assert low <= float(np.min(c.rho_mm)) and float(np.max(c.rho_mm)) <= high
    assert "clipped" not in ax.get_title(loc="right")


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in followers.names() if followers.get(n).rocking])
def test_refined_extrema_take_the_design_as_data(name, monkeypatch):
    """A rocker's exact extrema take the dimensions a design varies and the base radius as data:
    the scene's follower and another design (each such dimension 5 % + 0.5 mm larger, the base
    radius 2 mm larger) run one compiled program, and the other design's extrema are its own:
    never beaten by a 20 000-sample grid of its curves (beyond round-off), and where they differ
    from it by more than 1e-6 of the curve's scale (a grid of h = 0.018 deg misses a smooth peak
    by about |f''| h^2 / 8, less than that), a grid four times as fine comes closer."""
    from dataclasses import replace

    from camjax import runtime
    from camjax.evaluate import scene_arrays
    from camjax.followers._rocking import _refined_curves
    from camjax.scene import load_scene

    monkeypatch.setattr(runtime, "_PROGRAM_DIR", [None])  # jax.jit's own cache counts the programs
    kind, scene = followers.get(name), load_scene(followers.get(name).example_scene)
    arrays = scene_arrays(scene, extrema="exact")
    sizing = kind.sizing(scene, arrays.kin, arrays.model.program)
    radius, _ = kind.drawing_radius(scene, arrays.kin, sizing)
    other = replace(scene.follower, **{k: 1.05 * v + 0.5 for k, v in kind.design_numbers(scene.follower).items()})
    other_radius = radius + 2.0
    assert kind.closure_problem(replace(scene, follower=other), arrays.kin, other_radius) is None

    kind.curve_extremes(scene, arrays, None, radius)
    programs = _refined_curves.jitted._cache_size()
    exact = kind.curve_extremes(scene, arrays, None, other_radius, follower=other)
    assert _refined_curves.jitted._cache_size() == programs  # the other design: the same program

    def grid(samples):
        dense = with_samples(scene, samples)
        return kind.curve_extremes(dense, scene_arrays(dense, extrema="grid"), tuple(exact), other_radius,
                                   follower=other)

    coarse, fine = grid(20_000), None
    for key, e in exact.items():
        g, scale = coarse[key], max(abs(e.max), abs(e.min), 1e-300)
        assert e.max >= g.max - 1e-12 * scale and e.min <= g.min + 1e-12 * scale, (key, e, g)
        for value, sampled, sense in ((e.max, g.max, "max"), (e.min, g.min, "min")):
            if abs(value - sampled) > 1e-6 * scale:  # a sharp peak: a grid four times as fine comes closer
                fine = fine or grid(80_003)
                assert abs(value - getattr(fine[key], sense)) < abs(value - sampled), (key, sense, e, g)
