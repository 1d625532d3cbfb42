"""README Performance tables from a benchmark JSON: ``python benchmarks/readme_table.py FILE``."""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _g(v, digits: int = 3) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int):
        return str(v)
    return f"{v:.{digits}g}"


def render(data: dict) -> str:
    """Markdown: provenance line, targets table, fitness-by-population table, trade table."""
    env = data["environment"]
    lines = [
        f"Run: `python benchmarks/run.py --out {data.get('out', 'FILE.json')}` on {env['date_utc']}, "
        f"{env['machine']}, {env['cpu_count']} CPUs, {env['backend']} backend, jax/jaxlib {env['jax']}/"
        f"{env['jaxlib']}, NumPy {env['numpy']}, SciPy {env['scipy']}, Python {env['python']}, "
        f"{env['dtype']}; load average at start "
        f"{', '.join(f'{x:.1f}' for x in env['load_average_at_start'])} "
        f"(the machine was shared), total {data['wall_s']['total']:.0f} s.",
        "",
        "| target | goal | measured | |",
        "|---|---|---|---|",
    ]
    for t in data["targets"]:
        lines.append(
            f"| {t['description']} (`{t['key']}`) | {t['target']} | {_g(t['measured'])} | {t['status']} |"
        )
    fit = data.get("fitness", {})
    if "by_population" in fit:
        lines += [
            "",
            "| population (N = 360, float64) | camjax GA fitness /s | same, blocked /s | hand-fused /s "
            "| NumPy /s |",
            "|---|---|---|---|---|",
        ]
        for r in fit["by_population"]:
            lines.append(
                f"| {r['population']:,} | {_g(r['library_evals_per_s'])} | "
                f"{_g(r['library_blocked_evals_per_s'])} | {_g(r['fused_evals_per_s'])} | "
                f"{_g(r.get('numpy_evals_per_s'))} |"
            )
    acc = data.get("accuracy", {})
    if "grid" in acc:
        lines += ["", "| knob | setting | dtype | time (s) | max rel. error |", "|---|---|---|---|---|"]
        for r in acc["grid"] + acc["solvers"]:
            setting = r.get("setting", f"N = {r['samples']}") + (" **(default)**" if r.get("default") else "")
            lines.append(
                f"| {r['knob']} | {setting} | {r['dtype']} | {_g(r['time_s'])} | {r['max_rel_error']:.1e} |"
            )
    return "\n".join(lines)


if __name__ == "__main__":
    print(render(json.loads(Path(sys.argv[1]).read_text())))
