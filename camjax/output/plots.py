"""Figures of a design report: motion (s, v, a, j), cam profile, loads, contact stress.

Each function takes :class:`camjax.evaluate.DesignCurves` and returns a matplotlib ``Figure``
built without pyplot (no global state, no GUI backend: ``Figure.savefig`` renders with Agg), so
that plotting is safe in scripts, tests and threads. Saving is the caller's job (``export.py``).
Angles are in degrees on every horizontal axis; the vertical dotted lines mark segment joints.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from camjax.evaluate import DesignCurves

_JOINT_STYLE = {"color": "0.6", "linestyle": ":", "linewidth": 0.8}
_SIZE = (7.0, 6.0)


def _cycle_axis(ax, curves: DesignCurves, label: bool = True) -> None:
    """0..360 deg axis with the segment joints marked."""
    for start in curves.segment_starts_deg:
        ax.axvline(start, **_JOINT_STYLE)
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 60))
    ax.grid(True, alpha=0.3)
    if label:
        ax.set_xlabel("cam angle θ (deg)")


def _mark_extremes(ax, theta, values, fmt: str) -> None:
    """Dots and labels at the max and min of a curve."""
    for i in {int(np.argmax(values)), int(np.argmin(values))}:
        ax.plot(theta[i], values[i], "o", color="C3", markersize=3)
        ax.annotate(fmt.format(values[i], theta[i]), (theta[i], values[i]), fontsize=7,
                    xytext=(4, 0), textcoords="offset points", va="center")


def svaj_figure(curves: DesignCurves) -> Figure:
    """Displacement (mm), velocity (m/s), acceleration (m/s²) and jerk (m/s³) over the cycle."""
    fig = Figure(figsize=_SIZE, layout="constrained")
    axes = fig.subplots(4, 1, sharex=True)
    t = curves.theta_deg
    rows = [(curves.s_mm, "s (mm)", "{:.3g} @ {:g}°"),
            (curves.velocity_m_s, "v (m/s)", "{:.4g} @ {:g}°"),
            (curves.accel_m_s2, "a (m/s²)", "{:.5g} @ {:g}°"),
            (curves.jerk_m_s3, "j (m/s³)", "{:.4g} @ {:g}°")]
    for k, (ax, (values, name, fmt)) in enumerate(zip(axes, rows, strict=True)):
        ax.plot(t, values, color=f"C{k}", linewidth=1.2)
        ax.set_ylabel(name)
        ax.axhline(0.0, color="0.3", linewidth=0.5)
        if k > 0:
            _mark_extremes(ax, t, values, fmt)
        _cycle_axis(ax, curves, label=k == 3)
    axes[0].set_title("Follower motion (dotted: segment joints)", fontsize=10)
    return fig


def profile_figure(curves: DesignCurves) -> Figure:
    """Cam outline in cam coordinates (mm) with base circle and the follower drawn at one angle.

    Flat face: the face (width L) at the angle of largest contact offset |s'|, where the face width
    is decided. Roller: the roller at the angle of largest pressure angle, with the pitch curve.
    """
    fig = Figure(figsize=(6.0, 6.6), layout="constrained")
    ax = fig.subplots()
    x, y = curves.profile_x_mm, curves.profile_y_mm
    ax.fill(x, y, color="C0", alpha=0.12)
    ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C0", linewidth=1.5, label="cam profile")
    phi = np.linspace(0.0, 2.0 * np.pi, 361)
    rb = curves.base_radius_mm
    ax.plot(rb * np.sin(phi), rb * np.cos(phi), color="0.5", linestyle="--", linewidth=0.8,
            label=f"base circle R_b = {rb:.3f} mm")
    ax.plot([0.0], [0.0], "+", color="k")
    theta = np.deg2rad(curves.theta_deg)
    sign = 1.0 if curves.rotation == "ccw" else -1.0  # a cw cam is the mirror image (X -> -X)
    if curves.follower_type == "flat":
        i = int(np.argmax(np.abs(curves.ds_mm)))
        axis = np.array([sign * np.sin(theta[i]), np.cos(theta[i])])  # follower axis at this angle
        along = np.array([sign * np.cos(theta[i]), -np.sin(theta[i])])  # along the face
        centre = (rb + curves.s_mm[i]) * axis
        half = 0.5 * curves.face_width_mm
        ends = np.array([centre - half * along, centre + half * along])
        ax.plot(ends[:, 0], ends[:, 1], color="C1", linewidth=3,
                label=f"flat face L = {curves.face_width_mm:.3f} mm at θ = {curves.theta_deg[i]:g}°")
        stem = np.array([centre, centre + 0.6 * rb * axis])
        ax.plot(stem[:, 0], stem[:, 1], color="C1", linewidth=1.5)
        ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point")
        if curves.rho_mm is not None:
            j = int(np.argmin(curves.rho_mm))
            ax.plot(x[j], y[j], "s", color="C2", markersize=4,
                    label=f"min ρ = {curves.rho_mm[j]:.3g} mm at {curves.theta_deg[j]:g}°")
    else:
        i = int(np.argmax(np.abs(curves.pressure_angle_deg)))
        ax.plot(curves.pitch_x_mm, curves.pitch_y_mm, color="C2", linestyle="-.", linewidth=0.8,
                label="pitch curve")
        cx, cy = curves.pitch_x_mm[i], curves.pitch_y_mm[i]
        rf = curves.roller_radius_mm
        ax.plot(cx + rf * np.sin(phi), cy + rf * np.cos(phi), color="C1", linewidth=1.5,
                label=f"roller R_f = {rf:g} mm at θ = {curves.theta_deg[i]:g}° "
                      f"(φ = {curves.pressure_angle_deg[i]:.1f}°)")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    turn = "clockwise" if curves.rotation == "ccw" else "counterclockwise"  # contact point vs the cam
    ax.set_title(f"Cam profile (follower axis +Y at θ = 0; θ {turn}; cam turns {curves.rotation})",
                 fontsize=10)
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    return fig


def loads_figure(curves: DesignCurves) -> Figure:
    """Contact force (N) and cam torque (N·m); shaded where F < 0 (the follower leaves the cam)."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax_f, ax_t = fig.subplots(2, 1, sharex=True)
    t, force = curves.theta_deg, curves.force_N
    ax_f.plot(t, force, color="C0", linewidth=1.2, label="contact force F")
    ax_f.axhline(0.0, color="0.3", linewidth=0.6)
    _mark_extremes(ax_f, t, force, "{:.4g} N @ {:g}°")
    lost = force < 0
    if lost.any():
        ax_f.fill_between(t, 0, 1, where=lost, transform=ax_f.get_xaxis_transform(), color="C3",
                          alpha=0.2, label="loss of contact (F < 0)")
        ax_f.legend(fontsize=7)
    ax_f.set_ylabel("F (N)")
    ax_f.margins(y=0.15)
    _cycle_axis(ax_f, curves, label=False)
    ax_t.plot(t, curves.torque_Nm, color="C1", linewidth=1.2)
    ax_t.axhline(0.0, color="0.3", linewidth=0.6)
    _mark_extremes(ax_t, t, curves.torque_Nm, "{:.4g} N·m @ {:g}°")
    ax_t.set_ylabel("T (N·m)")
    ax_t.margins(y=0.15)
    _cycle_axis(ax_t, curves)
    ax_f.set_title("Kinetostatic loads", fontsize=10)
    return fig


