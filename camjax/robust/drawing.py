"""robust.png (histograms with their limits, P1-P99 envelopes over the cam angle) and
robust_sensitivity.png (the ranked effects): NumPy and matplotlib only."""

from __future__ import annotations

from pathlib import Path

import numpy as np

ENVELOPE_LABELS = {"lift": "lift", "accel": "acceleration", "load": "contact load"}


def figures(data: dict, outputs: np.ndarray, envelope: dict, folder: Path, dpi: int = 100) -> list[Path]:
    """Write robust.png and robust_sensitivity.png into ``folder``; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(data["outputs"])
    rocking = any(n.endswith("_Nm") or n.endswith("rad_s2") for n in names)
    ncol = 3
    nrow = -(-len(names) // ncol) + 1
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.0 * nrow), squeeze=False)
    for j, n in enumerate(names):
        ax = axes[j // ncol][j % ncol]
        ax.hist(outputs[:, j], bins=60, color="tab:blue", alpha=0.8)
        s = data["outputs"][n]
        for key, style in (("p1", ":"), ("p99", ":")):
            ax.axvline(s[key], color="k", ls=style, lw=0.8)
        ax.axvline(s["nominal"], color="tab:green", lw=1.0, label="nominal")
        if s["limit"] is not None:
            ax.axvline(s["limit"], color="tab:red", lw=1.5, label="limit")
        ax.set_title(n, fontsize=9)
        ax.legend(fontsize=7)
    for j in range(len(names), (nrow - 1) * ncol):
        axes[j // ncol][j % ncol].axis("off")
    theta = envelope["theta_deg"]
    units = {"lift": "rad" if rocking else "mm", "accel": "rad/s^2" if rocking else "m/s^2",
             "load": "N m" if rocking else "N"}
    for k, key in enumerate(("lift", "accel", "load")):
        ax = axes[nrow - 1][k]
        p1, p50, p99 = envelope[key]
        ax.fill_between(theta, p1, p99, color="tab:orange", alpha=0.4, label="P1-P99")
        ax.plot(theta, p50, color="tab:orange", lw=1.0, label="P50")
        if key == "load":
            ax.axhline(0.0, color="tab:red", lw=1.0)
        ax.set_xlabel("cam angle, deg")
        ax.set_title(f"{ENVELOPE_LABELS[key]}, {units[key]} (first {data['envelope_samples']} samples)",
                     fontsize=9)
        ax.legend(fontsize=7)
    fig.suptitle(f"{data['scene']}: {data['samples']} samples, P(any limit broken) = "
                 f"{data['any_limit_probability']:.3%}", fontsize=10)
    fig.tight_layout()
    main = folder / "robust.png"
    fig.savefig(main, dpi=dpi)
    plt.close(fig)

    fig, axes = plt.subplots(len(names), 1, figsize=(7, 1.0 + 1.1 * sum(
        len(data["sensitivities"][n]) for n in names) / max(len(names), 1) * len(names) / 2), squeeze=False)
    for j, n in enumerate(names):
        rows = data["sensitivities"][n][::-1]
        ax = axes[j][0]
        ax.barh([r["value"] for r in rows], [abs(r["effect"]) for r in rows],
                color=["tab:red" if r["effect"] > 0 else "tab:blue" for r in rows])
        ax.set_title(f"{n}: |d output / d value| x sd (red: raises it)", fontsize=9)
        ax.tick_params(labelsize=7)
    fig.tight_layout()
    bars = folder / "robust_sensitivity.png"
    fig.savefig(bars, dpi=dpi)
    plt.close(fig)
    return [main, bars]
