"""Process-wide set-up: the persistent compilation cache, and computing so that Ctrl-C is heard.

The CLI calls :func:`enable_compilation_cache` before its first compile; scale-out workers call
:func:`use_compilation_cache` with the folder the driver hands them, so every process of a run
shares one cache.
"""

from __future__ import annotations

import contextlib
import os
import threading
from pathlib import Path
from typing import Any, NamedTuple


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


# XLA's CPU fusion emitters (on by default in this jaxlib) compile camjax's programs slower and
# run them no faster: measured on 2 cores, the default scene's first design compiles in 13 s
# instead of 19 s, and a warm 8-weighting sweep runs in 0.19 s instead of 0.43 s (gradient) and
# 0.24 s instead of 0.46 s (GA). The flag is read once, when JAX starts its backend.
CPU_XLA_FLAGS = ("--xla_cpu_use_fusion_emitters=false",)


def use_cpu_xla_flags(flags: tuple[str, ...] = CPU_XLA_FLAGS) -> None:
    """Add ``flags`` to ``XLA_FLAGS`` (each one the variable does not set already), before JAX
    starts its backend; the command line calls it first. CAMJAX_XLA_FLAGS=0 leaves XLA_FLAGS as it is.
    """
    if os.environ.get("CAMJAX_XLA_FLAGS", "").strip() == "0":
        return
    present = os.environ.get("XLA_FLAGS", "").split()
    named = {f.split("=")[0] for f in present}
    os.environ["XLA_FLAGS"] = " ".join(present + [f for f in flags if f.split("=")[0] not in named])


# A full garbage collection (generation 2) walks every object the process holds: with JAX loaded
# and a design's programs traced, 0.1-0.6 s each. Tracing makes many short-lived containers, so at
# Python's default thresholds a cold `camjax design` of the oscillating roller ran 8-9 of them
# (0.9-1.0 s of its 12 s), and a test worker with the heap of hundreds of compiled programs more.
# A full collection after 100 middle ones instead of 10 (the young generations unchanged): one
# in that design. Garbage without cycles is freed at once either way (reference counting);
# cyclic garbage waits longer for its collection.
FULL_COLLECTION_EVERY = 100


def fewer_full_collections(every: int = FULL_COLLECTION_EVERY) -> None:
    """Run a full garbage collection after ``every`` collections of the middle generation
    (Python's default: 10); the command line and the test suite call it. Computes nothing
    differently: only when unreachable cycles are freed changes."""
    import gc

    young, middle, _ = gc.get_threshold()
    gc.set_threshold(young, middle, every)


def enable_caches() -> None:
    """What the command line turns on before its first computation: the compilation cache, the
    program cache (:func:`enable_program_cache`) and compiling ahead (:func:`enable_compiling_ahead`)."""
    enable_compilation_cache()
    enable_program_cache()
    enable_compiling_ahead()


# ----------------------------------------------------------------------- compiling ahead

# A cold design compiles its solver's program, then the drawing's (the smallest cam, the refined
# extrema, the curves), one after the other, each on one core. The drawing's programs take the
# design's dimensions as data, so they can be compiled before the design is known: :func:`ahead`
# runs the drawing for the scene's own follower in a second thread while the design solves, and the
# drawing at the design then finds its programs compiled (measured in docs/development.md). The
# library default is off (a library call makes no threads); the command line turns it on.
_AHEAD: list = [False]
AHEAD_THREAD = "camjax-ahead"


def enable_compiling_ahead() -> None:
    """Turn :func:`ahead` on where there is a second core to compile on; CAMJAX_COMPILE_AHEAD=0
    leaves it off."""
    _AHEAD[0] = os.environ.get("CAMJAX_COMPILE_AHEAD", "").strip() != "0" and (os.cpu_count() or 1) > 1


def compiling_ahead() -> bool:
    """Whether :func:`ahead` runs its function (see :func:`enable_compiling_ahead`)."""
    return _AHEAD[0]


