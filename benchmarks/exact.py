"""Benchmark: exact extrema (refined off the grid) against the grid's, in time and in accuracy.

``exact.time_ratio``: steady-state time of the exact path over the grid path (both warm, the
same 360-sample grid; the two alternate call by call, ``exact.ratio_rounds`` the ratio of each
round, so that both see the same load of a shared machine) for the report
(``camjax.pipeline.design_report``), the pointwise design (problem + solve) and a
100-weighting global sweep. ``exact.max_rel_error``: the exact path's largest relative error at
360 samples over four figures against independent references: the smallest flat-face base radius
(closed form, cos 2 pi u = -1/35), the peak force, the peak stress at the optimum and the alpha
= gamma = 1 optimum base radius (NumPy closed forms, a 1e6-sample grid polished by SciPy; the
optimum as the root of the envelope-theorem slope by brentq).

``python -m benchmarks.exact --out FILE.json`` runs it alone.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
from pathlib import Path

import numpy as np
from scipy.optimize import brentq, minimize_scalar

import camjax
from benchmarks.harness import environment, time_python
from camjax.followers.flat import problem as P
from camjax.pipeline import design_report
from camjax.solvers.base import solve
from camjax.solvers.sweep import sweep

H, OMEGA, N_NORM, SIGMA_MAX = 5.0, 240 * 2 * math.pi / 60, 65.0, 1230.0


# Its own closed forms (as tests/reference.py has them): no benchmark imports from tests/.
def _reference_curves(theta_deg):
    """NumPy q = s + s'', force F and stress coefficient C of the default scene (SPEC 4, 5)."""
    th = np.asarray(theta_deg, dtype=float)
    s, v, a = (np.zeros_like(th) for _ in range(3))
    b1, b2 = math.radians(80), math.radians(60)
    m = (th >= 100) & (th < 180)
    x = (th[m] - 100) / 80
    s[m], v[m], a[m] = (H * (x - np.sin(2 * np.pi * x) / (2 * np.pi)), H * (1 - np.cos(2 * np.pi * x)) / b1,
                        H * 2 * np.pi * np.sin(2 * np.pi * x) / b1**2)
    s[(th >= 180) & (th < 300)] = H
    m = th >= 300
    x = (th[m] - 300) / 60
    s[m] = H * (1 - (x - np.sin(2 * np.pi * x) / (2 * np.pi)))
    v[m] = -H * (1 - np.cos(2 * np.pi * x)) / b2
    a[m] = -H * 2 * np.pi * np.sin(2 * np.pi * x) / b2**2
    force = 1e-3 * (a * OMEGA**2 + 0.345 * v * OMEGA + 3004.0 * (s + 13.0)) + 9.81
    k = (1 - 0.3**2) / 2.1e5 + (1 - 0.26**2) / 1.15e5
    return s + a, force, 0.564 * np.sqrt(force / 10.0 / k)


def _dense_max(f, theta):
    """max of f: the best of the dense grid ``theta``, polished by bounded Brent in its bracket."""
    i = int(np.argmax(f(theta)))
    r = minimize_scalar(lambda x: -f(np.array([x]))[0], bounds=(theta[i - 1], theta[i + 1]),
                        method="bounded", options={"xatol": 1e-13})
    return max(-r.fun, f(theta[i:i + 1])[0]), r.x


def references(samples: int = 1_000_000) -> dict:
    """The four figures, independently of camjax."""
    a = math.acos(1.0 / 35.0)
    u = (math.pi + a) / (2 * math.pi)
    min_base = -H * (u + math.sin(a) / (2 * math.pi) - 2 * math.pi / (math.pi / 3) ** 2 * math.sin(a))
    theta = np.arange(samples) * 360.0 / samples
    force, _ = _dense_max(lambda t: _reference_curves(t)[1], theta)

    def stress_at(r):
        return lambda t: (lambda q, _, c: c / np.sqrt(r + q))(*_reference_curves(t))

    def slope(r):  # envelope theorem at the peak angle
        _, angle = _dense_max(stress_at(r), theta)
        q, _, c = _reference_curves(np.array([angle]))
        return 1 / N_NORM - c[0] / (2 * SIGMA_MAX * (r + q[0]) ** 1.5)

    optimum = brentq(slope, 26.0, 30.0, xtol=1e-14, rtol=1e-15)
    stress, _ = _dense_max(stress_at(optimum), theta)
    return {"min_base_radius_mm": min_base, "peak_force_N": float(force),
            "optimal_base_radius_mm": float(optimum), "peak_stress_MPa": float(stress)}


def _with_extrema(scene, mode: str):
    return dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema=mode))


def figures(scene) -> dict:
    """The four figures by camjax on the scene's grid, in the scene's extrema mode."""
    report = design_report(scene)
    return {"min_base_radius_mm": report["min_base_radius_mm"],
            "peak_force_N": report["loads"]["force_N"]["max"],
            "optimal_base_radius_mm": report["design"]["base_radius_mm"],
            "peak_stress_MPa": report["design"]["stress_max_MPa"]}


def run(scene, quick: bool = False) -> dict:
    repeats = 2 if quick else 5
    out: dict = {"samples": scene.motion.samples, "times_s": {}, "compile_s": {}, "ratio_rounds": {},
                 "load_average_1min": [os.getloadavg()[0]]}
    alphas = np.linspace(0.05, 1.0, 10 if quick else 100)

    def paths(sc):
        return {
            "report": lambda: design_report(sc),
            "pointwise": lambda: solve(P.problem_from_scene(sc), (1.0, 1.0), mode="pointwise"),
            "sweep": lambda: sweep(P.problem_from_scene(sc), alphas, 1.0 - alphas + 0.05,
                                   progress=False).records(),
        }

    calls = {mode: paths(_with_extrema(scene, mode)) for mode in ("grid", "exact")}
    for name in calls["grid"]:
        firsts = {mode: time_python(calls[mode][name], repeats=1, warmup=0)[0].median_s for mode in calls}
        # the two modes alternate call by call, so that both see the same load of a shared machine
        times: dict = {mode: [] for mode in calls}
        for _ in range(repeats + 1):  # the first round warms up
            for mode in calls:
                times[mode].append(time_python(calls[mode][name], repeats=1, warmup=0)[0].median_s)
        for mode in calls:
            median = float(np.median(times[mode][1:]))
            out["times_s"].setdefault(name, {})[mode] = median
            out["compile_s"].setdefault(name, {})[mode] = firsts[mode] - median
        rounds = zip(times["grid"][1:], times["exact"][1:], strict=True)
        out["ratio_rounds"][name] = [e / g for g, e in rounds]
    out["load_average_1min"].append(os.getloadavg()[0])
    out["time_ratio"] = {name: t["exact"] / t["grid"] for name, t in out["times_s"].items()}
    out["time_ratio_max"] = max(out["time_ratio"].values())
    ref = references(100_000 if quick else 1_000_000)
    errors = {}
    for mode in ("grid", "exact"):
        got = figures(_with_extrema(scene, mode))
        errors[mode] = {k: abs(got[k] / ref[k] - 1.0) for k in ref}
        out[f"{mode}_figures"] = got
    out["references"] = ref
    out["rel_error"] = errors
    out["max_rel_error"] = max(errors["exact"].values())
    out["grid_max_rel_error"] = max(errors["grid"].values())
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    data = {"environment": environment("float64"), "exact": run(camjax.load_scene(), args.quick)}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(data, indent=1, default=float))
    e = data["exact"]
    print(json.dumps({"time_ratio": e["time_ratio"], "max_rel_error": e["max_rel_error"],
                      "grid_max_rel_error": e["grid_max_rel_error"]}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
