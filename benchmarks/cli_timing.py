"""Wall time of camjax CLI commands against ``python -c "import jax"`` on the same machine.

``python benchmarks/cli_timing.py [--runs 3] [--out FILE.json]`` prints (and writes) JSON:
``cli.import_jax_s`` (median of the import runs) and, per command, ``cli.<name>_s`` and
``cli.<name>_over_import`` (median of warm runs / median import time), with the per-phase
lines the command printed on stderr timed as they arrived (``cli.<name>_phases_s``). Each
command runs once untimed first so that the compilation cache is warm; ``cold`` instead runs
``camjax design`` of every built-in scene once in a fresh process with empty caches
(``cli.cold.<scene>_s``; ``python benchmarks/cli_timing.py cold`` alone). CPU time (user + sys of
the child) is reported beside the wall time (``cli.<name>_cpu_s``): on a shared machine the wall
time also measures the other processes.

One function per command (:func:`dynamics`, :func:`design`, :func:`laws`, :func:`sweep`); add another
the same way.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _run(argv: list[str], env: dict | None = None) -> tuple[float, float, list[tuple[float, str]]]:
    """(wall s, child CPU s, [(s since start, stderr line)]) of one run from the repository root."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=env)
    lines = [(time.perf_counter() - start, line.rstrip("\n")) for line in proc.stderr]
    if proc.wait() != 0:
        raise RuntimeError(f"{' '.join(argv)} exited {proc.returncode}: {lines[-3:]}")
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, lines


