"""Run a block sweep on any backend: skip finished blocks, stream results to disk, retry failures.

:func:`run_blocks` is the whole driver: it opens the sweep folder (checking the manifest when
resuming), hands the unfinished blocks to the backend, writes each block's records the moment
it arrives, and gives every failed block up to ``attempts`` tries in total, in rounds. A block
that fails every try gets an error file with the last traceback and is left for a later resume;
the others are never lost.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NamedTuple

from camjax.scaleout.backends import make_backend
from camjax.scaleout.blocks import BlockTask, SweepSpec, make_blocks, pareto_records, solve_block
from camjax.scaleout.store import BlockStore, manifest_of

DEFAULT_ATTEMPTS = 3  # first try + 2 retries


class SweepRun(NamedTuple):
    """What a call to :func:`run_blocks` did (block numbers)."""

    computed: list[int]  # finished in this call
    skipped: list[int]  # already on disk (resume): not recomputed
    failed: dict[int, str]  # failed every attempt: block -> last error
    retried: list[int]  # needed more than one attempt (and then finished or failed)

    @property
    def complete(self) -> bool:
        return not self.failed


def run_blocks(blocks: Sequence[BlockTask], folder: str | Path, backend, *, block_size: int,
               resume: bool = False, attempts: int = DEFAULT_ATTEMPTS,
               block_fn: Callable[[BlockTask], list[dict]] = solve_block,
               progress: Callable[[str], None] | None = None) -> SweepRun:
    """Compute every block not yet in ``folder`` with ``backend``; store each as it finishes.

    Args:
      blocks: the sweep's blocks (:func:`camjax.scaleout.blocks.make_blocks`).
      folder: sweep folder (manifest + blocks/); created if needed.
      backend: a map from :mod:`camjax.scaleout.backends`.
      block_size: recorded in the manifest (a resume must use the same cut).
      resume: continue a sweep already in ``folder`` (refused if its parameters differ).
      attempts: tries per block in total (>= 1).
      block_fn: the pure block function (top level, picklable); tests inject faults here.
      progress: called with one line per event.
    """
    if attempts < 1:
        raise ValueError(f"attempts: {attempts} must be >= 1")
    say = progress or (lambda _line: None)
    store = BlockStore(folder)
    store.open(manifest_of(list(blocks), block_size), resume)
    done = store.finished()
    skipped = sorted(b.index for b in blocks if b.index in done)
    todo = [b for b in blocks if b.index not in done]
    if skipped:
        say(f"resume: {len(skipped)} of {len(blocks)} blocks already finished")
    tries = {b.index: 0 for b in todo}
    computed, failed, errors = [], {}, {}
    for _round in range(attempts):
        if not todo:
            break
        again = []
        for pos, outcome in backend.map_unordered(block_fn, todo):
            task = todo[pos]
            tries[task.index] += 1
            if outcome.ok:
                store.write_block(task, outcome.value, tries[task.index], outcome.seconds, outcome.worker)
                computed.append(task.index)
                say(f"block {task.index}: {len(outcome.value)} records in {outcome.seconds:.2f} s "
                    f"({outcome.worker}, attempt {tries[task.index]})")
            else:
                errors[task.index] = outcome.error
                again.append(task)
                say(f"block {task.index}: attempt {tries[task.index]} failed: "
                    f"{outcome.error.splitlines()[-1] if outcome.error else '?'}")
        todo = sorted(again, key=lambda b: b.index)
    for task in todo:
        failed[task.index] = errors[task.index]
        store.write_error(task, errors[task.index], tries[task.index])
    retried = sorted(i for i, n in tries.items() if n > 1)
    return SweepRun(sorted(computed), skipped, failed, retried)


def sweep_blocks(scenes: Sequence[tuple[str, str]], alphas, gammas, folder: str | Path, *,
                 spec: SweepSpec | None = None, backend: str = "sequential", workers: int | None = None,
                 address: str | None = None, block_size: int = 64, resume: bool = False,
                 attempts: int = DEFAULT_ATTEMPTS, cache_dir: str | None = None,
                 progress: Callable[[str], None] | None = None) -> tuple[SweepRun, list[dict]]:
    """Every (alpha, gamma) pair of two lists (alpha-major, as :func:`camjax.solvers.sweep.sweep`)
    for every scene, in blocks on the named backend; the records with the Pareto flag when complete.

    Args:
      scenes: (name, TOML text) pairs.
      backend: "sequential", "process" (``workers`` spawned processes) or "ray" (``address`` of
        a running cluster, or a local instance with ``workers`` CPUs).
      cache_dir: persistent JAX compilation cache shared by the workers.
    Returns (what ran, records of every finished block with "pareto"; [] if some block failed).
    """
    from camjax.solvers.sweep import weight_grid

    a, g = weight_grid(alphas, gammas)
    blocks = make_blocks(scenes, list(zip(a.tolist(), g.tolist(), strict=True)), block_size,
                         spec or SweepSpec(), cache_dir)
    engine = make_backend(backend, workers=workers, address=address)
    try:
        run = run_blocks(blocks, folder, engine, block_size=block_size, resume=resume, attempts=attempts,
                         progress=progress)
    finally:
        engine.close()
    return run, (pareto_records(BlockStore(folder).records()) if run.complete else [])
