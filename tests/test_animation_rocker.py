"""Animation of oscillating (rocker) followers: the drawn arm, roller and face against closed-form
rocker geometry and the reference cycloids, contact read back from the drawn artists, the GIF and
`camjax design --animate` on rocker scenes."""

import functools
import math

import numpy as np
import pytest
from PIL import Image
from reference import reference_motion
from test_cli import break_outline
from test_rocker import FLAT_SCENE, ROLLER_SCENE

import camjax
from camjax import cli
from camjax.followers._rocking_drawing import mechanism as mechanism_from_rocker
from camjax.followers._rocking_drawing import violation_samples as rocker_violation_samples
from camjax.output.animation import UndrawableGeometry, frame_poses, motion_frames, write_motion_gif
from camjax.scene import parse_scene

# the scenes' program (tests/test_rocker.py): cycloidal 20 deg rise over 0..120 deg, dwell, cycloidal
# return over 180..300 deg, dwell; the arm's swing in deg
SWING = {"lift_mm": 20.0, "rise_deg": (0.0, 120.0), "return_deg": (180.0, 120.0)}
CASES = [("oscillating_roller", "ccw"), ("oscillating_roller", "cw"), ("oscillating_flat", "ccw"),
         ("oscillating_flat", "cw")]


def _scene(kind, rotation):
    text = ROLLER_SCENE if kind == "oscillating_roller" else FLAT_SCENE
    return parse_scene(text.replace("ROT", rotation), kind)


@functools.cache
def _case(kind, rotation):
    """(curves, mechanism) of a rocker scene at its drawing radius (feasible)."""
    curves = camjax.analyse(_scene(kind, rotation)).curves
    assert not rocker_violation_samples(curves).any()
    return curves, mechanism_from_rocker(curves, kind)


@pytest.fixture(params=[pytest.param(c, marks=pytest.mark.slow) for c in CASES],
                ids=["-".join(c) for c in CASES])  # each case designs its rocker first (~8 CPU s)
def rocker(request):
    return _case(*request.param)


def _start_angle_deg(m):
    """psi0 (deg) in closed form (SPEC 3): roller, cos psi0 = (d^2 + l^2 - R_p^2) / (2 d l) with
    R_p = R_b + R_f; flat face, sin psi0 = (R_b + f) / d."""
    d = m.pivot_distance_mm
    if m.follower_type == "oscillating_roller":
        rp, arm = m.base_radius_mm + m.roller_radius_mm, m.arm_length_mm
        return math.degrees(math.acos((d * d + arm * arm - rp * rp) / (2 * d * arm)))
    return math.degrees(math.asin((m.base_radius_mm + m.face_offset_mm) / d))


def _segment_distances(px, py, x, y):
    """Distances (mm) from point (px, py) to every segment of the closed polyline (x, y)."""
    ax, ay = x, y
    bx, by = np.roll(x, -1), np.roll(y, -1)
    vx, vy = bx - ax, by - ay
    t = np.clip(((px - ax) * vx + (py - ay) * vy) / (vx * vx + vy * vy), 0.0, 1.0)
    return np.hypot(ax + t * vx - px, ay + t * vy - py)


def test_poses_follow_psi0_plus_s(rocker):
    _, m = rocker
    p = frame_poses(m, 36)
    np.testing.assert_allclose(p.theta_deg, np.arange(0.0, 360.0, 10.0), atol=1e-12)
    s = reference_motion(p.theta_deg, **SWING)[0]  # independent NumPy cycloids, deg
    psi_deg = _start_angle_deg(m) + s
    # psi0 from the curves against its closed form: 1e-9 deg (arccos/arcsin rounding near ~40 deg)
    np.testing.assert_allclose(p.arm_angle_deg, psi_deg, atol=1e-9)
    psi, d = np.deg2rad(psi_deg), m.pivot_distance_mm
    if m.follower_type == "oscillating_roller":  # C = (d - l cos psi, l sin psi)
        ref_x, ref_y = d - m.arm_length_mm * np.cos(psi), m.arm_length_mm * np.sin(psi)
    else:  # the pivot's foot on the face, A - f (sin psi, cos psi)
        ref_x, ref_y = d - m.face_offset_mm * np.sin(psi), -m.face_offset_mm * np.cos(psi)
    # 1e-9 mm: an angle error of 1e-9 deg moves a point on a 60 mm arm by 1e-9 mm
    np.testing.assert_allclose(p.follower_x_mm, ref_x, atol=1e-9)
    np.testing.assert_allclose(p.follower_y_mm, ref_y, atol=1e-9)
    assert np.ptp(p.arm_angle_deg) > 19.0  # the arm swings through the lift: not a vacuous check


