"""Figures, profile table and animation of a curved-face follower (NumPy and matplotlib only).

The shared figures are :mod:`camjax.followers._translating_drawing`'s; the curved face adds its
part of the profile figure (the face, an arc of radius R_c and chord W, at the angle where the
contact travels furthest across it, with the pitch curve of its centre) and its shape in the
animation (the arc on its stem). profile.csv gains the contact's travel on the face
(``face_travel_mm``, R_c sin phi) and the sliding speed (``sliding_speed_m_s``).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _translating_drawing as drawing
from camjax.followers._translating_drawing import DrawnFollower, mechanism, profile_table
from camjax.output.animation import FollowerArtists

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "face_outline", "figure_builders", "follower_points",
           "mechanism", "profile_table"]


# what touches the cam: a circle of radius ``roller_radius_mm`` (the Mechanism's; here R_c), of
# which the face is the arc within +-W/2 of the axis
CONTACT_SHAPE = "circle"


def face_outline(cx, cy, axis, along, radius: float, width: float,
                 points: int = 41) -> tuple[np.ndarray, np.ndarray]:
    """The face (its arc, closed by its chord) around the circle's centre (cx, cy), the follower
    axis ``axis`` pointing away from the cam and ``along`` across it (unit vectors), mm."""
    a_max = np.arcsin(min(width / (2.0 * radius), 1.0))
    a = np.linspace(-a_max, a_max, points)
    px = cx + radius * (np.sin(a) * along[0] - np.cos(a) * axis[0])
    py = cy + radius * (np.sin(a) * along[1] - np.cos(a) * axis[1])
    return np.append(px, px[0]), np.append(py, py[0])


def draw_follower(ax, curves, theta, sign: float) -> DrawnFollower:
    """The face at the angle where the contact travels furthest across it, its stem, the pitch
    curve (the face circle's centre), the contact point and the smallest |rho| of the pitch curve;
    undercut samples are the bad ones."""
    x, y, t, rb = curves.profile_x_mm, curves.profile_y_mm, curves.theta_deg, curves.base_radius_mm
    travel = curves.own_curves["face_travel_mm"]
    i = int(np.argmax(np.abs(travel)))
    px, py = curves.pitch_x_mm, curves.pitch_y_mm
    ax.plot(np.append(px, px[0]), np.append(py, py[0]), color="C2", linestyle="-.",
            linewidth=0.8, label="pitch curve (centre of the face's circle)")
    rc, width = curves.roller_radius_mm, curves.face_width_mm
    axis = np.array([sign * np.sin(theta[i]), np.cos(theta[i])])  # follower axis at this angle
    along = np.array([np.cos(theta[i]), -sign * np.sin(theta[i])])  # the follower's +x
    fx, fy = face_outline(px[i], py[i], axis, along, rc, width)
    ax.plot(fx, fy, color="C1", linewidth=1.8,
            label=f"curved face, R_c = {rc:g} mm, W = {width:.3g} mm, at θ = {t[i]:g}° "
                  f"(contact {travel[i]:.3g} mm off the axis)")
    chord = np.array([fx[0], fy[0]]) + 0.5 * np.array([fx[-2] - fx[0], fy[-2] - fy[0]])
    stem = np.array([chord, chord + 0.35 * rb * axis])
    ax.plot(stem[:, 0], stem[:, 1], color="C1", linewidth=1.5)
    ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point")
    j = int(np.argmin(np.abs(curves.pitch_rho_mm)))
    ax.plot(px[j], py[j], "s", color="C2", markersize=5, zorder=4,
            label=f"smallest |ρ_pitch| = {abs(curves.pitch_rho_mm[j]):.3g} mm at θ = {t[j]:g}°")
    reach = float(max(np.max(np.hypot(fx, fy)), np.max(np.hypot(stem[:, 0], stem[:, 1]))))
    return DrawnFollower(reach, curves.undercut_margin_mm <= 0, "undercut: |ρ_pitch| ≤ R_c")


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile and, when declared, loads and stress."""
    return drawing.figure_builders(curves, draw_follower)


def follower_points(m, s) -> tuple[np.ndarray, np.ndarray]:
    """The centre of the face's circle at displacements ``s`` (mm), fixed frame: (e, d + s),
    d = sqrt(R_p^2 - e^2), R_p = R_b + R_c."""
    rp = m.base_radius_mm + m.roller_radius_mm
    return np.full_like(s, m.offset_mm), np.sqrt(max(rp**2 - m.offset_mm**2, 0.0)) + s


def artists(ax, m, poses, r_max: float) -> FollowerArtists:
    """The face (an arc of radius R_c, chord W) on its stem, sliding along +Y at the offset e; the
    stem leaves the middle of the chord."""
    rc, width = m.roller_radius_mm, m.face_width_mm
    sag = rc * (1.0 - np.cos(np.arcsin(min(width / (2.0 * rc), 1.0))))  # the crown's height over the chord
    stem = 0.5 * r_max
    apex = np.asarray(poses.follower_y_mm) - rc  # the face's lowest point on the axis
    top = float(np.max(apex)) + sag + stem
    reach = max(r_max, abs(m.offset_mm) + 0.5 * width) * 1.08
    gx = m.offset_mm + np.array([-1.0, 1.0]) * 0.12 * r_max
    for xg in gx:
        ax.plot([xg, xg], [top - 0.35 * stem, top], color="0.35", linewidth=2.5)
    (face,) = ax.plot([], [], color="C1", linewidth=2.0,
                      label=f"curved face, R_c = {rc:g} mm, W = {width:.3g} mm")
    (stem_line,) = ax.plot([], [], color="C1", linewidth=2.0)
    up, across = np.array([0.0, 1.0]), np.array([1.0, 0.0])

    def update(i):
        cx, cy = poses.follower_x_mm[i], poses.follower_y_mm[i]
        face.set_data(*face_outline(cx, cy, up, across, rc, width))
        base = cy - rc + sag
        stem_line.set_data([cx, cx], [base, base + stem])
        return face, stem_line

    def normal(i):
        # the contact normal runs through the circle's centre at phi from the axis (as a roller's)
        phi = np.deg2rad(poses.pressure_angle_deg[i])
        return -np.sin(phi), np.cos(phi)

    return FollowerArtists({"follower": face}, [face, stem_line], update, normal, (-reach, reach),
                           (-r_max * 1.08, top + 0.05 * r_max))
