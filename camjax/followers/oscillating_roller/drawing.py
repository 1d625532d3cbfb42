"""Figures, profile table and animation of an oscillating roller follower (NumPy and matplotlib only).

The shared figures are :mod:`camjax.followers._rocking_drawing`'s; the rocker roller adds its part
of the profile figure (the roller and its arm at the angle of largest pressure angle, with the pitch
curve) and its point in the animation (the roller's centre on its arc).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _rocking_drawing as drawing
from camjax.followers._rocking_drawing import mechanism, profile_table, to_cam_frame

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "figure_builders", "follower_points", "mechanism",
           "profile_table"]


CONTACT_SHAPE = "circle"  # what touches the cam: a circle of radius ``roller_radius_mm`` (the Mechanism's)


def draw_follower(ax, curves, theta, psi) -> tuple[float, float]:
    """The pitch curve, the roller at the angle of largest |phi| and its arm; the pivot's position
    (cam coordinates) at that angle."""
    c = curves
    a = np.linspace(0.0, 2.0 * np.pi, 361)
    i = int(np.argmax(np.abs(c.pressure_angle_deg)))
    ax.plot(c.pitch_x_mm, c.pitch_y_mm, color="C2", linestyle="-.", linewidth=0.8, label="pitch curve")
    cx, cy = c.pitch_x_mm[i], c.pitch_y_mm[i]
    rf = c.roller_radius_mm
    ax.plot(cx + rf * np.sin(a), cy + rf * np.cos(a), color="C1", linewidth=1.5,
            label=f"roller R_f = {rf:g} mm at θ = {c.theta_deg[i]:g}° "
                  f"(φ = {c.pressure_angle_deg[i]:.1f}°)")
    px, py = to_cam_frame(c.pivot_distance_mm, 0.0, theta[i], c.rotation)
    ax.plot([px, cx], [py, cy], color="C1", linewidth=2.5, label=f"arm l = {c.arm_length_mm:g} mm")
    return px, py


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile, pressure angle and curvature, loads."""
    return drawing.figure_builders(curves, draw_follower)


def follower_points(m, psi) -> tuple[np.ndarray, np.ndarray]:
    """The roller's centre C = (d - l cos psi, l sin psi) at arm angles psi (rad), fixed frame, mm
    (:func:`camjax.followers.oscillating_roller.geometry.roller_centre`, in NumPy)."""
    return m.pivot_distance_mm - m.arm_length_mm * np.cos(psi), m.arm_length_mm * np.sin(psi)


def artists(ax, m, poses, r_max: float):
    """The pivot, the arm and the roller at its end, the arc of the roller's centre."""
    return drawing.rocker_artists(ax, m, poses, r_max, "circle", follower_points)
