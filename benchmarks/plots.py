"""Figures drawn next to the JSON: speed/accuracy trade and scaling (matplotlib, Agg)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def speed_accuracy(accuracy: dict, path: Path) -> Path:
    """Max relative error vs steady-state time, log axes; defaults marked with a star."""
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5))
    series = [("grid", "float64", "o-", "grid N, float64"), ("grid", "float32", "s--", "grid N, float32")]
    for _knob, dtype, style, label in series:
        rows = [r for r in accuracy["grid"] if r["dtype"] == dtype]
        ax.plot(
            [r["time_s"] for r in rows], [max(r["max_rel_error"], 2e-9) for r in rows], style, label=label
        )
        for r in rows:
            ax.annotate(
                str(r["samples"]),
                (r["time_s"], max(r["max_rel_error"], 2e-9)),
                fontsize=7,
                textcoords="offset points",
                xytext=(3, 3),
            )
    for knob, style, label in (
        ("gradient", "^-", "gradient solver max_steps (N=360)"),
        ("ga", "v-", "GA pop x gens (N=360)"),
    ):
        rows = sorted([r for r in accuracy["solvers"] if r["knob"] == knob], key=lambda r: r["time_s"])
        ax.plot(
            [r["time_s"] for r in rows], [max(r["max_rel_error"], 2e-9) for r in rows], style, label=label
        )
    defaults = [r for r in accuracy["grid"] + accuracy["solvers"] if r.get("default")]
    ax.plot(
        [r["time_s"] for r in defaults],
        [max(r["max_rel_error"], 2e-9) for r in defaults],
        "k*",
        markersize=14,
        label="defaults",
    )
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(bottom=1e-9)
    ax.set_xlabel("steady-state time per call (s), after compile")
    ax.set_ylabel("max relative error vs float64 N = 36 000 reference (floored at 2e-9)")
    ax.set_title("Grid size and dtype (R_b min/optimal, peak force, peak stress)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    for knob, style, label in (
        ("gradient", "^-", "gradient solver: max_steps"),
        ("ga", "v-", "GA pop x gens (N=360)"),
    ):
        rows = sorted([r for r in accuracy["solvers"] if r["knob"] == knob], key=lambda r: r["time_s"])
        bx.plot(
            [r["time_s"] for r in rows],
            [max(r["solver_abs_error_mm"], 1e-13) for r in rows],
            style,
            label=label,
        )
        for r in rows:
            bx.annotate(
                r["setting"].split(" (")[0].replace("population=", "p").replace("generations=", "g"),
                (r["time_s"], max(r["solver_abs_error_mm"], 1e-13)),
                fontsize=6,
                textcoords="offset points",
                xytext=(3, 3),
            )
    sd = [r for r in accuracy["solvers"] if r.get("default")]
    bx.plot(
        [r["time_s"] for r in sd],
        [max(r["solver_abs_error_mm"], 1e-13) for r in sd],
        "k*",
        markersize=14,
        label="defaults",
    )
    bx.set_xscale("log")
    bx.set_yscale("log")
    bx.set_xlabel("steady-state time per solve (s), N = 360, float64")
    bx.set_ylabel("|R_b - exact optimum on the same grid| (mm)")
    bx.set_title("Solver budget (global, alpha = gamma = 1)", fontsize=10)
    bx.grid(True, which="both", alpha=0.3)
    bx.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def scaling(fitness: dict, path: Path) -> Path:
    """Design-angle evaluations per second vs population and vs N."""
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.5))
    rows = fitness["by_population"]
    pops = [r["population"] for r in rows]
    for key, style, label in (
        ("library_evals_per_s", "o-", "camjax GA fitness (vmap)"),
        ("library_blocked_evals_per_s", "d-", "camjax GA fitness, blocked"),
        ("fused_evals_per_s", "s-", "hand-fused kernel"),
        ("numpy_evals_per_s", "^--", "vectorized NumPy"),
    ):
        pts = [(r["population"], r[key]) for r in rows if key in r]
        if pts:
            a.plot(*zip(*pts, strict=True), style, label=label)
    a.axhline(3e8, color="gray", ls=":", label="target 3e8/s")
    a.set_xscale("log")
    a.set_yscale("log")
    a.set_xlabel("population (designs), N = 360")
    a.set_ylabel("design-angle evaluations / s")
    a.legend(fontsize=8)
    a.grid(True, which="both", alpha=0.3)
    for key, rows_n, style, label in (
        ("library_evals_per_s", fitness["by_samples_float64"], "o-", "camjax float64"),
        ("fused_evals_per_s", fitness["by_samples_float64"], "s-", "fused float64"),
        ("library_evals_per_s", fitness["by_samples_float32"], "o--", "camjax float32"),
        ("fused_evals_per_s", fitness["by_samples_float32"], "s--", "fused float32"),
    ):
        b.plot([r["samples"] for r in rows_n], [r[key] for r in rows_n], style, label=label)
    b.set_xscale("log")
    b.set_yscale("log")
    b.set_xlabel(f"grid size N (population {fitness['by_samples_float64'][0]['population']})")
    b.set_ylabel("design-angle evaluations / s")
    b.legend(fontsize=8)
    b.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"Fitness throughput (pops {min(pops)}..{max(pops)})")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
