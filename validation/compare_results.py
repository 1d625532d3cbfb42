"""Compare two result JSON files key by key: ``python validation/compare_results.py OLD.json NEW.json``.

``--dirs OLD_DIR NEW_DIR`` compares every ``*.json`` of two folders (as written by
``validation/snapshot.py``), file by file; a file in only one of them is a difference.

Exit 0 when every key path holds the same value in both files, 1 otherwise (each differing path
listed, one a line). Floats are compared exactly unless ``--rtol`` is given; ``--ignore KEY``
(repeatable) skips a key path, written dotted with list indices in brackets (``design.seconds``,
``flcd[0].jump_s``), or a bare key name that is skipped wherever it occurs.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any


def _same_number(a: float, b: float, rtol: float) -> bool:
    if a == b:
        return True
    if math.isnan(a) and math.isnan(b):
        return True
    return rtol > 0 and abs(a - b) <= rtol * max(abs(a), abs(b))


def differences(old: Any, new: Any, rtol: float = 0.0, ignore: frozenset[str] = frozenset(),
                path: str = "") -> list[str]:
    """Key paths where ``old`` and ``new`` differ, with both values (empty list: equal)."""
    name = path.rsplit(".", 1)[-1].split("[", 1)[0]
    if path in ignore or (name and name in ignore):
        return []
    where = path or "<root>"
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for key in sorted(old.keys() ^ new.keys()):
            sub = f"{path}.{key}" if path else key
            if sub not in ignore and key not in ignore:
                out.append(f"{sub}: only in {'OLD' if key in old else 'NEW'}")
        for key in old.keys() & new.keys():
            out += differences(old[key], new[key], rtol, ignore, f"{path}.{key}" if path else key)
        return sorted(out)
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{where}: list length {len(old)} != {len(new)}"]
        out = []
        for i, (a, b) in enumerate(zip(old, new, strict=True)):
            out += differences(a, b, rtol, ignore, f"{path}[{i}]")
        return out
    numbers = (int, float)
    if (isinstance(old, numbers) and isinstance(new, numbers)
            and not isinstance(old, bool) and not isinstance(new, bool)):
        if type(old) is not type(new) and not rtol:
            return [f"{where}: {old!r} ({type(old).__name__}) != {new!r} ({type(new).__name__})"]
        return [] if _same_number(float(old), float(new), rtol) else [f"{where}: {old!r} != {new!r}"]
    if type(old) is not type(new) or old != new:
        return [f"{where}: {old!r} != {new!r}"]
    return []


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old", help="reference JSON (e.g. the result before a change)")
    p.add_argument("new", help="JSON to check against it")
    p.add_argument("--rtol", type=float, default=0.0,
                   help="relative tolerance for numbers (default 0: exact)")
    p.add_argument("--ignore", action="append", default=[], metavar="KEY",
                   help="key path or bare key name to skip (repeatable)")
    p.add_argument("--dirs", action="store_true", help="OLD and NEW are folders: compare every *.json")
    args = p.parse_args(argv)
    if args.dirs:
        return _compare_dirs(args)
    with open(args.old) as f_old, open(args.new) as f_new:
        old, new = json.load(f_old), json.load(f_new)
    diff = differences(old, new, args.rtol, frozenset(args.ignore))
    for line in diff:
        print(line)
    if diff:
        print(f"{len(diff)} difference(s) between {args.old} and {args.new}")
        return 1
    print(f"identical: {args.old} == {args.new}"
          + (f" (rtol {args.rtol:g})" if args.rtol else " (exact)")
          + (f", ignoring {', '.join(args.ignore)}" if args.ignore else ""))
    return 0


def _compare_dirs(args) -> int:
    from pathlib import Path

    old_dir, new_dir = Path(args.old), Path(args.new)
    old_files = {p.name for p in old_dir.glob("*.json")}
    new_files = {p.name for p in new_dir.glob("*.json")}
    bad = [f"{name}: only in {'OLD' if name in old_files else 'NEW'}"
           for name in sorted(old_files ^ new_files)]
    for name in sorted(old_files & new_files):
        old = json.loads((old_dir / name).read_text())
        new = json.loads((new_dir / name).read_text())
        bad += [f"{name}: {line}" for line in differences(old, new, args.rtol, frozenset(args.ignore))]
    for line in bad:
        print(line)
    same = len(old_files & new_files)
    print(f"{same} file(s) compared, {len(bad)} difference(s)"
          + (f" (rtol {args.rtol:g})" if args.rtol else " (exact)"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
