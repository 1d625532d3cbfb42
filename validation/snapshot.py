"""Write the JSON of every built-in scene and of the test scenes, to compare two versions of camjax.

``python validation/snapshot.py OUT_DIR`` runs each case below through the command line (the
cache off, figures drawn: each run as a user's) and keeps its result.json, pareto.json or
dynamics.json as ``OUT_DIR/<case>.json``. Take one snapshot before a change that must not move any
number, one after, and compare them with ``python validation/compare_results.py --dirs OLD NEW``
(every file, key by key, exactly).

The cases: each built-in scene through ``design`` (and ``dynamics`` where it has [dynamics]), the
reference case in pointwise mode and with every solver, a sweep, and the scenes of the cache
matrix (``tests/cache_matrix.py``: every follower type with each option and scene edit).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def cases(tmp: Path) -> dict[str, list[str]]:
    """Case name -> CLI arguments (without --out); scene files written into ``tmp``."""
    sys.path.insert(0, str(ROOT / "tests"))
    import cache_matrix as matrix

    out = {
        "default": ["design"], "default-pointwise": ["design", "--mode", "pointwise"],
        "default-ga": ["design", "--solver", "ga"], "default-hybrid": ["design", "--solver", "hybrid"],
        "default-r30": ["design", "--base-radius", "30"],
        "roller": ["design", "roller"], "roller-pointwise": ["design", "roller", "--mode", "pointwise"],
        "thesis-bench": ["design", "thesis-bench"], "thesis-bench-dynamics": ["dynamics", "thesis-bench"],
        "sweep-default": ["sweep", "--alpha", "0.1,1,10", "--gamma", "1"],
        "sweep-roller": ["sweep", "roller", "--alpha", "1,2", "--gamma", "0,1"],
    }
    for follower in matrix.SCENES:
        for k, argv in enumerate(matrix._runs(follower, tmp)):
            out[f"{follower}-{k:02d}"] = argv
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("out", help="folder for the JSON files (replaced)")
    p.add_argument("--only", default="", help="comma-separated case names (default: all)")
    args = p.parse_args(argv)
    os.environ["CAMJAX_PROGRAM_CACHE"] = "0"
    from camjax import cli

    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    names = {"design": "result.json", "sweep": "pareto.json", "dynamics": "dynamics.json"}
    with tempfile.TemporaryDirectory() as tmp:
        todo = cases(Path(tmp))
        only = [n for n in args.only.split(",") if n]
        failed = []
        for name, cli_args in todo.items():
            if only and name not in only:
                continue
            folder = Path(tmp) / "runs" / name
            code = cli.main([*cli_args, "--out", str(folder)])
            if code not in (0, 3):
                failed.append(name)
                continue
            shutil.copy(folder / names[cli_args[0]], out / f"{name}.json")
    print(f"wrote {len(list(out.glob('*.json')))} JSON files to {out}"
          + (f"; failed: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