def _median_runs(argv: list[str], runs: int, warmup: bool = True, env: dict | None = None) -> dict:
    if warmup:
        _run(argv, env)
    results = [_run(argv, env) for _ in range(runs)]
    walls = [r[0] for r in results]
    pick = results[walls.index(sorted(walls)[len(walls) // 2])]
    return {"wall_s": statistics.median(walls), "cpu_s": statistics.median(r[1] for r in results),
            "walls_s": walls, "phases_s": pick[2]}


def import_jax(runs: int) -> dict:
    """``python -c "import jax"``: the reference every command is divided by."""
    r = _median_runs([sys.executable, "-c", "import jax"], runs)
    return {"cli.import_jax_s": r["wall_s"], "cli.import_jax_cpu_s": r["cpu_s"]}


def dynamics(runs: int, reference: dict) -> dict:
    """``camjax dynamics thesis-bench`` (this checkout's package, a temporary output folder)."""
    with tempfile.TemporaryDirectory(prefix="camjax-cli-timing-") as tmp:
        r = _median_runs([sys.executable, "-m", "camjax.cli", "dynamics", "thesis-bench",
                          "--out", str(Path(tmp) / "out")], runs)
    # each phase lasts until the next line (the time-domain thread's lines interleave with the
    # main thread's: read them as "started at", not as exclusive costs)
    marks = [(0.0, "start (imports, scene, nominal)"), *r["phases_s"], (r["wall_s"], "")]
    phases = {line.removeprefix("camjax dynamics: "): round(t_next - t, 3)
              for (t, line), (t_next, _) in zip(marks[:-1], marks[1:], strict=True)}
    return {"cli.dynamics_s": r["wall_s"], "cli.dynamics_walls_s": r["walls_s"],
            "cli.dynamics_cpu_s": r["cpu_s"],
            "cli.dynamics_over_import": r["wall_s"] / reference["cli.import_jax_s"],
            "cli.dynamics_cpu_over_import": r["cpu_s"] / reference["cli.import_jax_cpu_s"],
            "cli.dynamics_phases_s": phases}


def design(runs: int, reference: dict) -> dict:
    """``camjax design`` on the default scene (this checkout's package, a temporary output folder).

    Phases from the command's progress lines, each lasting until the next: import (until
    "computing": Python, JAX, camjax and the scene), compute (the design run, its report and
    result.json), plots (waiting for the drawing processes: the PNG figures, profile.csv and
    profile.dxf, then the folder swap and the exit); files (~0: the job handed to the drawing
    processes)."""
    with tempfile.TemporaryDirectory(prefix="camjax-cli-timing-") as tmp:
        argv = [sys.executable, "-m", "camjax.cli", "design", "--out", str(Path(tmp) / "out")]
        # piped, design prints its phases only when asked
        r = _median_runs(argv, runs, env={**os.environ, "CAMJAX_PROGRESS": "1"})
    names = {"computing": "compute", "figures": "plots", "files": "files"}
    marks = [(0.0, "import"),
             *((t, names[line.removeprefix("camjax design: ")]) for t, line in r["phases_s"]),
             (r["wall_s"], "")]  # the last phase runs to the end of the process (exit included)
    phases = {name: round(t_next - t, 3)
              for (t, name), (t_next, _) in zip(marks[:-1], marks[1:], strict=True)}
    return {"cli.design_s": r["wall_s"], "cli.design_walls_s": r["walls_s"], "cli.design_cpu_s": r["cpu_s"],
            "cli.design_over_import": r["wall_s"] / reference["cli.import_jax_s"],
            "cli.design_cpu_over_import": r["cpu_s"] / reference["cli.import_jax_cpu_s"],
            "cli.design_phases_s": phases}


def laws(runs: int, reference: dict) -> dict:
    """``camjax laws``: the table of every built-in law's dimensionless figures (goal <= 1.5x import)."""
    r = _median_runs([sys.executable, "-m", "camjax.cli", "laws"], runs)
    return {"cli.laws_s": r["wall_s"], "cli.laws_walls_s": r["walls_s"], "cli.laws_cpu_s": r["cpu_s"],
            "cli.laws_over_import": r["wall_s"] / reference["cli.import_jax_s"],
            "cli.laws_cpu_over_import": r["cpu_s"] / reference["cli.import_jax_cpu_s"]}


SWEEP_ARGS = ["--alpha", "0.1,1,10", "--gamma", "1,2"]  # 6 weightings: one chunk of the CPU's 10


def sweep(runs: int, reference: dict) -> dict:
    """``camjax sweep`` of the default scene, 6 weightings (:data:`SWEEP_ARGS`), warm (its programs
    saved and compiled by the untimed first run)."""
    with tempfile.TemporaryDirectory(prefix="camjax-cli-timing-") as tmp:
        r = _median_runs([sys.executable, "-m", "camjax.cli", "sweep", *SWEEP_ARGS, "--out",
                          str(Path(tmp) / "out")], runs)
    return {"cli.sweep_s": r["wall_s"], "cli.sweep_walls_s": r["walls_s"], "cli.sweep_cpu_s": r["cpu_s"],
            "cli.sweep_over_import": r["wall_s"] / reference["cli.import_jax_s"],
            "cli.sweep_cpu_over_import": r["cpu_s"] / reference["cli.import_jax_cpu_s"]}


def _builtin_scenes() -> list[str]:
    return sorted(p.stem for p in (ROOT / "camjax" / "scenes").glob("*.toml"))


def cold(runs: int, reference: dict, scenes: list[str] | None = None) -> dict:
    """``camjax design SCENE`` of every built-in scene (``scenes``: those), each in a fresh process
    with empty caches (a new compilation cache and program cache folder per run, nothing compiled
    before): the first run a user ever makes. Once per scene (``runs`` does not apply: a cold run
    cannot be repeated in one folder); wall and CPU seconds, the phases as in :func:`design`, and
    the wall over ``import jax``.
    """
    out: dict = {}
    walls = []
    for scene in scenes or _builtin_scenes():
        with tempfile.TemporaryDirectory(prefix="camjax-cli-cold-") as tmp:
            env = {**os.environ, "CAMJAX_PROGRESS": "1", "CAMJAX_COMPILATION_CACHE": str(Path(tmp) / "xla"),
                   "CAMJAX_PROGRAM_CACHE": str(Path(tmp) / "programs")}
            wall, cpu, lines = _run([sys.executable, "-m", "camjax.cli", "design", scene, "--out",
                                     str(Path(tmp) / "out")], env)
        names = {"computing": "compute", "figures": "plots", "files": "files"}
        marks = [(0.0, "import"), *((t, names.get(line.removeprefix("camjax design: "), line))
                                    for t, line in lines if line.startswith("camjax design: ")), (wall, "")]
        out[f"cli.cold.{scene}_s"] = wall
        walls.append(wall)
        out[f"cli.cold.{scene}_cpu_s"] = cpu
        out[f"cli.cold.{scene}_over_import"] = wall / reference["cli.import_jax_s"]
        out[f"cli.cold.{scene}_phases_s"] = {name: round(t_next - t, 3) for (t, name), (t_next, _)
                                             in zip(marks[:-1], marks[1:], strict=True)}
        print(f"cold {scene}: {wall:.1f} s", file=sys.stderr)
    out["cli.cold_count"] = len(walls)
    out["cli.cold_max_s"] = max(walls)
    out["cli.cold_median_s"] = statistics.median(walls)
    return out


COMMANDS = {"dynamics": dynamics, "design": design, "laws": laws, "sweep": sweep, "cold": cold}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="timed warm runs per command (default 3)")
    parser.add_argument("--out", type=Path, help="also write the JSON here")
    parser.add_argument("commands", nargs="*", default=list(COMMANDS), help=f"of {', '.join(COMMANDS)}")
    args = parser.parse_args(argv)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    result = {"date_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "git_commit": commit or None,
              "cpu_count": os.cpu_count(), "load_average_1min": os.getloadavg()[0]}
    result.update(import_jax(args.runs))
    for name in args.commands:
        result.update(COMMANDS[name](args.runs, result))
    result["load_average_1min_after"] = os.getloadavg()[0]
    text = json.dumps(result, indent=2)
    print(text)
    if args.out:
        args.out.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
