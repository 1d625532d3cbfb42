"""Figures, profile table and animation of a knife-edge follower (NumPy and matplotlib only).

The shared figures are :mod:`camjax.followers._translating_drawing`'s; the knife edge adds its part
of the profile figure (the edge at the angle of largest pressure angle, its tip on the outline) and
its shape in the animation (a wedge on the stem, offset e, its tip on the cam).
"""

from __future__ import annotations

import numpy as np

from camjax.followers import _translating_drawing as drawing
from camjax.followers._translating_drawing import DrawnFollower, mechanism
from camjax.output.animation import LENGTH_TOL_MM, FollowerArtists

__all__ = ["CONTACT_SHAPE", "artists", "draw_follower", "figure_builders", "follower_points", "mechanism",
           "profile_table"]


# what touches the cam: a circle of radius 0 (the Mechanism's ``roller_radius_mm`` is 0), the tip
CONTACT_SHAPE = "circle"


def _wedge(tip, axis, size: float) -> np.ndarray:
    """The edge's outline: a wedge of half-angle 20 deg with its tip at ``tip``, opening along ``axis``."""
    across = np.array([axis[1], -axis[0]])
    back = tip + size * axis
    half = size * np.tan(np.radians(20.0))
    return np.array([back - half * across, tip, back + half * across])


def draw_follower(ax, curves, theta, sign: float) -> DrawnFollower:
    """The edge at the angle of largest pressure angle on its stem, its tip (the contact point) and
    the smallest |rho| of the profile; samples whose convex radius is below the minimum are bad."""
    x, y, t, rb = curves.profile_x_mm, curves.profile_y_mm, curves.theta_deg, curves.base_radius_mm
    i = int(np.argmax(np.abs(curves.pressure_angle_deg)))
    axis = np.array([sign * np.sin(theta[i]), np.cos(theta[i])])  # follower axis at this angle
    tip = np.array([x[i], y[i]])
    wedge = _wedge(tip, axis, 0.12 * rb)
    ax.fill(wedge[:, 0], wedge[:, 1], color="C1", alpha=0.8,
            label=f"knife-edge follower, e = {curves.offset_mm:g} mm, at θ = {t[i]:g}° "
                  f"(largest pressure angle {curves.pressure_angle_deg[i]:.1f}°)")
    stem = np.array([tip + 0.12 * rb * axis, tip + 0.45 * rb * axis])
    ax.plot(stem[:, 0], stem[:, 1], color="C1", linewidth=1.5)
    ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point (the tip)")
    j = int(np.argmin(np.abs(curves.pitch_rho_mm)))
    ax.plot(x[j], y[j], "s", color="C2", markersize=5, zorder=4,
            label=f"smallest |ρ| = {abs(curves.pitch_rho_mm[j]):.3g} mm at θ = {t[j]:g}°")
    limit = np.asarray(curves.undercut_margin_mm)  # rho - rho_min on convex parts
    return DrawnFollower(float(np.max(np.hypot(stem[:, 0], stem[:, 1]))), limit < -LENGTH_TOL_MM,
                         "convex radius below min_curvature_radius_mm")


def figure_builders(curves) -> dict:
    """{file name: figure function}: motion, profile and, with loads, the loads (no stress)."""
    return drawing.figure_builders(curves, draw_follower)


def profile_table(curves) -> tuple[list[str], np.ndarray]:
    """The shared table without the pitch curve's columns (the tip's pitch curve is the outline,
    ``x_mm``, ``y_mm``) and with the profile's radius of curvature as ``rho_mm``."""
    names, table = drawing.profile_table(curves)
    keep = [k for k, n in enumerate(names) if n not in ("pitch_x_mm", "pitch_y_mm")]
    names = ["rho_mm" if names[k] == "pitch_rho_mm" else names[k] for k in keep]
    return names, table[:, keep]


def follower_points(m, s) -> tuple[np.ndarray, np.ndarray]:
    """The tip at displacements ``s`` (mm), fixed frame: at (e, d + s), d = sqrt(R_b^2 - e^2)."""
    return np.full_like(s, m.offset_mm), np.sqrt(max(m.base_radius_mm**2 - m.offset_mm**2, 0.0)) + s


def artists(ax, m, poses, r_max: float) -> FollowerArtists:
    """The edge on its stem, sliding in a guide along +Y at the offset e, its tip on the cam."""
    from matplotlib.patches import Polygon

    size = 0.12 * r_max
    stem = 0.5 * r_max
    top = float(np.max(poses.follower_y_mm)) + stem
    reach = max(r_max, abs(m.offset_mm) + size) * 1.08
    gy = top - 0.35 * stem
    for xg in m.offset_mm + np.array([-1.0, 1.0]) * 0.12 * r_max:  # the guide: two fixed bars
        ax.plot([xg, xg], [gy, top], color="0.35", linewidth=2.5)
    (stem_line,) = ax.plot([], [], color="C1", linewidth=2.0)
    edge = Polygon(_wedge(np.zeros(2), np.array([0.0, 1.0]), size), closed=True, color="C1",
                   label=f"knife edge, e = {m.offset_mm:g} mm")
    ax.add_patch(edge)

    def update(i):
        fx, fy = poses.follower_x_mm[i], poses.follower_y_mm[i]
        edge.set_xy(_wedge(np.array([fx, fy]), np.array([0.0, 1.0]), size))
        stem_line.set_data([fx, fx], [fy + size, fy + stem])
        return edge, stem_line

    def normal(i):
        # the force line at phi from the follower axis, through the tip (camjax.followers._pitch)
        phi = np.deg2rad(poses.pressure_angle_deg[i])
        return -np.sin(phi), np.cos(phi)

    return FollowerArtists({"follower": edge}, [stem_line, edge], update, normal, (-reach, reach),
                           (-r_max * 1.08, top + 0.05 * r_max))
