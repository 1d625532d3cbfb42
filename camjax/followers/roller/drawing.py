"""Figures, profile table and animation of a roller follower (NumPy and matplotlib only).

The shared figures are :mod:`camjax.followers._translating_drawing`'s; the roller adds its part of
the profile figure (the roller at the angle of largest pressure angle, with the pitch curve) and
its shape in the animation (a circle of radius R_f on the stem, offset e).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _translating_drawing as drawing
from camjax.followers._translating_drawing import DrawnFollower, mechanism, profile_table

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "figure_builders", "follower_points", "mechanism",
           "profile_table"]


CONTACT_SHAPE = "circle"  # what touches the cam: a circle of radius ``roller_radius_mm`` (the Mechanism's)


def draw_follower(ax, curves, theta, sign: float) -> DrawnFollower:
    """The roller at the angle of largest pressure angle on its stem, the pitch curve, the contact
    point and the smallest |rho| of the pitch curve; undercut samples are the bad ones."""
    x, y, t, rb = curves.profile_x_mm, curves.profile_y_mm, curves.theta_deg, curves.base_radius_mm
    phi = np.linspace(0.0, 2.0 * np.pi, 361)
    i = int(np.argmax(np.abs(curves.pressure_angle_deg)))
    px, py = curves.pitch_x_mm, curves.pitch_y_mm
    ax.plot(np.append(px, px[0]), np.append(py, py[0]), color="C2", linestyle="-.",
            linewidth=0.8, label="pitch curve (roller centre)")
    cx, cy = curves.pitch_x_mm[i], curves.pitch_y_mm[i]
    rf = curves.roller_radius_mm
    ax.plot(cx + rf * np.sin(phi), cy + rf * np.cos(phi), color="C1", linewidth=1.5,
            label=f"roller follower, R_f = {rf:g} mm, at θ = {t[i]:g}° "
                  f"(largest pressure angle {curves.pressure_angle_deg[i]:.1f}°)")
    axis = np.array([sign * np.sin(theta[i]), np.cos(theta[i])])  # follower axis at this angle
    stem = np.array([[cx, cy], [cx, cy] + (rf + 0.35 * rb) * axis])
    ax.plot(stem[:, 0], stem[:, 1], color="C1", linewidth=1.5)
    ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point")
    j = int(np.argmin(np.abs(curves.pitch_rho_mm)))
    ax.plot(curves.pitch_x_mm[j], curves.pitch_y_mm[j], "s", color="C2", markersize=5, zorder=4,
            label=f"smallest |ρ_pitch| = {abs(curves.pitch_rho_mm[j]):.3g} mm at θ = {t[j]:g}°")
    return DrawnFollower(float(np.max(np.hypot(stem[:, 0], stem[:, 1]))), curves.undercut_margin_mm <= 0,
                         "undercut: |ρ_pitch| ≤ R_f")


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile and, when declared, loads and stress."""
    return drawing.figure_builders(curves, draw_follower)


def follower_points(m, s) -> tuple[np.ndarray, np.ndarray]:
    """The roller's centre at displacements ``s`` (mm), fixed frame: on the prime circle, the pitch
    point is at (e, d + s), d = sqrt(R_p^2 - e^2)."""
    rp = m.base_radius_mm + m.roller_radius_mm
    return np.full_like(s, m.offset_mm), np.sqrt(max(rp**2 - m.offset_mm**2, 0.0)) + s


def artists(ax, m, poses, r_max: float):
    """The roller on its stem, sliding along +Y at the offset e."""
    return drawing.slider_artists(ax, m, poses, r_max, "circle")
