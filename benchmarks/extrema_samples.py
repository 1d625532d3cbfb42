"""Benchmark: time and error of every follower's reported extrema against the sample count, grid and exact.

For each registered follower type (:func:`camjax.followers.names`) its example scene
(``Follower.example_scene``) is analysed without its [design] section at one fixed base radius
(the one the reference run draws at), so that the figures are those of one cam and no solver runs:
:func:`camjax.pipeline.design_report` at N = 90, 360, 3600 and 36 000 samples with
``extrema = "grid"`` (the sampled max / min) and ``extrema = "exact"`` (refined between the
samples).

Figures: every extremum the report holds (:func:`figures`: a number under a ``max``, ``min``,
``max_abs`` or ``min_abs`` key, or a key that starts with ``min_`` / ``max_`` or holds ``_min_`` /
``_max_``; not the angles where they occur): smallest radii of curvature, pressure angles, peak
force, torque and stress, smallest admissible base radius, ... Error: relative to the reference,
|v - v_ref| / |v_ref| (absolute where |v_ref| < 1e-9, e.g. a swing whose minimum is 0), and for each
setting the largest over the figures and the figure it belongs to. Reference: the grid extrema
of the same report at :data:`REFERENCE_SAMPLES` samples (1e6: a sampled extremum's error falls as
N^-2, so ~1e-11 relative there; it does not use the refinement it judges).

Time: the median of warm calls of ``design_report`` (the whole analysis: curves, extrema, loads,
report), compile time apart (first call minus the median). With exact extrema every figure is
refined, the smallest admissible base radius included (the root of the sizing's limits refined
between the samples, :mod:`camjax.followers._sizing`); a roller rocker's smallest cam-surface radius
is exact where its pitch curve is convex at every angle (the example scenes' are). ``--check``
prints, per follower, the exact figures' largest error at N = 360 and fails (exit 1) above
:data:`EXACT_TOLERANCE` (:data:`QUICK_TOLERANCE` with ``--quick``).

``python -m benchmarks.extrema_samples --out benchmarks/results/extrema.json [FOLLOWER ...]``
(followers already in the file and not named are kept; ``--quick``: N = 90 and 360, reference
36 000).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import time
from pathlib import Path

import camjax
from benchmarks.harness import environment, time_python
from camjax import followers
from camjax.pipeline import design_report

SAMPLES = (90, 360, 3600, 36_000)
REFERENCE_SAMPLES = 1_000_000
MODES = ("grid", "exact")
_EXTREMUM_LEAVES = ("max", "min", "max_abs", "min_abs")
# exact figures at N = 360 must be within this of the reference (whose own error is ~1e-11;
# --quick's 36 000-sample reference is off by up to ~2e-6 in its worst figure, a sharp minimum)
EXACT_TOLERANCE = 1e-9
QUICK_TOLERANCE = 1e-5


def figures(report: dict, prefix: str = "") -> dict[str, float]:
    """Every extremum of a report as {dotted.key: value} (see the module docstring)."""
    out: dict[str, float] = {}
    for key, value in report.items():
        path = prefix + key
        if isinstance(value, dict):
            out.update(figures(value, path + "."))
        elif isinstance(value, int | float) and not isinstance(value, bool) and not key.endswith("_deg"):
            named = key.startswith(("min_", "max_")) or "_min_" in key or "_max_" in key
            if (key in _EXTREMUM_LEAVES or named) and "samples" not in key and math.isfinite(value):
                out[path] = float(value)
    return out


def errors(got: dict[str, float], reference: dict[str, float]) -> dict[str, float]:
    """|v - v_ref| / |v_ref| per figure (absolute where |v_ref| < 1e-9)."""
    out = {}
    for key, ref in reference.items():
        if key in got:
            diff = abs(got[key] - ref)
            out[key] = diff / abs(ref) if abs(ref) >= 1e-9 else diff
    return out


def _scene(follower: str, samples: int, mode: str):
    scene = camjax.load_scene(followers.get(follower).example_scene)
    return dataclasses.replace(scene, design=None,
                               motion=dataclasses.replace(scene.motion, samples=samples, extrema=mode))


def _drawn_radius(report: dict) -> float:
    """The base radius a report's cam is drawn at."""
    return float(report["evaluated_at"]["base_radius_mm"])


