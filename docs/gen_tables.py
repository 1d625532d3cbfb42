"""Tables and figures of the documentation, generated from the JSON that camjax's own commands write.

The sources, all committed (:data:`SOURCES`):

- ``bench``, ``benchmarks/results/full.json``: ``python benchmarks/run.py --out
  benchmarks/results/full.json``;
- ``extremes``, ``docs/data/extremes.json``: ``python -m camjax.cli check-extremes --out DIR``, then
  ``cp DIR/extremes.json docs/data/``;
- ``result``, ``docs/data/default/result.json``: ``python -m camjax.cli design --out DIR``, then
  ``cp DIR/result.json docs/data/default/``;
- ``dynamics``, ``docs/data/thesis-bench/dynamics.json``: ``python -m camjax.cli dynamics
  thesis-bench --out DIR``, then ``cp DIR/dynamics.json docs/data/thesis-bench/``;
- ``roller``, ``benchmarks/results/roller.json``: ``python -m benchmarks.follower_sweep roller --out
  benchmarks/results/roller.json``;
- ``cli``, ``benchmarks/results/cli_timing.json``: ``python benchmarks/cli_timing.py --runs 5 --out
  benchmarks/results/cli_timing.json``;
- ``exact``, ``benchmarks/results/exact.json``: ``python -m benchmarks.exact --out
  benchmarks/results/exact.json``;
- ``followers``, ``benchmarks/results/followers.json``: ``python -m benchmarks.follower_sweep
  oscillating_roller oscillating_flat --out benchmarks/results/followers.json``;
- ``extrema``, ``benchmarks/results/extrema.json``: ``python -m benchmarks.extrema_samples --out
  benchmarks/results/extrema.json [FOLLOWER ...]``;
- ``codesign``, ``benchmarks/results/codesign.json``: ``python -m benchmarks.codesign``;
- ``synthesis``, ``benchmarks/results/synthesis.json``: ``python -m benchmarks.synthesis --out FILE``
  (``synthesis_device``, ``synthesis_device.json``: the same on a GPU machine, then on its CPU);
- ``robust``, ``benchmarks/results/robust.json``: ``python -m benchmarks.robust --samples 100000
  --out benchmarks/results/robust.json``;
- ``newton``, ``benchmarks/results/newton.json``: ``python -m benchmarks.newton --out
  benchmarks/results/newton.json``;
- ``line_search``, ``benchmarks/results/line_search.json``: ``python -m benchmarks.line_search
  --out benchmarks/results/line_search.json``.

``{{ table: performance }}`` is every target of every benchmark in one table (:func:`targets`:
goal, measured, machine, status); ``{{ status: KEY }}`` writes one target's status (``met`` or
``missed``) in prose, so a page that names a figure cannot call it otherwise.

A page asks for a table with a line ``{{ table: NAME }}`` (NAME one of :data:`TABLES`) and for a
single figure with ``{{ SOURCE: dotted.path[*factor][:format] }}``, e.g.
``{{ bench: pointwise.camjax_s*1e3:.2f }}`` (SOURCE a key of :data:`SOURCES`; list items by
index, ``accuracy.grid.2.time_s``); ``\\{{`` is a literal ``{{``. ``docs/hooks.py`` runs
:func:`render` on every page at ``mkdocs build``; a placeholder that names nothing is an error,
so a renamed JSON key fails the strict build instead of printing a stale number.

Run by hand: ``python docs/gen_tables.py [NAME ...]`` prints the named tables (default: all).
"""

from __future__ import annotations

import json
import math
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SOURCES = {
    "bench": ROOT / "benchmarks" / "results" / "full.json",
    "extremes": ROOT / "docs" / "data" / "extremes.json",
    "result": ROOT / "docs" / "data" / "default" / "result.json",
    "dynamics": ROOT / "docs" / "data" / "thesis-bench" / "dynamics.json",
    "roller": ROOT / "benchmarks" / "results" / "roller.json",
    "cli": ROOT / "benchmarks" / "results" / "cli_timing.json",
    "exact": ROOT / "benchmarks" / "results" / "exact.json",
    "followers": ROOT / "benchmarks" / "results" / "followers.json",
    "extrema": ROOT / "benchmarks" / "results" / "extrema.json",
    "codesign": ROOT / "benchmarks" / "results" / "codesign.json",
    "synthesis": ROOT / "benchmarks" / "results" / "synthesis.json",
    "synthesis_device": ROOT / "benchmarks" / "results" / "synthesis_device.json",
    "robust": ROOT / "benchmarks" / "results" / "robust.json",
    "newton": ROOT / "benchmarks" / "results" / "newton.json",
    "line_search": ROOT / "benchmarks" / "results" / "line_search.json",
}


def load(source: str) -> dict:
    """The JSON of one source (a key of :data:`SOURCES`)."""
    return json.loads(SOURCES[source].read_text())


def _g(v, digits: int = 3) -> str:
    """A measured value for a table cell: ``–`` for none, integers and text as they are, else 3 digits."""
    if v is None:
        return "–"
    if isinstance(v, bool | int | str):
        return str(v)
    return f"{v:.{digits}g}"


