"""Process-wide JAX set-up: the persistent compilation cache, in one place.

The CLI calls :func:`enable_compilation_cache` before its first compile; scale-out workers call
:func:`use_compilation_cache` with the folder the driver hands them, so every process of a run
shares one cache.
"""

from __future__ import annotations

import os
from pathlib import Path


def use_compilation_cache(folder: str | os.PathLike) -> None:
    """Persist every compiled kernel in ``folder`` (created if missing; OSError if it cannot be).

    A minimum compile time of 0 s caches even the small kernels: a fresh process then loads them
    instead of recompiling (measured 1.38 -> 0.39 s for a first call on 2 CPU cores).
    """
    import jax

    os.makedirs(folder, exist_ok=True)
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)


def enable_compilation_cache() -> None:
    """Persist compiled kernels between runs (a fresh process then starts in ~0.5 s, not ~2 s).

    Folder: $CAMJAX_COMPILATION_CACHE, else ~/.cache/camjax/jax; set CAMJAX_COMPILATION_CACHE=0
    to switch it off. A folder configured through JAX itself (JAX_COMPILATION_CACHE_DIR) wins.
    """
    import jax

    setting = os.environ.get("CAMJAX_COMPILATION_CACHE")
    if setting in ("0", "") or jax.config.jax_compilation_cache_dir:
        return
    folder = Path(setting) if setting else Path.home() / ".cache" / "camjax" / "jax"
    try:
        use_compilation_cache(folder)
    except OSError:
        return  # read-only home: run without the cache
