"""Making the cam ([manufacture], [export]): cutter path, G-code, solid and cam table, each checked
by a reader written here and an independent computation.

Two `camjax design` runs in process, shared by the module: the built-in `manufacture` scene (a
translating roller, a cutter of the roller's size, a bore, a 360-point cam table) and the reference
flat face without its [design] (a 20 mm cutter, no bore, `--cam-table-points 90`). The G-code is
parsed here, its arcs expanded at 5 µm steps (chord sag < 1e-7 mm on these radii, negligible
against the 1 µm tolerance), and measured against the cam surface; a follower rides the surface
rebuilt from the G-code; the STL is read back; the cam table is re-interpolated against the
profile.
"""

import json
import math
import re
import tomllib

import numpy as np
import pytest

from camjax import cli, followers
from camjax.scene import SceneError, builtin_scene_text, parse_scene, scene_from_dict

STEP_MM = 0.005  # expansion step of the G-code's arcs


# ------------------------------------------------------------------------------ readers


def read_csv(path):
    names = path.read_text().splitlines()[0].split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {n: data[:, i] for i, n in enumerate(names)}


def parse_gcode(text):
    """Moves of a G-code program as (G number, points (K, 2) in mm, Z in mm), arcs expanded from
    their start, I J incremental centre, radius from the start; and the set of G words."""
    pos = {"X": None, "Y": None, "Z": None}
    moves, words_seen, scale = [], set(), 1.0
    for raw in text.splitlines():
        line = re.sub(r"\(.*?\)", "", raw).strip()
        if not line or line == "%":
            continue
        words = {w[0]: float(w[1:]) for w in re.findall(r"[A-Z][-+]?[0-9.]+", line)}
        gs = [int(v) for v in re.findall(r"G(\d+)", line)]
        words_seen.update(gs)
        scale = 25.4 if 20 in gs else 1.0 if 21 in gs else scale
        g = next((v for v in gs if v in (0, 1, 2, 3)), None)
        new = {a: words[a] * scale if a in words else pos[a] for a in "XYZ"}
        if g in (2, 3):
            x0, y0 = pos["X"], pos["Y"]
            cx, cy = x0 + words["I"] * scale, y0 + words["J"] * scale
            r = math.hypot(x0 - cx, y0 - cy)
            a0, a1 = math.atan2(y0 - cy, x0 - cx), math.atan2(new["Y"] - cy, new["X"] - cx)
            sweep = (a1 - a0) % (2 * math.pi) if g == 3 else -((a0 - a1) % (2 * math.pi))
            a = a0 + sweep * np.linspace(0.0, 1.0, max(2, int(abs(sweep) * r / STEP_MM) + 1))
            moves.append((g, np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]), new["Z"]))
        elif g in (0, 1) and pos["X"] is not None:
            n = max(2, int(math.hypot(new["X"] - pos["X"], new["Y"] - pos["Y"]) / STEP_MM) + 1)
            s = np.linspace(0.0, 1.0, n)[:, None]
            moves.append((g, np.array([pos["X"], pos["Y"]]) * (1 - s) + np.array([new["X"], new["Y"]]) * s,
                          new["Z"]))
        pos = new
    return moves, words_seen


def contour(moves):
    """The cutting contour: the moves at depth after the plunge and the lead-in, before the lead-out."""
    cut = [m for m in moves if m[2] is not None and m[2] < 0]
    return cut[2:-1]


def read_stl(path):
    raw = path.read_bytes()
    n = int(np.frombuffer(raw, "<u4", 1, 80)[0])
    rec = np.frombuffer(raw, np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]), n, 84)
    assert len(raw) == 84 + 50 * n
    return rec["v"].astype(np.float64)


