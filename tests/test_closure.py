"""Positive drive (groove and conjugate cams) of both roller followers, against independent checks.

Every check reads the files camjax writes (profile.csv, profile.dxf, result.json) and recomputes from
positions only: the rollers ride the exported flanks and cams (brute-force distance from each roller
centre to the whole closed polyline), the yoke and the two-arm rocker stay rigid, and the load's
sign switches match a finite-difference acceleration of the exported motion.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

import camjax
from camjax import cli, followers
from camjax.errors import SceneError
from camjax.output import export
from camjax.scene import builtin_scene_text, parse_scene, with_samples

SAMPLES = 7200
# riding tolerance: the polyline's chords cut inside a convex flank by at most (arc step)^2 / (8 rho):
# (2 pi 60 mm / 7200)^2 / (8 x 10 mm) ~ 3e-6 mm at the smallest radii here, far below 1 um
RIDE_TOL_MM = 1e-3


def _scene_text(name: str, old: str, new: str, drop: tuple[str, ...] = ()) -> str:
    text = builtin_scene_text(name)
    assert old in text
    text = text.replace(old, new)
    for line in drop:
        assert line in text
        text = text.replace(line + "\n", "")
    return text


ROCKER_GROOVE = _scene_text("oscillating-roller", 'type = "oscillating_roller"\n',
                            'type = "oscillating_roller"\nclosure = "groove"\ngroove_clearance_mm = 0.05\n',
                            ("spring_N_m_per_rad = 20.0", "preload_rad = 0.3"))
YOKE = _scene_text("groove", 'closure = "groove"', 'closure = "conjugate"', ()).replace(
    "groove_clearance_mm = 0.02    # the outer flank lies R_f + this from the pitch curve",
    "yoke_span_mm = 70.0\nsecond_roller_radius_mm = 5.0")
CASES = {"groove": builtin_scene_text("groove"), "rocker_groove": ROCKER_GROOVE, "yoke": YOKE,
         "conjugate": builtin_scene_text("conjugate")}


def _run(text: str, folder):
    """The scene without [design] on 7200 samples (grid extrema: the files' samples are what is
    checked), its report and profile.csv/DXF written and read back, and the run itself."""
    scene = with_samples(parse_scene(text), SAMPLES)
    scene = replace(scene, design=None, motion=replace(scene.motion, extrema="grid"))
    run = camjax.run_design(scene)
    data = followers.of(scene).report(scene, run)
    export.write_profile_csv(folder / "profile.csv", run.curves)
    export.write_profile_dxf(folder / "profile.dxf", run.curves)
    with open(folder / "profile.csv") as f:
        names = f.readline().strip().split(",")
    table = np.loadtxt(folder / "profile.csv", delimiter=",", skiprows=1)
    return scene, data, {n: table[:, k] for k, n in enumerate(names)}, run


class _Exported(dict):
    """Each case's (scene, result, columns, run, folder), run when a test first asks for it: the quick
    loop runs the groove and the conjugate cams; the yoke and the rocker's groove are slow cases."""

    def __init__(self, tmp_path_factory):
        super().__init__()
        self._tmp = tmp_path_factory

    def __missing__(self, name):
        folder = self._tmp.mktemp(name)
        self[name] = _run(CASES[name], folder) + (folder,)
        return self[name]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    return _Exported(tmp_path_factory)


SLOW = pytest.mark.slow


