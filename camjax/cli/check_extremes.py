"""``camjax check-extremes``: the numerical-stability matrix of a scene (from a source checkout)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from camjax import runtime
from camjax.cli.common import UsageError, add_samples_option, apply_samples, command
from camjax.output.files import write_json
from camjax.output.folder import check_output_dir, replaced_folder


def _stability_matrix():
    """``validation.extremes`` from the source checkout this package runs from (it is not installed)."""
    import importlib

    source = Path(__file__).resolve().parents[2] / "validation" / "extremes.py"
    if not source.is_file():
        raise UsageError(f"{source} is missing: check-extremes runs from a source checkout "
                         "(git clone, then pip install -e .), not from an installed wheel")
    if str(source.parents[1]) not in sys.path:
        sys.path.insert(0, str(source.parents[1]))
    module = importlib.import_module("validation.extremes")
    if Path(module.__file__).resolve() != source:  # another package named 'validation' came first
        raise UsageError(f"import validation.extremes found {module.__file__}, not {source}")
    return module


@command("check-extremes", "run the numerical-stability matrix and write extremes.json")
def _setup_check_extremes(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None, help="scene file or built-in name (default: default)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (replaced whole)")
    add_samples_option(p)

    def run(args) -> int:
        from camjax.scene import load_scene

        out = check_output_dir(args.out)
        matrix = _stability_matrix()
        scene = apply_samples(load_scene(args.scene), args)
        skipped = matrix.skipped_groups(scene)
        for s in skipped:
            print(f"  skipping {s['group']}: {s['reason']}", file=sys.stderr)
        cases = runtime.interruptible(matrix.run_matrix, scene,
                                      progress=lambda g: print(f"  running {g} ...", file=sys.stderr))
        failed = [c for c in cases if not c.passed]
        with replaced_folder(out) as tmp:
            write_json(tmp / "extremes.json", {
                "scene": scene.name,
                "cases": [c.as_dict() for c in cases],
                "skipped": skipped,
                "summary": {"cases": len(cases), "passed": len(cases) - len(failed), "failed": len(failed)},
            })
            (tmp / "extremes.txt").write_text(matrix.format_table(cases) + "\n")
            (tmp / "extremes.md").write_text(matrix.format_markdown(cases) + "\n")
        print(matrix.format_table(failed) if failed else f"all {len(cases)} cases pass")
        written = out / "extremes.json"
        print(f"{len(cases) - len(failed)} passed, {len(failed)} failed; wrote {written}")
        return 1 if failed else 0

    return run