def distance_to_curve(points, curve):
    """Distance from points (P, 2) to a closed, densely sampled smooth curve (K, 2): to the circle
    through the nearest sample and its two neighbours (error O(h^3), far below 1e-7 mm here)."""
    from scipy.spatial import cKDTree

    _, k = cKDTree(curve).query(points)
    best = np.full(len(points), np.inf)
    n = len(curve)
    for shift in (-1, 0, 1):
        j = (k + shift) % n
        a, b, c = curve[(j - 1) % n], curve[j], curve[(j + 1) % n]
        # circumcentre of a, b, c
        d = 2 * (a[:, 0] * (b[:, 1] - c[:, 1]) + b[:, 0] * (c[:, 1] - a[:, 1]) + c[:, 0] * (a[:, 1] - b[:, 1]))
        sa, sb, sc = (a**2).sum(1), (b**2).sum(1), (c**2).sum(1)
        ux = (sa * (b[:, 1] - c[:, 1]) + sb * (c[:, 1] - a[:, 1]) + sc * (a[:, 1] - b[:, 1])) / d
        uy = (sa * (c[:, 0] - b[:, 0]) + sb * (a[:, 0] - c[:, 0]) + sc * (b[:, 0] - a[:, 0])) / d
        r = np.hypot(b[:, 0] - ux, b[:, 1] - uy)
        best = np.minimum(best, np.abs(np.hypot(points[:, 0] - ux, points[:, 1] - uy) - r))
    return best


# ------------------------------------------------------------------------------ the runs

FLAT_MANUFACTURE = """
[manufacture]
cutter_diameter_mm = 20.0
tolerance_mm = 0.001
feed_mm_per_min = 250.0
"""


def _flat_scene_text():
    data = tomllib.loads(builtin_scene_text("default"))
    data.pop("design")
    text = builtin_scene_text("default")
    return text[:text.index("[design]")] + FLAT_MANUFACTURE, data


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """{"roller": folder, "flat": folder} of two `camjax design` runs (exit 0 each)."""
    base = tmp_path_factory.mktemp("shop")
    flat = base / "flat.toml"
    flat.write_text(_flat_scene_text()[0])
    out = {"roller": base / "roller", "flat": base / "flat"}
    assert cli.main(["design", "manufacture", "--out", str(out["roller"]), "--dpi", "20"]) == 0
    assert cli.main(["design", str(flat), "--out", str(out["flat"]), "--dpi", "20",
                     "--cam-table-points", "90"]) == 0
    return out


def _load(folder):
    return (json.loads((folder / "result.json").read_text()), read_csv(folder / "profile.csv"),
            read_csv(folder / "cutter_path.csv"), (folder / "cam.nc").read_text())