def run_follower(follower: str, quick: bool = False) -> dict:
    """Time and error per (samples, mode) of one follower: the dict stored under its name."""
    load_before = os.getloadavg()
    samples = SAMPLES[:2] if quick else SAMPLES
    ref_samples = 36_000 if quick else REFERENCE_SAMPLES
    t0 = time.perf_counter()
    ref_report = design_report(_scene(follower, ref_samples, "grid"))
    radius = _drawn_radius(ref_report)
    ref_report = design_report(_scene(follower, ref_samples, "grid"), base_radius_mm=radius)
    reference = figures(ref_report)
    out = {"scene": followers.get(follower).example_scene, "base_radius_mm": radius,
           "reference": {"samples": ref_samples, "extrema": "grid", "seconds": time.perf_counter() - t0,
                         "figures": reference},
           "rows": []}
    for n in samples:
        for mode in MODES:
            scene = _scene(follower, n, mode)
            call = lambda scene=scene: design_report(scene, base_radius_mm=radius)  # noqa: E731
            t = time.perf_counter()
            call()
            first = time.perf_counter() - t
            timing, report = time_python(call, repeats=3 if n <= 3600 else 2, warmup=0)
            err = errors(figures(report), reference)
            worst = max(err, key=err.get)
            out["rows"].append({"samples": n, "extrema": mode, "time_s": timing.median_s,
                                "compile_s": max(first - timing.median_s, 0.0), "max_rel_error": err[worst],
                                "worst_figure": worst, "errors": err})
            print(f"  {follower} N={n} {mode}: {timing.median_s:.3f} s, error {err[worst]:.1e} ({worst})",
                  flush=True)
    by = {(r["samples"], r["extrema"]): r for r in out["rows"]}
    out["exact_over_grid_time_360"] = by[(360, "exact")]["time_s"] / by[(360, "grid")]["time_s"]
    out["load_average_1min"] = [load_before[0], os.getloadavg()[0]]
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("followers", nargs="*", help="follower types (default: every registered one)")
    parser.add_argument("--out", type=Path, required=True, help="JSON file (followers not run are kept)")
    parser.add_argument("--quick", action="store_true", help="N = 90 and 360, reference 36 000")
    parser.add_argument("--check", action="store_true",
                        help=f"exit 1 when an exact figure at N = 360 is off by more than "
                             f"{EXACT_TOLERANCE:g} ({QUICK_TOLERANCE:g} with --quick)")
    args = parser.parse_args(argv)
    names = args.followers or list(followers.names())
    unknown = [n for n in names if n not in followers.names()]
    if unknown:
        parser.error(f"unknown follower type(s) {', '.join(unknown)}; "
                     f"registered: {', '.join(followers.names())}")
    data = json.loads(args.out.read_text()) if args.out.exists() else {}
    data.setdefault("followers", {})
    for name in names:
        print(f"[{name}]", flush=True)
        data["followers"][name] = run_follower(name, args.quick)
        data.setdefault("environment", {})[name] = environment("float64")
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(data, indent=1, default=float))
    if args.check:
        worst = {name: next(r for r in data["followers"][name]["rows"]
                            if r["samples"] == 360 and r["extrema"] == "exact") for name in names}
        for name, row in worst.items():
            print(f"{name}: exact at N = 360 off by {row['max_rel_error']:.1e} ({row['worst_figure']})")
        tolerance = QUICK_TOLERANCE if args.quick else EXACT_TOLERANCE
        if any(row["max_rel_error"] > tolerance for row in worst.values()):
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
