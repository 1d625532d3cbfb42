"""Animation: frame poses against closed-form follower geometry, artists of a frame, the GIF."""

import math

import numpy as np
import pytest
from PIL import Image
from reference import reference_motion
from test_report import ROLLER

import camjax
from camjax.followers._translating_drawing import mechanism as mechanism_from_curves
from camjax.output.animation import (
    frame_indices,
    frame_poses,
    motion_frames,
    rotate,
    write_motion_gif,
)
from camjax.scene import parse_scene


@pytest.fixture(scope="module")
def flat_mechanism(default_scene, default_arrays):
    curves = camjax.analyse(default_scene, default_arrays).curves
    return mechanism_from_curves(curves, "default")


@pytest.fixture(scope="module")
def roller_mechanism():
    scene = parse_scene(ROLLER, "roller")
    curves = camjax.analyse(scene, base_radius_mm=30.0).curves
    return mechanism_from_curves(curves, "roller")


def test_frame_indices_spread_one_turn():
    np.testing.assert_array_equal(frame_indices(360, 72), np.arange(0, 360, 5))
    np.testing.assert_array_equal(frame_indices(7, 7), np.arange(7))
    k = frame_indices(360, 7)  # uneven: strictly increasing, inside the turn
    assert k[0] == 0 and np.all(np.diff(k) > 0) and k[-1] < 360
    for bad in (0, 361):
        with pytest.raises(ValueError, match="frames"):
            frame_indices(360, bad)


def test_rotation_brings_the_contact_angle_onto_the_follower_axis():
    # geometry.py: the contact point at cam angle theta sits at polar angle theta clockwise from +Y
    th = np.deg2rad(np.array([0.0, 30.0, 123.0, 270.0]))
    x, y = rotate(np.sin(th), np.cos(th), th)
    np.testing.assert_allclose(x, 0.0, atol=1e-15)
    np.testing.assert_allclose(y, 1.0, rtol=1e-15)


@pytest.mark.slow
def test_flat_poses_match_closed_form(flat_mechanism):
    m = flat_mechanism
    p = frame_poses(m, 72)
    s, ds, _ = reference_motion(p.theta_deg)  # independent NumPy cycloids
    # the face sits at R_b + s on the axis; the contact point is s' along the face (SPEC 3);
    # 1e-9 mm: float64 rounding of the rotation of a ~35 mm outline
    np.testing.assert_allclose(p.follower_y_mm, m.base_radius_mm + s, atol=1e-9)
    np.testing.assert_allclose(p.contact_y_mm, m.base_radius_mm + s, atol=1e-9)
    np.testing.assert_allclose(p.contact_x_mm, ds, atol=1e-9)
    np.testing.assert_array_equal(p.pressure_angle_deg, 0.0)
    assert np.all(np.abs(p.contact_x_mm) <= 0.5 * m.face_width_mm + 1e-9)  # on the face


@pytest.mark.slow
def test_roller_poses_touch_the_roller_along_the_pressure_angle(roller_mechanism):
    m = roller_mechanism
    p = frame_poses(m, 36)
    rb, rf, e = m.base_radius_mm, m.roller_radius_mm, m.offset_mm
    s = np.asarray(m.s_mm)[p.index]
    np.testing.assert_allclose(p.follower_x_mm, e)
    np.testing.assert_allclose(p.follower_y_mm, math.sqrt((rb + rf) ** 2 - e**2) + s, atol=1e-12)
    dx, dy = p.follower_x_mm - p.contact_x_mm, p.follower_y_mm - p.contact_y_mm
    # the contact point lies on the roller, and the line to its centre is the contact normal,
    # at the pressure angle from the axis (1e-9: rounding of the ~40 mm outline's rotation)
    np.testing.assert_allclose(np.hypot(dx, dy), rf, atol=1e-9)
    np.testing.assert_allclose(np.rad2deg(np.arctan2(-dx, dy)), p.pressure_angle_deg, atol=1e-7)
    assert np.ptp(p.pressure_angle_deg) > 10.0  # the check is not vacuous: phi varies


@pytest.mark.slow  # > 2 s (a compile of its own)
@pytest.mark.parametrize("k", [0, 25, 50])
def test_frame_artists_show_the_follower_at_s_of_theta(flat_mechanism, k):
    mf = motion_frames(flat_mechanism, 72)
    mf.update(k)
    theta = 5.0 * k  # 72 frames over 360 deg
    s = reference_motion([theta])[0][0]
    _, ys = mf.artists["follower"].get_data()
    np.testing.assert_allclose(ys, flat_mechanism.base_radius_mm + s, atol=1e-9)
    np.testing.assert_allclose(mf.artists["marker"].get_data(), [[theta], [s]], atol=1e-9)
    assert f"θ = {theta:5.1f}°" in mf.artists["label"].get_text()