@contextlib.contextmanager
def ahead(fn):
    """Run ``fn()`` in a thread of its own while the ``with`` body runs, for the programs it
    compiles: its result and any exception it raises are dropped, and the body's end waits for it
    (a program both compile is then compiled once: :func:`program_cache`'s lock per key). Nothing
    happens when compiling ahead is off, when ``fn`` is None, or inside a thread that runs ahead
    itself (what it runs is ahead of the body already; the machines have few cores).

    ``fn`` must be a pure computation (no output, no warnings): it runs on provisional inputs.
    If the body raises, the thread is left to end on its own (a daemon; :func:`computing` counts it).
    """
    if not _AHEAD[0] or fn is None or threading.current_thread().name == AHEAD_THREAD:
        yield
        return
    done = threading.Event()

    def work():
        try:
            fn()
        except BaseException:  # noqa: BLE001, S110  (provisional inputs: only the compiles count)
            pass
        finally:
            done.set()
            _RUNNING.discard(done)

    _RUNNING.add(done)
    threading.Thread(target=work, name=AHEAD_THREAD, daemon=True).start()
    yield
    done.wait()


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
#
# A saved program is right only if its key holds everything its trace can depend on. Under
# ``jax.jit`` the dynamic arguments are abstract values, so a trace depends on exactly:
#   1. the code: camjax's source (a digest of every file) and the versions of jax, jaxlib, optax
#      and numpy;
#   2. the static arguments, by value;
#   3. the dynamic arguments' tree structure (with every node's auxiliary data), shapes, dtypes,
#      weak types and PRNG key implementations;
#   4. the process's JAX configuration (x64, dtype promotion, precision, PRNG, ...) and devices.
# The key is a digest of all four. A trace that read anything else (an environment variable, a
# mutable module global, a closed-over value that is not an argument) would be a leak: the
# verify mode (CAMJAX_PROGRAM_CACHE_VERIFY=1; the test matrix runs in it) traces every program
# it reads from the folder again and compares its StableHLO with the saved program's, so a leak
# fails loudly. (A program already traced or compared in this process is reused as it is, as
# ``jax.jit`` reuses its trace: a leak between two calls of one process is no saved program's.)
PROGRAM_FORMAT = 3  # layout of a saved program's file (and of its module text); another is exported again
_PROGRAM_DIR: list = [None]  # folder of the program cache; None: off (the library default)
_VERIFY: list = [False]  # trace every program read from the folder and compare (tests)
_LOADED: dict = {}  # key -> _Entry, loaded or exported in this process
_KEY_LOCKS: dict = {}  # key -> threading.Lock held while its entry is made
_KEY_LOCKS_LOCK = threading.Lock()
_UNEXPORTABLE: dict = {}  # qualified name -> why its export failed here: called directly from then on
PROGRAM_SUFFIX = ".jaxprog"
# JAX options that cannot change a trace (where compiled code is kept, what is logged or dumped):
# left out of the key so that the command line and a test that configure them differently share
# programs. Every other option is in the key.
_CONFIG_NOT_TRACED = ("jax_compilation_cache_", "jax_persistent_cache_", "jax_enable_compilation_cache",
                      "jax_raise_persistent_cache_errors", "jax_log_compiles", "jax_logging_level",
                      "jax_explain_cache_misses", "jax_debug_log_modules", "jax_dump_ir_")


class StaleProgramError(RuntimeError):
    """In verify mode: a saved program differs from what tracing gives now (a key that misses a
    trace-time input; a bug in camjax, never the user's)."""


def use_program_cache(folder: str | os.PathLike | None, *, verify: bool | None = None) -> None:
    """Keep the exported programs of :func:`program_cache` entry points in ``folder`` (created if
    missing; OSError if it cannot be); None switches the program cache off. The folder is trusted
    as the compilation cache's is: its files are unpickled and run.

    ``verify``: trace every program read from the folder anyway and raise
    :class:`StaleProgramError` when the saved program's StableHLO differs from the fresh trace's
    (default: $CAMJAX_PROGRAM_CACHE_VERIFY=1).
    """
    if folder is not None:
        os.makedirs(folder, exist_ok=True)
    _PROGRAM_DIR[0] = None if folder is None else Path(folder)
    _VERIFY[0] = os.environ.get("CAMJAX_PROGRAM_CACHE_VERIFY") == "1" if verify is None else bool(verify)
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


