"""Tables and figures of the documentation, generated from the JSON that camjax's own commands write.

Eleven sources, all committed (:data:`SOURCES`):

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
- ``newton``, ``benchmarks/results/newton.json``: ``python -m benchmarks.newton --out
  benchmarks/results/newton.json``.

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
    "newton": ROOT / "benchmarks" / "results" / "newton.json",
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
            f"| {t['description']} (`{t['key']}`) | {t['target']} | {_g(t['measured'])} | {t['status']} |"
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


def _yes(flag) -> str:
    return "–" if flag is None else ("yes" if flag else "**no**")


def _sweeps(followers: dict) -> dict[str, dict]:
    """The 100-weighting sweep of each follower that has one: the flat face (full.json ``sweep``),
    the roller (roller.json) and the rockers (followers.json)."""
    out = {name: {**v, "_file": "followers.json"} for name, v in followers.items()
           if isinstance(v, dict) and "gradient_speedup" in v}
    for source, key, name in (("roller", "roller", "roller"), ("bench", "sweep", "flat")):
        try:
            out.setdefault(name, {**load(source)[key], "_file": SOURCES[source].name})
        except (OSError, KeyError):
            pass
    return out


def follower_speed(followers: dict) -> str:
    """A row per registered follower: the sweep speed-ups against SciPy at matched accuracy, the
    gradient solver's largest iteration count, and the exact report's time over the grid one at 360
    samples, with the goals; a follower not measured says so."""
    sweeps = _sweeps(followers)
    try:
        extrema = load("extrema")["followers"]
    except OSError:
        extrema = {}
    lines = [
        f"| follower | gradient vs SLSQP (goal ≥ {SWEEP_GOALS['gradient_speedup']:g}×) | matched | "
        f"GA or hybrid vs differential evolution (goal ≥ {SWEEP_GOALS['ga_speedup']:g}×) | matched | "
        f"gradient steps (max) | exact / grid report, N = 360 (goal ≤ {EXACT_GOAL:g}×) | sweep from |",
        "|---|---|---|---|---|---:|---|---|",
    ]
    for name in _follower_names():
        s = sweeps.get(name)
        e = extrema.get(name, {})
        exact = _ratio_cell(e.get("exact_over_grid_time_360"), EXACT_GOAL, at_least=False)
        if s is None:
            lines.append(f"| `{name}` | no sweep benchmark | | no sweep benchmark | | – | {exact} | |")
            continue
        gradient = s.get("methods", {}).get("camjax_gradient", {})
        steps = gradient.get("iterations_max")
        via = s.get("ga_speedup_method", "camjax_ga").removeprefix("camjax_")
        gradient_cell = _ratio_cell(s["gradient_speedup"], SWEEP_GOALS["gradient_speedup"],
                                    matched=s.get("gradient_accuracy_matched"))
        ga_cell = _ratio_cell(s["ga_speedup"], SWEEP_GOALS["ga_speedup"],
                              matched=s.get("ga_accuracy_matched"))
        lines.append(
            f"| `{name}` | {gradient_cell} | {_yes(s.get('gradient_accuracy_matched'))} | {ga_cell} "
            f"({via}) | {_yes(s.get('ga_accuracy_matched'))} | {_g(steps)} | {exact} | `{s['_file']}` |"
        )
    return "\n".join(lines)


def follower_sweeps(followers: dict) -> str:
    """Every method of each rocker's sweep: time for all weightings, worst gap, infeasible results."""
    lines = ["| follower | method | time, 100 weightings (s) | weightings measured | worst rel. gap | "
             "infeasible | steps (max) |", "|---|---|---:|---:|---:|---:|---:|"]
    for name, s in followers.items():
        if not isinstance(s, dict) or "methods" not in s:
            continue
        for method, m in s["methods"].items():
            extra = " (extrapolated)" if m.get("extrapolated") else ""
            lines.append(f"| `{name}` | `{method}` | {_g(m['time_s'])}{extra} | {m['weightings']} | "
                         f"{m['max_rel_objective_gap']:.1e} | {m['infeasible']} | "
                         f"{_g(m.get('iterations_max'))} |")
    return "\n".join(lines)


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
    """A row per follower and sample count: time and largest relative error of the grid and the exact
    extrema against the dense reference."""
    lines = ["| follower | N | grid: time (s) | grid: max rel. error | exact: time (s) "
             "| exact: max rel. error | worst figure (exact) |", "|---|---:|---:|---:|---:|---:|---|"]
    for name, f in extrema["followers"].items():
        by = {(r["samples"], r["extrema"]): r for r in f["rows"]}
        for n in sorted({r["samples"] for r in f["rows"]}):
            g, e = by.get((n, "grid"), {}), by.get((n, "exact"), {})
            err = lambda r: f"{r['max_rel_error']:.1e}" if r else "–"  # noqa: E731
            lines.append(f"| `{name}` | {n:,} | {_g(g.get('time_s'))} | {err(g)} | {_g(e.get('time_s'))} | "
                         f"{err(e)} | {e.get('worst_figure', '–')} |")
    return "\n".join(lines)


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
    scenes = sorted(k[len("cli.cold."):-len("_s")] for k in data
                    if k.startswith("cli.cold.") and k.endswith("_s") and not k.endswith(("_cpu_s", "_phases_s")))
    rows = ["| scene | wall s | CPU s | × import jax | compute s | ≤ 10 s |", "|---|---|---|---|---|---|"]
    for scene in scenes:
        wall = data[f"cli.cold.{scene}_s"]
        compute = data.get(f"cli.cold.{scene}_phases_s", {}).get("compute")
        rows.append(f"| `{scene}` | {wall:.1f} | {data[f'cli.cold.{scene}_cpu_s']:.1f} | "
                    f"{data[f'cli.cold.{scene}_over_import']:.1f} | "
                    f"{'' if compute is None else f'{compute:.1f}'} | {'yes' if wall <= 10.0 else '**no**'} |")
    return "\n".join(rows)


