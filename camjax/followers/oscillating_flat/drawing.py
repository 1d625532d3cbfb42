"""Figures, profile table and animation of an oscillating flat-face follower (NumPy and matplotlib
only).

The shared figures are :mod:`camjax.followers._rocking_drawing`'s; the rocker face adds its part of
the profile figure (the face at the contact's furthest reach along it, its offset from the pivot)
and its point in the animation (the foot of the pivot on the face).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _rocking_drawing as drawing
from camjax.followers._rocking_drawing import mechanism, profile_table, to_cam_frame

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "figure_builders", "follower_points", "mechanism",
           "profile_table"]


CONTACT_SHAPE = "face"  # what touches the cam: a straight face (a line in the follower frame)


def draw_follower(ax, curves, theta, psi) -> tuple[float, float]:
    """The stretch of the face the contact sweeps, at the angle of its furthest reach, the face's
    offset from the pivot and the contact point; the pivot's position (cam coordinates)."""
    c, x, y = curves, curves.profile_x_mm, curves.profile_y_mm
    xi = c.contact_distance_mm
    i = int(np.argmax(xi))
    d, f, p = c.pivot_distance_mm, c.face_offset_mm, psi[i]
    foot = np.array([d - f * np.sin(p), -f * np.cos(p)])  # follower frame
    u = np.array([-np.cos(p), np.sin(p)])
    ends = [foot + xi.min() * u, foot + xi.max() * u]
    pts = [np.array([d, 0.0]), foot, *ends]
    px, fx, e0, e1 = (np.array(to_cam_frame(q[0], q[1], theta[i], c.rotation)) for q in pts)
    ax.plot([e0[0], e1[0]], [e0[1], e1[1]], color="C1", linewidth=3,
            label=f"face ({xi.max() - xi.min():.3f} mm swept) at θ = {c.theta_deg[i]:g}°")
    ax.plot([px[0], fx[0]], [px[1], fx[1]], color="C1", linewidth=1.5, label=f"face offset f = {f:g} mm")
    ax.plot([px[0], e0[0]], [px[1], e0[1]], color="C1", linewidth=1.0, linestyle=":")
    ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point")
    return float(px[0]), float(px[1])


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile, pressure angle and curvature, loads."""
    return drawing.figure_builders(curves, draw_follower)


def follower_points(m, psi) -> tuple[np.ndarray, np.ndarray]:
    """The foot of the pivot on the face, A - f m with m = (sin psi, cos psi) the face normal, at arm
    angles psi (rad), fixed frame, mm."""
    f = m.face_offset_mm
    return m.pivot_distance_mm - f * np.sin(psi), -f * np.cos(psi)


def artists(ax, m, poses, r_max: float):
    """The pivot, the arm to the face's foot and the face, the path of the face point in contact."""
    return drawing.rocker_artists(ax, m, poses, r_max, "face", follower_points)