_TRACE_CONTEXT: list = []


def _source_digest() -> str:
    """Digest of every camjax source file: any change of the code invalidates every program."""
    import hashlib

    h = hashlib.sha256()
    root = Path(__file__).resolve().parent
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def trace_context() -> str:
    """Items 1 and 4 of the key (see the comment above :data:`PROGRAM_FORMAT`): camjax's source,
    the versions of the libraries a trace runs, the JAX configuration and the devices, as text.

    The configuration is read at every call (a test or a user may change it between calls); the
    source digest and the versions once per process.
    """
    import jax

    if not _TRACE_CONTEXT:
        from importlib import metadata

        versions = []
        for dist in ("jax", "jaxlib", "optax", "numpy"):
            try:
                versions.append(f"{dist}=={metadata.version(dist)}")
            except metadata.PackageNotFoundError:
                versions.append(f"{dist} missing")
        _TRACE_CONTEXT.append(f"format {PROGRAM_FORMAT}\nsource {_source_digest()}\n" + "\n".join(versions))
    config = sorted((k, repr(v)) for k, v in jax.config.values.items()
                    if not k.startswith(_CONFIG_NOT_TRACED))
    devices = [(d.platform, d.device_kind) for d in jax.devices()]
    return f"{_TRACE_CONTEXT[0]}\nconfig {config!r}\ndevices {devices!r}"


