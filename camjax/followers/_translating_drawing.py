"""Figures, profile table and animation of a translating follower: what every such type shares.

A translating follower's ``drawing.py`` supplies its own part of the profile figure
(``draw_follower``, returning a :class:`DrawnFollower`) and of the animation (its point on the
axis and its shape); everything else is drawn here from the run's
:class:`camjax.followers._translating.DesignCurves` (or a namespace with the same fields: the
drawing processes rebuild them without JAX). NumPy and matplotlib only.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import NamedTuple

import numpy as np
from matplotlib.figure import Figure

from camjax.followers._closure_drawing import draw_closure, second_outline, second_roller
from camjax.output import animation
from camjax.output.animation import ANGLE_RTOL, LENGTH_TOL_MM, FollowerArtists, Mechanism
from camjax.output.export import profile_columns
from camjax.output.plots import (
    FIGURE_SIZE,
    angle_ring,
    cam_outline,
    clip_axis,
    closed,
    cycle_axis,
    dimension,
    mark_extremes,
    rho_axis_limit_mm,
    rotation_arrow,
    title_figure,
)
from camjax.output.titles import TURNS


class DrawnFollower(NamedTuple):
    """What a follower's part of the profile figure tells the rest of it."""

    reach_mm: float  # the largest distance from the cam centre it draws at
    bad: np.ndarray  # (N,) samples where the outline breaks a constraint (drawn red)
    bad_label: str  # the legend's words for them


# ---------------------------------------------------------------------------- figures


