"""Figures of a design report: motion (s, v, a, j), cam profile, loads, contact stress.

Each function takes :class:`camjax.evaluate.DesignCurves` and returns a matplotlib ``Figure``
built without pyplot (no global state, no GUI backend: ``Figure.savefig`` renders with Agg), so
that plotting is safe in scripts, tests and threads. Saving is the caller's job (``export.py``).
Angles are in degrees on every horizontal axis; the vertical dotted lines mark segment joints.
Every cycle is drawn closed, 0 to 360 deg inclusive: the value at 360 deg is the one at 0 (the
motion is periodic). A ``title`` (see :func:`camjax.output.titles.title_block`) names the run on
every figure, so printouts of two runs can be told apart. The module imports NumPy and matplotlib
only (not JAX), so that :mod:`camjax.output.drawing` can draw in processes of their own.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from camjax.output.titles import TURNS

if TYPE_CHECKING:  # imported without JAX: figures are drawn in worker processes (camjax.output.drawing)
    from camjax.evaluate import DesignCurves

_JOINT_STYLE = {"color": "0.6", "linestyle": ":", "linewidth": 0.8}
_SIZE = (7.0, 6.4)
_TITLE_FONT = 7.5


# ---------------------------------------------------------------------------- helpers


def closed(theta_deg, values):
    """(theta, values) with the 360 deg point appended (= the value at 0 deg): a closed cycle."""
    t = np.asarray(theta_deg)
    v = np.asarray(values)
    return np.append(t, t[0] + 360.0), np.append(v, v[0])


def _title(fig: Figure, title: str, what: str) -> None:
    """Figure title: what it shows, then the run's title block (top left)."""
    fig.suptitle(what + ("\n" + title if title else ""), fontsize=_TITLE_FONT, x=0.01, ha="left",
                 linespacing=1.3)


def _cycle_axis(ax, curves: DesignCurves, label: bool = True) -> None:
    """0..360 deg axis with the segment joints marked."""
    for start in curves.segment_starts_deg:
        ax.axvline(start, **_JOINT_STYLE)
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 60))
    ax.grid(True, alpha=0.3)
    if label:
        ax.set_xlabel("cam angle θ (deg)")


def _mark_extremes(ax, theta, values, fmt: str, which=("max", "min")) -> None:
    """Dots and labels at the max and min (``which``) of a curve (labels kept inside the axes;
    NaN samples are passed over)."""
    if np.all(np.isnan(values)):
        return
    picks = {"max": np.nanargmax, "min": np.nanargmin}
    for i in {int(picks[w](values)) for w in which}:
        ax.plot(theta[i], values[i], "o", color="C3", markersize=3)
        right = theta[i] > 250  # label to the left near the right edge
        ax.annotate(fmt.format(values[i], theta[i]), (theta[i], values[i]), fontsize=7,
                    xytext=(-4 if right else 4, 0), textcoords="offset points", va="center",
                    ha="right" if right else "left")