def program_cache(fn=None, *, static_argnames: tuple[str, ...] = ()):
    """Decorate a host-level entry point so that a fresh process can skip tracing it.

    ``fn`` must be a pure function of its arguments (arrays and pytrees of arrays; the names in
    ``static_argnames`` are hashable, picklable Python values it may branch on) and of camjax's
    own code, traceable by ``jax.jit``: it may read no other Python state (a module global that
    changes, an environment variable) while it traces. With the program cache on
    (:func:`enable_program_cache`) and concrete arguments, the call runs the program exported
    for the key of these arguments (the comment above :data:`PROGRAM_FORMAT` lists what it
    holds), exporting and saving it on the first call; otherwise (cache off, called under a trace,
    or arguments the cache cannot key) it is ``jax.jit(fn)``. The results are the same either way:
    the exported program is ``fn``'s own jaxpr.

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

    def split(args, kwargs):
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        static = {k: v for k, v in bound.arguments.items() if k in static_argnames}
        dynamic = {k: v for k, v in bound.arguments.items() if k not in static_argnames}
        return static, dynamic

    def load(*args, **kwargs):
        static, dynamic = split(args, kwargs)

        def plain(*args, **kwargs):  # jax.jit(fn) with the static arguments given to load
            given = signature.bind_partial(*args, **kwargs).arguments
            return jitted(*args, **kwargs, **{k: v for k, v in static.items() if k not in given})

        folder = _PROGRAM_DIR[0]
        if folder is None or name in _UNEXPORTABLE:
            return plain
        try:
            entry = _program(folder, name, fn, static, dynamic)
        except _NotCacheable:  # e.g. a tree structure that does not pickle: traced as usual
            return plain

        def run(*args, **kwargs):  # new values of the dynamic arguments given to load
            given = signature.bind_partial(*args, **kwargs).arguments
            again, dynamic = split(args, {**kwargs, **{k: v for k, v in static.items() if k not in given}})
            if again != static:
                raise ValueError(f"{name}: a loaded program runs with the static arguments it was "
                                 f"loaded for ({static!r}), not {again!r}")
            leaves = [jax.random.key_data(x) if _is_key(x) else x for x in jax.tree.leaves(dynamic)]
            return jax.tree.unflatten(entry.out_tree, entry.compiled(*leaves))

        return run

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        return load(*args, **kwargs)(*args, **kwargs)

    wrapper.load = load
    wrapper.jitted = jitted
    return wrapper


class _NotCacheable(Exception):
    """The arguments cannot key a program (traced, or structure that does not pickle)."""


class _Entry(NamedTuple):
    compiled: Any  # the compiled flat program: leaves -> output leaves
    out_tree: Any  # the output's tree structure


def _is_key(x) -> bool:
    import jax

    return hasattr(x, "dtype") and jax.dtypes.issubdtype(x.dtype, jax.dtypes.prng_key)


def program_cache_on() -> bool:
    """Whether :func:`program_cache` entry points run exported programs (see
    :func:`enable_program_cache`)."""
    return _PROGRAM_DIR[0] is not None


def module_text(exported) -> str:
    """An exported program's StableHLO text without its source locations.

    Locations name the Python frames that created each operation (the call stack of the trace),
    which differ between two traces of the same program; what the program computes does not. The
    module is printed without them (MLIR's printer without debug info).
    """
    from jax.extend.mlir import deserialize_portable_artifact, ir

    with ir.Context():
        module = deserialize_portable_artifact(exported.mlir_module_serialized)
        return module.operation.get_asm(enable_debug_info=False)


def _sha256(data: bytes | str) -> str:
    import hashlib

    return hashlib.sha256(data.encode() if isinstance(data, str) else data).hexdigest()


def program_key(name: str, static: dict, dynamic: dict) -> str:
    """The key of entry point ``name`` called with these static and dynamic arguments (hex).

    Raises :class:`_NotCacheable` for traced arguments or ones that do not pickle (an auxiliary
    value of the tree structure or a static value that pickle cannot write has no reliable key).
    """
    import pickle

    import jax

    leaves, in_tree = jax.tree.flatten(dynamic)
    if any(isinstance(x, jax.core.Tracer) for x in leaves):
        raise _NotCacheable
    specs = []
    for x in leaves:
        impl = str(jax.random.key_impl(x)) if _is_key(x) else None
        data = jax.random.key_data(x) if impl is not None else x
        weak = getattr(data, "weak_type", isinstance(data, (bool, int, float, complex)))
        specs.append((jax.numpy.shape(data), str(jax.numpy.result_type(data)), weak, impl))
    try:
        arguments = pickle.dumps((sorted(static.items()), in_tree, specs), protocol=4)
    except Exception as exc:  # noqa: BLE001  (any pickling failure: no reliable key)
        raise _NotCacheable from exc
    return _sha256(b"\0".join([name.encode(), trace_context().encode(), arguments]))


def _export(name: str, fn, static: dict, dynamic: dict):
    """(exported program, output tree structure) of ``fn`` traced for these arguments."""
    import jax

    leaves, in_tree = jax.tree.flatten(dynamic)
    impls = [jax.random.key_impl(x) if _is_key(x) else None for x in leaves]
    arrays = [jax.random.key_data(x) if k is not None else x for x, k in zip(leaves, impls, strict=True)]
    specs = [jax.ShapeDtypeStruct(jax.numpy.shape(x), jax.numpy.result_type(x),
                                  weak_type=getattr(x, "weak_type", isinstance(x, (int, float, complex))))
             for x in arrays]
    out_tree: list = []

    def flat(*flat_arrays):
        values = [jax.random.wrap_key_data(x, impl=k) if k is not None else x
                  for x, k in zip(flat_arrays, impls, strict=True)]
        out = fn(**jax.tree.unflatten(in_tree, values), **static)
        out_leaves, tree = jax.tree.flatten(out)
        out_tree.append(tree)
        return out_leaves

    try:
        exported = jax.export.export(jax.jit(flat))(*specs)
    except Exception as exc:  # noqa: BLE001  (not exportable, e.g. a host callback: trace it every time)
        _UNEXPORTABLE[name] = f"{type(exc).__name__}: {exc}"[:500]
        raise _NotCacheable from exc
    return exported, out_tree[0], arrays


def _compile(exported, arrays):
    """The exported program compiled for these arguments (the compilation cache supplies it)."""
    import jax

    return jax.jit(exported.call).lower(*arrays).compile()


def _read(path: Path, key: str):
    """(exported program, output skeleton, module digest or None) saved at ``path`` for ``key``, or None
    when the file is missing, unreadable, truncated, of another format or key, or corrupted."""
    import pickle

    import jax

    try:
        saved = pickle.loads(path.read_bytes())
        if not (isinstance(saved, dict) and saved.get("format") == PROGRAM_FORMAT and saved.get("key") == key
                and _sha256(saved["program"]) == saved["program_sha256"]):
            return None
        exported = jax.export.deserialize(bytearray(saved["program"]))
        return exported, saved["outputs"], saved["module_sha256"]
    except Exception:  # noqa: BLE001  (any damage: export it again)
        return None


def _write(path: Path, key: str, exported, out_tree) -> None:
    """Save the program for ``key`` (atomically: a reader sees the old file or the whole new one;
    two writers each replace the file whole). A read-only or full folder leaves the cache as it
    was (the program still runs)."""
    import pickle

    import jax

    # the module's digest only where a later run may verify against it (computing it prints the
    # whole StableHLO: ~0.1 s for a design program); a file without it is digested when verified
    module = _sha256(module_text(exported)) if _VERIFY[0] else None
    program = bytes(exported.serialize())
    skeleton = jax.tree.unflatten(out_tree, [0] * out_tree.num_leaves)
    blob = pickle.dumps({"format": PROGRAM_FORMAT, "key": key, "program": program,
                         "program_sha256": _sha256(program), "module_sha256": module, "outputs": skeleton})
    tmp = path.with_name(f"{path.name}.{os.getpid()}.{id(blob)}.tmp")
    try:
        tmp.write_bytes(blob)
        os.replace(tmp, path)
    except OSError:
        try:
            tmp.unlink(missing_ok=True)
        except OSError:
            pass


def _program(folder: Path, name: str, fn, static: dict, dynamic: dict) -> _Entry:
    """The compiled program for these arguments: from this process, else from ``folder``, else
    exported now and saved there. In verify mode a program read from ``folder`` is traced again
    and compared before it runs; one this process holds already was traced or compared here (as
    ``jax.jit`` reuses its own trace within a process) and runs as it is."""
    key = program_key(name, static, dynamic)
    with _key_lock(key):  # a program asked for by two threads at once (:func:`ahead`) is made once
        entry = _LOADED.get(key)
        if entry is None:
            entry = _LOADED[key] = _made(folder, name, key, fn, static, dynamic)
    return entry


def _key_lock(key: str) -> threading.Lock:
    """The lock of one program key (created on first use)."""
    with _KEY_LOCKS_LOCK:
        return _KEY_LOCKS.setdefault(key, threading.Lock())


def _made(folder: Path, name: str, key: str, fn, static: dict, dynamic: dict) -> _Entry:
    """:func:`_program`'s entry for ``key``, read from ``folder`` (verified in verify mode) or
    exported now and saved there, and compiled."""
    import jax

    path = folder / f"{name}-{key[:40]}{PROGRAM_SUFFIX}"
    saved = _read(path, key)
    if saved is None:  # traced just now: nothing to verify
        exported, out_tree, arrays = _export(name, fn, static, dynamic)
        _write(path, key, exported, out_tree)
        entry = _Entry(_compile(exported, arrays), out_tree)
    else:
        exported, skeleton, module = saved
        if _VERIFY[0]:
            _verify(name, key, fn, static, dynamic, exported, module)
        arrays = [jax.random.key_data(x) if _is_key(x) else x for x in jax.tree.leaves(dynamic)]
        entry = _Entry(_compile(exported, arrays), jax.tree.structure(skeleton))
    return entry


def _verify(name: str, key: str, fn, static: dict, dynamic: dict, saved, module_sha256: str | None) -> None:
    """Raise :class:`StaleProgramError` unless a fresh trace of ``fn`` for these arguments has the
    module digest ``module_sha256`` of the program ``saved`` for ``key`` (None: a file written
    outside verify mode; the saved program's own text is digested here)."""
    exported, _, _ = _export(name, fn, static, dynamic)
    if module_sha256 is None:
        module_sha256 = _sha256(module_text(saved))
    if _sha256(module_text(exported)) != module_sha256:
        raise StaleProgramError(
            f"{name}: the saved program for key {key[:12]} differs from a fresh trace; its key "
            "misses something the trace reads (see camjax.runtime.program_key)")