def _segment_distances(x, y, ax, ay, dx, dy):
    """Distance from points (x, y) to segments from (ax, ay) along (dx, dy), broadcast."""
    u = np.clip(((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy), 0.0, 1.0)
    return np.hypot(x - ax - u * dx, y - ay - u * dy)


def _distances(cx, cy, px, py, near=48):
    """Distance (mm) from each centre (cx, cy) to the closed polyline (px, py): the exact minimum
    over every segment that can be the nearest. The nearest vertex is at D; each point of a segment
    lies within L/2 of one of its ends (L <= the longest segment), so a segment with both ends farther
    than D + L/2 is farther than D: the segments at the ``near`` nearest vertices (a k-d tree) hold
    the minimum wherever the next vertex is that far; elsewhere every segment is measured."""
    from scipy.spatial import cKDTree

    dx, dy = np.roll(px, -1) - px, np.roll(py, -1) - py
    centres = np.column_stack([cx, cy])
    dist, idx = cKDTree(np.column_stack([px, py])).query(centres, k=near)
    segments = np.concatenate([idx, (idx - 1) % len(px)], axis=1)  # those starting or ending there
    x, y = cx[:, None], cy[:, None]
    out = np.min(_segment_distances(x, y, px[segments], py[segments], dx[segments], dy[segments]), axis=1)
    unsure = dist[:, -1] <= dist[:, 0] + 0.5 * np.max(np.hypot(dx, dy))
    for k in np.flatnonzero(unsure):  # the whole polyline
        out[k] = np.min(_segment_distances(cx[k], cy[k], px, py, dx, dy))
    return out


def _pivot(scene, theta_deg):
    """The rocker's pivot (d, 0) of the follower frame in cam coordinates (rotation by -sign theta)."""
    sign = 1.0 if scene.motion.rotation == "ccw" else -1.0
    t = np.radians(theta_deg)
    d = scene.follower.pivot_distance_mm
    return d * np.cos(t), -sign * d * np.sin(t)


@pytest.mark.parametrize("case", ["groove", pytest.param("rocker_groove", marks=SLOW)])
def test_the_roller_rides_both_exported_flanks(exported, case):
    scene, data, col = exported[case][:3]
    rf, c = scene.follower.roller_radius_mm, scene.follower.closure.clearance_mm
    assert c > 0
    px, py = col["pitch_x_mm"], col["pitch_y_mm"]
    inner = _distances(px, py, col["inner_x_mm"], col["inner_y_mm"])
    outer = _distances(px, py, col["outer_x_mm"], col["outer_y_mm"])
    # the roller touches the inner flank and clears the outer one by exactly the clearance
    assert np.max(np.abs(inner - rf)) < RIDE_TOL_MM
    assert np.max(np.abs(outer - (rf + c))) < RIDE_TOL_MM
    assert np.array_equal(col["inner_x_mm"], col["x_mm"])  # the inner flank is the cam profile
    assert data["closure"]["kind"] == "groove" and data["evaluated_at"]["feasible"]


@pytest.mark.parametrize("case", [pytest.param("yoke", marks=SLOW), "conjugate"])
def test_both_rollers_ride_their_exported_cams(exported, case):
    scene, data, col = exported[case][:3]
    r1, r2 = scene.follower.roller_radius_mm, scene.follower.closure.second_roller_radius_mm
    first = _distances(col["pitch_x_mm"], col["pitch_y_mm"], col["x_mm"], col["y_mm"])
    second = _distances(col["conjugate_pitch_x_mm"], col["conjugate_pitch_y_mm"], col["conjugate_x_mm"],
                        col["conjugate_y_mm"])
    assert np.max(np.abs(first - r1)) < RIDE_TOL_MM
    assert np.max(np.abs(second - r2)) < RIDE_TOL_MM
    assert data["closure"]["kind"] == "conjugate"


@SLOW
def test_the_yoke_is_rigid_on_the_exported_pitch_curves(exported):
    scene, _, col = exported["yoke"][:3]
    span = np.hypot(col["pitch_x_mm"] - col["conjugate_pitch_x_mm"], col["pitch_y_mm"] - col["conjugate_pitch_y_mm"])
    assert np.max(np.abs(span - scene.follower.closure.yoke_span_mm)) < 1e-9
    # and the two centres stay on one line through the follower axis' direction: the axis at theta
    theta = np.radians(col["theta_deg"])
    axis = np.stack([np.sin(theta), np.cos(theta)])  # +Y of the follower frame seen from a ccw cam
    along = ((col["pitch_x_mm"] - col["conjugate_pitch_x_mm"]) * axis[0]
             + (col["pitch_y_mm"] - col["conjugate_pitch_y_mm"]) * axis[1])
    assert np.max(np.abs(along - scene.follower.closure.yoke_span_mm)) < 1e-9


def test_the_two_arm_rocker_is_rigid_on_the_exported_pitch_curves(exported):
    scene, _, col = exported["conjugate"][:3]
    f, cl = scene.follower, scene.follower.closure
    ax, ay = _pivot(scene, col["theta_deg"])
    l1 = np.hypot(col["pitch_x_mm"] - ax, col["pitch_y_mm"] - ay)
    l2 = np.hypot(col["conjugate_pitch_x_mm"] - ax, col["conjugate_pitch_y_mm"] - ay)
    chord = np.hypot(col["pitch_x_mm"] - col["conjugate_pitch_x_mm"], col["pitch_y_mm"] - col["conjugate_pitch_y_mm"])
    beta = math.radians(cl.second_arm_angle_deg)
    assert np.max(np.abs(l1 - f.arm_length_mm)) < 1e-9
    assert np.max(np.abs(l2 - cl.second_arm_length_mm)) < 1e-9
    want = math.sqrt(f.arm_length_mm**2 + cl.second_arm_length_mm**2
                     - 2 * f.arm_length_mm * cl.second_arm_length_mm * math.cos(beta))
    assert np.max(np.abs(chord - want)) < 1e-9


def _sign_changes(theta_deg, load):
    """Angles (deg) where a sampled load changes sign, linear between samples (cyclic), skipping
    exact zeros."""
    keep = np.flatnonzero(np.abs(load) > 1e-9 * np.max(np.abs(load)))
    out = []
    for i, j in zip(keep, np.roll(keep, -1), strict=True):
        if np.sign(load[i]) != np.sign(load[j]):
            step = ((theta_deg[j] - theta_deg[i]) % 360.0)
            out.append((theta_deg[i] + step * load[i] / (load[i] - load[j])) % 360.0)
    return np.sort(out)


@pytest.mark.parametrize("case", ["groove", pytest.param("yoke", marks=SLOW)])
def test_translating_switches_match_a_finite_difference_acceleration(exported, case):
    scene, data, col = exported[case][:3]
    train = scene.follower.train
    omega = scene.motion.rpm * 2.0 * math.pi / 60.0
    h = math.radians(360.0 / SAMPLES)
    s = col["s_mm"] * 1e-3
    v = (np.roll(s, -1) - np.roll(s, 1)) / (2 * h) * omega
    a = (np.roll(s, -1) - 2 * s + np.roll(s, 1)) / h**2 * omega**2
    load = train.mass_kg * (a + train.gravity_m_s2) + train.damping_Ns_per_m * v
    want = _sign_changes(col["theta_deg"], load)
    got = np.array(data["closure"]["switch_angles_deg"])
    assert len(got) == len(want) >= 2
    # the FD acceleration is O(h^2) off: its zero moves by far less than one sample (0.05 deg)
    assert np.max(np.abs(got - want)) < 0.01
    for sw in data["closure"]["switches"]:  # the contact that takes over carries the load's sign
        i = int(round(sw["angle_deg"] / (360.0 / SAMPLES)) + 2) % SAMPLES
        assert (load[i] > 0) == (sw["to"] in ("inner", "first"))
        assert np.sign(sw["load_rate_N_per_deg"]) == np.sign(load[i])


@pytest.mark.parametrize("case", [pytest.param("rocker_groove", marks=SLOW), "conjugate"])
def test_rocker_switches_match_a_finite_difference_acceleration(exported, case):
    scene, data, col = exported[case][:3]
    h = math.radians(360.0 / SAMPLES)
    psi = np.radians(col["swing_deg"])
    moment = scene.follower.train.inertia_kg_m2 * (np.roll(psi, -1) - 2 * psi + np.roll(psi, 1)) / h**2
    want = _sign_changes(col["theta_deg"], moment)
    got = np.array(data["closure"]["switch_angles_deg"])
    assert len(got) == len(want) >= 2
    assert np.max(np.abs(got - want)) < 0.06  # a zero on a dwell's edge: within a sample


def test_each_flank_and_cam_is_a_dxf_layer(exported):
    import ezdxf

    for case, layers in (("groove", ("GROOVE_INNER", "GROOVE_OUTER")), ("conjugate", ("CAM_PROFILE", "CONJUGATE_CAM"))):
        _, _, col, _, folder = exported[case]
        doc = ezdxf.readfile(folder / "profile.dxf")
        polylines = {p.dxf.layer: np.array(p.get_points("xy")) for p in doc.modelspace().query("LWPOLYLINE")}
        assert set(polylines) == set(layers)
        names = {"GROOVE_INNER": "inner", "GROOVE_OUTER": "outer", "CAM_PROFILE": "", "CONJUGATE_CAM": "conjugate"}
        for layer, xy in polylines.items():
            prefix = names[layer] + "_" if names[layer] else ""
            assert np.max(np.abs(xy - np.column_stack([col[f"{prefix}x_mm"], col[f"{prefix}y_mm"]]))) < 1e-9


def test_the_outer_flank_limit_is_the_pitch_curves_concavity():
    """The outer flank's margin is |rho_pitch| - R_f - c on concave parts: a concave pitch curve of
    radius rho (a circle seen from outside) against a roller of R_f + c, closed form."""
    from camjax.followers import _closure

    kappa = np.array([-1 / 10.0, -1 / 6.0, 0.0, 1 / 8.0])
    margin = np.asarray(_closure.outer_flank_margin(kappa, 6.0 + 0.5))
    assert margin[0] == pytest.approx(10.0 - 6.5) and margin[1] == pytest.approx(6.0 - 6.5)
    assert margin[2] > 1e300 and margin[3] > 1e300
    g = np.asarray(_closure.outer_flank_constraint(kappa, 6.5))
    assert np.all((g <= 0) == (np.minimum(margin, 1e9) >= 0))
    # the equivalent radius on the outer flank: 1 / (1/R_f - 1/(rho + R_f + c)), rho = 8 (convex pitch)
    rho_eq = float(_closure.outer_equivalent_radius(1 / 8.0, 6.0, 0.5))
    assert rho_eq == pytest.approx(1.0 / (1 / 6.0 - 1 / (8.0 + 6.5)), rel=1e-12)


BAD = {
    "flat_groove": ("default", "[follower]\n", '[follower]\nclosure = "groove"\n', "follower.closure"),
    "negative_clearance": ("groove", "groove_clearance_mm = 0.02", "groove_clearance_mm = -0.1",
                           "follower.groove_clearance_mm"),
    "clearance_on_spring": ("roller", "offset_mm = 0.0", "offset_mm = 0.0\ngroove_clearance_mm = 0.1",
                            "follower.groove_clearance_mm"),
    "span_inside_shaft": (YOKE, "yoke_span_mm = 70.0", "yoke_span_mm = 20.0", "follower.yoke_span_mm"),
    "arm_on_the_same_side": ("conjugate", "second_arm_angle_deg = 80.0", "second_arm_angle_deg = 10.0",
                             "follower.second_arm_angle_deg"),
    "yoke_on_a_rocker": ("conjugate", "second_arm_length_mm = 60.0", "yoke_span_mm = 60.0",
                         "follower.yoke_span_mm"),
}


# refused after the sizing, where the cam's size is known (a run up to the drawing): the full suite's;
# the rest are refused as the scene is read
AFTER_SIZING = ("arm_on_the_same_side", "span_inside_shaft")


@pytest.mark.parametrize("case", [pytest.param(c, marks=SLOW) if c in AFTER_SIZING else c for c in sorted(BAD)])
def test_bad_closures_exit_2_naming_the_field(case, tmp_path, capsys):
    name, old, new, field = BAD[case]
    text = builtin_scene_text(name) if "\n" not in name else name
    assert old in text
    bad = tmp_path / "bad.toml"
    # without [design], on the samples: the span and the second arm are judged where the cam's size
    # is known, after its sizing
    text = text.replace(old, new, 1).split("\n[design]")[0].replace("[motion]\n", '[motion]\nextrema = "grid"\n')
    bad.write_text(text)
    assert cli.main(["design", str(bad), "--out", str(tmp_path / "out"), "--samples", "360"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f" {field}" in err[0], err


def test_spring_scenes_parse_to_the_spring_closure():
    for name in ("roller", "oscillating-roller", "default"):
        assert camjax.load_scene(name).follower.closure.kind == "spring"
    with pytest.raises(SceneError, match="follower.closure"):
        parse_scene(builtin_scene_text("roller").replace('type = "roller"', 'type = "roller"\nclosure = "box"'))


@pytest.fixture
def no_figures(monkeypatch):
    """The design and sweep commands' figures not drawn (~0.7 CPU s a design): no figure is checked
    here (tests/test_followers.py checks they are drawn); profile.csv, profile.dxf and the JSON are
    written as the command writes them."""
    from camjax.solvers import sweep

    class NoFigure:
        def savefig(self, *args, **kwargs):
            pass

    monkeypatch.setattr(export, "write_figures", lambda *args, **kwargs: [])
    monkeypatch.setattr(sweep, "plot_pareto", lambda *args, **kwargs: NoFigure())


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["groove", "conjugate", "wide_groove"])
def test_design_and_sweep_run_on_both_closures(scene, tmp_path, capsys, no_figures):
    wide = scene == "wide_groove"
    if wide:  # the outer flank binds the design
        (tmp_path / "wide.toml").write_text(WIDE)
        scene = str(tmp_path / "wide.toml")
    assert cli.main(["design", scene, "--out", str(tmp_path / "design"), "--dpi", "40"]) == 0
    data = json.loads((tmp_path / "design" / "result.json").read_text())
    assert data["closure"]["positive_drive"] and data["design"]["feasible"]
    assert data["evaluated_at"]["feasible"], data["evaluated_at"]["violations"]
    table = np.loadtxt(tmp_path / "design" / "profile.csv", delimiter=",", skiprows=1)
    names = (tmp_path / "design" / "profile.csv").read_text().splitlines()[0].split(",")
    second = "outer_margin_mm" if data["closure"]["kind"] == "groove" else "conjugate_margin_mm"
    assert np.min(table[:, names.index(second)]) > -1e-6  # the design keeps the second contact cuttable
    if wide:  # the outer flank binds: its margin at the samples within 0.01 mm of 0 (measured 0.0017 mm;
        # exact extrema hold it >= 0 between the samples, so the samples sit a grid step's sag above 0).
        # The sweep on a groove is the built-in groove's (the same programs, another scene's values).
        assert np.min(table[:, names.index(second)]) < 0.01
        return
    # the sweep on the design's grid, one weighting per compiled call: its solve program is the one
    # the design above compiled (the same problem, one weighting), so the sweep compiles nothing of
    # its own; what is checked is that it runs on the closure's problem and finds a front
    assert cli.main(["sweep", scene, "--out", str(tmp_path / "sweep"), "--chunk-size", "1", "--alpha", "1",
                     "--gamma", "0,0.1"]) == 0
    records = json.loads((tmp_path / "sweep" / "pareto.json").read_text())["records"]
    assert len(records) == 2 and all(r["feasible"] for r in records) and any(r["pareto"] for r in records)


def _edited(name: str, edits) -> str:
    """A built-in scene's text with each (old, new) of ``edits`` replaced (each old found once)."""
    text = builtin_scene_text(name)
    for old, new in edits:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


# A wide groove (R_o = R_f + 10 mm) under a 45-degree limit: the outer flank's concavity, not the first
# contact, sets the smallest cam, and the design sits on it. Only values differ from the built-in
# groove (its segments' angles, which the motion program carries in its tree structure, are the same):
# its design runs the built-in groove's compiled programs.
WIDE_EDITS = (("max_pressure_angle_deg = 30.0", "max_pressure_angle_deg = 45.0"),
               ("groove_clearance_mm = 0.02 ", "groove_clearance_mm = 10.0 "))
WIDE = _edited("groove", WIDE_EDITS)
# edits of a built-in scene's values only: the design problem's and the sizing's data change, their
# tree structures and shapes do not
VALUE_EDITS = {
    "groove": (*WIDE_EDITS, ("min_curvature_radius_mm = 1.0", "min_curvature_radius_mm = 0.5"),
               ("sigma_max_MPa = 1200.0", "sigma_max_MPa = 1500.0")),
    "conjugate": (("second_arm_length_mm = 60.0", "second_arm_length_mm = 55.0"),
                  ("second_arm_angle_deg = 80.0", "second_arm_angle_deg = 85.0"),
                  ("roller_radius_mm = 8.0", "roller_radius_mm = 7.0\nsecond_roller_radius_mm = 6.0"),
                  ("max_pressure_angle_deg = 30.0", "max_pressure_angle_deg = 35.0")),
}


# the conjugate pair in the full suite only (1.2 s): the groove's case runs the same check in the quick loop
@pytest.mark.parametrize("name", ["groove", pytest.param("conjugate", marks=SLOW)])
def test_scenes_that_differ_in_values_only_share_the_closure_programs(name):
    """A positive drive's values (clearance, second arm, second roller, limits) are data: another
    scene of the same shape has the design program's key (camjax.runtime.program_key: the tree
    structure and shapes of its arguments) and runs the sizing's compiled second-contact program
    again (its jit cache does not grow), and a rocker's drawing its second cam's program."""
    from camjax import runtime
    from camjax.evaluate import scene_arrays
    from camjax.followers.oscillating_roller.follower import _second_start_angle
    from camjax.followers.roller.follower import _second_prime_radius
    from camjax.solvers.base import problem_from_scene

    scenes = [camjax.load_scene(name), parse_scene(_edited(name, VALUE_EDITS[name]))]
    arrays = [scene_arrays(s, extrema="grid") for s in scenes]  # the sizing on the samples
    problems = [problem_from_scene(s, a) for s, a in zip(scenes, arrays, strict=True)]
    assert problems[0].closure[0] != problems[1].closure[0]  # the clearance, the second arm: edited
    keys = {runtime.program_key("solve", {}, {"problem": p}) for p in problems}
    assert len(keys) == 1
    follower = followers.of(scenes[0])
    program = (_second_start_angle if follower.rocking else _second_prime_radius).jitted
    sizes, sized = [], []
    for scene, a in zip(scenes, arrays, strict=True):
        sized.append(follower.sizing(scene, a.kin) if follower.rocking else follower.min_base_radius(scene, a))
        sizes.append(program._cache_size())
    assert sizes[0] >= 1 and sizes[1] == sizes[0]  # compiled for the first scene, run again for the other
    if follower.rocking:  # the second arm's cam (the drawing's): its arm and roller are the program's data
        from camjax.followers.oscillating_roller.follower import _arm_curves

        cams = []
        for scene, a, size in zip(scenes, arrays, sized, strict=True):
            f, c = scene.follower, scene.follower.closure
            second = (c.second_arm_length_mm, c.second_arm_angle_deg, c.second_roller_radius_mm)
            out, _ = _arm_curves(second, f.pivot_distance_mm, f.arm_length_mm, f.roller_radius_mm,
                                 size.min_prime_radius_mm + 1.0, a.kin, scene.motion.rotation,
                                 f.min_curvature_radius_mm, None, None)
            cams.append(np.asarray(out["conjugate_x_mm"]))
            sizes.append(_arm_curves._cache_size())
        assert sizes[2] >= 1 and sizes[3] == sizes[2]
        assert not np.allclose(cams[0], cams[1])  # each scene its own second cam


def _turning_radii(x, y):
    """Signed radius (mm) of the circle through each vertex and its two neighbours of a closed
    polyline: > 0 where it turns left (counterclockwise)."""
    ax, ay, bx, by = np.roll(x, 1) - x, np.roll(y, 1) - y, np.roll(x, -1) - x, np.roll(y, -1) - y
    cross = ax * by - ay * bx
    a, b, c = np.hypot(ax, ay), np.hypot(bx, by), np.hypot(bx - ax, by - ay)
    return -a * b * c / (2.0 * cross)  # the polyline runs clockwise (a ccw cam): left turns are concave parts


def test_the_smallest_groove_keeps_its_outer_flank_cuttable(tmp_path):
    """A wide groove under a 45-degree limit: the outer flank, not the first contact, sets the smallest cam.
    There the outer flank's tightest convex bend (seen from the roller: where the pitch curve is
    concave) is min_curvature_radius_mm, measured on the exported outline by three-point circles;
    1 mm smaller and it is tighter and the run reports the broken outer flank."""
    scene = with_samples(parse_scene(WIDE), SAMPLES)
    scene = replace(scene, design=None, motion=replace(scene.motion, extrema="grid"))
    run = camjax.run_design(scene)
    minimum = run.min_base_radius
    assert minimum.binding == "outer_flank"
    rho_min = scene.follower.min_curvature_radius_mm

    def tightest(radius):
        r = camjax.run_design(scene, base_radius_mm=radius)
        own = r.curves.own_curves
        turning = _turning_radii(own["outer_x_mm"], own["outer_y_mm"])
        return float(np.min(turning[turning > 0])), r.violations

    at_min, ok = tightest(minimum.radius_mm)
    assert at_min == pytest.approx(rho_min, abs=2e-4) and not ok  # three-point circles: O(h^2) ~ 1e-5 mm
    smaller, broken = tightest(minimum.radius_mm - 1.0)
    assert smaller < rho_min - 0.05 and [v.constraint for v in broken] == ["outer_flank"]


@pytest.mark.parametrize("case", ["groove", "yoke", "conjugate"])
def test_closure_constraints_have_finite_gradients_inside_and_far_outside_the_box(case):
    """The design problems' second-contact constraints: finite values and gradients for a design in
    the box and for one far outside it (a tiny cam, the second roller on the shaft)."""
    import jax
    import jax.numpy as jnp

    from camjax.solvers.base import problem_from_scene

    text = {"groove": builtin_scene_text("groove"), "yoke": YOKE, "conjugate": builtin_scene_text("conjugate")}[case]
    scene = parse_scene(text.replace("[motion]\n", '[motion]\nextrema = "grid"\n'))
    problem = problem_from_scene(scene)
    module = followers.of(scene).problem_module()
    assert problem.closure is not None
    mid = jax.tree.map(lambda lo, hi: 0.5 * (lo + hi), problem.lower, problem.upper)
    far = jax.tree.map(lambda lo: 0.05 * lo, problem.lower)
    total = jax.jit(jax.value_and_grad(lambda d: sum(jnp.sum(c) for c in module.constraints(problem, d))))
    for design in (mid, far):
        value, grad = total(design)
        assert np.isfinite(float(value)) and all(np.isfinite(np.asarray(g)).all() for g in jax.tree.leaves(grad))


def test_a_positive_drive_has_no_jump_analysis():
    text = builtin_scene_text("groove") + '\n[dynamics]\nfollower = "translating"\nI3 = 0.1\nc3 = 1.0\nk23 = 1e6\n' \
        'compute = ["jump"]\nspring_rate = 1000.0\n'
    with pytest.raises(SceneError, match=r"dynamics\.compute.*positive drive"):
        parse_scene(text)


# a roller drawn on its cam's polyline: the chords cut inside a convex cam by at most
# (arc step)^2 / (8 rho) ~ (2 pi 70 mm / 7200)^2 / (8 x 5 mm) ~ 1e-5 mm, far below 1e-3 mm; the run is
# the exported case's (its 7200 samples), so no sizing of another grid is compiled for the drawing


@pytest.mark.parametrize("case", [pytest.param("yoke", marks=SLOW), "conjugate"])
def test_the_animation_draws_the_second_roller_on_its_cam_and_keeps_the_link_rigid(exported, case):
    """At every 9th frame of the animation: the second roller drawn touches the second cam as drawn
    (distance from its centre to the drawn polyline = its radius, positions only) and the link that
    carries it is rigid: the yoke's length is yoke_span_mm, the second arm's second_arm_length_mm."""
    from camjax.output.animation import motion_frames

    scene, _, _, run, _ = exported[case]
    m = followers.drawing(scene.follower.type).mechanism(run.curves)
    mf = motion_frames(m, 72)
    closure = scene.follower.closure
    link = closure.second_arm_length_mm if case == "conjugate" else closure.yoke_span_mm
    for i in range(0, 72, 9):
        mf.update(i)
        circle = mf.artists["second_roller"]
        (cx, cy), radius = circle.center, circle.radius
        x2, y2 = (np.asarray(v) for v in mf.artists["second_cam"].get_data())
        gap = _distances(np.array([cx]), np.array([cy]), x2, y2)[0]
        assert gap == pytest.approx(radius, abs=1e-3), (i, gap, radius)
        (x0, x1), (y0, y1) = mf.artists["second_link"].get_data()
        assert (x1, y1) == (cx, cy)
        assert math.hypot(x1 - x0, y1 - y0) == pytest.approx(link, abs=1e-6), i


# ------------------------------------------------------------------ the free span or arm angle

FREE = {  # scene text, [design] key, bounds whose low end the second cam cannot hold; size only (gamma 0)
    "yoke": (YOKE.replace("gamma = 0.0 ", "yoke_span_mm = [20.0, 120.0]\ngamma = 0.0 "), "yoke_span_mm"),
    "conjugate": (builtin_scene_text("conjugate").replace("gamma = 0.1", "gamma = 0.0\nsecond_arm_angle_deg = [30.0, 170.0]"),
                  "second_arm_angle_deg"),
}
# the chosen value against the positions' scan: the design judges 360 samples, the scan 7200, where
# the second cam's largest pressure angle can exceed the 360 samples' by ~ (0.5 deg)^2 / 2 x its
# second derivative over the cam angle (< 1 deg/deg^2 here): SAMPLING_DEG = 0.01 deg over the limit
# is admitted; the chosen value then sits within 0.02 (mm of span, deg of arm angle: the pressure
# angle moves by > 0.5 deg per mm or deg of either near the choice) of the scan's smallest
SAMPLING_DEG = 0.01
FREE_TOL = 0.02


def _second_pressure_angle_deg(cx, cy, path_x, path_y):
    """The second cam's largest pressure angle (deg) from the second roller's centres (cam frame) and
    the direction that cam drives each (any length, either sign): the angle between the curve's
    normal (central differences, O(h^2) at h = 0.05 deg) and that direction."""
    tx, ty = np.roll(cx, -1) - np.roll(cx, 1), np.roll(cy, -1) - np.roll(cy, 1)
    cos_phi = np.abs(-ty * path_x + tx * path_y) / (np.hypot(tx, ty) * np.hypot(path_x, path_y))
    return float(np.degrees(np.arccos(np.min(np.clip(cos_phi, 0.0, 1.0)))))


def _second_cam_cuttable(cx, cy, r2, rho_min):
    """The second roller off the shaft and the second cam's convex radius >= rho_min where its pitch
    curve bends towards the cam centre (three-point circles)."""
    radius = np.abs(_turning_radii(cx, cy))
    ax, ay = np.roll(cx, 1) + np.roll(cx, -1) - 2 * cx, np.roll(cy, 1) + np.roll(cy, -1) - 2 * cy
    convex = ax * -cx + ay * -cy > 0
    return np.min(np.hypot(cx, cy)) > r2 and np.min(radius[convex], initial=np.inf) >= r2 + rho_min


def _first_within(f, limit, low, high, steps=400, iterations=60):
    """The smallest value in [low, high] with f <= limit (positions only): a scan, the least f refined
    by a golden section where no scanned value is within (a narrow admissible range), a bisection."""
    grid = np.linspace(low, high, steps + 1)
    values = np.array([f(v) for v in grid])
    within = np.flatnonzero(values <= limit)
    if len(within):
        j = int(within[0])
        if j == 0:
            return low
        a, b = grid[j - 1], grid[j]
    else:
        k = int(np.argmin(values))
        a, b = grid[max(k - 1, 0)], grid[min(k + 1, steps)]
        for _ in range(iterations):
            c, d = b - 0.618 * (b - a), a + 0.618 * (b - a)
            a, b = (a, d) if f(c) <= f(d) else (c, b)
        assert f(b) <= limit, (b, f(b))
        a = grid[max(k - 1, 0)]
    for _ in range(iterations):
        m = 0.5 * (a + b)
        a, b = (a, m) if f(m) <= limit else (m, b)
    return b


def _slsqp_objectives(scene, key, starts=(0.25, 0.5, 0.75)):
    """SciPy SLSQP on the same design problem with the span or angle as one more variable: the
    objective of each converged, feasible answer from starts spread over the box."""
    import jax
    import jax.numpy as jnp
    from scipy.optimize import minimize

    from camjax.family import weights_of
    from camjax.followers._closure_design import with_dimension
    from camjax.solvers.base import family_of, problem_from_scene

    problem = problem_from_scene(scene)
    fam = family_of(problem)
    names = fam.Design._fields
    lo = [float(getattr(problem.lower, n)) for n in names] + [scene.design.bounds(key)[0]]
    hi = [float(getattr(problem.upper, n)) for n in names] + [scene.design.bounds(key)[1]]
    weights = weights_of(scene.design.alpha, scene.design.gamma, jnp.float64)

    def split(z):
        return fam.Design(*z[:-1]), z[-1]

    def objective(z):
        return fam.objective(problem, weights, split(z)[0])

    def rows(z):
        return -jnp.concatenate(fam.constraints(with_dimension(problem, key, split(z)[1]), split(z)[0]))

    # two compiled programs: the objective with its gradient, the rows with their jacobian (SLSQP
    # asks for each half at the same points; the other half costs little at 360 samples)
    f_and_grad = jax.jit(jax.value_and_grad(objective))
    g_and_jac = jax.jit(lambda z: (rows(z), jax.jacfwd(rows)(z)))
    out = []
    for t in starts:
        z0 = np.array([a + t * (b - a) for a, b in zip(lo, hi, strict=True)])
        r = minimize(lambda z: float(f_and_grad(z)[0]), z0, jac=lambda z: np.asarray(f_and_grad(z)[1]),
                     method="SLSQP", bounds=list(zip(lo, hi, strict=True)), options={"maxiter": 500, "ftol": 1e-12},
                     constraints=[{"type": "ineq", "fun": lambda z: np.asarray(g_and_jac(z)[0]),
                                   "jac": lambda z: np.asarray(g_and_jac(z)[1])}])
        if r.success and np.min(np.asarray(g_and_jac(r.x)[0])) > -1e-7:
            out.append(float(r.fun))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("case", sorted(FREE))
def test_a_free_span_or_arm_angle_is_the_smallest_the_second_cam_allows(case, tmp_path, no_figures):
    """[design] frees the yoke span or the second arm angle: the CLI's design keeps the optimum
    (SciPy SLSQP over the same problem with the span or angle as one more variable finds none
    smaller) and reports the chosen value in its design and closure blocks; drawn at 7200 samples
    with that value, both rollers ride their exported cams, the link is rigid at that value, and a
    scan over the value on the exported positions (the second cam's pressure angle by finite
    differences, its distance from the shaft and its convex radius by three-point circles) puts the
    smallest admissible value where the design put it."""
    text, key = FREE[case]
    text = text.replace("[motion]\n", '[motion]\nextrema = "grid"\n')  # the samples' problem, as SLSQP's
    (tmp_path / "free.toml").write_text(text)
    assert cli.main(["design", str(tmp_path / "free.toml"), "--out", str(tmp_path / "design"), "--dpi", "40"]) == 0
    data = json.loads((tmp_path / "design" / "result.json").read_text())
    design, chosen = data["design"], data["design"][key]
    low, high = parse_scene(text).design.bounds(key)
    assert design["feasible"] and data["closure"][key] == chosen and low < chosen < high, (chosen, design)
    # the scene's newton certifies the solve it made (the first contact's rows, whose optimum the
    # chosen value keeps): converged, within 1e-8 on each scaled KKT residual
    cert = design["certificate"]
    assert cert["converged"] and max(cert["stationarity"], cert["primal_feasibility"],
                                     cert["complementarity"]) <= 1e-8, cert
    best = _slsqp_objectives(parse_scene(text), key)
    assert best and design["objective"] <= min(best) + 1e-6, (design["objective"], best)

    # the design drawn at 7200 samples with the chosen value in [follower] (the rocker's curves at the
    # design's radius: at 7200 samples the second cam may pass its limit by the sampling's ~0.01 deg,
    # and the run's sizing would refuse the follower)
    scene = parse_scene(text)
    kind = followers.of(scene)
    scene = with_samples(replace(scene, follower=kind.drawn_follower(scene, design), design=None,
                                 motion=replace(scene.motion, extrema="grid")), SAMPLES)
    f, r2 = scene.follower, scene.follower.closure.second_roller_radius_mm
    assert getattr(f.closure, key) == chosen
    if case == "yoke":
        curves = camjax.run_design(scene, base_radius_mm=design["base_radius_mm"]).curves
    else:
        arrays = camjax.scene_arrays(scene)
        curves = kind.evaluate(scene, arrays.kin, arrays.cam_speed_rad_s, design["base_radius_mm"])
    export.write_profile_csv(tmp_path / "profile.csv", curves)
    names = (tmp_path / "profile.csv").read_text().splitlines()[0].split(",")
    table = np.loadtxt(tmp_path / "profile.csv", delimiter=",", skiprows=1)
    col = {n: table[:, k] for k, n in enumerate(names)}
    first = _distances(col["pitch_x_mm"], col["pitch_y_mm"], col["x_mm"], col["y_mm"])
    second = _distances(col["conjugate_pitch_x_mm"], col["conjugate_pitch_y_mm"], col["conjugate_x_mm"],
                        col["conjugate_y_mm"])
    assert np.max(np.abs(first - f.roller_radius_mm)) < RIDE_TOL_MM
    assert np.max(np.abs(second - r2)) < RIDE_TOL_MM
    c1x, c1y, c2x, c2y = col["pitch_x_mm"], col["pitch_y_mm"], col["conjugate_pitch_x_mm"], col["conjugate_pitch_y_mm"]
    if case == "yoke":
        span = np.hypot(c1x - c2x, c1y - c2y)
        assert np.max(np.abs(span - chosen)) < 1e-9
        ux, uy = (c1x - c2x) / span, (c1y - c2y) / span  # the follower axis, first roller up

        def second_centres(value):
            return c1x - value * ux, c1y - value * uy, ux, uy
    else:
        px, py = _pivot(scene, col["theta_deg"])
        a1, a2 = np.arctan2(c1y - py, c1x - px), np.arctan2(c2y - py, c2x - px)
        turn = np.angle(np.exp(1j * (a2 - a1)))  # from the first arm to the second, signed
        assert np.max(np.abs(np.abs(turn) - math.radians(chosen))) < 1e-9
        l2, sense = f.closure.second_arm_length_mm, np.sign(turn[0])

        def second_centres(value):
            a = a1 + sense * math.radians(value)
            cx, cy = px + l2 * np.cos(a), py + l2 * np.sin(a)
            return cx, cy, -(cy - py), cx - px  # driven square to the second arm

    def pressure(value):
        return _second_pressure_angle_deg(*second_centres(value))

    limit = f.max_pressure_angle_deg + SAMPLING_DEG
    assert pressure(chosen) <= limit and _second_cam_cuttable(*second_centres(chosen)[:2], r2,
                                                              f.min_curvature_radius_mm)
    assert _first_within(pressure, limit, low, high) == pytest.approx(chosen, abs=FREE_TOL)


FREE_BAD = {
    "span_on_a_groove": ("groove", "gamma = 0.0 ", "yoke_span_mm = [40.0, 80.0]\ngamma = 0.0 ", "design.yoke_span_mm"),
    "span_overlapping": (YOKE, "gamma = 0.0 ", "yoke_span_mm = [8.0, 80.0]\ngamma = 0.0 ", "design.yoke_span_mm"),
    "span_reversed": (YOKE, "gamma = 0.0 ", "yoke_span_mm = [80.0, 40.0]\ngamma = 0.0 ", "design.yoke_span_mm"),
    "angle_past_the_first_arm": ("conjugate", "gamma = 0.1", "gamma = 0.1\nsecond_arm_angle_deg = [30.0, 360.0]",
                                 "design.second_arm_angle_deg"),
    "angle_on_a_yoke": (YOKE, "gamma = 0.0 ", "second_arm_angle_deg = [30.0, 90.0]\ngamma = 0.0 ",
                        "design.second_arm_angle_deg"),
    "span_on_a_flat_face": ("default", "[design]\n", "[design]\nyoke_span_mm = [40.0, 80.0]\n", "design.yoke_span_mm"),
}


@pytest.mark.parametrize("case", sorted(FREE_BAD))
def test_bad_span_or_arm_angle_bounds_exit_2_naming_the_key(case, tmp_path, capsys):
    name, old, new, field = FREE_BAD[case]
    text = builtin_scene_text(name) if "\n" not in name else name
    assert old in text
    (tmp_path / "bad.toml").write_text(text.replace(old, new, 1))
    assert cli.main(["design", str(tmp_path / "bad.toml"), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f" {field}" in err[0], err
