"""Block functions with injected faults, importable by spawned and Ray workers (tests/ on their path)."""

import os
from pathlib import Path

from camjax.scaleout.blocks import BlockTask, solve_block


def crash_once(task: BlockTask, victim: int, marker: str) -> list[dict]:
    """Kill the worker process (no cleanup, as a crash or an OOM kill would) on the victim
    block's first attempt; the marker file remembers that the crash happened."""
    if task.index == victim and not Path(marker).exists():
        Path(marker).write_text(str(os.getpid()))
        os._exit(17)
    return solve_block(task)