def lookup(data, path: str):
    """``data`` followed along a dotted path; integer parts index lists. A key that itself holds
    dots (``cli.design_s``) is taken whole where the rest of the path names it."""
    parts = path.split(".")
    if isinstance(data, list):
        value, used = data[int(parts[0])], 1
    else:  # the longest leading run of parts that is a key
        used = next((i for i in range(len(parts), 0, -1) if ".".join(parts[:i]) in data), 1)
        value = data[".".join(parts[:used])]
    return lookup(value, ".".join(parts[used:])) if used < len(parts) else value


# ------------------------------------------------------------------------------------ benchmark


def bench_provenance(bench: dict) -> str:
    """One line: the command, date, machine, versions and load of the benchmark run."""
    env = bench["environment"]
    load_avg = ", ".join(f"{x:.1f}" for x in env["load_average_at_start"])
    return (
        f"Run: `python benchmarks/run.py --out {bench.get('out', 'FILE.json')}` on {env['date_utc']}, "
        f"{env['machine']}, {env['cpu_count']} CPUs, {env['backend']} backend, jax/jaxlib "
        f"{env['jax']}/{env['jaxlib']}, NumPy {env['numpy']}, SciPy {env['scipy']}, Python "
        f"{env['python']}, {env['dtype']}; load average at start {load_avg}, total "
        f"{bench['wall_s']['total']:.0f} s (commit `{env.get('git_commit', '?')[:10]}`)."
    )


def bench_targets(bench: dict) -> str:
    """Every benchmark target: goal, measured value, pass or miss."""
    lines = ["| target | goal | measured | |", "|---|---|---|---|"]
    for t in bench["targets"]:
        lines.append(
            f"| {t['description']} (`{t['key']}`) | {t['target']} | {_g(t['measured'])} | "
            f"{'pass' if t['status'] == 'pass' else '**miss**'} |"
        )
    return "\n".join(lines)


def bench_fitness(bench: dict) -> str:
    """GA fitness evaluations per second by population: camjax, blocked, hand-fused, NumPy."""
    lines = [
        "| population (N = 360, float64) | camjax GA fitness /s | same, blocked /s | hand-fused /s "
        "| NumPy /s |",
        "|---:|---:|---:|---:|---:|",
    ]
    for r in bench["fitness"]["by_population"]:
        lines.append(
            f"| {r['population']:,} | {_g(r['library_evals_per_s'])} | "
            f"{_g(r['library_blocked_evals_per_s'])} | {_g(r['fused_evals_per_s'])} | "
            f"{_g(r.get('numpy_evals_per_s'))} |"
        )
    return "\n".join(lines)


def bench_knobs(bench: dict) -> str:
    """The speed/accuracy trade: grid size, dtype and solver budgets, time and error."""
    acc = bench["accuracy"]
    lines = ["| knob | setting | dtype | time (s) | max rel. error |", "|---|---|---|---:|---:|"]
    for r in acc["grid"] + acc["solvers"]:
        setting = r.get("setting", f"N = {r['samples']}") + (" **(default)**" if r.get("default") else "")
        lines.append(
            f"| {r['knob']} | {setting} | {r['dtype']} | {_g(r['time_s'])} | {r['max_rel_error']:.1e} |"
        )
    return "\n".join(lines)


def bench_sweep_methods(bench: dict) -> str:
    """The 100-weighting sweep: each method's time, weightings measured, accuracy."""
    sweep = bench["sweep"]
    lines = [
        "| method | time for all weightings (s) | weightings measured | extrapolated |",
        "|---|---:|---:|---|",
    ]
    for name, m in sweep["methods"].items():
        extrapolated = sweep.get("scipy_extrapolated", {}).get(name, False)
        lines.append(
            f"| `{name}` | {_g(m['time_s'])} | {m['weightings']} | {'yes' if extrapolated else 'no'} |"
        )
    return "\n".join(lines)


# ------------------------------------------------------------------------------------ followers

SWEEP_GOALS = {"gradient_speedup": 20.0, "ga_speedup": 30.0}
EXACT_GOAL = 2.0


def _follower_names() -> list[str]:
    """Every registered follower type (the folders of camjax/followers, read without importing camjax)."""
    base = ROOT / "camjax" / "followers"
    return sorted(p.name for p in base.iterdir()
                  if (p / "follower.py").exists() and not p.name.startswith("_"))


def _ratio_cell(value, goal: float, at_least: bool = True, matched: bool | None = None) -> str:
    """A measured ratio and its verdict; a speed-up whose accuracy is not matched is a miss."""
    if value is None:
        return "not measured"
    ok = value >= goal if at_least else value <= goal
    if ok and matched is False:
        return f"{value:.1f}× (**miss**: accuracy not matched)"
    return f"{value:.1f}× ({'pass' if ok else '**miss**'})"


def _matched(cell: str, matched: bool | None) -> str:
    """A speed-up cell that says so when its accuracy is not matched (a miss either way)."""
    return cell if matched is not False or "accuracy not matched" in cell else cell + ", accuracy not matched"


def _sweeps(followers: dict) -> dict[str, dict]:
    """The 100-weighting sweep of each follower that has one: the flat face (full.json ``sweep``),
    the roller (roller.json) and the rockers (followers.json)."""
    envs = followers.get("environment", {})
    out = {name: {**v, "_file": "followers.json", "_env": envs.get(name)} for name, v in followers.items()
           if isinstance(v, dict) and "gradient_speedup" in v}
    for source, key, name in (("roller", "roller", "roller"), ("bench", "sweep", "flat")):
        try:
            data = load(source)
            env = data["environment"]
            out.setdefault(name, {**data[key], "_file": SOURCES[source].name,
                                  "_env": env.get(name, env) if name in env else env})
        except (OSError, KeyError):
            pass
    return out


