"""The figure of docs/laws.md: a table law fitted to noisy points, with its residuals.

Run from the repository root: ``python docs/gen_table_fit.py`` (writes docs/table-fit.png). The
points are a cycloidal rise of 5 mm over 80 deg sampled every degree with 0.01 mm of Gaussian noise
(seed 22); the fit is camjax's own (law = "table", quintic, smoothing by GCV).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import camjax
from camjax.program import segment_motion

H, BETA, NOISE, SEED = 5.0, 80.0, 0.01, 22
SCENE = """[motion]
rpm = 240
segments = [
  {kind = "dwell", angle_deg = 100},
  {kind = "rise", law = "table", file = "points.csv", lift_mm = 5},
  {kind = "dwell", angle_deg = 120},
  {kind = "return", angle_deg = 60, law = "cycloidal", lift_mm = 5},
]
[follower]
type = "flat"
"""


def main(out: Path = Path(__file__).parent / "table-fit.png") -> None:
    angles = np.arange(0.0, BETA + 0.5)
    x = angles / BETA
    exact = H * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    lifts = exact + NOISE * np.random.default_rng(SEED).normal(size=angles.size)
    with tempfile.TemporaryDirectory() as tmp:
        rows = "\n".join(f"{a!r},{v!r}" for a, v in zip(angles.tolist(), lifts.tolist(), strict=True))
        (Path(tmp) / "points.csv").write_text(f"angle_deg,lift_mm\n{rows}\n")
        (Path(tmp) / "s.toml").write_text(SCENE)
        scene = camjax.load_scene(Path(tmp) / "s.toml")
    fit = scene.motion.segments[1]["fit"]
    theta = np.linspace(0.0, BETA, 801)
    kin = segment_motion(scene.motion.program, 1, 100.0 + theta)
    s, a = np.asarray(kin.s), np.asarray(kin.d2s) * (np.pi / 180) ** 2  # mm, mm/deg^2
    at_points = np.asarray(segment_motion(scene.motion.program, 1, 100.0 + angles).s)
    xt = theta / BETA
    fig = Figure(figsize=(7.5, 6.5), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True, height_ratios=[2, 1, 1.4])
    ax1.plot(angles, lifts, ".", ms=3, label=f"points (cycloidal + {NOISE} mm noise)")
    ax1.plot(theta, s, lw=1.2, label=f"fit: quintic, GCV (RMS residual {fit['rms_residual']:.4f} mm)")
    ax1.set_ylabel("lift, mm")
    ax1.legend(loc="upper left", fontsize=8)
    ax2.axhline(0.0, color="0.6", lw=0.8)
    ax2.plot(angles, lifts - at_points, ".", ms=3)
    ax2.set_ylabel("residual, mm")
    ax3.plot(theta, a, lw=1.2, label=f"fit (peak {fit['peak_accel']:.5f})")
    ax3.plot(theta, H * 2 * np.pi / BETA**2 * np.sin(2 * np.pi * xt), "--", lw=1.0,
             label=f"cycloidal (peak {H * 2 * np.pi / BETA**2:.5f})")
    ax3.set_ylabel("accel., mm/deg²")
    ax3.set_xlabel("angle from the segment's start, deg")
    ax3.legend(loc="upper right", fontsize=8)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}: {fit}")


if __name__ == "__main__":
    main()
