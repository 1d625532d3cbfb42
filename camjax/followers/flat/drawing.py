"""Figures, profile table and animation of a flat-face follower (NumPy and matplotlib only).

The shared figures are :mod:`camjax.followers._translating_drawing`'s; the flat face adds its part
of the profile figure (the face at the angle of largest contact offset |s'|, where the face width
is decided) and its shape in the animation (a face of width L on the stem).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _translating_drawing as drawing
from camjax.followers._translating_drawing import DrawnFollower, mechanism, profile_table

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "figure_builders", "follower_points", "mechanism",
           "profile_table"]


CONTACT_SHAPE = "face"  # what touches the cam: a straight face (a line in the follower frame)


def draw_follower(ax, curves, theta, sign: float) -> DrawnFollower:
    """The face (width L) at the angle of largest |s'|, its stem, the contact point at its edge,
    and the smallest rho of the outline."""
    x, y, t, rb = curves.profile_x_mm, curves.profile_y_mm, curves.theta_deg, curves.base_radius_mm
    i = int(np.argmax(np.abs(curves.ds_mm)))
    axis = np.array([sign * np.sin(theta[i]), np.cos(theta[i])])  # follower axis at this angle
    along = np.array([sign * np.cos(theta[i]), -np.sin(theta[i])])  # along the face
    centre = (rb + curves.s_mm[i]) * axis
    half = 0.5 * curves.face_width_mm
    ends = np.array([centre - half * along, centre + half * along])
    ax.plot(ends[:, 0], ends[:, 1], color="C1", linewidth=3,
            label=f"flat-face follower, L = {curves.face_width_mm:.3f} mm, at θ = {t[i]:g}°")
    stem = np.array([centre, centre + 0.35 * rb * axis])
    ax.plot(stem[:, 0], stem[:, 1], color="C1", linewidth=1.5)
    ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point (at the face's edge)")
    bad = curves.rho_mm < 0 if curves.rho_mm is not None else np.zeros_like(x, bool)
    if curves.rho_mm is not None:
        j = int(np.argmin(curves.rho_mm))
        ax.plot(x[j], y[j], "s", color="C2", markersize=5, zorder=4,
                label=f"smallest ρ = {curves.rho_mm[j]:.3g} mm at θ = {t[j]:g}°")
    return DrawnFollower(float(np.max(np.hypot(ends[:, 0], ends[:, 1]))), bad,
                         "ρ < 0: the face cannot follow the outline")


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile and, when declared, loads and stress."""
    return drawing.figure_builders(curves, draw_follower)


def follower_points(m, s) -> tuple[np.ndarray, np.ndarray]:
    """The face's centre, on the axis, at displacements ``s`` (mm), fixed frame."""
    return np.zeros_like(s), m.base_radius_mm + s


def artists(ax, m, poses, r_max: float):
    """The face on its stem, sliding along +Y."""
    return drawing.slider_artists(ax, m, poses, r_max, "face")
