"""``camjax sweep --backend ...``: the scale-out options of the sweep command and the run behind them.

Without any of these options ``camjax sweep`` solves in this process as before. With them the
sweep is cut into blocks that are stored in the output folder as they finish (``manifest.json``
and ``blocks/``), so ``--resume`` continues an interrupted sweep, and pareto.json / pareto.png
are written from the merged blocks at the end. Then the folder is replaced whole, as every
command's is: it holds that checkpoint (:data:`CHECKPOINT`) and the two files, nothing of an
earlier run (a design's figures, say). A run that stops early leaves the checkpoint beside
what the folder held before, for ``--resume``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from camjax.scaleout.backends import BACKENDS

DEFAULT_BLOCK_SIZE = 64
# what a resume reads from --out (camjax.scaleout.store): kept when the folder is replaced at the end
CHECKPOINT = ("manifest.json", "blocks")


def add_options(p: argparse.ArgumentParser) -> None:
    """--backend, --address, --workers, --block-size, --resume."""
    g = p.add_argument_group("scale-out (blocks stored in --out as they finish)")
    g.add_argument("--backend", choices=BACKENDS, default=None,
                   help="run the sweep in blocks: in this process (sequential), in a spawn process pool "
                   "(process), or on Ray (ray); default: one in-process sweep, no blocks")
    g.add_argument("--address", default=None, metavar="HOST:PORT",
                   help="Ray cluster to connect to (ray.init(address=...)); default: start a local one")
    g.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes (process) or CPUs of a local Ray instance (default: all cores)")
    g.add_argument("--block-size", type=int, default=None, metavar="W",
                   help=f"weightings per block (default {DEFAULT_BLOCK_SIZE})")
    g.add_argument("--resume", action="store_true",
                   help="continue the block sweep already in --out; finished blocks are not recomputed")


def requested(args) -> bool:
    """True when any scale-out option was given."""
    return (args.backend is not None or args.address is not None or args.workers is not None
            or args.block_size is not None or args.resume)


def check(args, usage_error) -> None:
    """Validate the options; ``usage_error(message)`` is the CLI's exception class."""
    from camjax.scene import quote

    if args.address is not None and args.backend not in (None, "ray"):
        raise usage_error(f"--address = {quote(args.address)}: only the ray backend connects to a cluster "
                          "(allowed: --backend ray)")
    if args.workers is not None and not 1 <= args.workers <= 4096:
        raise usage_error(f"--workers = {args.workers}: out of range (allowed: 1..4096)")
    if args.block_size is not None and not 1 <= args.block_size <= 100_000:
        raise usage_error(f"--block-size = {args.block_size}: out of range (allowed: 1..100000)")


def run_sweep(args, scene, scene_text: str, alphas, gammas, *, mode: str, solver: str, seed: int,
              cache_dir: str | None, usage_error):
    """The block sweep of one scene; returns a :class:`camjax.solvers.sweep.SweepResult`.

    Raises ``usage_error`` when a resume does not match the folder; exits with status 1 (and
    writes no pareto.json) when blocks failed every attempt: they are named, ``--resume`` retries
    them and keeps the finished ones.
    """
    from camjax.scaleout.blocks import SweepSpec
    from camjax.scaleout.driver import sweep_blocks
    from camjax.scaleout.store import ManifestMismatch

    spec = SweepSpec(solver=solver, mode=mode, seed=seed)
    say = lambda line: print(line, file=sys.stderr)  # noqa: E731
    try:
        run, records = sweep_blocks(
            [(scene.name, scene_text)], alphas, gammas, Path(args.out), spec=spec,
            backend=args.backend or "sequential", workers=args.workers, address=args.address,
            block_size=args.block_size or DEFAULT_BLOCK_SIZE, resume=args.resume, cache_dir=cache_dir,
            progress=say)
    except ManifestMismatch as exc:
        raise usage_error(str(exc)) from None
    if not run.complete:
        failed = ", ".join(map(str, run.failed))
        say(f"camjax sweep: error: {len(run.failed)} block(s) failed every attempt ({failed}); errors in "
            f"{Path(args.out) / 'blocks'}/*.error.json; finished blocks are kept: rerun with --resume")
        raise SystemExit(1)
    if run.skipped:
        say(f"resumed: {len(run.skipped)} blocks read from {args.out}, {len(run.computed)} computed")
    return sweep_result_from_records(records, mode, solver)


def sweep_result_from_records(records: list[dict], mode: str, solver: str):
    """A :class:`camjax.solvers.sweep.SweepResult` rebuilt from block records (for pareto.json and
    the plot): the records themselves, their "pareto" flags as the mask."""
    import numpy as np

    from camjax.solvers.sweep import SweepResult

    block_keys = ("pareto", "scene", "weighting", "solver", "mode")  # added by the blocks, not per design
    rows = [{k: v for k, v in r.items() if k not in block_keys} for r in records]
    return SweepResult(mode, solver, rows, np.array([r["pareto"] for r in records], bool))


def scene_text(path_or_name: str | None) -> str:
    """TOML text of a scene given as ``camjax.scene.load_scene`` takes it (file or built-in name)."""
    from camjax.scene import BUILTIN_SCENES, builtin_scene_text

    name = "default" if path_or_name is None else str(path_or_name)
    if name in BUILTIN_SCENES and not Path(name).is_file():
        return builtin_scene_text(name)
    return Path(name).read_text()