@pytest.mark.parametrize("i", [0, 9, 20, 33, 50, 63])  # dwell, rise, dwell, return (72 frames)
def test_drawn_rocker_is_at_psi_and_touches_the_drawn_cam(rocker, i):
    curves, m = rocker
    mf = motion_frames(m, 72)
    mf.update(i)
    theta = 5.0 * i  # 72 frames over 360 deg
    psi_ref = math.radians(_start_angle_deg(m) + float(reference_motion([theta], **SWING)[0][0]))
    d = m.pivot_distance_mm
    (x0, x1), (y0, y1) = mf.artists["arm"].get_data()
    assert (x0, y0) == (d, 0.0)  # the arm is hinged at the pivot
    xr, yr = (np.asarray(v) for v in mf.artists["cam"].get_data())  # the cam as drawn at frame i
    k = 5 * i  # the frame's sample (360 samples)
    if m.follower_type == "oscillating_roller":
        circle = mf.artists["follower"]
        (cx, cy), rf = circle.center, circle.radius
        assert (cx, cy) == (x1, y1) and rf == m.roller_radius_mm  # the arm ends at the roller centre
        # arm angle read back from the drawing: C - A = l (-cos psi, sin psi); 1e-9 rad as above
        assert math.atan2(cy, d - cx) == pytest.approx(psi_ref, abs=1e-9)
        assert math.hypot(cx - d, cy) == pytest.approx(m.arm_length_mm, abs=1e-9)
        # tangency, from the drawn artists only: the cam outline's nearest point is R_f away. The
        # vertices lie on the true outline, which stays >= R_f from the centre (no undercut), and
        # the vertex of this frame's sample is the contact point; a chord can come closer than the
        # curve by its sagitta h^2 / (8 rho) <= h^2 / (8 R_f) (a concave stretch has radius >= R_f).
        dist = _segment_distances(cx, cy, xr, yr)
        h = np.hypot(np.diff(xr, append=xr[0]), np.diff(yr, append=yr[0]))
        tol = float(np.max(h)) ** 2 / (8 * rf) + 1e-9
        assert rf - tol <= dist.min() <= rf + 1e-9
        vertex = np.hypot(xr - cx, yr - cy)
        assert vertex[k] == pytest.approx(rf, abs=1e-9) and int(np.argmin(vertex)) == k
        (px,), (py,) = mf.artists["contact"].get_data()
        assert (px, py) == pytest.approx((xr[k], yr[k]), abs=1e-12)
    else:
        (fx0, fx1), (fy0, fy1) = mf.artists["face"].get_data()
        ux, uy = fx1 - fx0, fy1 - fy0
        norm = math.hypot(ux, uy)
        ux, uy = ux / norm, uy / norm
        # the face runs along u = (-cos psi, sin psi) (SPEC 3), read back from the drawing
        assert math.atan2(uy, -ux) == pytest.approx(psi_ref, abs=1e-9)
        # its normal away from the cam (the cam centre is on the other side); the face line at
        # distance d sin psi - f from the cam centre
        nx, ny = uy, -ux
        if nx * fx0 + ny * fy0 < 0:
            nx, ny = -nx, -ny
        assert nx * fx0 + ny * fy0 == pytest.approx(d * math.sin(psi_ref) - m.face_offset_mm, abs=1e-9)
        # the arm reaches the face at its offset: the foot of the pivot on the face line
        assert nx * x1 + ny * y1 == pytest.approx(nx * fx0 + ny * fy0, abs=1e-9)
        assert math.hypot(x1 - d, y1) == pytest.approx(m.face_offset_mm, abs=1e-9)
        # the drawn cam touches the drawn face and does not cross it: signed distances of the
        # outline's vertices, all <= 0, the largest 0 at this frame's sample. The vertices lie on the
        # envelope of the face lines (a convex cam, rho > 0), so the chords between them stay
        # inside too; 1e-9 mm: rounding of the ~100 mm outline's rotation
        signed = nx * (xr - fx0) + ny * (yr - fy0)
        assert signed.max() <= 1e-9 and signed[k] == pytest.approx(0.0, abs=1e-9)
        assert int(np.argmax(signed)) == k
        # the contact point lies on the drawn face, between its ends
        along = (xr[k] - fx0) * ux + (yr[k] - fy0) * uy
        assert 0.0 < along < norm


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_force_line_runs_through_the_roller_centre_at_the_pressure_angle(rotation):
    curves, m = _case("oscillating_roller", rotation)
    mf = motion_frames(m, 24)
    for i in (2, 5, 15, 17):
        mf.update(i)
        (px, qx), (py, qy) = mf.artists["normal"].get_data()
        cx, cy = mf.artists["follower"].center
        # the contact normal passes through the roller centre: cross product of the two
        # directions 0 (1e-9: rounding)
        assert (qx - px) * (cy - py) - (qy - py) * (cx - px) == pytest.approx(0.0, abs=1e-9)
        # and makes the pressure angle with the drawn path of the centre (the tangent of the arc,
        # perpendicular to the arm): |cos| of the angle between them = cos phi
        (ox, tx), (oy, ty) = mf.artists["path"].get_data()
        assert (ox, oy) == (cx, cy)
        a = np.array([qx - px, qy - py])
        b = np.array([tx - ox, ty - oy])
        cos = abs(a @ b) / (np.linalg.norm(a) * np.linalg.norm(b))
        phi = math.radians(curves.pressure_angle_deg[mf.poses.index[i]])
        assert cos == pytest.approx(math.cos(phi), abs=1e-9)


