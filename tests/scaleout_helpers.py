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


def compile_in_worker(cache_dir: str) -> str:
    """In a worker: point JAX at ``cache_dir`` as every block function does
    (:func:`camjax.scaleout.blocks.configure_worker`), then compile one small program; returns the
    folder JAX now caches in."""
    import jax
    import jax.numpy as jnp

    from camjax.scaleout.blocks import configure_worker

    configure_worker(cache_dir)
    jax.jit(lambda x: jnp.sin(x) * 3.0 + 1.0)(jnp.arange(7.0)).block_until_ready()
    return jax.config.jax_compilation_cache_dir