def machine(env: dict | None) -> str:
    """A short name of the machine a benchmark ran on: cores, CPU maker, JAX version."""
    if not env:
        return "not recorded"
    text = env.get("machine", "")
    maker = next((m for m in ("AMD EPYC", "Xeon", "Apple") if m in text), "")
    cores = f"{env['cpu_count']}-core " if env.get("cpu_count") else ""
    jax = f", JAX {env['jax']}" if env.get("jax") else ""
    return f"{cores}{maker + ' ' if maker else ''}CPU{jax}"


def follower_speed(followers: dict) -> str:
    """A row per registered follower: the sweep speed-ups against SciPy at matched accuracy (the
    gradient-based solver named beside its figure: the interior point where it was measured, else
    the first-order solver) and that solver's largest iteration count, with the goals and the
    machine of that follower's run (one machine per row); a follower not measured says so."""
    sweeps = _sweeps(followers)
    lines = [
        f"| follower | gradient vs SLSQP (goal ≥ {SWEEP_GOALS['gradient_speedup']:g}×) | "
        f"GA or hybrid vs differential evolution (goal ≥ {SWEEP_GOALS['ga_speedup']:g}×) | "
        "its steps (max) | machine |",
        "|---|---|---|---:|---|",
    ]
    for name in _follower_names():
        s = sweeps.get(name)
        if s is None:
            lines.append(f"| `{name}` | no sweep benchmark | no sweep benchmark | – | |")
            continue
        gradient_method = s.get("gradient_speedup_method", "camjax_gradient")
        gradient = s.get("methods", {}).get(gradient_method, {})
        steps = gradient.get("iterations_max")
        via = s.get("ga_speedup_method", "camjax_ga").removeprefix("camjax_")
        gradient_cell = _ratio_cell(s["gradient_speedup"], SWEEP_GOALS["gradient_speedup"],
                                    matched=s.get("gradient_accuracy_matched"))
        ga_cell = _ratio_cell(s["ga_speedup"], SWEEP_GOALS["ga_speedup"],
                              matched=s.get("ga_accuracy_matched"))
        lines.append(
            f"| `{name}` | {_matched(gradient_cell, s.get('gradient_accuracy_matched'))} "
            f"({gradient_method.removeprefix('camjax_')}) | "
            f"{_matched(ga_cell, s.get('ga_accuracy_matched'))} ({via}) | {_g(steps)} | "
            f"{machine(s.get('_env'))} |"
        )
    return "\n".join(lines)