# ------------------------------------------------------------------------------ the tests


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
@pytest.mark.parametrize("which", ["roller", "flat"])
def test_writes_the_shop_files_and_reports_them(runs, which):
    names = {p.name for p in runs[which].iterdir()}
    assert {"cutter_path.csv", "cam.nc", "cam.stl", "cam_table.csv", "cam_table.json"} <= names
    data, _, _, gcode = _load(runs[which])
    fit = data["manufacture"]["fit"]
    assert fit["max_deviation_mm"] <= data["manufacture"]["tolerance_mm"]
    moves, words = parse_gcode(gcode)
    arcs = sum(g in (2, 3) for g, _, _ in contour(moves))
    assert arcs == fit["arcs"] and len(contour(moves)) == fit["contour_blocks"]
    assert fit["program_blocks"] == sum(1 for line in gcode.splitlines()
                                        if line != "%" and not line.startswith("("))
    assert {21, 90, 17, 40} <= words  # mm, absolute, XY plane, no cutter compensation
    first_cut = next(i for i, line in enumerate(gcode.splitlines()) if re.match(r"G[23] ", line))
    head = gcode.splitlines()[:first_cut]
    assert any(line.startswith("G0 Z") and float(line.split("Z")[1]) > 0 for line in head)  # safe height
    c = contour(moves)
    assert np.allclose(c[0][1][0], c[-1][1][-1], atol=1e-9)  # one closed contour


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
@pytest.mark.parametrize("which", ["roller", "flat"])
def test_gcode_path_is_the_cutter_radius_from_the_cam_surface(runs, which):
    """Every point of the expanded G-code lies R_t +- (tolerance + 1 nm) from the cam surface, and
    every exact path sample lies within tolerance + 1 nm of the G-code. The surface is
    cutter_path.csv's, first checked against profile.csv at every shared sample (1e-9 mm) and its
    normals against finite differences of its points."""
    data, profile, path, gcode = _load(runs[which])
    m = data["manufacture"]
    radius, tol = m["cutter_diameter_mm"] / 2, m["tolerance_mm"]
    surface = np.column_stack([path["surface_x_mm"], path["surface_y_mm"]])
    k = len(surface) // len(profile["x_mm"])
    assert np.max(np.abs(surface[::k] - np.column_stack([profile["x_mm"], profile["y_mm"]]))) < 1e-9
    tangent = np.roll(surface, -1, 0) - np.roll(surface, 1, 0)
    normal = np.column_stack([path["normal_x"], path["normal_y"]])
    assert np.max(np.abs(np.sum(tangent * normal, 1)) / np.hypot(*tangent.T)) < 1e-4  # FD: O(h^2)
    tool = np.column_stack([path["x_mm"], path["y_mm"]])
    assert np.allclose(np.hypot(*(tool - surface).T), radius, atol=1e-9)
    pts = np.vstack([p for _, p, _ in contour(parse_gcode(gcode)[0])])
    d = distance_to_curve(pts, surface)
    assert np.all(np.abs(d - radius) <= tol + 1e-6), (d.min() - radius, d.max() - radius)
    assert np.max(distance_to_curve(tool, pts)) <= tol + 1e-6


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_roller_sized_cutter_runs_on_the_pitch_curve(runs):
    _, profile, path, _ = _load(runs["roller"])
    k = len(path["x_mm"]) // len(profile["x_mm"])
    assert np.max(np.abs(path["x_mm"][::k] - profile["pitch_x_mm"])) < 1e-9
    assert np.max(np.abs(path["y_mm"][::k] - profile["pitch_y_mm"])) < 1e-9


