"""Figures of a dynamics report (``camjax dynamics``): load motion, compensated cam, robustness.

Each function takes the ``curves`` and ``summary`` of :class:`camjax.dynamics.DynamicsReport`
and returns a matplotlib ``Figure`` built without pyplot (no global state; ``Figure.savefig``
renders with Agg). :func:`write_dynamics_figures` saves the ones the report has data for.
"""

from __future__ import annotations

import io
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

_SIZE = (7.0, 6.0)


def _axis(ax) -> None:
    ax.set_xlim(0.0, 360.0)
    ax.set_xticks(np.arange(0, 361, 60))
    ax.grid(True, alpha=0.3)


def motion_figure(curves: dict, summary: dict) -> Figure:
    """Nominal follower motion theta2 and steady-state load theta3; their difference below."""
    unit = summary["units"]["motion"]
    fig = Figure(figsize=_SIZE, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    phi = curves["phi_deg"]
    top.plot(phi, curves["nominal"], label="cam (nominal motion θ₂)")
    top.plot(phi, curves["nominal_load"], "--", label="load θ₃ (steady state)")
    top.set_ylabel(f"motion ({unit})")
    top.legend(fontsize=8)
    top.set_title(f"{summary['scene']}: f_n = {summary['natural_frequency_hz']:.2f} Hz, "
                  f"ζ = {summary['damping_ratio']:.4f}, cam {summary['cam_speed_hz']:g} Hz", fontsize=9)
    bottom.plot(phi, curves["nominal_load"] - curves["nominal"], color="C3")
    bottom.set_ylabel(f"θ₃ − θ₂ ({unit})")
    bottom.set_xlabel("cam angle (deg)")
    for ax in (top, bottom):
        _axis(ax)
    return fig


def compensation_figure(curves: dict, summary: dict) -> Figure:
    """Nominal vs compensated cam law, and the change cut into the cam."""
    unit = summary["units"]["motion"]
    fig = Figure(figsize=_SIZE, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    phi = curves["phi_deg"]
    top.plot(phi, curves["nominal"], label="nominal cam")
    top.plot(phi, curves["compensated"], "--", label="linearly compensated cam (G⁻¹)")
    if "shaped" in curves:
        top.plot(phi, curves["shaped"], ":", label="gradient-shaped law")
    top.set_ylabel(f"follower motion ({unit})")
    top.legend(fontsize=8)
    c = summary["compensated"]
    top.set_title(f"max tracking error: nominal {summary['nominal']['max_tracking_error']:.3g}, "
                  f"compensated {c['max_tracking_error']:.2g} {unit}", fontsize=9)
    bottom.plot(phi, curves["compensated"] - curves["nominal"], color="C1", label="compensated − nominal")
    if "shaped" in curves:
        bottom.plot(phi, curves["shaped_load"] - curves["shaped"], color="C2",
                    label="shaped law: load − cam")
    bottom.set_ylabel(f"({unit})")
    bottom.set_xlabel("cam angle (deg)")
    bottom.legend(fontsize=8)
    for ax in (top, bottom):
        _axis(ax)
    return fig


def robustness_figure(curves: dict, summary: dict) -> Figure:
    """Maps of the compensated max tracking error over (speed, omega_n) and (damping, omega_n)."""
    unit = summary["units"]["motion"]
    mu, lam, kap, grid = curves["rob_mu"], curves["rob_lam"], curves["rob_kap"], curves["rob"]
    fig = Figure(figsize=(10.0, 3.8), layout="constrained")
    a, b, c = fig.subplots(1, 3)
    floor = max(float(grid[grid > 0].min(initial=1e-300)), 1e-12 * float(grid.max()))
    norm = LogNorm(vmin=floor, vmax=float(max(grid.max(), curves["rob_nominal"].max())))
    i1 = int(np.argmin(np.abs(mu - 1.0)))
    j1 = int(np.argmin(np.abs(lam - 1.0)))
    im = a.pcolormesh(kap, lam, np.maximum(grid[i1], floor), norm=norm, shading="nearest")
    a.set_xlabel("ω_n factor κ (true / estimated)")
    a.set_ylabel("speed factor λ")
    a.set_title(f"damping factor μ = {mu[i1]:g}", fontsize=9)
    b.pcolormesh(kap, mu, np.maximum(grid[:, j1, :], floor), norm=norm, shading="nearest")
    b.set_xlabel("ω_n factor κ")
    b.set_ylabel("damping factor μ")
    b.set_title(f"speed factor λ = {lam[j1]:g}", fontsize=9)
    fig.colorbar(im, ax=[a, b], label=f"compensated max |θ₃ − θ₂| ({unit})")
    order = np.argsort(curves["rob_ratio"])
    c.semilogy(curves["rob_ratio"][order], np.maximum(curves["rob_at_ratio"][order], floor), "-",
               color="0.4", label="κ = 1, speed factor = λ/κ")
    c.semilogy(curves["rob_ratio"], np.maximum(grid[i1].ravel(), floor), "o", markersize=4,
               fillstyle="none", label="all (λ, κ) of the grid")
    c.set_xlabel("λ / κ")
    c.set_ylabel(f"max tracking error ({unit})")
    c.set_title("speed and ω_n errors act only as λ/κ", fontsize=9)
    c.legend(fontsize=7)
    c.grid(True, alpha=0.3)
    return fig


def drive_figure(curves: dict, summary: dict) -> Figure:
    """Cam-speed ripple and load tracking error with drive flexibility, per cam."""
    unit = summary["units"]["motion"]
    fig = Figure(figsize=_SIZE, layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True)
    phi = curves["drive_phi_deg"]
    for name in ("nominal", "linear", "nonlinear"):
        if f"drive_{name}_speed" in curves:
            top.plot(phi, curves[f"drive_{name}_speed"], label=f"{name} cam")
            bottom.plot(phi, curves[f"drive_{name}_load"] - curves["drive_target"], label=f"{name} cam")
    top.axhline(summary["cam_speed_hz"], color="0.5", linestyle=":")
    top.set_ylabel("cam speed (Hz)")
    top.legend(fontsize=8)
    bottom.set_ylabel(f"load − nominal motion ({unit})")
    bottom.set_xlabel("motor angle Ω t (deg)")
    bottom.legend(fontsize=8)
    for ax in (top, bottom):
        _axis(ax)
    return fig


def jump_figure(curves: dict, summary: dict) -> Figure:
    """Minimum contact force over the cycle against cam speed; the jump speed marked."""
    force = summary["units"]["force"]
    fig = Figure(figsize=(7.0, 4.0), layout="constrained")
    ax = fig.subplots()
    ax.plot(curves["jump_speeds_hz"], curves["jump_fmin"])
    ax.axhline(0.0, color="0.5", linewidth=0.8)
    j = summary["jump"]["jump_speed_hz"]
    if j is not None:
        ax.axvline(j, color="C3", linestyle="--", label=f"contact lost from {j:.4g} Hz")
        ax.legend(fontsize=8)
    elif summary["jump"].get("jump_speed_status") == "lost_at_lowest_speed":
        ax.set_title("no jump speed: contact already lost at the lowest speed scanned", fontsize=9)
    else:
        ax.set_title("no jump speed: contact holds at every speed scanned", fontsize=9)
    ax.axvline(summary["cam_speed_hz"], color="0.5", linestyle=":")
    # resonances reach far below zero: a symmetric log scale keeps the sign change readable
    fmin = curves["jump_fmin"]
    ax.set_yscale("symlog", linthresh=max(float(np.median(np.abs(fmin))), 1e-12))
    ax.set_xscale("log")
    ax.set_xlabel("cam speed (Hz)")
    ax.set_ylabel(f"min contact force over the cycle ({force})")
    ax.grid(True, alpha=0.3)
    return fig


FIGURES = (("dynamics_motion.png", motion_figure, "nominal_load"),
           ("dynamics_compensated_cam.png", compensation_figure, "compensated"),
           ("dynamics_robustness.png", robustness_figure, "rob"),
           ("dynamics_drive.png", drive_figure, "drive_target"),
           ("dynamics_jump.png", jump_figure, "jump_fmin"))
"""(file name, figure function, the curve it needs), in the order they are written."""


def render_dynamics_figures(curves: dict, summary: dict, dpi: int = 100,
                            skip: Iterable[str] = ()) -> dict[str, bytes]:
    """PNG bytes of every figure the report has data for, by file name (``skip``: names left out)."""
    out = {}
    for name, make, key in FIGURES:
        if key in curves and name not in skip:
            buffer = io.BytesIO()
            make(curves, summary).savefig(buffer, format="png", dpi=dpi)
            out[name] = buffer.getvalue()
    return out


def write_dynamics_figures(folder: Path, curves: dict, summary: dict, dpi: int = 100,
                           rendered: dict[str, bytes] | None = None) -> list[Path]:
    """Save every figure the report has data for as PNG in ``folder``; return the paths.

    ``rendered``: figures already drawn (:func:`render_dynamics_figures`), written as they are.
    """
    pngs = dict(rendered or {})
    pngs.update(render_dynamics_figures(curves, summary, dpi, skip=pngs))
    out = []
    for name, _make, _key in FIGURES:
        if name in pngs:
            path = Path(folder) / name
            path.write_bytes(pngs[name])
            out.append(path)
    return out
