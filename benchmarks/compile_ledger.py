"""Where a test run's compiles go, from the ledger ``pytest --compile-ledger=DIR`` writes.

``python benchmarks/compile_ledger.py DIR [--top 25] [--out FILE.json]`` prints (and writes) JSON:
the run's XLA compile and tracing seconds, per test file and per program name (compile seconds,
compiles), and, per program name lowered under more than one set of argument shapes, how many
shape sets (``signatures``) and which shapes occur in some sets and not others (``varying``). That
names candidates only: two sets of one name may differ in structure (another follower type, other
free variables) as well as in sizes, and static settings (solver, mode) are not in the shapes; those
that differ in a grid size or a batch alone are the programs a shared shape would make one.
``sizes_only`` bounds what shared sizes could save: per program name, the compile seconds of every
compiled program whose argument shapes, sizes left out, are another compiled program's, all but the
costliest of each such set (an upper bound, for the same reason). ``solves`` does the same for the
design programs with what the shapes do not show: each compile of ``jit(search_batch)`` is paired
with the solve the test traced before it (its problem type, mode, solver and settings: the
ledger's "solve" records), and the sets of one such label and equal sizeless shapes that were
compiled under several grid sizes or batches are listed with their tests: the programs a shared
size would make one. Reads the ledger only (no JAX).
"""

from __future__ import annotations

import argparse
import collections
import json
import re
from pathlib import Path


def read(folder: str | Path) -> list[dict]:
    """Every ledger line of every worker in ``folder``: {"test": nodeid, "records": [...]}."""
    lines = []
    for path in sorted(Path(folder).glob("ledger-*.jsonl")):
        lines += [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    return lines


def summary(lines: list[dict], top: int = 25) -> dict:
    """The ledger's totals, the ``top`` files and programs by compile seconds, and the programs
    lowered under several argument shapes (see the module's docstring)."""
    compile_s = trace_s = 0.0
    by_file: dict = collections.defaultdict(lambda: {"compile_s": 0.0, "compiles": 0, "trace_s": 0.0})
    by_program: dict = collections.defaultdict(lambda: {"compile_s": 0.0, "compiles": 0})
    signatures: dict = collections.defaultdict(set)
    for line in lines:
        file = line["test"].split("::")[0]
        for kind, name, value in line["records"]:
            if kind == "compile":
                compile_s += value
                by_file[file]["compile_s"] += value
                by_file[file]["compiles"] += 1
                by_program[name]["compile_s"] += value
                by_program[name]["compiles"] += 1
            elif kind == "trace":
                trace_s += value
                by_file[file]["trace_s"] += value
            elif kind == "lower":
                signatures[name].add(tuple(sorted(value.items())))

    def ranked(table):
        rows = sorted(table.items(), key=lambda kv: -kv[1]["compile_s"])[:top]
        return {k: {f: round(v, 2) if isinstance(v, float) else v for f, v in row.items()} for k, row in rows}

    shaped = {}
    for name, sigs in signatures.items():
        if len(sigs) < 2:
            continue
        counts = [dict(sig) for sig in sigs]
        every = set().union(*counts)
        varying = sorted(s for s in every if len({c.get(s, 0) for c in counts}) > 1)
        shaped[name] = {"signatures": len(sigs), "varying": varying}
    shaped = dict(sorted(shaped.items(), key=lambda kv: -kv[1]["signatures"])[:top])
    return {"compile_s": round(compile_s, 1), "trace_s": round(trace_s, 1), "files": ranked(by_file),
            "programs": ranked(by_program), "shapes": shaped, "sizes_only": sizes_only(lines, top),
            "solves": solves(lines, top)}


def _sizeless(signature: dict) -> tuple:
    """A set of argument shapes with every size written N (counts of equal shapes added up)."""
    counts: collections.Counter = collections.Counter()
    for shape, count in signature.items():
        counts[re.sub(r"\d+", "N", shape)] += count
    return tuple(sorted(counts.items()))


def _compiles(lines: list[dict]):
    """Each compile paired with the shapes its program was last lowered with and the solve traced
    before it (None where the ledger has none): (test, name, shapes, seconds, solve)."""
    for line in lines:
        lowered: dict = {}
        solve = None
        for kind, name, value in line["records"]:
            if kind == "solve":
                solve = (name, value["n"])
            elif kind == "lower":
                lowered[name] = value
            elif kind == "compile" and name in lowered:
                yield line["test"], name, lowered.pop(name), value, solve
                solve = None


def _saving(seconds) -> float:
    """What one program instead of these would save: all but the costliest."""
    return sum(sorted(seconds, reverse=True)[1:])


def sizes_only(lines: list[dict], top: int = 25) -> dict:
    """Per program name, the compile seconds a shared size could at most save: of the compiled shape
    sets that are equal with their sizes left out, all but the costliest count. {"compile_s": total,
    "programs": {name: {"compile_s", "structures"}}} (structures: the sets of more than one size),
    the top names."""
    # (name, sizeless shapes) -> shapes -> seconds
    seconds: dict = collections.defaultdict(lambda: collections.defaultdict(float))
    for _, name, shapes, value, _ in _compiles(lines):
        seconds[(name, _sizeless(shapes))][tuple(sorted(shapes.items()))] += value
    by_name: dict = collections.defaultdict(lambda: {"compile_s": 0.0, "structures": 0})
    for (name, _), per_shapes in seconds.items():
        if len(per_shapes) > 1:
            by_name[name]["compile_s"] += _saving(per_shapes.values())
            by_name[name]["structures"] += 1
    rows = sorted(by_name.items(), key=lambda kv: -kv[1]["compile_s"])
    return {"compile_s": round(sum(v["compile_s"] for _, v in rows), 1),
            "programs": {k: {"compile_s": round(v["compile_s"], 2), "structures": v["structures"]}
                         for k, v in rows[:top]}}


def solves(lines: list[dict], top: int = 25) -> dict:
    """The design programs compiled under several sizes for one solve (see the module's docstring):
    {"compile_s": what shared sizes would save, "sets": [{"solve", "compile_s", "programs": [{"n",
    "shapes", "compile_s", "tests"}]}]}, the ``top`` sets by that saving."""
    seconds: dict = collections.defaultdict(dict)  # (label, sizeless) -> shapes -> [n, s, tests]
    for test, name, shapes, value, solve in _compiles(lines):
        if name != "jit(search_batch)" or solve is None:
            continue
        same_solve = seconds[(solve[0], _sizeless(shapes))]
        row = same_solve.setdefault(tuple(sorted(shapes.items())), [solve[1], 0.0, []])
        row[1] += value
        row[2].append(test)
    sets = []
    for (label, _), programs in seconds.items():
        if len(programs) < 2:
            continue
        rows = sorted(programs.items(), key=lambda kv: -kv[1][1])
        sets.append({"solve": label, "compile_s": round(_saving(row[1] for _, row in rows), 2), "programs": [
            {"n": n, "shapes": dict(shapes), "compile_s": round(s, 2), "tests": sorted(set(tests))}
            for shapes, (n, s, tests) in rows]})
    sets.sort(key=lambda row: -row["compile_s"])
    return {"compile_s": round(sum(row["compile_s"] for row in sets), 1), "sets": sets[:top]}


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="the folder --compile-ledger wrote")
    parser.add_argument("--top", type=int, default=25)
    parser.add_argument("--out", default=None, help="write the JSON here too")
    args = parser.parse_args(argv)
    result = summary(read(args.folder), args.top)
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n")
    return result


if __name__ == "__main__":
    main()