def svaj_figure(curves, title: str = "") -> Figure:
    """Displacement (mm), velocity (m/s), acceleration (m/s²) and jerk (m/s³) over the cycle."""
    fig = Figure(figsize=FIGURE_SIZE, layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    t = curves.theta_deg
    rows = [(curves.s_mm, "s (mm)", "{:.3g} @ {:g}°"),
            (curves.velocity_m_s, "v (m/s)", "{:.4g} @ {:g}°"),
            (curves.accel_m_s2, "a (m/s²)", "{:.5g} @ {:g}°"),
            (curves.jerk_m_s3, "j (m/s³)", "{:.4g} @ {:g}°")]
    for k, (ax, (values, name, fmt)) in enumerate(zip(axes, rows, strict=True)):
        ax.plot(*closed(t, values), color=f"C{k}", linewidth=1.2)
        ax.set_ylabel(name)
        ax.axhline(0.0, color="0.3", linewidth=0.5)
        flat = np.ptp(values) <= 1e-9 * (1.0 + np.max(np.abs(values)))  # e.g. a of the uniform law
        if flat:  # a fixed span: autoscaling would blow rounding noise (1e-17) up to full height
            ax.set_ylim(values[0] - 1.0, values[0] + 1.0)
        elif k > 0:
            mark_extremes(ax, t, values, fmt)
        ax.margins(y=0.12)
        cycle_axis(ax, curves, label=k == 3)
    title_figure(fig, title, "Follower motion over one cycle (dotted: segment joints; dots: extremes)")
    return fig


def profile_figure(curves, title: str = "", draw_follower=None) -> Figure:
    """Cam outline in cam coordinates (mm) with base circle, dimensions and the follower at one angle.

    Drawn: the direction of rotation, cam-angle ticks every 30 deg (the radius at θ meets the
    follower when the cam has turned by θ), the lift and the largest radius as dimensions, the
    smallest radius of curvature, and in red the outline where it breaks a constraint (ρ < 0 for a
    flat face, undercut for a roller). Flat face: the face (width L) at the angle of largest
    contact offset |s'|, where the face width is decided. Roller: the roller at the angle of
    largest pressure angle, with the pitch curve. ``draw_follower(ax, curves, theta_rad, sign)``
    (the follower's drawing module) draws the follower and returns a :class:`DrawnFollower`.
    """
    fig = Figure(figsize=(6.2, 7.6), layout="constrained")
    ax = fig.subplots()
    x, y, rb = curves.profile_x_mm, curves.profile_y_mm, curves.base_radius_mm
    t = curves.theta_deg
    cam_outline(ax, x, y, rb, markersize=9)
    theta = np.deg2rad(t)
    sign = 1.0 if curves.rotation == "ccw" else -1.0  # a cw cam is the mirror image (X -> -X)
    radius = np.hypot(x, y)
    reach = float(np.max(radius))
    drawn = draw_follower(ax, curves, theta, sign)
    reach = max(reach, drawn.reach_mm, draw_closure(ax, curves))
    bad, bad_label = drawn.bad, drawn.bad_label
    if bad.any():
        ax.plot(np.where(bad, x, np.nan), np.where(bad, y, np.nan), color="C3", linewidth=2.5,
                label=bad_label)
    # lift: base circle to R_b + h, radially, in the middle of the highest part of the motion
    top = np.flatnonzero(curves.s_mm >= np.max(curves.s_mm) - 1e-9 * max(1.0, np.max(curves.s_mm)))
    k = int(top[len(top) // 2])
    u = np.array([sign * np.sin(theta[k]), np.cos(theta[k])])
    lift = float(np.max(curves.s_mm) - np.min(curves.s_mm))
    dimension(ax, (rb + np.min(curves.s_mm)) * u, (rb + np.max(curves.s_mm)) * u, f"lift h = {lift:.3g} mm")
    # largest radius of the outline, centre to the outline
    m = int(np.argmax(radius))
    dimension(ax, (0.0, 0.0), (x[m], y[m]), f"R_max = {radius[m]:.3f} mm\nat θ = {t[m]:g}°")
    # the arrow sits opposite the largest-radius dimension, clear of it
    rotation_arrow(ax, 0.3 * rb, float(np.degrees(np.arctan2(-y[m], -x[m]))), sign)
    ring = 1.06 * reach
    angle_ring(ax, ring, sign)
    lim = 1.22 * ring
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.25)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    turns = TURNS[curves.rotation]
    title_figure(fig, title, "Cam profile in cam coordinates: follower axis +Y at θ = 0, θ "
                       f"{TURNS['cw' if curves.rotation == 'ccw' else 'ccw']}; the cam turns {turns} (ω)")
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    return fig


def loads_figure(curves, title: str = "") -> Figure:
    """Contact force (N) with its parts, and cam torque (N·m); shaded where F < 0.

    The parts (inertia m a, spring k (y + x0), damping c v, gravity m g) add up to the total F;
    the contact margin is min F over the cycle (> 0: the follower stays on the cam).
    """
    fig = Figure(figsize=(7.0, 5.6), layout="constrained")
    ax_f, ax_t = fig.subplots(2, 1, sharex=True, height_ratios=[1.6, 1.0])
    t, force = curves.theta_deg, curves.force_N
    parts = curves.force_parts_N or {}
    styles = {"inertia": ("C2", "--"), "spring": ("C4", "-."), "damping": ("C5", ":"),
              "gravity": ("C7", (0, (5, 2, 1, 2)))}
    for name, values in parts.items():
        color, ls = styles.get(name, ("0.5", "--"))
        ax_f.plot(*closed(t, values), color=color, linestyle=ls, linewidth=1.0, label=f"{name}")
    ax_f.plot(*closed(t, force), color="C0", linewidth=1.8, label="total contact force F")
    ax_f.axhline(0.0, color="0.3", linewidth=0.6)
    lost = force < 0
    if lost.any():
        ax_f.fill_between(t, 0, 1, where=lost, transform=ax_f.get_xaxis_transform(), color="C3",
                          alpha=0.2, label="loss of contact (F < 0)")
    i = int(np.argmin(force))
    ax_f.plot(t[i], force[i], "o", color="C3", markersize=4)
    verdict = "the follower stays on the cam" if force[i] > 0 else "the follower leaves the cam"
    ax_f.axhline(force[i], color="C3", linewidth=0.7, linestyle="--", label="contact margin (min F)")
    # the label opens towards the middle of the cycle, so that it stays inside the axes wherever
    # the minimum falls (at 0 deg a label to the left would leave them and squeeze the layout)
    left = t[i] < 180.0
    ax_f.annotate(f"contact margin: min F = {force[i]:.4g} N at {t[i]:g}° ({verdict})",
                  (t[i], force[i]), fontsize=7, xytext=(8 if left else -8, -12), textcoords="offset points",
                  ha="left" if left else "right", va="top",
                  bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.7"})
    j = int(np.argmax(force))
    ax_f.plot(t[j], force[j], "o", color="C3", markersize=3)
    ax_f.annotate(f"max F = {force[j]:.4g} N @ {t[j]:g}°", (t[j], force[j]), fontsize=7, xytext=(4, 2),
                  textcoords="offset points", ha="right" if t[j] > 250 else "left")
    ax_f.set_ylabel("force (N)")
    ax_f.margins(y=0.15)
    # below the figure, clear of the curves and their labels
    fig.legend(*ax_f.get_legend_handles_labels(), fontsize=7, loc="outside lower center", ncols=4)
    cycle_axis(ax_f, curves, label=False)
    ax_t.plot(*closed(t, curves.torque_Nm), color="C1", linewidth=1.2)
    ax_t.axhline(0.0, color="0.3", linewidth=0.6)
    mark_extremes(ax_t, t, curves.torque_Nm, "{:.4g} N·m @ {:g}°")
    ax_t.set_ylabel("cam torque T (N·m)")
    ax_t.margins(y=0.15)
    cycle_axis(ax_t, curves)
    title_figure(fig, title, "Kinetostatic loads: contact force and its parts, cam torque")
    return fig


def stress_figure(curves, title: str = "") -> Figure:
    """Hertz contact stress (MPa) scaled to its own range, σ_max as a line and the margin;
    below, the radius of curvature of the profile (flat face) or of the pitch curve (roller), mm."""
    fig = Figure(figsize=(7.0, 5.2), layout="constrained")
    ax_s, ax_r = fig.subplots(2, 1, sharex=True)
    t = curves.theta_deg
    finite = np.isfinite(curves.stress_MPa)
    if curves.rho_mm is not None:  # where ρ < 0 there is no contact to stress: left out
        finite &= curves.rho_mm > 0
    stress = np.where(finite, curves.stress_MPa, np.nan)
    ax_s.plot(*closed(t, stress), color="C3", linewidth=1.2, label="σ (Hertz, 0.564 factor)")
    if not finite.all():
        ax_s.fill_between(t, 0, 1, where=~finite, transform=ax_s.get_xaxis_transform(), color="C3",
                          alpha=0.2, label="no valid contact (ρ ≤ 0)")
    i = int(np.nanargmax(np.where(finite, stress, np.nan))) if finite.any() else 0
    peak = float(stress[i])
    ax_s.plot(t[i], peak, "o", color="k", markersize=3)
    ax_s.annotate(f"peak {peak:.5g} MPa @ {t[i]:g}°", (t[i], peak), fontsize=7, xytext=(-6, -2),
                  textcoords="offset points", ha="right", va="top")
    # the axis follows the data (a far-away σ_max would squash the curve flat)
    lo, hi = (float(np.min(stress[finite])), peak) if finite.any() else (0.0, 1.0)
    pad = 0.12 * max(hi - lo, 1e-9 * max(abs(hi), 1.0))
    ax_s.set_ylim(lo - pad, hi + 2.2 * pad)
    smax = curves.sigma_max_MPa
    if smax is not None:
        if smax <= hi + 2.2 * pad:
            ax_s.axhline(smax, color="0.2", linestyle="--", linewidth=0.9, label=f"σ_max = {smax:g} MPa")
            ax_s.set_ylim(lo - pad, max(hi, smax) + 2.2 * pad)
            where = ""
        else:
            where = " (above this scale)"
        margin = smax - peak
        if not finite.all():  # σ grows without bound as ρ -> 0+: no margin to speak of
            text, bad = f"σ_max = {smax:g} MPa{where}: EXCEEDED (σ → ∞ where ρ → 0)", True
        elif margin < 0:
            text, bad = f"σ_max = {smax:g} MPa{where}: EXCEEDED by {-margin:.4g} MPa", True
        else:
            text, bad = (f"σ_max = {smax:g} MPa{where}: margin {margin:.4g} MPa "
                         f"(peak = {peak / smax:.0%} of σ_max)"), False
        ax_s.text(0.01, 0.96, text, transform=ax_s.transAxes, fontsize=7, va="top",
                  color="C3" if bad else "0.1",
                  bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "0.7"})
    ax_s.set_ylabel("σ (MPa)")
    ax_s.legend(fontsize=7, loc="upper right")
    cycle_axis(ax_s, curves, label=False)
    cut = np.zeros(t.shape, bool)
    if curves.rho_mm is not None:  # flat face: the profile's radius of curvature
        lower, name, what = curves.rho_mm, "ρ (mm)", "radius of curvature"
        limit = rho_axis_limit_mm(curves.profile_x_mm, curves.profile_y_mm)
        cut = clip_axis(ax_r, t, lower, limit)
        j = int(np.argmin(lower))  # below the axis: clip_axis has written it at the edge
        label = f"smallest {lower[j]:.4g} mm @ {t[j]:g}°" if lower[j] >= -limit else None
    else:  # roller: the pressure angle that tilts the normal force F / cos φ
        lower, name, what = curves.pressure_angle_deg, "φ (°)", "pressure angle"
        limit = curves.pressure_angle_limit_deg
        for lim in (-limit, limit):
            ax_r.axhline(lim, color="0.3", linestyle="--", linewidth=0.8)
        ax_r.text(0.01, 0.96, f"limit ±{limit:g}°", transform=ax_r.transAxes, fontsize=7, va="top")
        j = int(np.argmax(np.abs(lower)))
        label = f"max |φ| {abs(lower[j]):.4g}° @ {t[j]:g}°"
    ax_r.plot(*closed(t, lower), color="C2", linewidth=1.2)
    ax_r.axhline(0.0, color="0.3", linewidth=0.6)
    if label is not None:
        ax_r.plot(t[j], lower[j], "o", color="k", markersize=3)
        ax_r.annotate(label, (t[j], lower[j]), fontsize=7, xytext=(-6 if t[j] > 180 else 6, 4),
                      textcoords="offset points", ha="right" if t[j] > 180 else "left")  # inside the axes
    if curves.rho_mm is not None and (lower < 0).any():
        ax_r.fill_between(t, 0, 1, where=lower < 0, transform=ax_r.get_xaxis_transform(), color="C3",
                          alpha=0.2, label="ρ < 0: the face cannot follow")
        ax_r.legend(fontsize=7, loc="upper left")
    ax_r.set_ylabel(name)
    if not cut.any():  # a clipped axis keeps its stated bounds
        ax_r.margins(y=0.15)
    cycle_axis(ax_r, curves)
    title_figure(fig, title, f"Contact stress and {what} at R_b = {curves.base_radius_mm:.3f} mm")
    return fig




def figure_builders(curves, draw_follower) -> dict[str, Callable]:
    """{file name: figure function (curves, title) -> Figure} for what the scene declares: no loads
    or stress figure without them (nothing is drawn here); ``draw_follower``: the follower's part
    of the profile figure (see :func:`profile_figure`)."""
    out = {"svaj.png": svaj_figure, "profile.png": partial(profile_figure, draw_follower=draw_follower)}
    if curves.force_N is not None:
        out["loads.png"] = loads_figure
    if curves.stress_MPa is not None:
        out["stress.png"] = stress_figure
    return out


# ----------------------------------------------------------------------------- profile.csv


def profile_table(curves) -> tuple[list[str], np.ndarray]:
    """Column names and an (N, k) table: angle, outline X/Y, follower motion, curvature, then
    every curve whose extrema result.json reports (so that each can be checked against samples).

    The first columns keep their order (angle, outline, s, s', rho or pitch curve and pressure
    angle); the later ones were appended after them: s'' (mm/rad^2), v, a, j (SI), the roller's
    pitch-curve radius of curvature, and with the models the force, cam torque and stress.
    """
    names = ["theta_deg", "x_mm", "y_mm", "s_mm", "ds_mm_per_rad"]
    cols = [curves.theta_deg, curves.profile_x_mm, curves.profile_y_mm, curves.s_mm, curves.ds_mm]
    if curves.rho_mm is not None:
        names.append("rho_mm")
        cols.append(curves.rho_mm)
    if curves.pitch_x_mm is not None:
        names += ["pitch_x_mm", "pitch_y_mm", "pressure_angle_deg"]
        cols += [curves.pitch_x_mm, curves.pitch_y_mm, curves.pressure_angle_deg]
    names += ["d2s_mm_per_rad2", "velocity_m_s", "accel_m_s2", "jerk_m_s3"]
    cols += [curves.d2s_mm, curves.velocity_m_s, curves.accel_m_s2, curves.jerk_m_s3]
    optional = (("pitch_rho_mm", curves.pitch_rho_mm), ("force_N", curves.force_N),
                ("torque_Nm", curves.torque_Nm), ("stress_MPa", curves.stress_MPa))
    return profile_columns(names, cols, optional, curves)


# ------------------------------------------------------------------------------- animation


def violation_samples(curves) -> np.ndarray:
    """(N,) booleans: the samples where the outline breaks a constraint, to be drawn red.

    The outline checks of :func:`camjax.followers._translating.geometry_violations`, per sample:
    rho < 0 (the outline crosses itself); undercut (margin < 0) and |pressure angle| over its limit.
    Within the solvers' tolerances nothing is marked (an optimum sits on its limits).
    """
    bad = np.zeros(np.shape(curves.theta_deg), bool)
    if curves.rho_mm is not None:
        bad |= np.asarray(curves.rho_mm) < -LENGTH_TOL_MM
    if curves.undercut_margin_mm is not None:
        bad |= np.asarray(curves.undercut_margin_mm) < -LENGTH_TOL_MM
    limit = curves.pressure_angle_limit_deg
    if curves.pressure_angle_deg is not None and limit is not None:
        bad |= np.abs(np.asarray(curves.pressure_angle_deg)) > limit * (1.0 + ANGLE_RTOL)
    return bad


def mechanism(curves, title: str = "", violation: str | None = None, bad=None) -> Mechanism:
    """The :class:`camjax.output.animation.Mechanism` of a translating follower's design curves
    (``bad``: default :func:`violation_samples`)."""
    return Mechanism(
        np.asarray(curves.theta_deg), np.asarray(curves.profile_x_mm), np.asarray(curves.profile_y_mm),
        np.asarray(curves.s_mm), curves.follower_type, float(curves.base_radius_mm),
        curves.face_width_mm, curves.roller_radius_mm, float(curves.offset_mm or 0.0),
        None if curves.pressure_angle_deg is None else np.asarray(curves.pressure_angle_deg),
        title, violation, violation_samples(curves) if bad is None else bad, curves.rotation,
        second_outline=second_outline(curves), second_roller=second_roller(curves),
    )


def slider_artists(ax, m: Mechanism, poses: animation.FramePoses, r_max: float, shape: str) -> FollowerArtists:
    """A translating follower on its stem, sliding in a guide along +Y: a face of the width
    ``m.face_width_mm`` (``shape = "face"``) or a circle of radius ``m.roller_radius_mm``
    (``shape = "circle"``, a roller or a curved face)."""
    from matplotlib.patches import Circle

    flat = shape == "face"
    half = 0.5 * (m.face_width_mm if flat else 2.0 * m.roller_radius_mm)
    stem = 0.5 * r_max + (0.0 if flat else m.roller_radius_mm)
    top = float(np.max(poses.follower_y_mm)) + stem
    reach = max(r_max, abs(m.offset_mm) + half) * 1.08
    # guide of the follower stem: two fixed bars beside it
    gx = (m.offset_mm if not flat else 0.0) + np.array([-1.0, 1.0]) * 0.12 * r_max
    gy = top - 0.35 * stem
    for xg in gx:
        ax.plot([xg, xg], [gy, top], color="0.35", linewidth=2.5)
    (stem_line,) = ax.plot([], [], color="C1", linewidth=2.0)
    if flat:
        (follower,) = ax.plot([], [], color="C1", linewidth=4.0, solid_capstyle="butt",
                              label=f"flat face, L = {m.face_width_mm:.2f} mm")
        roller = None
    else:
        roller = Circle((0.0, 0.0), m.roller_radius_mm, fill=False, color="C1", linewidth=2.0,
                        label=f"roller, R_f = {m.roller_radius_mm:g} mm")
        ax.add_patch(roller)
        (follower,) = ax.plot([], [], "o", color="C1", markersize=3)  # roller centre

    def update(i):
        fx, fy = poses.follower_x_mm[i], poses.follower_y_mm[i]
        if flat:
            follower.set_data([fx - half, fx + half], [fy, fy])
        else:
            roller.center = (fx, fy)
            follower.set_data([fx], [fy])
        stem_line.set_data([fx, fx], [fy, fy + stem])
        return (follower, stem_line) + (() if roller is None else (roller,))

    def normal(i):
        # the force line at phi from the follower axis; for a roller it runs through the roller's
        # centre, (-sin phi, cos phi) with phi = atan((s' - e) / (d + s)) of camjax.followers._pitch
        phi = np.deg2rad(poses.pressure_angle_deg[i])
        return -np.sin(phi), np.cos(phi)

    moving = [stem_line, follower] + ([roller] if roller is not None else [])
    return FollowerArtists({"follower": roller if roller is not None else follower}, moving, update,
                           normal, (-reach, reach), (-r_max * 1.08, top + 0.05 * r_max))