def follower_sweeps(followers: dict) -> str:
    """Every method of each rocker's sweep, a table per follower: time for all weightings, worst
    gap, infeasible results, steps."""
    parts = []
    for name, s in followers.items():
        if not isinstance(s, dict) or "methods" not in s:
            continue
        lines = [f"**`{name}`**", "", "| method | time, 100 weightings (s) | weightings measured | "
                 "worst rel. gap | infeasible | steps (max) |", "|---|---:|---:|---:|---:|---:|"]
        for method, m in s["methods"].items():
            extra = " (extrapolated)" if m.get("extrapolated") else ""
            lines.append(f"| `{method}` | {_g(m['time_s'])}{extra} | {m['weightings']} | "
                         f"{m['max_rel_objective_gap']:.1e} | {m['infeasible']} | "
                         f"{_g(m.get('iterations_max'))} |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


def extrema_provenance(extrema: dict) -> str:
    """One line per run: followers, date, load average before and after."""
    parts = []
    for name, f in extrema["followers"].items():
        env = extrema["environment"][name]
        before, after = f["load_average_1min"]
        parts.append(f"`{name}` {env['date_utc']} (load {before:.1f} → {after:.1f})")
    env = next(iter(extrema["environment"].values()))
    return (f"Run: `python -m benchmarks.extrema_samples --out benchmarks/results/extrema.json` on "
            f"{env['machine']}, {env['cpu_count']} CPUs, jax {env['jax']}, {env['dtype']}; "
            + "; ".join(parts) + ".")


def extrema_table(extrema: dict) -> str:
    """A table per follower, a row per sample count: time and largest relative error of the grid
    and the exact extrema against the dense reference."""
    parts = []
    for name, f in extrema["followers"].items():
        lines = [f"**`{name}`**", "", "| N | grid: time (s) | grid: max rel. error | exact: time (s) "
                 "| exact: max rel. error | worst figure (exact) |", "|---:|---:|---:|---:|---:|---|"]
        by = {(r["samples"], r["extrema"]): r for r in f["rows"]}
        for n in sorted({r["samples"] for r in f["rows"]}):
            g, e = by.get((n, "grid"), {}), by.get((n, "exact"), {})
            err = lambda r: f"{r['max_rel_error']:.1e}" if r else "–"  # noqa: E731
            lines.append(f"| {n:,} | {_g(g.get('time_s'))} | {err(g)} | {_g(e.get('time_s'))} | "
                         f"{err(e)} | {e.get('worst_figure', '–')} |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


# ------------------------------------------------------------------------------------ extremes


def _ratio(case: dict) -> float:
    error, tol = float(case["error"]), float(case["tolerance"])
    if tol > 0:
        return error / tol
    return 0.0 if error == 0 else math.inf


def extremes_summary(extremes: dict) -> str:
    """One line: scene, number of cases, passed and failed, and the groups skipped with their reasons."""
    s = extremes["summary"]
    line = (
        f"`camjax check-extremes` on the `{extremes['scene']}` scene: {s['cases']} cases, "
        f"{s['passed']} pass, {s['failed']} fail."
    )
    skipped = extremes.get("skipped", [])
    if skipped:
        line += " Skipped: " + "; ".join(f"{g['group']} ({g['reason']})" for g in skipped) + "."
    return line


def extremes_groups(extremes: dict) -> str:
    """Per group of the stability matrix: cases, passed, largest error / tolerance."""
    groups: dict[str, list[dict]] = {}
    for c in extremes["cases"]:
        groups.setdefault(c["group"], []).append(c)
    lines = ["| group | cases | passed | largest error / tolerance |", "|---|---:|---:|---:|"]
    for name, cases in groups.items():
        worst = max(_ratio(c) for c in cases)
        lines.append(f"| {name} | {len(cases)} | {sum(bool(c['passed']) for c in cases)} | {worst:.2g} |")
    return "\n".join(lines)


def extremes_precision(extremes: dict) -> str:
    """The precision group: each reference-scene figure in float64 and float32."""
    lines = [
        "| figure (reference scene) | float64 | float32 | relative difference | tolerance | |",
        "|---|---:|---:|---:|---:|---|",
    ]
    for c in extremes["cases"]:
        if c["group"] != "precision":
            continue
        label = c["name"].removeprefix("float32 ")
        lines.append(
            f"| {label} | {float(c['reference']):.7g} | {float(c['value']):.7g} | {float(c['error']):.1e} | "
            f"{float(c['tolerance']):.0e} | {'pass' if c['passed'] else 'FAIL'} |"
        )
    return "\n".join(lines)


def extremes_failures(extremes: dict) -> str:
    """The failed cases, or a line saying there are none."""
    failed = [c for c in extremes["cases"] if not c["passed"]]
    if not failed:
        return "No case failed."
    lines = ["| group | case | value | reference | error | tolerance |", "|---|---|---:|---:|---:|---:|"]
    for c in failed:
        lines.append(
            f"| {c['group']} | {c['name']} | {_g(c['value'])} | {_g(c['reference'])} | {_g(c['error'])} | "
            f"{_g(c['tolerance'])} |"
        )
    return "\n".join(lines)


def cli_cold(data: dict) -> str:
    """Every built-in scene's cold ``camjax design`` (benchmarks/cli_timing.py ``cold``): wall and
    CPU seconds, the wall over ``import jax``, its compute phase, against the 10 s target."""
    scenes = sorted(k[len("cli.cold."):-len("_s")] for k in data if k.startswith("cli.cold.")
                    and k.endswith("_s") and not k.endswith(("_cpu_s", "_phases_s")))
    rows = ["| scene | wall s | CPU s | × import jax | compute s | ≤ 10 s |", "|---|---|---|---|---|---|"]
    for scene in scenes:
        wall = data[f"cli.cold.{scene}_s"]
        compute = data.get(f"cli.cold.{scene}_phases_s", {}).get("compute")
        rows.append(f"| `{scene}` | {wall:.1f} | {data[f'cli.cold.{scene}_cpu_s']:.1f} | "
                    f"{data[f'cli.cold.{scene}_over_import']:.1f} | "
                    f"{'' if compute is None else f'{compute:.1f}'} | "
                    f"{'yes' if wall <= 10.0 else '**no**'} |")
    return "\n".join(rows)


# ------------------------------------------------------------------------------------ targets

DETAILS = "benchmarks.md"


def _figure(value: float) -> str:
    """A measured figure for the targets table: whole numbers from 100 up, else 3 digits."""
    return f"{value:,.0f}" if 100 <= abs(value) < 1e6 else f"{value:.3g}"


def _target(key, what, goal, value, at_least, env, anchor, unit="×", matched=None) -> dict:
    met = None if value is None else (value >= goal if at_least else value <= goal)
    if met and matched is False:
        met = False
    return {"key": key, "what": what, "goal": f"{'≥' if at_least else '≤'} {goal:g}{unit}",
            "measured": "not measured" if value is None else f"{_figure(value)}{unit}",
            "machine": machine(env) if isinstance(env, dict) else env, "met": met,
            "note": "accuracy not matched" if matched is False else "", "details": f"{DETAILS}#{anchor}"}


def targets() -> list[dict]:
    """Every target of every benchmark, one row per measurement (one machine per row): ``key``,
    ``what``, ``goal``, ``measured``, ``machine``, ``met`` (None where not measured), ``note`` and
    ``details`` (the benchmark page's section). The one list the performance table and the
    ``{{ status: KEY }}`` placeholders read, so a figure has the same status wherever it appears."""
    rows = []
    bench = load("bench")
    for t in bench["targets"]:
        op, goal = t["target"].split()
        unit = "×" if t["description"].endswith("(x)") else ""
        what = ("flat-face " if t["key"].startswith("sweep.") else "") + t["description"].removesuffix(" (x)")
        rows.append({**_target(t["key"], what, float(goal), t["measured"],
                               op == ">=", bench["environment"], "last-full-run", unit=unit),
                     "met": t["status"] == "pass"})
    followers = load("followers")
    sweeps = _sweeps(followers)
    for name in _follower_names():
        s = sweeps.get(name)
        if s is None or name == "flat":  # the flat face's sweep is full.json's sweep.* above
            continue
        for figure, solver in (("gradient_speedup", "gradient vs SLSQP"), ("ga_speedup", "GA or hybrid vs "
                                                                           "differential evolution")):
            kind = "gradient" if figure.startswith("gradient") else "ga"
            rows.append(_target(f"{name}.{figure}", f"{name} sweep, {solver}", SWEEP_GOALS[figure],
                                s.get(figure), True, s.get("_env"), "follower-speed",
                                matched=s.get(f"{kind}_accuracy_matched")))
    exact = load("exact")
    rows.append(_target("exact.time_ratio.sweep", "exact extrema: 100-weighting sweep time / grid's",
                        EXACT_GOAL, exact["exact"]["time_ratio"]["sweep"], False, exact["environment"],
                        "extrema-per-follower"))
    extrema = load("extrema")
    ratio = {n: f.get("exact_over_grid_time_360") or 0.0 for n, f in extrema["followers"].items()}
    worst = max(ratio, key=ratio.get)
    rows.append(_target("extrema.exact_over_grid_time_360",
                        f"exact / grid report time, N = 360 (worst: {worst})",
                        EXACT_GOAL, extrema["followers"][worst].get("exact_over_grid_time_360"), False,
                        extrema["environment"][worst], "extrema-per-follower"))
    cli = load("cli")
    cli_machine = f"{cli['cpu_count']}-core CPU"
    for key, what, goal in (("cli.design_over_import", "`camjax design` warm / `import jax`", 2.0),
                            ("cli.dynamics_over_import", "`camjax dynamics` warm / `import jax`", 8.0),
                            ("cli.laws_over_import", "`camjax laws` / `import jax`", 1.5)):
        rows.append(_target(key, what, goal, cli.get(key), False, cli_machine, "the-cli"))
    rows.append(_target("cli.cold_max_s", "`camjax design` cold, slowest built-in scene", 10.0,
                        cli.get("cli.cold_max_s"), False, cli_machine, "the-cli", unit=" s"))
    codesign = load("codesign")
    rows.append(_target("codesign.slsqp_speedup", "co-design vs SciPy SLSQP (median)", 10.0,
                        codesign["codesign"]["slsqp_speedup"], True, codesign["environment"],
                        "notes-on-the-targets"))
    synthesis = load("synthesis")["synthesis"]
    rows.append(_target("synthesis.linprog_speedup", "256 law syntheses vs SciPy linprog (HiGHS)", 10.0,
                        synthesis["linprog_speedup"], True, "shared 2-core CPU",  # not in its JSON
                        "law-synthesis"))
    device = load("synthesis_device")
    rows.append(_target("synthesis_device.gpu.linprog_speedup", "the same, JAX on a GPU", 10.0,
                        device["gpu"]["linprog_speedup"], True, f"{device['gpu']['device']} GPU",
                        "law-synthesis"))
    rows.append(_target("synthesis_device.cpu_16_cores.linprog_speedup", "the same, on that machine's CPU",
                        10.0, device["cpu_16_cores"]["linprog_speedup"], True,
                        "16-core CPU, JAX 0.11.2",  # the machine's line in the JSON
                        "law-synthesis"))
    robust = load("robust")
    rows.append(_target("robust.cli_wall_s.warm_median", "`camjax robust`, 100000 samples, warm", 10.0,
                        robust["robust"]["cli_wall_s"]["warm_median"], False, robust["environment"], "robust",
                        unit=" s"))
    rows.append(_target("robust.cli_wall_s.cold_first", "`camjax robust`, 100000 samples, cold", 20.0,
                        robust["robust"]["cli_wall_s"]["cold_first"], False, robust["environment"], "robust",
                        unit=" s"))
    if "robust_dynamics" in robust:
        dyn = robust["robust_dynamics"]
        rows.append(_target("robust_dynamics.cli_wall_s.warm_median",
                            "`camjax robust` with [dynamics], 1000 samples, warm", 30.0,
                            dyn["cli_wall_s"]["warm_median"], False, dyn["environment"], "robust", unit=" s"))
    return rows


def _status(row: dict) -> str:
    if row["met"] is None:
        return "not measured"
    return ("pass" if row["met"] else "**miss**") + (f" ({row['note']})" if row["note"] else "")


def performance(_: dict | None = None) -> str:
    """Every target in one table: what, goal, measured, machine, status, where it is detailed."""
    lines = ["| target | goal | measured | machine | status |", "|---|---|---|---|---|"]
    for r in targets():
        lines.append(f"| [{r['what']}]({r['details']}) | {r['goal']} | {r['measured']} | {r['machine']} | "
                     f"{_status(r)} |")
    return "\n".join(lines)


def status(key: str) -> str:
    """``met`` or ``missed`` for the target ``key`` (the performance table's pass or miss), for prose."""
    rows = {r["key"]: r for r in targets()}
    if key not in rows:
        raise PlaceholderError(f"unknown target {key!r} (known: {', '.join(rows)})")
    r = rows[key]
    return "not measured" if r["met"] is None else ("met" if r["met"] else "missed")


def newton_followers(data: dict) -> str:
    """A row per follower type and weighting of benchmarks/newton.py: the newton solver's iterations,
    KKT residual, time and gap to SciPy SLSQP (its iterations and time), and the design program's
    compile time per follower type (on its first row)."""
    rows = ["| follower | alpha, gamma | newton: iterations, KKT residual, s | SLSQP: iterations, s | "
            "gap to SLSQP | compile s |", "|---|---|---|---|---|---|"]
    for name, f in data["followers"].items():
        for i, r in enumerate(f["runs"]):
            ok = r["newton_converged"] and r["newton_feasible"]
            rows.append(f"| {'' if i else name} | {r['alpha']:g}, {r['gamma']:g} | "
                        f"{r['newton_iterations']}{'' if ok else ' **(not converged)**'}, "
                        f"{r['newton_kkt']:.1e}, {r['newton_s']:.3f} | {r['slsqp_iterations']}, "
                        f"{r['slsqp_s']:.3f} | {r['relative_gap']:.1e} | "
                        f"{'' if i else format(f['newton_compile_s'], '.1f')} |")
    return "\n".join(rows)


TABLES: dict[str, tuple[str, Callable[[dict], str]]] = {
    "performance": ("bench", performance),
    "newton_followers": ("newton", newton_followers),
    "cli_cold": ("cli", cli_cold),
    "bench_provenance": ("bench", bench_provenance),
    "bench_targets": ("bench", bench_targets),
    "bench_fitness": ("bench", bench_fitness),
    "bench_knobs": ("bench", bench_knobs),
    "bench_sweep_methods": ("bench", bench_sweep_methods),
    "follower_speed": ("followers", follower_speed),
    "follower_sweeps": ("followers", follower_sweeps),
    "extrema_provenance": ("extrema", extrema_provenance),
    "extrema_table": ("extrema", extrema_table),
    "extremes_summary": ("extremes", extremes_summary),
    "extremes_groups": ("extremes", extremes_groups),
    "extremes_precision": ("extremes", extremes_precision),
    "extremes_failures": ("extremes", extremes_failures),
}
"""Table name -> (source, renderer)."""


# ------------------------------------------------------------------------------------ pages

_TABLE = re.compile(r"(?<!\\)\{\{\s*table:\s*(\w+)\s*\}\}")
_VALUE = re.compile(
    r"(?<!\\)\{\{\s*(" + "|".join(SOURCES) + r"):\s*([\w.]+)(?:\*([0-9.eE+-]+))?(?::([^}\s]+))?\s*\}\}"
)


class PlaceholderError(ValueError):
    """A placeholder names a table or a JSON key that does not exist."""


# ------------------------------------------------------------------------------------ lists

# ``{{ list: NAME }}``: a list the code keeps (follower types, built-in scenes, solvers), written
# from its registry when the site is built, so a new follower folder or scene file appears on every
# page that lists them without editing prose.


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _followers(rocking: bool | None = None) -> list:
    from camjax import followers

    return [f for f in followers.all_followers() if rocking is None or bool(f.rocking) == rocking]


def _follower_titles(rocking: bool | None = None) -> str:
    return _and([f.title for f in _followers(rocking)])


def _follower_folders(rocking: bool) -> str:
    return ", ".join(f"`{f.name}/`" for f in _followers(rocking))


def _scenes() -> str:
    from camjax.scene import BUILTIN_SCENES

    return ", ".join(f"`{name}`" for name in BUILTIN_SCENES)


def _solvers() -> str:
    from camjax.solvers.registry import SOLVERS

    return ", ".join(f"`{name}`" for name in SOLVERS)


def _laws() -> str:
    from camjax.laws import LAWS

    return ", ".join(f"`{name}`" for name in LAWS)


def _commands() -> str:
    """A table of the ``camjax`` commands, as ``camjax --help`` lists them (the CLI's registry)."""
    from camjax.cli.app import COMMANDS, HELP_ORDER

    order = sorted(COMMANDS, key=lambda n: HELP_ORDER.index(n) if n in HELP_ORDER else len(HELP_ORDER))
    rows = ["| command | what it does |", "|---|---|"]
    rows += [f"| [`camjax {name}`](#camjax-{name}) | {COMMANDS[name][0]} |" for name in order]
    return "\n".join(rows)


NAV_BLURBS = {"Getting started": "new to camjax: the first design, its files and figures, Python",
              "Tasks": "a job to do", "Reference": "looking something up",
              "How it works": "the models, the solvers, how exact and how fast",
              "Developing camjax": "changing camjax"}


def _nav() -> str:
    """The site's sections and their pages, read from mkdocs.yml's nav (a page added there appears
    here too), for the home page: one line per section, a nested section by its first page."""
    import yaml

    def first(value):
        return value if isinstance(value, str) else first(next(iter(value[0].values())))

    lines = []
    for item in yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]:
        (title, value), = item.items()
        if value == "index.md":
            continue
        blurb = NAV_BLURBS.get(title, "")
        if isinstance(value, str):
            lines.append(f"- [{title}]({value}){': ' + blurb if blurb else ''}")
            continue
        links = [f"[{t}]({first(v)})" for entry in value for t, v in entry.items()]
        lines.append(f"- **{title}**{' (' + blurb + ')' if blurb else ''}: " + " · ".join(links))
    return "\n".join(lines)


GALLERY = ROOT / "docs" / "gallery"

# one line on each follower type for the home page (a type not named here shows its title alone)
FOLLOWER_BLURBS = {
    "flat": "a flat face sliding on a straight stem; sized by the cam's curvature and contact stress",
    "roller": "a roller on a sliding stem, offset or in line; sized by pressure angle and undercut",
    "knife_edge": "a sharp tip riding the profile itself; pressure angle and crest radius",
    "curved_face": "a crowned (mushroom) face on a sliding stem",
    "oscillating_roller": "a roller on an arm swinging about a pivot",
    "oscillating_flat": "a flat face on an arm swinging about a pivot",
    "oscillating_curved_face": "a crowned face on an arm swinging about a pivot",
}


def _follower_types() -> str:
    """The follower types as a row of thumbnails (each type's example scene's profile from the
    gallery, docs/gen_gallery.py) with the type, its motion and its built-in example scene; for a
    page at the top of docs/ (the image paths are relative to it)."""
    cells = []
    for f in _followers():
        image = GALLERY / f"{f.example_scene}-profile.png"
        scene = f"gallery/#{f.example_scene}"
        img = (f'<a href="{scene}"><img src="gallery/{image.name}" alt="{f.title} follower: the '
               f'{f.example_scene} scene\'s cam" loading="lazy"></a>') if image.exists() else ""
        motion = "rocking" if f.rocking else "translating"
        blurb = FOLLOWER_BLURBS.get(f.name, "")
        cells.append(f'<figure>{img}<figcaption><strong>{f.title}</strong> · {motion} · '
                     f'<code>type = "{f.name}"</code><br>{blurb + ". " if blurb else ""}'
                     f'Scene <a href="{scene}"><code>{f.example_scene}</code></a></figcaption></figure>')
    return '<div class="figure-row thumbs" markdown="0">\n' + "\n".join(cells) + "\n</div>"


GALLERY_FIGURES = {"profile": "the cam and its follower", "svaj": "s, v, a, j over one turn",
                   "loads": "contact force and cam torque"}
"""The gallery's figures per scene, in docs/gen_gallery.py's file names (``SCENE-NAME.png``)."""
GALLERY_ANIMATION = "one turn of the mechanism"
"""The caption of a designed scene's animation (``SCENE-motion.gif``, docs/gen_gallery.py)."""


GALLERY_COLUMN_PX = 660
"""About the width of the gallery's figure column beside the TOML in a 1280 px window (extra.css)."""


def _png_width(path: Path) -> int:
    """A PNG's width in pixels, from its header (the IHDR chunk)."""
    with open(path, "rb") as f:
        return int.from_bytes(f.read(24)[16:20], "big")


def gallery_missing() -> dict[str, str]:
    """Built-in scene -> the command that draws its gallery figures, for each scene without them
    (its s/v/a/j figure, its title block and what the run wrote; the profile and the animation where
    ``camjax design`` drew them)."""
    from camjax.scene import BUILTIN_SCENES

    def drawn(name: str) -> bool:
        meta = GALLERY / f"{name}.json"
        if not meta.exists() or not (GALLERY / f"{name}-svaj.png").exists():
            return False
        record = json.loads(meta.read_text())
        if "files" not in record:  # what the run wrote, for the CLI page (:func:`_outputs`)
            return False
        designed = " design " in record["command"]
        return not designed or all((GALLERY / f"{name}-{fig}").exists() for fig in ("profile.png", "motion.gif"))

    return {name: f"python docs/gen_gallery.py --scene {name}" for name in BUILTIN_SCENES if not drawn(name)}


def _gallery() -> str:
    """Every built-in scene (from the registry): its TOML beside its committed figures. The build
    only shows the images docs/gen_gallery.py drew; a scene without them says how to draw them."""
    from camjax.scene import BUILTIN_SCENES, builtin_scene_text

    parts = []
    for name in BUILTIN_SCENES:
        text = builtin_scene_text(name)
        kind = next((line.split("=", 1)[1].split("#")[0].strip().strip('"') for line in text.splitlines()
                     if line.strip().startswith("type")), "")
        meta = GALLERY / f"{name}.json"
        verb = json.loads(meta.read_text())["command"].split()[1] if meta.exists() else "design"
        captions = {**GALLERY_FIGURES, **({"svaj": "the designed laws against the best built-in ones"}
                                          if verb == "synthesize" else {})}
        drawn = [(fig, what) for fig, what in captions.items() if (GALLERY / f"{name}-{fig}.png").exists()]
        # a figure wider than the column beside the TOML goes below it, at its own width
        wide = [f"![{name}: {what}](gallery/{name}-{fig}.png)" for fig, what in drawn
                if _png_width(GALLERY / f"{name}-{fig}.png") > GALLERY_COLUMN_PX]
        figures = [f"![{name}: {what}](gallery/{name}-{fig}.png)" for fig, what in drawn]
        figures = [f for f in figures if f not in wide]
        if (GALLERY / f"{name}-motion.gif").exists():
            figures.append(f"![{name}: {GALLERY_ANIMATION}](gallery/{name}-motion.gif)")
        if not drawn:
            figures = [f"No figures yet: `python docs/gen_gallery.py --scene {name}` draws them."]
        parts.append(
            f"## `{name}` {{ #{name} }}\n\n`camjax {verb} {name} --out out/`"
            + (f" · follower `{kind}`" if kind else "") + "\n\n"
            '<div class="gallery-scene" markdown>\n<div markdown>\n\n'
            f'```toml\n{text.rstrip()}\n```\n\n</div>\n'
            f'<div markdown>\n\n' + "\n\n".join(figures) + "\n\n</div>\n</div>\n"
            + "".join(f"\n{f}\n" for f in wide))
    return "\n".join(parts)


def _outputs() -> str:
    """What ``camjax design`` (or ``synthesize``) of each built-in scene wrote, as docs/gen_gallery.py
    recorded it from the run: its files, result.json's top-level keys and profile.csv's columns.
    A scene drawn before these were recorded says how to record them."""
    from camjax.scene import BUILTIN_SCENES

    parts = []
    for name in BUILTIN_SCENES:
        meta = GALLERY / f"{name}.json"
        record = json.loads(meta.read_text()) if meta.exists() else {}
        if "files" not in record:
            parts.append(f"**`{name}`**: not recorded yet (`python docs/gen_gallery.py --scene {name}`).")
            continue
        cells = [f"**`{name}`** (`{record['command'].split(' --dpi')[0]}`)",
                 "files: " + ", ".join(f"`{f}`" for f in record["files"]),
                 "result.json: " + ", ".join(f"`{k}`" for k in record["result_keys"])]
        if record["profile_columns"]:
            cells.append("profile.csv: " + ", ".join(f"`{c}`" for c in record["profile_columns"]))
        parts.append("\n".join(f"- {c}" if i else c for i, c in enumerate(cells)))
    return "\n\n".join(parts)


LISTS: dict[str, Callable[[], str]] = {
    "outputs": _outputs,  # files, result.json keys, profile.csv columns per built-in scene (cli.md)
    "gallery": _gallery,  # every built-in scene: TOML beside its figures (docs/gallery.md)
    "follower_types": _follower_types,  # thumbnails and one line per type (home page)
    "followers": _follower_titles,  # "curved-face, flat-face, ... and roller"
    "followers_count": lambda: str(len(_followers())),
    "translating_followers": lambda: _follower_titles(False),
    "rocking_followers": lambda: _follower_titles(True),
    "translating_folders": lambda: _follower_folders(False),  # "`flat/`, `roller/`, ..."
    "rocking_folders": lambda: _follower_folders(True),
    "scenes": _scenes,  # "`default`, `codesign`, ..." (the embedded default first)
    "solvers": _solvers,
    "nav": _nav,  # the site's sections and pages, from mkdocs.yml (home page)
    "laws": _laws,  # the named laws, as scenes spell them
    "commands": _commands,  # a table of the camjax commands (cli.md: links to its own sections)
}
_LIST = re.compile(r"(?<!\\)\{\{\s*list:\s*(\w+)\s*\}\}")
_STATUS = re.compile(r"(?<!\\)\{\{\s*status:\s*([\w.]+)\s*\}\}")


def render(markdown: str, page: str = "<page>") -> str:
    """``markdown`` with every ``{{ table: NAME }}``, ``{{ SOURCE: path }}``, ``{{ list: NAME }}``
    and ``{{ status: KEY }}`` replaced."""
    cache: dict[str, dict] = {}

    def data(source: str) -> dict:
        if source not in cache:
            cache[source] = load(source)
        return cache[source]

    def table(m: re.Match) -> str:
        name = m.group(1)
        if name not in TABLES:
            raise PlaceholderError(f"{page}: unknown table {name!r} (known: {', '.join(TABLES)})")
        source, fn = TABLES[name]
        return fn(data(source))

    def value(m: re.Match) -> str:
        source, path, factor, spec = m.groups()
        try:
            v = lookup(data(source), path)
        except (KeyError, IndexError, ValueError, TypeError) as e:
            raise PlaceholderError(f"{page}: {source} has no {path!r} ({e!r})") from e
        if factor is not None:
            v = v * float(factor)
        try:
            return format(v, spec) if spec else _g(v)
        except (TypeError, ValueError) as e:
            raise PlaceholderError(f"{page}: {source} {path!r} = {v!r} does not format as {spec!r}") from e

    def listed(m: re.Match) -> str:
        if m.group(1) not in LISTS:
            raise PlaceholderError(f"{page}: unknown list {m.group(1)!r} (known: {', '.join(LISTS)})")
        return LISTS[m.group(1)]()

    # "\\{{" is a literal "{{" (a page that shows the syntax)
    def target_status(m: re.Match) -> str:
        try:
            return status(m.group(1))
        except PlaceholderError as e:
            raise PlaceholderError(f"{page}: {e}") from e

    out = _LIST.sub(listed, _VALUE.sub(value, _TABLE.sub(table, markdown)))
    return _STATUS.sub(target_status, out).replace("\\{{", "{{")


def main(argv: list[str]) -> int:
    names = argv or list(TABLES)
    unknown = [n for n in names if n not in TABLES]
    if unknown:
        print(f"unknown table(s): {', '.join(unknown)}; known: {', '.join(TABLES)}", file=sys.stderr)
        return 2
    for name in names:
        print(f"<!-- {name} -->\n{render('{{ table: ' + name + ' }}')}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
