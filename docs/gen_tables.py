"""Tables and figures of the documentation, generated from the JSON that camjax's own commands write.

Seven sources, all committed (:data:`SOURCES`):

- ``bench``, ``benchmarks/results/full.json``: ``python benchmarks/run.py --out
  benchmarks/results/full.json``;
- ``extremes``, ``docs/data/extremes.json``: ``python -m camjax.cli check-extremes --out DIR``, then
  ``cp DIR/extremes.json docs/data/``;
- ``result``, ``docs/data/default/result.json``: ``python -m camjax.cli design --out DIR``, then
  ``cp DIR/result.json docs/data/default/``;
- ``dynamics``, ``docs/data/thesis-bench/dynamics.json``: ``python -m camjax.cli dynamics
  thesis-bench --out DIR``, then ``cp DIR/dynamics.json docs/data/thesis-bench/``;
- ``roller``, ``benchmarks/results/roller.json``: ``python -m benchmarks.roller --out
  benchmarks/results/roller.json``;
- ``cli``, ``benchmarks/results/cli_timing.json``: ``python benchmarks/cli_timing.py --runs 5 --out
  benchmarks/results/cli_timing.json``;
- ``exact``, ``benchmarks/results/exact.json``: ``python -m benchmarks.exact --out
  benchmarks/results/exact.json``.

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


TABLES: dict[str, tuple[str, Callable[[dict], str]]] = {
    "bench_provenance": ("bench", bench_provenance),
    "bench_targets": ("bench", bench_targets),
    "bench_fitness": ("bench", bench_fitness),
    "bench_knobs": ("bench", bench_knobs),
    "bench_sweep_methods": ("bench", bench_sweep_methods),
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


def render(markdown: str, page: str = "<page>") -> str:
    """``markdown`` with every ``{{ table: NAME }}`` and ``{{ SOURCE: path }}`` replaced."""
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

    # "\\{{" is a literal "{{" (a page that shows the syntax)
    return _VALUE.sub(value, _TABLE.sub(table, markdown)).replace("\\{{", "{{")


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
