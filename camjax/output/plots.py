"""What every figure shares: closed cycles, the cam-angle axis, extremes, clipped axes, dimensions,
the banner of a broken constraint, and the laws' chart.

The figures themselves are each follower family's (``camjax/followers/_translating_drawing.py``,
``_rocking_drawing.py``) and each follower's own panels (its ``drawing.py``); they are built
without pyplot (no global state, no GUI backend: ``Figure.savefig`` renders with Agg), so that
plotting is safe in scripts, tests and threads. Angles are in degrees on every horizontal axis;
the vertical dotted lines mark segment joints. Every cycle is drawn closed, 0 to 360 deg
inclusive: the value at 360 deg is the one at 0 (the motion is periodic). A ``title`` (see
:func:`camjax.output.titles.title_block`) names the run on every figure, so printouts of two runs
can be told apart. The module imports NumPy and matplotlib only (not JAX), so that
:mod:`camjax.output.drawing` can draw in processes of their own.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

JOINT_STYLE = {"color": "0.6", "linestyle": ":", "linewidth": 0.8}
FIGURE_SIZE = (7.0, 6.4)
TITLE_FONT = 7.5


# ---------------------------------------------------------------------------- helpers


def closed(theta_deg, values):
    """(theta, values) with the 360 deg point appended (= the value at 0 deg): a closed cycle."""
    t = np.asarray(theta_deg)
    v = np.asarray(values)
    return np.append(t, t[0] + 360.0), np.append(v, v[0])


def title_figure(fig: Figure, title: str, what: str) -> None:
    """Figure title: what it shows, then the run's title block (top left)."""
    fig.suptitle(what + ("\n" + title if title else ""), fontsize=TITLE_FONT, x=0.01, ha="left",
                 linespacing=1.3)


def cycle_axis(ax, curves, label: bool = True) -> None:
    """0..360 deg axis with the segment joints (``curves.segment_starts_deg``) marked."""
    for start in curves.segment_starts_deg:
        ax.axvline(start, **JOINT_STYLE)
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 60))
    ax.grid(True, alpha=0.3)
    if label:
        ax.set_xlabel("cam angle θ (deg)")


def mark_extremes(ax, theta, values, fmt: str, which=("max", "min")) -> None:
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


def true_runs(mask) -> list[tuple[int, int]]:
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
        stretches = true_runs(mask)
        if not stretches:
            continue
        peaks = [a + int(np.argmax(sign * v[a:b + 1])) for a, b in stretches]
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


def cam_outline(ax, profile_x_mm, profile_y_mm, base_radius_mm: float, **centre_mark) -> None:
    """The cam's profile (filled, outlined and labelled "cam profile"), its base circle R_b (dashed,
    labelled with its radius, mm) and the cam centre's "+" (``centre_mark``: its matplotlib options)."""
    x, y, rb = profile_x_mm, profile_y_mm, base_radius_mm
    ax.fill(x, y, color="C0", alpha=0.12)
    ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C0", linewidth=1.5, label="cam profile")
    a = np.linspace(0.0, 2.0 * np.pi, 361)
    ax.plot(rb * np.sin(a), rb * np.cos(a), color="0.5", linestyle="--", linewidth=0.8,
            label=f"base circle R_b = {rb:.3f} mm")
    ax.plot([0.0], [0.0], "+", color="k", **centre_mark)


def dimension(ax, start, end, text: str, color: str = "0.15", **text_kw) -> None:
    """A dimension line with arrows at both ends and its text at the middle."""
    ax.annotate("", xy=end, xytext=start,
                arrowprops={"arrowstyle": "<|-|>", "color": color, "linewidth": 0.9,
                            "shrinkA": 0, "shrinkB": 0, "mutation_scale": 8})
    mid = 0.5 * (np.asarray(start) + np.asarray(end))
    ax.annotate(text, mid, fontsize=7, color=color, xytext=(4, 4), textcoords="offset points",
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.8},
                **text_kw)


def rotation_arrow(ax, radius: float, toward_deg: float, sign: float, label: str = "ω") -> None:
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


def angle_ring(ax, radius: float, sign: float) -> None:
    """Ticks every 30 deg of cam angle on a ring around the cam (θ from +Y, clockwise on a
    counter-clockwise cam, ``sign`` = +1; mirrored for a clockwise one, ``sign`` = -1)."""
    for deg in range(0, 360, 30):
        u = np.array([sign * np.sin(np.deg2rad(deg)), np.cos(np.deg2rad(deg))])
        ax.plot(*np.column_stack([radius * u, 1.05 * radius * u]), color="0.35", linewidth=0.8)
        ax.text(*(1.13 * radius * u), f"{deg}°", fontsize=6.5, ha="center", va="center", color="0.3")
    phi = np.linspace(0.0, 2.0 * np.pi, 181)
    ax.plot(radius * np.sin(phi), radius * np.cos(phi), color="0.75", linewidth=0.5)


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
