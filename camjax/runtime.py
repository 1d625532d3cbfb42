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


def enable_caches() -> None:
    """What the command line turns on before its first computation: the compilation cache and the
    program cache (:func:`enable_program_cache`)."""
    enable_compilation_cache()
    enable_program_cache()


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


# ----------------------------------------------------------------------- exported programs

# The persistent compilation cache keeps XLA's compiled code, but a fresh process still traces
# and lowers every jitted function before it can look it up (~1.6 s for a design's solver). The
# program cache keeps the traced program itself (``jax.export``, serialized StableHLO) for the
# few host-level entry points decorated with :func:`program_cache`; a warm process deserializes
# it instead of tracing, and the compilation cache then supplies the executable.
_PROGRAM_DIR: list = [None]  # folder of the program cache; None: off (the library default)
_LOADED: dict = {}  # key -> (compiled program, output treedef), loaded or exported in this process
_UNEXPORTABLE: set = set()  # qualified names whose export failed here: called directly from then on
PROGRAM_SUFFIX = ".jaxprog"


def use_program_cache(folder: str | os.PathLike | None) -> None:
    """Keep the exported programs of :func:`program_cache` entry points in ``folder`` (created if
    missing; OSError if it cannot be); None switches the program cache off. The folder is trusted
    as the compilation cache's is: its files are unpickled and run."""
    if folder is not None:
        os.makedirs(folder, exist_ok=True)
    _PROGRAM_DIR[0] = None if folder is None else Path(folder)
    _LOADED.clear()


def enable_program_cache() -> None:
    """Keep exported programs between runs (the command line calls this beside the compilation
    cache). Folder: $CAMJAX_PROGRAM_CACHE, else ~/.cache/camjax/programs; set it to 0 to switch
    the cache off. Without JAX's serialization support (the ``flatbuffers`` package) it stays off.
    """
    setting = os.environ.get("CAMJAX_PROGRAM_CACHE")
    if setting in ("0", ""):
        return
    try:
        import flatbuffers  # noqa: F401  (jax.export's serialization)
    except ImportError:
        return
    try:
        use_program_cache(Path(setting) if setting else Path.home() / ".cache" / "camjax" / "programs")
    except OSError:
        return


_SOURCE_DIGEST: list = []


def _source_digest() -> str:
    """Digest of every camjax source file: any change of the code invalidates every program."""
    if not _SOURCE_DIGEST:
        import hashlib

        h = hashlib.sha256()
        root = Path(__file__).resolve().parent
        for path in sorted(root.rglob("*.py")):
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
        _SOURCE_DIGEST.append(h.hexdigest())
    return _SOURCE_DIGEST[0]


def program_cache(fn=None, *, static_argnames: tuple[str, ...] = ()):
    """Decorate a host-level entry point so that a fresh process can skip tracing it.

    ``fn`` must be a pure function of its arguments (arrays and pytrees of arrays; the names in
    ``static_argnames`` are hashable Python values it may branch on) and of camjax's own code,
    traceable by ``jax.jit``. With the program cache on (:func:`enable_program_cache`) and
    concrete arguments, the call runs the program exported for the arguments' structure, shapes,
    dtypes and static values, exporting and saving it on the first call; otherwise (cache off,
    called under a trace, or arguments the cache cannot key) it is ``jax.jit(fn)``. The results
    are the same either way: the exported program is ``fn``'s own jaxpr.

    The wrapper's ``load(*args, **kwargs)`` returns a callable of the same arguments, compiled for
    these (when the program cache is on) but not run: to time loading apart from running.
    """
    if fn is None:
        return lambda f: program_cache(f, static_argnames=static_argnames)
    import functools
    import inspect

    import jax

    jitted = jax.jit(fn, static_argnames=static_argnames)
    signature = inspect.signature(fn)
    name = f"{fn.__module__}.{fn.__qualname__}"

    def load(*args, **kwargs):
        folder = _PROGRAM_DIR[0]
        if folder is None or name in _UNEXPORTABLE:
            return jitted
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        static = {k: v for k, v in bound.arguments.items() if k in static_argnames}
        dynamic = {k: v for k, v in bound.arguments.items() if k not in static_argnames}
        try:
            caller, treedef = _program(folder, name, fn, static, dynamic)
        except _NotCacheable:
            return jitted

        def run(*args, **kwargs):  # arguments of the structure, shapes and static values given to load
            bound = signature.bind(*args, **kwargs)
            bound.apply_defaults()
            dynamic = {k: v for k, v in bound.arguments.items() if k not in static_argnames}
            leaves = [jax.random.key_data(x) if _is_key(x) else x for x in jax.tree.leaves(dynamic)]
            return jax.tree.unflatten(treedef, caller(*leaves))

        return run

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        return load(*args, **kwargs)(*args, **kwargs)

    wrapper.load = load
    wrapper.jitted = jitted
    return wrapper