def newton_followers(data: dict) -> str:
    """A row per follower type and weighting of benchmarks/newton.py: the newton solver's iterations,
    KKT residual, time and gap to SciPy SLSQP (its iterations and time), and the design program's
    compile time per follower type (on its first row)."""
    rows = ["| follower | alpha, gamma | newton iterations | KKT residual | newton s | SLSQP iterations | "
            "SLSQP s | gap to SLSQP | compile s |", "|---|---|---|---|---|---|---|---|---|"]
    for name, f in data["followers"].items():
        for i, r in enumerate(f["runs"]):
            ok = r["newton_converged"] and r["newton_feasible"]
            rows.append(f"| {'' if i else name} | {r['alpha']:g}, {r['gamma']:g} | "
                        f"{r['newton_iterations']}{'' if ok else ' **(not converged)**'} | "
                        f"{r['newton_kkt']:.1e} | {r['newton_s']:.3f} | {r['slsqp_iterations']} | "
                        f"{r['slsqp_s']:.3f} | {r['relative_gap']:.1e} | "
                        f"{'' if i else format(f['newton_compile_s'], '.1f')} |")
    return "\n".join(rows)


TABLES: dict[str, tuple[str, Callable[[dict], str]]] = {
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


LISTS: dict[str, Callable[[], str]] = {
    "followers": _follower_titles,  # "curved-face, flat-face, ... and roller"
    "followers_count": lambda: str(len(_followers())),
    "translating_followers": lambda: _follower_titles(False),
    "rocking_followers": lambda: _follower_titles(True),
    "translating_folders": lambda: _follower_folders(False),  # "`flat/`, `roller/`, ..."
    "rocking_folders": lambda: _follower_folders(True),
    "scenes": _scenes,  # "`default`, `codesign`, ..." (the embedded default first)
    "solvers": _solvers,
}
_LIST = re.compile(r"(?<!\\)\{\{\s*list:\s*(\w+)\s*\}\}")


def render(markdown: str, page: str = "<page>") -> str:
    """``markdown`` with every ``{{ table: NAME }}``, ``{{ SOURCE: path }}`` and ``{{ list: NAME }}`` replaced."""
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
    return _LIST.sub(listed, _VALUE.sub(value, _TABLE.sub(table, markdown))).replace("\\{{", "{{")


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