def stress_figure(curves: DesignCurves) -> Figure:
    """Hertz contact stress (MPa, with the allowed value if any) below it the flat face's radius of
    curvature (mm) or the roller's pressure angle (deg, with its limit)."""
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax_s, ax_r = fig.subplots(2, 1, sharex=True)
    t = curves.theta_deg
    ax_s.plot(t, curves.stress_MPa, color="C3", linewidth=1.2, label="σ (0.564 Hertz factor)")
    i = int(np.argmax(curves.stress_MPa))
    ax_s.plot(t[i], curves.stress_MPa[i], "o", color="k", markersize=3)
    ax_s.annotate(f"{curves.stress_MPa[i]:.5g} MPa @ {t[i]:g}°", (t[i], curves.stress_MPa[i]),
                  fontsize=7, xytext=(-90, -4), textcoords="offset points")
    if curves.sigma_max_MPa is not None:
        ax_s.axhline(curves.sigma_max_MPa, color="0.3", linestyle="--", linewidth=0.8,
                     label=f"σ_max = {curves.sigma_max_MPa:g} MPa")
    ax_s.set_ylabel("σ (MPa)")
    ax_s.legend(fontsize=7, loc="upper left")
    _cycle_axis(ax_s, curves, label=False)
    if curves.rho_mm is not None:  # flat face: the profile's radius of curvature
        lower, unit, what = curves.rho_mm, "mm", "curvature"
        ax_r.set_ylabel("ρ (mm)")
        j = int(np.argmin(lower))
    else:  # roller: the pressure angle that tilts the normal force F / cos φ
        lower, unit, what = curves.pressure_angle_deg, "°", "pressure angle"
        ax_r.set_ylabel("φ (°)")
        for lim in (-curves.pressure_angle_limit_deg, curves.pressure_angle_limit_deg):
            ax_r.axhline(lim, color="0.3", linestyle="--", linewidth=0.8)
        j = int(np.argmax(np.abs(lower)))
    ax_r.plot(t, lower, color="C2", linewidth=1.2)
    ax_r.axhline(0.0, color="0.3", linewidth=0.6)
    ax_r.plot(t[j], lower[j], "o", color="k", markersize=3)
    ax_r.annotate(f"{'min' if curves.rho_mm is not None else 'max |φ|'} {lower[j]:.4g} {unit} @ {t[j]:g}°",
                  (t[j], lower[j]), fontsize=7, xytext=(-90, 4), textcoords="offset points")
    _cycle_axis(ax_r, curves)
    ax_s.set_title(f"Contact stress and {what} at R_b = {curves.base_radius_mm:.3f} mm", fontsize=10)
    return fig


def stamp_banner(fig: Figure, text: str) -> Figure:
    """A red banner across the top of ``fig`` (e.g. naming the constraints a geometry breaks).

    The layout keeps the top 0.35 inch free for it, so it covers no title or axis.
    """
    engine = fig.get_layout_engine()
    if engine is not None and hasattr(engine, "set"):
        engine.set(rect=(0.0, 0.0, 1.0, 1.0 - 0.35 / fig.get_figheight()))
    fig.text(0.5, 0.995, text, ha="center", va="top", fontsize=8, color="white", fontweight="bold",
             wrap=True, zorder=10, bbox={"boxstyle": "square,pad=0.4", "facecolor": "#c00000",
                                         "edgecolor": "none"})
    return fig


def design_figures(curves: DesignCurves) -> dict[str, Figure]:
    """{file name: figure} for what the scene declares: no loads or stress figure without them."""
    out = {"svaj.png": svaj_figure(curves), "profile.png": profile_figure(curves)}
    if curves.force_N is not None:
        out["loads.png"] = loads_figure(curves)
    if curves.stress_MPa is not None:
        out["stress.png"] = stress_figure(curves)
    return out


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