def _axis(theta_deg):
    """The follower's axis in the cam frame at cam angle theta (ccw cam, zero offset)."""
    t = np.radians(theta_deg)
    return np.column_stack([np.sin(t), np.cos(t)])


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_a_roller_riding_the_gcode_recovers_the_lift(runs):
    """The cam rebuilt from the G-code is its path less the cutter radius; a roller of that radius
    (the design's, zero offset) touches it where its centre is on the path: the path's crossing
    with the follower's axis, less the prime radius, is the lift, within 2 µm."""
    data, profile, _, gcode = _load(runs["roller"])
    pts = np.vstack([p for _, p, _ in contour(parse_gcode(gcode)[0])])
    rp = data["evaluated_at"]["base_radius_mm"] + 8.0  # the scene's roller
    lifts = []
    ang = np.arctan2(pts[:, 0], pts[:, 1])  # polar angle clockwise from +Y
    for t in profile["theta_deg"]:
        a = (np.radians(t) - ang + np.pi) % (2 * np.pi) - np.pi
        i = np.flatnonzero((a[:-1] <= 0) & (a[1:] > 0) | (a[:-1] >= 0) & (a[1:] < 0))
        i = i[np.argmin(np.abs(a[i]))]
        w = a[i] / (a[i] - a[i + 1])
        lifts.append(np.hypot(*((1 - w) * pts[i] + w * pts[i + 1])) - rp)
    assert np.max(np.abs(np.array(lifts) - profile["s_mm"])) < 2e-3  # 2 µm


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_a_flat_face_riding_the_gcode_recovers_the_lift(runs):
    """A flat face normal to its axis rests on the cam's support line: the G-code path's farthest
    point along the axis, less the cutter radius and the base radius, is the lift, within 2 µm."""
    data, profile, _, gcode = _load(runs["flat"])
    pts = np.vstack([p for _, p, _ in contour(parse_gcode(gcode)[0])])
    reach = np.max(_axis(profile["theta_deg"]) @ pts.T, axis=1)
    lift = reach - data["manufacture"]["cutter_diameter_mm"] / 2 - data["evaluated_at"]["base_radius_mm"]
    assert np.max(np.abs(lift - profile["s_mm"])) < 2e-3  # 2 µm


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
@pytest.mark.parametrize("which", ["roller", "flat"])
def test_stl_is_watertight_with_the_plate_volume(runs, which):
    """Every edge in exactly two triangles, once each way (a closed, consistently oriented surface);
    volume (divergence theorem) within 0.5 % of the profile's area x width - bore."""
    data, _, path, _ = _load(runs[which])
    tris = read_stl(runs[which] / "cam.stl")
    _, inv = np.unique(tris.reshape(-1, 3), axis=0, return_inverse=True)
    v = inv.reshape(-1, 3)
    directed = np.concatenate([v[:, [0, 1]], v[:, [1, 2]], v[:, [2, 0]]])
    keys = directed[:, 0] * (v.max() + 1) + directed[:, 1]
    assert len(np.unique(keys)) == len(keys)  # each directed edge once
    reverse = directed[:, 1] * (v.max() + 1) + directed[:, 0]
    assert set(reverse.tolist()) == set(keys.tolist())  # and its twin the other way
    volume = np.sum(np.einsum("ij,ij->i", tris[:, 0], np.cross(tris[:, 1], tris[:, 2]))) / 6
    x, y = path["surface_x_mm"], path["surface_y_mm"]
    area = abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)) / 2
    m = data["manufacture"]
    bore = math.pi * (m["bore_diameter_mm"] or 0.0) ** 2 / 4
    assert volume == pytest.approx((area - bore) * m["cam_width_mm"], rel=5e-3)
    assert tris[:, :, 2].min() == 0.0 and tris[:, :, 2].max() == pytest.approx(m["cam_width_mm"])


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_cam_table_is_the_profile_per_degree(runs):
    """360 points: the profile's own samples, per degree of master (mm, mm/deg, mm/deg^2); the JSON
    quintics meet position, velocity and acceleration at both ends of every segment."""
    _, profile, _, _ = _load(runs["roller"])
    table = read_csv(runs["roller"] / "cam_table.csv")
    d = math.pi / 180
    assert np.allclose(table["master_deg"], profile["theta_deg"], atol=1e-9)
    assert np.allclose(table["position"], profile["s_mm"], atol=1e-9)
    assert np.allclose(table["velocity"], profile["ds_mm_per_rad"] * d, atol=1e-9)
    assert np.allclose(table["acceleration"], profile["d2s_mm_per_rad2"] * d * d, atol=1e-9)
    doc = json.loads((runs["roller"] / "cam_table.json").read_text())
    c = np.array([s["c"] for s in doc["segments"]])
    h = doc["master"]["interval"]
    powers = np.arange(6)
    p_end = c @ h**powers
    v_end = c[:, 1:] @ (powers[1:] * h ** (powers[1:] - 1))
    a_end = c[:, 2:] @ (powers[2:] * (powers[2:] - 1) * h ** (powers[2:] - 2))
    for got, col in ((p_end, "position"), (v_end, "velocity"), (a_end, "acceleration")):
        assert np.allclose(got, np.roll(table[col], -1), rtol=1e-7, atol=1e-9), col
    assert np.allclose(c[:, 0], table["position"]) and np.allclose(c[:, 1], table["velocity"])


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_cam_table_reinterpolated_against_the_profile(runs):
    """90 points (the CLI flag): linear, cubic-Hermite and quintic interpolation between them,
    evaluated here at the profile's 360 angles, err from the profile's s by no more than result.json
    says (its checks include those angles: 4 per interval of 16 checks); and the fewest points it
    gives for linear interpolation keep the error within the tolerance, one fewer does not
    (64 checks per interval against the exact law here, 1 % slack for the check density)."""
    data, profile, _, _ = _load(runs["flat"])
    table = read_csv(runs["flat"] / "cam_table.csv")
    rep = data["cam_table"]
    assert rep["points"] == 90 and len(table["position"]) == 90
    h = 4.0
    t = profile["theta_deg"]
    k = np.floor(t / h).astype(int)
    u = t - k * h
    p, v = table["position"], table["velocity"]
    p1, v1 = np.roll(p, -1)[k], np.roll(v, -1)[k]
    s = u / h
    linear = p[k] + (p1 - p[k]) * s
    hermite = ((2 * s**3 - 3 * s**2 + 1) * p[k] + (s**3 - 2 * s**2 + s) * h * v[k]
               + (-2 * s**3 + 3 * s**2) * p1 + (s**3 - s**2) * h * v1)
    c = np.array([seg["c"] for seg in json.loads((runs["flat"] / "cam_table.json").read_text())["segments"]])
    quintic = np.sum(c[k] * u[:, None] ** np.arange(6), axis=1)
    for name, got in (("linear", linear), ("cubic_hermite", hermite), ("quintic", quintic)):
        err = np.max(np.abs(got - profile["s_mm"]))
        assert err <= rep["max_error"][name] + 1e-12, name
    assert np.max(np.abs(linear - profile["s_mm"])) > 0.5 * rep["max_error"]["linear"]

    import jax.numpy as jnp

    from camjax import program

    prog = parse_scene(_flat_scene_text()[0]).motion.program

    def linear_error(n):
        nodes = np.arange(n) * 360.0 / n
        fine = (nodes[:, None] + np.arange(1, 64) * (360.0 / n / 64)).ravel()
        exact = np.asarray(program.motion_at(prog, jnp.asarray(fine)).s).reshape(n, -1)
        at = np.asarray(program.motion_at(prog, jnp.asarray(nodes)).s)
        w = np.arange(1, 64) / 64
        return np.max(np.abs(at[:, None] * (1 - w) + np.roll(at, -1)[:, None] * w - exact))

    n = rep["fewest_points"]["linear"]
    assert linear_error(n) <= rep["tolerance"] * 1.01
    assert linear_error(n - 1) > rep["tolerance"] * 0.99


