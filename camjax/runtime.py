"""Process-wide set-up: the persistent compilation cache, and computing so that Ctrl-C is heard.

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


COMPUTE_THREAD = "camjax-compute"
_RUNNING: set = set()  # done-events of interruptible workers that have not finished


def interruptible(fn, *args, **kwargs):
    """``fn(*args, **kwargs)`` run in a worker thread while this (main) thread waits in short slices.

    A long XLA call (a compile, a solver loop, a sweep chunk) holds the thread that made it until
    it returns, and Python delivers Ctrl-C (KeyboardInterrupt) or SIGTERM only between bytecodes of
    the main thread: waiting here instead answers within about 0.1 s. On an interrupt the worker is
    abandoned (it is a daemon thread; :func:`computing` says whether it still runs, and a process
    that exits while it does must leave through ``os._exit``: XLA aborts when the interpreter
    shuts down under a running computation). Exceptions of ``fn`` are re-raised here. Called from
    any other thread, ``fn`` simply runs.
    """
    import threading

    if threading.current_thread() is not threading.main_thread():
        return fn(*args, **kwargs)
    box: dict = {}
    done = threading.Event()  # not Thread.is_alive: it can read False after an interrupted join

    def work():
        try:
            box["value"] = fn(*args, **kwargs)
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc
        finally:
            done.set()
            _RUNNING.discard(done)

    _RUNNING.add(done)
    threading.Thread(target=work, name=COMPUTE_THREAD, daemon=True).start()
    while not done.wait(0.05):
        pass
    if "error" in box:
        raise box["error"]
    return box["value"]


def computing() -> bool:
    """True while an abandoned :func:`interruptible` worker still runs."""
    return any(not done.is_set() for done in list(_RUNNING))


def quiet_startup_interrupts() -> None:
    """Until ``camjax.cli.main`` installs its handlers, Ctrl-C or SIGTERM ends the process with one
    line (status 130 / 143) instead of a traceback from inside ``import jax`` (about a second)."""
    import signal

    def leave(signum, frame):
        os.write(2, b"camjax: interrupted while starting; nothing was written\n")
        os._exit(143 if signum == signal.SIGTERM else 130)

    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:  # an ignored signal (nohup, `&`) stays ignored
            signal.signal(sig, leave)