class _NotCacheable(Exception):
    """The arguments cannot key a program (traced, or structure that does not pickle)."""


def _is_key(x) -> bool:
    import jax

    return hasattr(x, "dtype") and jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key)


def _compile(exported, arrays):
    """The exported program compiled for these arguments (the compilation cache supplies it)."""
    import jax

    return jax.jit(exported.call).lower(*arrays).compile()


def program_cache_on() -> bool:
    """Whether :func:`program_cache` entry points run exported programs (see
    :func:`enable_program_cache`)."""
    return _PROGRAM_DIR[0] is not None


def _program(folder: Path, name: str, fn, static: dict, dynamic: dict):
    """(compiled flat program, output treedef) for these arguments: from this
    process, else from ``folder``, else exported now and saved there."""
    import hashlib
    import pickle

    import jax

    leaves, in_tree = jax.tree.flatten(dynamic)
    if any(isinstance(x, jax.core.Tracer) for x in leaves):
        raise _NotCacheable
    keys = [jax.random.key_impl(x) if _is_key(x) else None for x in leaves]
    arrays = [jax.random.key_data(x) if k is not None else x for x, k in zip(leaves, keys, strict=True)]
    specs = [jax.ShapeDtypeStruct(jax.numpy.shape(x), jax.numpy.result_type(x),
                                  weak_type=getattr(x, "weak_type", isinstance(x, (int, float, complex))))
             for x in arrays]
    try:
        fingerprint = pickle.dumps((in_tree, static, [str(k) for k in keys],
                                    [(s.shape, str(s.dtype), s.weak_type) for s in specs]))
    except Exception as exc:  # an aux value that does not pickle cannot be keyed reliably
        raise _NotCacheable from exc
    platform = jax.devices()[0].platform
    digest = hashlib.sha256(b"\0".join([
        name.encode(), _source_digest().encode(), jax.__version__.encode(), platform.encode(),
        str(jax.config.jax_enable_x64).encode(), fingerprint])).hexdigest()[:40]
    if digest in _LOADED:
        return _LOADED[digest]
    path = folder / f"{name}-{digest}{PROGRAM_SUFFIX}"
    entry = None
    if path.exists():
        try:
            saved = pickle.loads(path.read_bytes())
            exported = jax.export.deserialize(bytearray(saved["program"]))
            entry = (_compile(exported, arrays), jax.tree.structure(saved["outputs"]))
        except Exception:  # unreadable or from another JAX: export it again
            entry = None
    if entry is None:
        out_tree: list = []

        def flat(*flat_arrays):
            values = [jax.random.wrap_key_data(x, impl=k) if k is not None else x
                      for x, k in zip(flat_arrays, keys, strict=True)]
            out = fn(**jax.tree.unflatten(in_tree, values), **static)
            out_leaves, tree = jax.tree.flatten(out)
            out_tree.append(tree)
            return out_leaves

        try:
            exported = jax.export.export(jax.jit(flat))(*specs)
            skeleton = jax.tree.unflatten(out_tree[0], [0] * out_tree[0].num_leaves)
            blob = pickle.dumps({"program": bytes(exported.serialize()), "outputs": skeleton})
        except Exception as exc:  # not exportable (e.g. a host callback): trace it every time
            _UNEXPORTABLE.add(name)
            raise _NotCacheable from exc
        entry = (_compile(exported, arrays), out_tree[0])
        try:
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_bytes(blob)
            os.replace(tmp, path)
        except OSError:
            pass  # a read-only cache: the program still runs
    _LOADED[digest] = entry
    return entry