def _runs(mask) -> list[tuple[int, int]]:
    """[first, last] indices of each run of True in a boolean array (no wrap)."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    edges = np.flatnonzero(np.diff(m.astype(int)))
    return [(int(a), int(b) - 1) for a, b in zip(edges[::2], edges[1::2], strict=True)]


RHO_AXIS_CAM_RADII = 4.0  # a radius-of-curvature axis spans at most +- this many largest cam radii


def rho_axis_limit_mm(profile_x_mm, profile_y_mm) -> float:
    """The largest |rho| (mm) a radius-of-curvature panel shows: 4 times the cam's largest radius.

    Near an inflection of the outline (or of a roller's pitch curve) rho runs off to +-infinity
    between samples; an autoscaled axis then spans spikes of 1e4 mm with the rest of the curve
    flat on zero. What the panel is read for lies at small |rho|: the curvature and undercut
    limits, and the contact stress, which grows as rho shrinks. A bound that scales with the cam
    (not a percentile of the samples, which could cut off a narrow dip to the smallest rho, the
    value that matters) keeps every rho of the order of the cam's own radii, the dwells' R_b
    among them; a stretch beyond it is flatter than a circle four times the size of the whole cam,
    nearly straight at the scale of the drawing, and is marked as leaving the axis
    (:func:`clip_axis`) with its extreme value written.
    """
    return RHO_AXIS_CAM_RADII * float(np.max(np.hypot(profile_x_mm, profile_y_mm)))


def clip_axis(ax, theta, values, limit: float, unit: str = "mm") -> np.ndarray:
    """Hold ``ax``'s y axis within +-``limit`` where ``values`` leave that band, and mark the cut.

    Each run of samples beyond the band gets a red triangle on the edge it leaves by (up above,
    down below) at its most extreme sample; the most extreme value on each side is written beside
    its triangle, and a note in the panel states the clip. Returns the mask of clipped samples;
    where none is clipped the axis is left alone (all False).
    """
    t, v = np.asarray(theta), np.asarray(values)
    over, under = v > limit, v < -limit
    cut = over | under
    if not cut.any():
        return cut
    inside = v[~cut]
    lo, hi = (float(inside.min()), float(inside.max())) if inside.size else (-limit, limit)
    pad = 0.08 * max(hi - lo, 1e-9 * limit)
    top = limit if over.any() else min(hi + pad, limit)
    bottom = -limit if under.any() else max(lo - pad, -limit)
    ax.set_ylim(bottom, top)
    for mask, edge, marker, sign in ((over, top, "^", 1.0), (under, bottom, "v", -1.0)):
        runs = _runs(mask)
        if not runs:
            continue
        peaks = [a + int(np.argmax(sign * v[a:b + 1])) for a, b in runs]
        ax.plot(t[peaks], np.full(len(peaks), edge), marker, color="C3", markersize=5, linestyle="none",
                clip_on=False, zorder=5)
        k = max(peaks, key=lambda i: sign * v[i])
        right = t[k] > 250  # label to the left near the right edge
        ax.annotate(f"{v[k]:.4g} {unit} @ {t[k]:g}°", (t[k], edge), fontsize=7, color="C3",
                    xytext=(-7 if right else 7, -4 * sign), textcoords="offset points",
                    ha="right" if right else "left", va="top" if sign > 0 else "bottom")
    # above the panel, right: clear of the curve and of the edge labels
    ax.set_title(f"axis clipped at ±{limit:.4g} {unit} (4 × the cam's largest radius); ▲▼: runs beyond it",
                 loc="right", fontsize=6.5, color="C3", pad=3)
    return cut


# ---------------------------------------------------------------------------- figures


def svaj_figure(curves: DesignCurves, title: str = "") -> Figure:
    """Displacement (mm), velocity (m/s), acceleration (m/s²) and jerk (m/s³) over the cycle."""
    fig = Figure(figsize=_SIZE, layout="constrained")
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
            _mark_extremes(ax, t, values, fmt)
        ax.margins(y=0.12)
        _cycle_axis(ax, curves, label=k == 3)
    _title(fig, title, "Follower motion over one cycle (dotted: segment joints; dots: extremes)")
    return fig


def _dimension(ax, start, end, text: str, color: str = "0.15", **text_kw) -> None:
    """A dimension line with arrows at both ends and its text at the middle."""
    ax.annotate("", xy=end, xytext=start,
                arrowprops={"arrowstyle": "<|-|>", "color": color, "linewidth": 0.9,
                            "shrinkA": 0, "shrinkB": 0, "mutation_scale": 8})
    mid = 0.5 * (np.asarray(start) + np.asarray(end))
    ax.annotate(text, mid, fontsize=7, color=color, xytext=(4, 4), textcoords="offset points",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8},
                **text_kw)


def _rotation_arrow(ax, radius: float, toward_deg: float, sign: float, label: str = "ω") -> None:
    """Arc arrow around the centre in the cam's direction of rotation (``sign`` +1:
    counter-clockwise, -1: clockwise), centred on the polar direction ``toward_deg``
    (counter-clockwise from +X)."""
    from matplotlib.patches import FancyArrowPatch

    a, b = np.deg2rad(toward_deg - 70.0 * sign), np.deg2rad(toward_deg + 70.0 * sign)
    ax.add_patch(FancyArrowPatch((radius * np.cos(a), radius * np.sin(a)),
                                 (radius * np.cos(b), radius * np.sin(b)),
                                 connectionstyle=f"arc3,rad={0.45 * sign}", arrowstyle="-|>",
                                 mutation_scale=11, color="0.25", linewidth=1.1))
    c = np.deg2rad(toward_deg)
    ax.text(1.5 * radius * np.cos(c), 1.5 * radius * np.sin(c), label, ha="center", va="center",
            fontsize=8, color="0.25")


def _angle_ring(ax, radius: float, sign: float) -> None:
    """Ticks every 30 deg of cam angle on a ring around the cam (θ from +Y, clockwise on a
    counter-clockwise cam, ``sign`` = +1; mirrored for a clockwise one, ``sign`` = -1)."""
    for deg in range(0, 360, 30):
        u = np.array([sign * np.sin(np.deg2rad(deg)), np.cos(np.deg2rad(deg))])
        ax.plot(*np.column_stack([radius * u, 1.05 * radius * u]), color="0.35", linewidth=0.8)
        ax.text(*(1.13 * radius * u), f"{deg}°", fontsize=6.5, ha="center", va="center", color="0.3")
    phi = np.linspace(0.0, 2.0 * np.pi, 181)
    ax.plot(radius * np.sin(phi), radius * np.cos(phi), color="0.75", linewidth=0.5)


def profile_figure(curves: DesignCurves, title: str = "") -> Figure:
    """Cam outline in cam coordinates (mm) with base circle, dimensions and the follower at one angle.

    Drawn: the direction of rotation, cam-angle ticks every 30 deg (the radius at θ meets the
    follower when the cam has turned by θ), the lift and the largest radius as dimensions, the
    smallest radius of curvature, and in red the outline where it breaks a constraint (ρ < 0 for a
    flat face, undercut for a roller). Flat face: the face (width L) at the angle of largest
    contact offset |s'|, where the face width is decided. Roller: the roller at the angle of
    largest pressure angle, with the pitch curve.
    """
    fig = Figure(figsize=(6.2, 7.6), layout="constrained")
    ax = fig.subplots()
    x, y = curves.profile_x_mm, curves.profile_y_mm
    t = curves.theta_deg
    ax.fill(x, y, color="C0", alpha=0.12)
    ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C0", linewidth=1.5, label="cam profile")
    phi = np.linspace(0.0, 2.0 * np.pi, 361)
    rb = curves.base_radius_mm
    ax.plot(rb * np.sin(phi), rb * np.cos(phi), color="0.5", linestyle="--", linewidth=0.8,
            label=f"base circle R_b = {rb:.3f} mm")
    ax.plot([0.0], [0.0], "+", color="k", markersize=9)
    theta = np.deg2rad(t)
    sign = 1.0 if curves.rotation == "ccw" else -1.0  # a cw cam is the mirror image (X -> -X)
    radius = np.hypot(x, y)
    reach = float(np.max(radius))
    if curves.follower_type == "flat":
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
        reach = max(reach, float(np.max(np.hypot(ends[:, 0], ends[:, 1]))))
        bad = curves.rho_mm < 0 if curves.rho_mm is not None else np.zeros_like(x, bool)
        bad_label = "ρ < 0: the face cannot follow the outline"
        if curves.rho_mm is not None:
            j = int(np.argmin(curves.rho_mm))
            ax.plot(x[j], y[j], "s", color="C2", markersize=5, zorder=4,
                    label=f"smallest ρ = {curves.rho_mm[j]:.3g} mm at θ = {t[j]:g}°")
    else:
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
        reach = max(reach, float(np.max(np.hypot(stem[:, 0], stem[:, 1]))))
        bad = curves.undercut_margin_mm <= 0
        bad_label = "undercut: |ρ_pitch| ≤ R_f"
        j = int(np.argmin(np.abs(curves.pitch_rho_mm)))
        ax.plot(curves.pitch_x_mm[j], curves.pitch_y_mm[j], "s", color="C2", markersize=5, zorder=4,
                label=f"smallest |ρ_pitch| = {abs(curves.pitch_rho_mm[j]):.3g} mm at θ = {t[j]:g}°")
    if bad.any():
        ax.plot(np.where(bad, x, np.nan), np.where(bad, y, np.nan), color="C3", linewidth=2.5,
                label=bad_label)
    # lift: base circle to R_b + h, radially, in the middle of the highest part of the motion
    top = np.flatnonzero(curves.s_mm >= np.max(curves.s_mm) - 1e-9 * max(1.0, np.max(curves.s_mm)))
    k = int(top[len(top) // 2])
    u = np.array([sign * np.sin(theta[k]), np.cos(theta[k])])
    lift = float(np.max(curves.s_mm) - np.min(curves.s_mm))
    _dimension(ax, (rb + np.min(curves.s_mm)) * u, (rb + np.max(curves.s_mm)) * u, f"lift h = {lift:.3g} mm")
    # largest radius of the outline, centre to the outline
    m = int(np.argmax(radius))
    _dimension(ax, (0.0, 0.0), (x[m], y[m]), f"R_max = {radius[m]:.3f} mm\nat θ = {t[m]:g}°")
    # the arrow sits opposite the largest-radius dimension, clear of it
    _rotation_arrow(ax, 0.3 * rb, float(np.degrees(np.arctan2(-y[m], -x[m]))), sign)
    ring = 1.06 * reach
    _angle_ring(ax, ring, sign)
    lim = 1.22 * ring
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.25)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    turns = TURNS[curves.rotation]
    _title(fig, title, "Cam profile in cam coordinates: follower axis +Y at θ = 0, θ "
                       f"{TURNS['cw' if curves.rotation == 'ccw' else 'ccw']}; the cam turns {turns} (ω)")
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    return fig


def loads_figure(curves: DesignCurves, title: str = "") -> Figure:
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
    _cycle_axis(ax_f, curves, label=False)
    ax_t.plot(*closed(t, curves.torque_Nm), color="C1", linewidth=1.2)
    ax_t.axhline(0.0, color="0.3", linewidth=0.6)
    _mark_extremes(ax_t, t, curves.torque_Nm, "{:.4g} N·m @ {:g}°")
    ax_t.set_ylabel("cam torque T (N·m)")
    ax_t.margins(y=0.15)
    _cycle_axis(ax_t, curves)
    _title(fig, title, "Kinetostatic loads: contact force and its parts, cam torque")
    return fig


def stress_figure(curves: DesignCurves, title: str = "") -> Figure:
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
    _cycle_axis(ax_s, curves, label=False)
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
    _cycle_axis(ax_r, curves)
    _title(fig, title, f"Contact stress and {what} at R_b = {curves.base_radius_mm:.3f} mm")
    return fig


def stamp_banner(fig: Figure, text: str) -> Figure:
    """A red banner across the top of ``fig`` (e.g. naming the constraints a geometry breaks).

    The figure's title block moves below the banner and the layout keeps both free, so the
    banner covers no title, axis or legend.
    """
    height = fig.get_figheight()
    top = 1.0 - 0.35 / height  # the banner's 0.35 inch
    title = fig.get_suptitle()
    if title:  # re-placed at an explicit height under the banner (the layout leaves it alone then)
        old = fig._suptitle
        lines = title.count("\n") + 1
        title_in = lines * old.get_fontsize() * old.get_linespacing() / 72.0 + 0.05
        fig.suptitle(title, x=old.get_position()[0], y=top, ha=old.get_ha(), va="top",
                     fontsize=old.get_fontsize(), linespacing=old.get_linespacing())
        top -= title_in / height
    engine = fig.get_layout_engine()
    if engine is not None and hasattr(engine, "set"):
        engine.set(rect=(0.0, 0.0, 1.0, top))
    fig.text(0.5, 0.995, text, ha="center", va="top", fontsize=8, color="white", fontweight="bold",
             wrap=True, zorder=10, bbox={"boxstyle": "square,pad=0.4", "facecolor": "#c00000",
                                         "edgecolor": "none"})
    return fig


def figure_builders(curves: DesignCurves) -> dict[str, Callable[[DesignCurves, str], Figure]]:
    """{file name: figure function} for what the scene declares: no loads or stress figure
    without them (nothing is drawn here)."""
    out = {"svaj.png": svaj_figure, "profile.png": profile_figure}
    if curves.force_N is not None:
        out["loads.png"] = loads_figure
    if curves.stress_MPa is not None:
        out["stress.png"] = stress_figure
    return out


def design_figures(curves: DesignCurves, title: str = "") -> dict[str, Figure]:
    """{file name: figure} of :func:`figure_builders`, drawn."""
    return {name: build(curves, title) for name, build in figure_builders(curves).items()}


def laws_figure(x, laws: dict[str, tuple[np.ndarray, ...]]) -> Figure:
    """Normalized s, v, a, j of several laws overlaid, one panel each (x and values dimensionless).

    ``laws`` maps a legend label (a law's name, with its joint classes if wanted) to
    (p, p', p'', p''') sampled at ``x`` in [0, 1], lift 1: the panels compare shapes and peaks.
    Where a law meets a dwell, the jump in each derivative is its value at x = 0 or x = 1.
    """
    fig = Figure(figsize=(10.0, 7.5), layout="constrained")
    axes = fig.subplots(2, 2, sharex=True).ravel()
    titles = ["displacement p", "velocity p'", "acceleration p''", "jerk p'''"]
    # 10 colours x 2 line styles: up to 20 laws stay distinguishable in print
    styles = [(f"C{k % 10}", "-" if k < 10 else "--") for k in range(len(laws))]
    for panel, (ax, title) in enumerate(zip(axes, titles, strict=True)):
        for (name, values), (color, ls) in zip(laws.items(), styles, strict=True):
            ax.plot(x, values[panel], color=color, linestyle=ls, linewidth=1.1, label=name)
        ax.axhline(0.0, color="0.3", linewidth=0.5)
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.set_xlim(0.0, 1.0)
        if panel >= 2:
            ax.set_xlabel("x = (θ − θ_start) / β")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside right center", fontsize=8,
               title="law [joint after / before a dwell]", title_fontsize=8)
    fig.suptitle("Motion laws, normalized: lift 1 over x in [0, 1]; derivatives with respect to x",
                 fontsize=11)
    return fig