@pytest.mark.slow
def test_roller_frame_artist_centre(roller_mechanism):
    mf = motion_frames(roller_mechanism, 36)
    mf.update(7)
    m = roller_mechanism
    s = float(np.asarray(m.s_mm)[70])  # frame 7 of 36 on 360 samples: sample 70
    cx, cy = mf.artists["follower"].center
    assert cx == pytest.approx(m.offset_mm)
    assert cy == pytest.approx(math.sqrt((m.base_radius_mm + m.roller_radius_mm) ** 2
                                         - m.offset_mm**2) + s, abs=1e-9)


@pytest.mark.slow
def test_gif_has_every_frame(flat_mechanism, tmp_path):
    path = write_motion_gif(tmp_path / "motion.gif", flat_mechanism, frames=24, fps=10, dpi=40)
    with Image.open(path) as im:
        assert im.format == "GIF" and im.n_frames == 24
        assert im.info["duration"] == 100  # 1000 ms / 10 fps (GIF stores whole centiseconds)
        assert im.info.get("loop") == 0
        # the frames differ: the cam turns between them
        im.seek(0)
        first = np.asarray(im.convert("RGB")).copy()
        im.seek(12)
        assert np.any(np.asarray(im.convert("RGB")) != first)


@pytest.mark.slow
def test_infeasible_outline_still_animates(default_scene, default_arrays, tmp_path):
    curves = camjax.analyse(default_scene, default_arrays, base_radius_mm=10.0).curves
    bad = curves.rho_mm < 0
    assert bad.any()  # R_b = 10 mm is below the flat face's minimum (about 27 mm)
    m = mechanism_from_curves(curves, "default", violation="ρ < 0: the face cannot follow", bad=bad)
    mf = motion_frames(m, 12)
    mf.update(3)
    xs, _ = mf.artists["bad"].get_data()  # the red part of the outline
    assert np.count_nonzero(np.isfinite(xs)) == np.count_nonzero(bad)
    path = write_motion_gif(tmp_path / "motion.gif", m, frames=12, dpi=40)
    with Image.open(path) as im:
        assert im.n_frames == 12


def test_violation_samples_are_where_rho_is_negative(default_scene, default_arrays):
    from camjax.followers._translating_drawing import violation_samples

    ok = camjax.analyse(default_scene, default_arrays).curves
    assert not violation_samples(ok).any()
    bad = camjax.analyse(default_scene, default_arrays, base_radius_mm=10.0).curves
    # independent: rho = R_b + s + s'' of the reference cycloids, negative late in the rise and in
    # the return
    s, _, d2s = reference_motion(bad.theta_deg)
    np.testing.assert_array_equal(violation_samples(bad), 10.0 + s + d2s < 0)
    assert violation_samples(bad).any()


@pytest.mark.slow
def test_clockwise_cam_is_the_mirror_image(roller_mechanism):
    # a cw cam: outline mirrored (X -> -X), turning the other way; the follower moves the same and
    # every contact point is the mirror of the ccw one (the mechanism seen from behind)
    m = roller_mechanism
    cw = m._replace(profile_x_mm=-np.asarray(m.profile_x_mm), offset_mm=-m.offset_mm, rotation="cw",
                    pressure_angle_deg=-np.asarray(m.pressure_angle_deg))
    a, b = frame_poses(m, 24), frame_poses(cw, 24)
    np.testing.assert_allclose(b.follower_y_mm, a.follower_y_mm, atol=1e-12)
    np.testing.assert_allclose(b.follower_x_mm, -a.follower_x_mm, atol=1e-12)
    np.testing.assert_allclose(b.contact_x_mm, -a.contact_x_mm, atol=1e-9)
    np.testing.assert_allclose(b.contact_y_mm, a.contact_y_mm, atol=1e-9)
    motion_frames(cw, 4).update(2)  # draws
    with pytest.raises(ValueError, match="rotation"):
        frame_poses(m._replace(rotation="left"), 4)


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_builtin_roller_touches_its_roller_for_either_rotation(rotation):
    import dataclasses

    from camjax.scene import load_scene

    scene = load_scene("roller")
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, rotation=rotation))
    m = mechanism_from_curves(camjax.analyse(scene).curves)
    assert m.rotation == rotation
    p = frame_poses(m, 18)
    dx, dy = p.follower_x_mm - p.contact_x_mm, p.follower_y_mm - p.contact_y_mm
    # the outline (camjax.geometry, mirrored for cw) turned into the frame touches the roller, and
    # the line to its centre is at the pressure angle (1e-9: rounding of the rotation)
    np.testing.assert_allclose(np.hypot(dx, dy), m.roller_radius_mm, atol=1e-9)
    np.testing.assert_allclose(np.rad2deg(np.arctan2(-dx, dy)), p.pressure_angle_deg, atol=1e-7)