@pytest.mark.slow
def test_rocker_gif_has_every_frame(rocker, tmp_path):
    _, m = rocker
    path = write_motion_gif(tmp_path / "motion.gif", m, frames=12, fps=10, dpi=40)
    with Image.open(path) as im:
        assert im.format == "GIF" and im.n_frames == 12
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(3)
        assert np.any(np.asarray(im.convert("RGB")) != first)  # the cam and the arm move


@pytest.mark.slow
def test_infeasible_flat_rocker_animates_with_the_violation_in_red(tmp_path):
    # R_b = 30 mm is far below this face's smallest admissible base radius (about 81 mm)
    curves = camjax.analyse(_scene("oscillating_flat", "cw"), base_radius_mm=30.0).curves
    bad = rocker_violation_samples(curves)
    assert bad.any()
    # independently, the sign of rho from the outline's points: the outline is the envelope of the
    # face lines, so dX/dtheta = -sigma Q rho u in follower-frame components (u = (-cos psi, sin psi)
    # along the face, Q = 1 + sigma s' > 0 here: |s'| <= 0.34); central differences of the points
    x, y = curves.profile_x_mm, curves.profile_y_mm
    h = 2 * math.pi / 360
    dx, dy = (np.roll(x, -1) - np.roll(x, 1)) / (2 * h), (np.roll(y, -1) - np.roll(y, 1)) / (2 * h)
    theta = np.deg2rad(curves.theta_deg)
    sigma = -1.0  # cw
    c, sn = np.cos(sigma * theta), np.sin(sigma * theta)
    fx, fy = dx * c - dy * sn, dx * sn + dy * c  # turned back into the follower frame
    psi = math.asin((30.0 + 10.0) / 150.0) + np.deg2rad(reference_motion(curves.theta_deg, **SWING)[0])
    negative = -sigma * (fx * -np.cos(psi) + fy * np.sin(psi)) < 0
    # a sample next to a sign change of rho can fall either way (the difference straddles it)
    edge = (negative != np.roll(negative, 1)) | (negative != np.roll(negative, -1))
    np.testing.assert_array_equal(bad[~edge], negative[~edge])
    assert np.count_nonzero(edge) <= 8  # two loops of the outline, four sign changes at most
    m = mechanism_from_rocker(curves, "flat", violation="curvature violated", bad=bad)
    mf = motion_frames(m, 12)
    mf.update(4)
    xs, _ = mf.artists["bad"].get_data()
    assert np.count_nonzero(np.isfinite(xs)) == np.count_nonzero(bad)
    assert mf.artists["bad"].get_color() == "C3"
    path = write_motion_gif(tmp_path / "motion.gif", m, frames=12, dpi=40)
    with Image.open(path) as im:
        assert im.n_frames == 12