@pytest.mark.slow  # shares the module's two design runs (about 20 s warm, 45 s cold)
def test_a_cutter_too_large_for_a_concave_stretch_exits_2(runs, tmp_path, capsys):
    """Exit 2, nothing written, naming manufacture.cutter_diameter_mm, the largest diameter that
    fits and the angle. That diameter: twice the smallest concave surface radius, which for a
    roller cam is |pitch radius| + R_f where the pitch curve is concave; on the profile's 360
    samples it can only be larger than on the dense grid, and close (0.5 %)."""
    data, profile, _, _ = _load(runs["roller"])
    largest = data["manufacture"]["largest_cutter_diameter_mm"]
    concave = profile["pitch_rho_mm"] < 0
    sampled = 2 * np.min(-profile["pitch_rho_mm"][concave] + 8.0)
    assert largest <= sampled * (1 + 1e-12) and largest == pytest.approx(sampled, rel=5e-3)
    scene = tmp_path / "big.toml"
    scene.write_text(builtin_scene_text("manufacture").replace("cutter_diameter_mm = 16.0",
                                                                "cutter_diameter_mm = 100.0"))
    out = tmp_path / "out"
    assert cli.main(["design", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "manufacture.cutter_diameter_mm = 100.0" in err
    assert f"{largest:.6g} mm" in err and f"{data['manufacture']['tightest_concave_deg']:.4g} deg" in err
    assert not out.exists()


@pytest.mark.parametrize("key, value, field", [
    ("cutter_diameter_mm", "0.0", "manufacture.cutter_diameter_mm"),
    ("tolerance_mm", "1e-6", "manufacture.tolerance_mm"),
    ("program", '"apt"', "manufacture.program"),
    ("cam_width_mm", "5.0", "manufacture.cam_width_mm"),  # [contact] gives it
])
def test_bad_manufacture_keys_name_the_field(key, value, field):
    data = tomllib.loads(builtin_scene_text("manufacture"))
    data["manufacture"][key] = tomllib.loads(f"v = {value}")["v"]
    with pytest.raises(SceneError, match=re.escape(field)):
        scene_from_dict(data)


def test_sections_are_optional_and_checked():
    assert parse_scene(builtin_scene_text("default")).manufacture is None
    assert parse_scene(builtin_scene_text("default")).export is None
    data = tomllib.loads(builtin_scene_text("knife-edge"))
    data["manufacture"] = {"cutter_diameter_mm": 10.0, "feed_mm_per_min": 100.0}
    with pytest.raises(SceneError, match=r"manufacture\.cam_width_mm.*required"):
        scene_from_dict(data)
    data["manufacture"]["cam_width_mm"] = 8.0
    assert scene_from_dict(data).manufacture.cam_width_mm == 8.0
    data["export"] = {"cam_table_points": 1}
    with pytest.raises(SceneError, match=r"export\.cam_table_points"):
        scene_from_dict(data)


@pytest.mark.parametrize("name", followers.names())
def test_every_follower_gets_a_cutter_path_within_tolerance(name):
    """Each follower type's example scene (its [design] dropped, drawn at the middle of its base
    radius bounds' upper end, or 3:1 towards it where the outline has a cusp there): the exact surface's tangent and curvature agree with central differences of its
    points (O(h^2): compared where |rho| >= 1 mm, and the curvature away from the segment joints,
    where it may jump), and the fitted, rounded arcs lie within the tolerance of the offset surface
    (distance to the circle through three surface samples, 1 nm slack)."""
    from camjax.output import machining

    data = tomllib.loads(builtin_scene_text(followers.get(name).example_scene))
    lo, hi = data.pop("design")["base_radius_mm"]
    scene = scene_from_dict(data, name)
    for radius_mm in (hi, 0.25 * lo + 0.75 * hi):  # the first that has no cusp
        try:
            surf = machining.cam_surface(scene, None, radius_mm, 3600)
            break
        except SceneError as exc:
            assert "cusp" in str(exc)
    xy = np.column_stack([surf.x_mm, surf.y_mm])
    orient = np.sign(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    joints = np.asarray(scene.motion.program.start_deg)
    gap = np.min(np.abs((surf.theta_deg[:, None] - joints[None, :] + 180) % 360 - 180), axis=1)
    away = (np.abs(surf.rho_mm) >= 0.5) & (gap > 0.35)  # 3 samples (0.1 deg) from a joint

    def fd(step):  # central differences of the points, spacing `step` samples: O(h^2)
        d1 = (np.roll(xy, -step, 0) - np.roll(xy, step, 0)) / 2
        d2 = np.roll(xy, -step, 0) - 2 * xy + np.roll(xy, step, 0)
        speed = np.hypot(*d1.T)
        return d1[:, 0] / speed, (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / speed**3 * orient

    (tx1, k1), (tx2, k2) = fd(1), fd(2)
    kappa = 1 / surf.rho_mm
    # the exact value is what the differences converge to: halving the step cuts the error ~4x
    e1, e2 = np.abs(tx1 - surf.tx)[away], np.abs(tx2 - surf.tx)[away]
    assert np.all(e1 <= 0.3 * e2 + 1e-9) and e1.max() < 1e-3
    scale = np.max(np.abs(kappa[away]))
    e1, e2 = np.abs(k1 - kappa)[away], np.abs(k2 - kappa)[away]
    assert np.all(e1 <= 0.3 * e2 + 1e-9 * scale)
    largest, _ = machining.largest_cutter(surf)
    radius = min(5.0, 0.45 * largest)
    tp = machining.tool_path(surf, radius)
    prog = machining.plan_program(tp, 1e-3)
    pts = np.vstack([np.linspace(p.start, p.end, 50) if p.centre is None else _arc_points(p)
                     for p in prog.fit.primitives])
    d = distance_to_curve(pts, xy)
    assert np.all(np.abs(d - radius) <= 1e-3 + 1e-6)


def _arc_points(p):
    c = p.centre
    r = np.hypot(*(p.start - c))
    a0, a1 = math.atan2(*(p.start - c)[::-1]), math.atan2(*(p.end - c)[::-1])
    sweep = (a1 - a0) % (2 * math.pi) if p.ccw else -((a0 - a1) % (2 * math.pi))
    a = a0 + sweep * np.linspace(0, 1, max(2, int(abs(sweep) * r / STEP_MM)))
    return c + r * np.column_stack([np.cos(a), np.sin(a)])


@pytest.mark.parametrize("units", ["mm", "in"])
def test_a_circle_is_cut_as_arcs_of_its_radius_in_either_unit(units):
    """A circular path of radius 20 mm (the surface a 15 mm circle, the cutter 5 mm): the program
    (G21 or G20, read back in mm here) lies on the circle to the rounding of its decimals, is
    nothing but arcs, and its largest deviation is what result.json would report."""
    from camjax.output import machining

    t = np.radians(np.arange(7200) * 0.05)
    surf = machining.Surface(np.degrees(t), 15 * np.sin(t), 15 * np.cos(t), np.cos(t), -np.sin(t),
                             np.sin(t), np.cos(t), np.full(len(t), 15.0))
    tp = machining.tool_path(surf, 5.0)
    prog = machining.plan_program(tp, 1e-3, units)
    lines = machining.gcode_lines(prog, tp, feed_mm_per_min=100.0, width_mm=8.0, cutter_diameter_mm=10.0,
                                  units=units)
    moves, words = parse_gcode("\n".join(lines))
    assert (20 if units == "in" else 21) in words
    pts = np.vstack([p for _, p, _ in contour(moves)])
    resolution = 10.0 ** -prog.decimals * (25.4 if units == "in" else 1.0)
    assert np.max(np.abs(np.hypot(*pts.T) - 20.0)) <= 2 * resolution
    assert prog.lines == 0 and prog.arcs >= 2 and prog.max_deviation_mm <= 2 * resolution
    assert min(p[2] for p in moves) == pytest.approx(-8.0, abs=resolution)


def test_writers_speak_inches(tmp_path):
    """units = "in": the cam table's positions, velocities, accelerations and the cutter path's and
    the STL's lengths are the millimetre values / 25.4 (the cam table of the manufacture scene's
    law, 36 points; a unit square plate for the STL)."""
    from camjax.output import cam_table, machining, solid

    scene = parse_scene(builtin_scene_text("manufacture"))
    mm, inch = cam_table.Law(scene, "mm"), cam_table.Law(scene, "in")
    master = np.arange(36) * 10.0
    for a, b in zip(mm(master), inch(master), strict=True):
        assert np.allclose(b, a / 25.4, rtol=1e-15, atol=0)
    t = np.radians(np.arange(8) * 45.0)
    surf = machining.Surface(np.degrees(t), np.sin(t), np.cos(t), np.cos(t), -np.sin(t), np.sin(t),
                             np.cos(t), np.ones(8))
    machining.write_cutter_path_csv(tmp_path / "p.csv", machining.tool_path(surf, 1.0), "in")
    table = read_csv(tmp_path / "p.csv")
    assert np.allclose(np.hypot(table["x_in"], table["y_in"]), 2.0 / 25.4)
    tris = solid.solid_triangles(np.array([[1.0, -1.0], [1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0]]), 25.4, None)
    solid.write_stl(tmp_path / "c.stl", tris, "in")
    back = read_stl(tmp_path / "c.stl")
    assert back[:, :, 2].max() == pytest.approx(1.0) and np.abs(back[:, :, 0]).max() == pytest.approx(1 / 25.4)


# the manufacture scene's keys and their inch spellings, with the exact factors (1 in = 25.4 mm,
# 1 lbf = 4.4482216152605 N, 1 lb = 0.45359237 kg), written here independently of camjax.units
_INCH = {"_mm_per_min": ("_in_per_min", 25.4), "_N_per_m": ("_lbf_per_in", 4.4482216152605 / 0.0254),
         "_MPa": ("_psi", 4.4482216152605 / 25.4**2), "_kg": ("_lb", 0.45359237), "_mm": ("_in", 25.4)}


def _inch_scene_text(text: str) -> str:
    def convert(m):
        new, factor = _INCH[m.group(2)]
        return f"{m.group(1)}{new} = {float(m.group(3)) / factor!r}"

    text = re.sub(r"#.*", "", text)
    return 'units = "in"\n' + re.sub(r"(\w+?)(_mm_per_min|_N_per_m|_mm|_kg|_MPa) = ([-\d.e+]+)", convert, text)


@pytest.mark.slow  # one more analysis of the manufacture scene (no [design]: the sizing only)
def test_the_inch_manufacture_scene_writes_the_mm_scenes_files_in_inches(runs, tmp_path):
    """The built-in manufacture scene written in inches: cutter path, cam table (and its tolerance,
    the scene's 1 um) and the reported fit equal the mm scene's divided by 25.4 (to 1e-9 relative:
    both fits run the same biarc search on values a factor apart, rounded to 5 and 6 decimals), the
    G-code says G20, the fewest points agree."""
    scene = tmp_path / "manufacture_in.toml"
    scene.write_text(_inch_scene_text(builtin_scene_text("manufacture")))
    out = tmp_path / "in"
    assert cli.main(["design", str(scene), "--out", str(out), "--dpi", "20"]) == 0
    mm_res, _, mm_path, _ = _load(runs["roller"])
    in_res, _, in_path, gcode = _load(out)
    assert "G20" in gcode and "G21" not in gcode
    for a, b in (("x_mm", "x_in"), ("y_mm", "y_in")):
        np.testing.assert_allclose(in_path[b], mm_path[a] / 25.4, rtol=0, atol=1e-11)
    mt, it = mm_res["cam_table"], in_res["cam_table"]
    assert it["position_unit"] == "in" and it["tolerance"] == pytest.approx(mt["tolerance"] / 25.4, rel=1e-12)
    assert it["fewest_points"] == mt["fewest_points"]
    # the quintic's 2e-8 mm error is a difference of positions of ~10 mm: their rounding (1e-15
    # relative) is 1e-6 of it; the other errors are far larger
    for method, err in mt["max_error"].items():
        assert it["max_error"][method] == pytest.approx(err / 25.4, rel=1e-6, abs=1e-15)
    m, i = mm_res["manufacture"], in_res["manufacture"]
    assert i["cutter_diameter_in"] == pytest.approx(m["cutter_diameter_mm"] / 25.4, rel=1e-12)
    assert i["solid"]["volume_in3"] == pytest.approx(m["solid"]["volume_mm3"] / 25.4**3, rel=1e-9)
    assert i["fit"]["max_deviation_in"] <= i["tolerance_in"] * (1 + 1e-9)
    # the same biarc fit (as many arcs and lines); its deviations differ by the rounding of the
    # written coordinates (5 decimals of mm, 6 of inches), each within the one tolerance
    assert i["fit"]["arcs"] == m["fit"]["arcs"] and i["fit"]["lines"] == m["fit"]["lines"]
