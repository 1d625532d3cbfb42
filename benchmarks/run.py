"""camjax benchmarks, one process: ``python benchmarks/run.py [--quick] --out FILE.json``.

Runs every benchmark (pointwise design, weight sweep, speed/accuracy trade, fitness scaling,
gradients), prints a table, writes the JSON and draws the plots next to it. ``--quick`` is the
CI smoke run (< 2 min on 2 cores; it asserts nothing about speed). Keys a script can read:
``pointwise.speedup``, ``sweep.gradient_speedup``, ``sweep.ga_speedup``,
``roller.gradient_speedup``, ``roller.ga_speedup``,
``fitness.evaluations_per_s``, ``fitness.numpy_ratio`` (and ``targets`` lists every target
with its measured value and pass/miss).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import camjax  # noqa: E402  (turns on float64)
from benchmarks import accuracy, follower_sweep, gradients, plots, pointwise, scaling, sweep  # noqa: E402
from benchmarks.harness import environment  # noqa: E402

# (json path, comparison, threshold, description)
TARGETS = (
    ("pointwise.speedup", ">=", 100.0, "pointwise design vs SciPy SLSQP loop (x)"),
    ("pointwise.max_abs_diff_base_radius_mm", "<=", 1e-4, "pointwise: max abs dR_b vs SciPy (mm)"),
    ("sweep.gradient_speedup", ">=", 20.0, "sweep, gradient vs SciPy SLSQP one by one (x)"),
    ("sweep.ga_speedup", ">=", 30.0, "sweep, GA vs SciPy differential_evolution (x)"),
    ("roller.gradient_speedup", ">=", 20.0, "roller sweep (R_b, R_f, e), gradient vs SciPy SLSQP (x)"),
    ("roller.ga_speedup", ">=", 30.0, "roller sweep, GA (or hybrid) vs SciPy differential_evolution (x)"),
    ("fitness.evaluations_per_s", ">=", 3e8, "fitness, design-angle evals/s, pop 1e4..1e6"),
    ("fitness.numpy_ratio", ">=", 5.0, "fitness vs vectorized NumPy (x)"),
    ("fitness.population_exponent_library", "<=", 1.15, "cost exponent in population (>= 1e3)"),
    ("fitness.samples_exponent_library", "<=", 1.15, "cost exponent in N (>= 360)"),
)
INFO = (
    ("fitness.fraction_of_fused", "fitness, fraction of the hand-fused kernel"),
    ("fitness.fused_evaluations_per_s", "hand-fused kernel, evals/s (same run)"),
    ("fitness.library_blocked_evaluations_per_s", "camjax fitness evaluated in blocks, evals/s"),
    ("fitness.fused_numpy_ratio", "hand-fused kernel vs NumPy (x)"),
    ("fitness.population_exponent_fused", "fused kernel cost exponent in population"),
    ("fitness.samples_exponent_fused", "fused kernel cost exponent in N"),
    ("fitness.samples_exponent_library_360_to_3600", "camjax cost exponent in N, 360..3600"),
    ("gradients.grad_cost_ratio", "value+grad / value, population (x)"),
    ("gradients.max_fd_rel_diff", "jax.grad vs central FD, max rel diff"),
    ("accuracy.default_max_rel_error", "default grid (N=360, f64) max rel error"),
)


def lookup(data: dict, path: str):
    """data['a']['b'] for path 'a.b'; None when missing."""
    for part in path.split("."):
        if not isinstance(data, dict) or part not in data:
            return None
        data = data[part]
    return data


def evaluate_targets(data: dict) -> list[dict]:
    """Every target with its measured value and pass / miss / not run."""
    out = []
    for path, op, threshold, text in TARGETS:
        value = lookup(data, path)
        if value is None:
            status = "not run"
        else:
            ok = value >= threshold if op == ">=" else value <= threshold
            status = "pass" if ok else "MISS"
        out.append(
            {
                "key": path,
                "target": f"{op} {threshold:g}",
                "measured": value,
                "status": status,
                "description": text,
            }
        )
    return out


def _fmt(v) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3g}"
    return str(v)


def print_table(data: dict) -> None:
    """Readable summary on stdout."""
    env = data["environment"]
    print(
        f"\ncamjax benchmarks ({'quick' if data['quick'] else 'full'} run, {env['date_utc']}, "
        f"{env['machine']}, {env['cpu_count']} CPUs, jax {env['jax']}, {env['backend']}, {env['dtype']})"
    )
    print(f"{'target':<52} {'goal':>10} {'measured':>11}  status")
    for t in data["targets"]:
        print(f"{t['description']:<52} {t['target']:>10} {_fmt(t['measured']):>11}  {t['status']}")
    print()
    for path, text in INFO:
        print(f"{text:<52} {'':>10} {_fmt(lookup(data, path)):>11}")
    fit = data.get("fitness", {})
    if "by_population" in fit:
        print(f"\n{'population':>10} {'camjax/s':>10} {'blocked/s':>10} {'fused/s':>10} {'numpy/s':>10}")
        for r in fit["by_population"]:
            print(
                f"{r['population']:>10} {_fmt(r['library_evals_per_s']):>10} "
                f"{_fmt(r['library_blocked_evals_per_s']):>10} {_fmt(r['fused_evals_per_s']):>10} "
                f"{_fmt(r.get('numpy_evals_per_s')):>10}"
            )
    acc = data.get("accuracy", {})
    if "grid" in acc:
        print(f"\n{'knob':<9} {'setting':<32} {'dtype':<8} {'time_s':>9} {'max rel err':>11}")
        for r in acc["grid"] + acc["solvers"]:
            setting = r.get("setting", f"N={r['samples']}")
            mark = " *default" if r.get("default") else ""
            print(
                f"{r['knob']:<9} {setting:<32} {r['dtype']:<8} {r['time_s']:>9.3g} "
                f"{r['max_rel_error']:>11.2e}{mark}"
            )
    for name in ("pointwise", "sweep", "roller"):
        section = data.get(name, {})
        scalars = {k: v for k, v in section.items() if not isinstance(v, dict | list)}
        if scalars:
            print(f"\n{name}: " + ", ".join(f"{k}={_fmt(v)}" for k, v in scalars.items()))


BENCHMARKS = (
    ("pointwise", pointwise.run),
    ("sweep", sweep.run),
    ("roller", follower_sweep.run),
    ("fitness", scaling.run),
    ("gradients", gradients.run),
    ("accuracy", accuracy.run),
)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smoke run, < 2 minutes")
    parser.add_argument("--out", type=Path, required=True, help="JSON file to write")
    parser.add_argument(
        "--plots-dir", type=Path, default=None, help="where to draw the plots (default: next to --out)"
    )
    parser.add_argument("--only", nargs="*", default=None, help="run only these benchmarks")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    scene = camjax.load_scene()
    data = {
        "quick": args.quick,
        "out": str(args.out),
        "environment": environment("float64"),
        "notes": "Every time is a median of repeated calls after warm-up; *_compile_s is jit lower+compile "
        "alone. Figures come from this one run (other processes may share the CPU: see "
        "environment.load_average_at_start).",
    }
    for name, bench in BENCHMARKS:
        if args.only and name not in args.only:
            continue
        t = time.perf_counter()
        print(f"[{name}] ...", flush=True)
        try:
            data[name] = bench(scene, args.quick)
        except Exception:  # a broken benchmark is reported, the others still run
            data[name] = {"error": traceback.format_exc()}
            print(data[name]["error"], file=sys.stderr)
        data.setdefault("wall_s", {})[name] = time.perf_counter() - t
        print(f"[{name}] {data['wall_s'][name]:.1f} s", flush=True)
    data["targets"] = evaluate_targets(data)
    data["wall_s"]["total"] = time.perf_counter() - t0
    args.out.parent.mkdir(parents=True, exist_ok=True)
    plot_dir = args.plots_dir or args.out.parent
    plot_dir.mkdir(parents=True, exist_ok=True)
    drawn = []
    if "grid" in data.get("accuracy", {}):
        drawn.append(str(plots.speed_accuracy(data["accuracy"], plot_dir / "perf_speed_accuracy.png")))
    if "by_population" in data.get("fitness", {}):
        drawn.append(str(plots.scaling(data["fitness"], plot_dir / "perf_scaling.png")))
    data["plots"] = drawn
    args.out.write_text(json.dumps(data, indent=1, default=float))
    print_table(data)
    print(f"\nwrote {args.out} and {', '.join(drawn)} in {data['wall_s']['total']:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