def test_undrawable_rocker_is_refused(rocker):
    _, m = rocker
    swing = np.array(m.swing_deg, dtype=float)
    swing[3] = np.nan
    with pytest.raises(UndrawableGeometry, match="swing_deg is not finite at 1 of 360"):
        frame_poses(m._replace(swing_deg=swing), 12)


@pytest.mark.slow
def test_design_refuses_an_undrawable_rocker_in_one_line(tmp_path, capsys, monkeypatch):
    from camjax.followers._rocking import RockingFollower

    break_outline(monkeypatch, RockingFollower, "evaluate", "profile_y_mm", 11, float("inf"))
    path = tmp_path / "scene.toml"
    path.write_text(ROLLER_SCENE.replace("ROT", "ccw"))
    out = tmp_path / "out"
    assert cli.main(["design", str(path), "--out", str(out), "--dpi", "30", "--animate"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "profile_y_mm is not finite at 1 of 360" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_design_thesis_bench_animate_writes_the_gif(tmp_path, capsys):
    out = tmp_path / "tb"
    assert cli.main(["design", "thesis-bench", "--out", str(out), "--dpi", "30", "--animate"]) == 0
    printed = capsys.readouterr().out
    assert "motion.gif" in printed
    with Image.open(out / "motion.gif") as im:
        assert im.format == "GIF" and im.n_frames == 72  # the default: one frame every 5 deg
    assert {p.name for p in out.iterdir()} >= {"result.json", "profile.png", "profile.csv", "motion.gif"}


@pytest.mark.slow
def test_design_animates_an_infeasible_rocker(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(ROLLER_SCENE.replace("ROT", "cw"))
    out = tmp_path / "out"
    # R_b = 14 mm: the roller closes (R_p = 22 > d - l = 20) but |phi| exceeds 30 deg
    assert cli.main(["design", str(path), "--out", str(out), "--dpi", "30", "--base-radius", "14",
                     "--animate"]) == 0
    printed = capsys.readouterr().out
    assert "INFEASIBLE (pressure_angle" in printed
    with Image.open(out / "motion.gif") as im:
        assert im.n_frames == 72


@pytest.mark.slow
def test_roller_rocker_past_its_pressure_angle_limit_is_drawn_red():
    """R_b = 14 mm on the roller scene: |phi| passes the scene's 30 deg limit on part of the turn
    (the CLI test above reports it); exactly those samples (and any undercut) are drawn red."""
    curves = camjax.analyse(_scene("oscillating_roller", "ccw"), base_radius_mm=14.0).curves
    assert curves.pressure_angle_limit_deg == 30.0  # the scene's follower.max_pressure_angle_deg default
    over = np.abs(curves.pressure_angle_deg) > 30.0 * (1 + 1e-6)
    assert 0 < over.sum() < over.size
    np.testing.assert_array_equal(rocker_violation_samples(curves), over | (curves.undercut_margin_mm < -1e-6))
