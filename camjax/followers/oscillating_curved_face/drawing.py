"""Figures, profile table and animation of an oscillating curved-face follower (NumPy and matplotlib
only).

The shared figures are :mod:`camjax.followers._rocking_drawing`'s; the crowned face adds its part
of the profile figure (the face, an arc of radius R_c and chord W, on its arm at the angle where
the contact travels furthest across it, with the pitch curve of its circle's centre) and its shape
in the animation (the arc at the arm's end, its axis perpendicular to the arm). profile.csv gains
the contact's travel on the face (``face_travel_mm``, R_c sin phi) and the sliding speed
(``sliding_speed_m_s``).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _rocking_drawing as drawing
from camjax.followers._rocking_drawing import to_cam_frame
from camjax.output.animation import FollowerArtists

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "face_outline", "figure_builders", "follower_points",
           "mechanism", "profile_table"]


# what touches the cam: a circle of radius ``roller_radius_mm`` (the Mechanism's; here R_c), of
# which the face is the arc within +-W/2 of its axis
CONTACT_SHAPE = "circle"


def face_outline(cx, cy, psi, radius: float, width: float, points: int = 41) -> tuple[np.ndarray, np.ndarray]:
    """The face (its arc, closed by its chord) of the circle centred at (cx, cy) (fixed frame, mm)
    on an arm at angle psi (rad): the arc is centred on -m, m = (sin psi, cos psi) the direction the
    circle's centre moves in, and spans +-asin(W / 2 R_c) about it."""
    a_max = np.arcsin(min(width / (2.0 * radius), 1.0))
    a = np.linspace(-a_max, a_max, points)
    m = np.array([np.sin(psi), np.cos(psi)])
    u = np.array([-np.cos(psi), np.sin(psi)])  # along the arm, away from the pivot
    px = cx - radius * (np.cos(a) * m[0] + np.sin(a) * u[0])
    py = cy - radius * (np.cos(a) * m[1] + np.sin(a) * u[1])
    return np.append(px, px[0]), np.append(py, py[0])


def draw_follower(ax, curves, theta, psi) -> tuple[float, float]:
    """The pitch curve, the face and its arm at the angle where the contact travels furthest across
    the face, the contact point; the pivot's position (cam coordinates) at that angle."""
    c = curves
    travel = np.asarray(c.face_travel_mm)
    i = int(np.argmax(np.abs(travel)))
    ax.plot(c.pitch_x_mm, c.pitch_y_mm, color="C2", linestyle="-.", linewidth=0.8,
            label="pitch curve (centre of the face's circle)")
    rc, width = c.roller_radius_mm, c.face_width_mm
    d, arm, p = c.pivot_distance_mm, c.arm_length_mm, psi[i]
    cx, cy = d - arm * np.cos(p), arm * np.sin(p)  # follower frame
    fx, fy = face_outline(cx, cy, p, rc, width)
    fx, fy = (np.asarray(v) for v in zip(*(to_cam_frame(x, y, theta[i], c.rotation)
                                           for x, y in zip(fx, fy, strict=True)), strict=True))
    ax.plot(fx, fy, color="C1", linewidth=1.8,
            label=f"curved face, R_c = {rc:g} mm, W = {width:.3g} mm, at θ = {c.theta_deg[i]:g}° "
                  f"(contact {travel[i]:.3g} mm off its axis)")
    px, py = to_cam_frame(d, 0.0, theta[i], c.rotation)
    mid = np.array([fx[0] + fx[-2], fy[0] + fy[-2]]) / 2.0  # the chord's middle
    ax.plot([px, mid[0]], [py, mid[1]], color="C1", linewidth=2.5,
            label=f"arm l = {arm:g} mm (to the circle's centre)")
    ax.plot(c.profile_x_mm[i], c.profile_y_mm[i], "o", color="C3", markersize=4, label="contact point")
    return px, py


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile, pressure angle and curvature, loads."""
    return drawing.figure_builders(curves, draw_follower)


def profile_table(curves) -> tuple[list[str], np.ndarray]:
    """The rocking family's columns, then the contact's travel on the face (mm, R_c sin phi) and the
    sliding speed (m/s)."""
    names, table = drawing.profile_table(curves)
    return ([*names, "face_travel_mm", "sliding_speed_m_s"],
            np.column_stack([table, curves.face_travel_mm, curves.sliding_speed_m_s]))


def mechanism(curves, title: str = "", violation: str | None = None, bad=None):
    """The rocking family's :class:`camjax.output.animation.Mechanism` (the face's circle as its
    ``roller_radius_mm``) with the face width, and the samples where the contact runs off the face
    among the bad ones."""
    if bad is None:
        half = 0.5 * curves.face_width_mm
        off = np.abs(np.asarray(curves.face_travel_mm)) > half * (1 + 1e-9)
        bad = drawing.violation_samples(curves) | off
    m = drawing.mechanism(curves, title, violation, bad)
    return m._replace(face_width_mm=float(curves.face_width_mm))


def follower_points(m, psi) -> tuple[np.ndarray, np.ndarray]:
    """The centre of the face's circle, C = (d - l cos psi, l sin psi), at arm angles psi (rad),
    fixed frame, mm."""
    return m.pivot_distance_mm - m.arm_length_mm * np.cos(psi), m.arm_length_mm * np.sin(psi)


def artists(ax, m, poses, r_max: float) -> FollowerArtists:
    """The pivot, the arm to the face's chord and the face (an arc of radius R_c, chord W) at its
    end, the arc of the circle's centre."""
    d, rc, width = m.pivot_distance_mm, m.roller_radius_mm, m.face_width_mm
    every_psi = np.deg2rad(m.arm_start_angle_deg + np.asarray(m.swing_deg))
    ax.plot([d], [0.0], "o", color="k", markersize=7, markerfacecolor="w", zorder=4,
            label=f"pivot, d = {d:g} mm")
    arc = np.linspace(every_psi.min(), every_psi.max(), 60)
    ax.plot(*follower_points(m, arc), color="0.45", linewidth=0.8, linestyle=":",
            label="arc of the face circle's centre")
    (face,) = ax.plot([], [], color="C1", linewidth=2.0,
                      label=f"curved face, R_c = {rc:g} mm, W = {width:.3g} mm")
    (arm_line,) = ax.plot([], [], color="C1", linewidth=3.0, solid_capstyle="round",
                          label=f"arm, l = {m.arm_length_mm:g} mm")

    def update(i):
        p = np.deg2rad(poses.arm_angle_deg[i])
        fx, fy = face_outline(poses.follower_x_mm[i], poses.follower_y_mm[i], p, rc, width)
        face.set_data(fx, fy)
        arm_line.set_data([d, (fx[0] + fx[-2]) / 2.0], [0.0, (fy[0] + fy[-2]) / 2.0])
        return face, arm_line

    def normal(i):  # from the contact point through the circle's centre
        nx = poses.follower_x_mm[i] - poses.contact_x_mm[i]
        ny = poses.follower_y_mm[i] - poses.contact_y_mm[i]
        n = np.hypot(nx, ny)
        return nx / n, ny / n

    cx, cy = follower_points(m, every_psi)
    xs = np.concatenate([cx - rc, cx + rc, [d, -r_max, r_max]])
    ys = np.concatenate([cy - rc, cy + rc, [0.0, -r_max, r_max]])
    pad = 0.06 * max(np.ptp(xs), np.ptp(ys))
    named = {"follower": face, "arm": arm_line, "face": face}
    return FollowerArtists(named, [face, arm_line], update, normal,
                           (xs.min() - pad, xs.max() + pad), (ys.min() - pad, ys.max() + pad))
