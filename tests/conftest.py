"""Tests run in float64 (camjax turns x64 on at import; asserted here).

Shared fixtures: the default scene, its arrays, and the reference case in NumPy (tests/reference.py).
"""

import collections
import gc
import json
import logging
import os
import re
import time
from pathlib import Path

# XLA compiles are most of the suite's time: compile as the command line does
# (camjax.runtime.CPU_XLA_FLAGS: XLA's loop emitters, not its CPU fusion emitters; the default
# scene's design compiles in 13 s instead of 19 s on 2 cores). Set before JAX starts its backend,
# so the tests' subprocesses (the CLI, process pools) inherit it; CAMJAX_XLA_FLAGS=0 runs with
# XLA's defaults. (LLVM's -O0, --xla_backend_optimization_level=0, would halve the compiles again
# but turns finite gradients of the oscillating flat face into NaN in this jaxlib: not used.)
from camjax.runtime import fewer_full_collections, use_cpu_xla_flags  # noqa: E402  (loads no JAX)

use_cpu_xla_flags()
fewer_full_collections()  # as the command line: a worker's heap makes each full collection costly

import jax  # noqa: E402
import pytest  # noqa: E402
from reference import reference_case  # noqa: E402

import camjax  # noqa: F401, E402  (enables x64)
from camjax.runtime import use_compilation_cache  # noqa: E402


def pytest_configure(config):
    assert jax.config.jax_enable_x64, "camjax tests run in float64"
    _no_forced_collection_at_exit(config)
    _persistent_compilation_cache(config)
    _ledger_start(config)
    _keep_file_order(config)
    _worker_leaves_without_finalizing(config)


def _no_forced_collection_at_exit(config) -> None:
    """pytest forces five full garbage collections when a session ends, to report objects whose
    finalizers raise; with JAX's heap of compiled programs each takes ~0.6 s, so ~3 s at the end of
    every worker. None forced here: unraisable exceptions from the collections the run itself made
    are still reported."""
    try:
        from _pytest.unraisableexception import gc_collect_iterations_key
    except ImportError:  # another pytest: its own behaviour
        return
    config.stash[gc_collect_iterations_key] = 0


def _worker_leaves_without_finalizing(config) -> None:
    """An xdist worker's process ends at once when its session is over (``os._exit`` as its last
    exit handler), without Python's finalization: with the heap of hundreds of compiled programs
    that took ~2 s after the last test, which the whole run waited for (the quick loop's last
    worker ended 2.0 s before the run did; 0.1 s with this). The worker has sent every report by
    then, and the persistent compilation cache writes each entry when it compiles it."""
    if not hasattr(config, "workerinput"):  # the controller (or a run without xdist) finalizes
        return
    import atexit
    import sys

    def leave() -> None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)

    # handlers registered later (by what the tests import) still run before it; JAX's and the
    # earlier imports' (clearing backends and caches) are skipped with the rest of the finalization
    atexit.register(leave)


def _persistent_compilation_cache(config) -> None:
    """Keep compiled kernels between test runs, in .pytest_cache/d/jax-compilation.

    XLA compiles are most of the suite's time; with them cached, a repeated quick loop
    (``-m "not slow"``) runs far faster. Turned on here, before any test, so a session does not
    depend on which CLI test first turns on the command's own cache. CAMJAX_COMPILATION_CACHE=0 (or
    ``-p no:cacheprovider``) runs without it, and then no CLI test turns one on either.
    """
    # The CLI tests trace as the library does: a saved program (camjax.runtime.program_cache)
    # compiles a module of its own, which would add a compile per scene shape to a fresh run;
    # tests/test_runtime.py and the CLI tests marked for it turn the program cache on themselves.
    os.environ.setdefault("CAMJAX_PROGRAM_CACHE", "0")
    # The CLI tests draw their figures in the test's own process: a drawing process imports NumPy,
    # matplotlib and ezdxf afresh (~0.8 CPU s, two per design), where the test worker imports them
    # once. tests/test_cli.py's design run draws in processes, as the command does by default, and
    # tests/test_export.py checks the processes' files against the in-process ones byte for byte.
    os.environ.setdefault("CAMJAX_DRAWING_PROCESSES", "0")
    # No second compiling thread beside a test's design (camjax.runtime.ahead): the workers already
    # keep both cores busy. tests/test_runtime.py runs the command with it.
    os.environ.setdefault("CAMJAX_COMPILE_AHEAD", "0")
    cache = getattr(config, "cache", None)
    if os.environ.get("CAMJAX_COMPILATION_CACHE") == "0" or cache is None:
        os.environ["CAMJAX_COMPILATION_CACHE"] = "0"
        return
    if not jax.config.jax_compilation_cache_dir:  # one set through JAX itself wins
        use_compilation_cache(cache.mkdir("jax-compilation"))
    # the command run in a subprocess (camjax.runtime.enable_compilation_cache) loads what the
    # tests compiled, not ~/.cache/camjax's; a test that needs a cold one sets its own folder or 0
    os.environ.setdefault("CAMJAX_COMPILATION_CACHE", str(jax.config.jax_compilation_cache_dir))


@pytest.fixture(scope="session")
def compilation_cache_env() -> dict:
    """JAX's own variables pointing a Python subprocess at the tests' compilation cache (empty where
    the cache is off): a subprocess that is not the command (which reads CAMJAX_COMPILATION_CACHE,
    set above) loads what the tests compiled."""
    cache = jax.config.jax_compilation_cache_dir
    if not cache:
        return {}
    return {"JAX_COMPILATION_CACHE_DIR": str(cache), "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0"}


@pytest.fixture(scope="session")
def default_scene():
    return camjax.load_scene()


@pytest.fixture(scope="session")
def default_arrays(default_scene):
    return camjax.scene_arrays(default_scene)


@pytest.fixture
def quiet_files(monkeypatch):
    """The saved-program matrix's command runs (tests/cache_matrix.py): figures and the DXF not
    drawn (they read no saved program); the JSON written as the command line writes it."""
    from camjax.output import export
    from camjax.solvers import sweep

    class NoFigure:
        def savefig(self, *args, **kwargs):
            pass

    monkeypatch.setattr(export, "write_design_files", lambda *args, **kwargs: [])
    monkeypatch.setattr(sweep, "plot_pareto", lambda *args, **kwargs: NoFigure())
    monkeypatch.setenv("CAMJAX_DRAWING_PROCESSES", "0")


@pytest.fixture(scope="session")
def reference_1deg():
    """The reference case (SPEC 5) in independent NumPy closed forms on the scene's 1 deg grid."""
    return reference_case(360)


# Each compiled XLA program holds a few memory mappings of its own (~3.3 measured); a whole suite in
# one process compiles tens of thousands and would pass the kernel's vm.max_map_count (65,530 by
# default), after which mmap fails inside XLA and the process dies (SIGSEGV). Past MAX_MAPPINGS the
# in-memory programs are dropped: JAX's caches and camjax's own tables of compiled programs
# (compiled kernels stay in the persistent cache on disk). The next drop waits until the count has
# grown MAPPINGS_MARGIN past what the last one left: a count the drop could not bring under the
# limit (programs some module still holds) would otherwise make every later test drop and compile
# again what the tests before it had compiled.
MAX_MAPPINGS = 25_000
MAPPINGS_MARGIN = 5_000
HARD_MAPPINGS = 50_000  # never wait past this: well under vm.max_map_count
_NEXT_DROP = [MAX_MAPPINGS]


def _mapping_count() -> int:
    try:
        with open("/proc/self/maps", "rb") as maps:
            return sum(1 for _ in maps)
    except OSError:  # not Linux: no such limit to keep under
        return 0


def _drop_compiled_programs() -> None:
    from camjax import runtime
    from camjax.robust import evaluate as robust_evaluate
    from camjax.solvers import base

    jax.clear_caches()
    base._COMPILED.clear()
    runtime._LOADED.clear()
    robust_evaluate._PROGRAMS.clear()
    gc.collect()


# Reading /proc/self/maps costs ~5 ms with tens of thousands of mappings: after every test, that was
# 4.7 CPU s of the quick loop (879 tests). The count is read at most once per COUNT_EVERY_S of wall
# time instead; a compile adds ~3.3 mappings and the fastest take ~5 ms, so the count grows by at
# most ~1,300 between two readings, far inside the 15,000 between HARD_MAPPINGS and the kernel's limit.
COUNT_EVERY_S = 2.0
_LAST_COUNT = [-COUNT_EVERY_S]


@pytest.fixture(autouse=True)
def _release_compiled_programs():
    """Drop the in-memory compiled programs once the process holds more than MAX_MAPPINGS."""
    yield
    now = time.monotonic()
    if now - _LAST_COUNT[0] < COUNT_EVERY_S:
        return
    _LAST_COUNT[0] = now
    if _mapping_count() > _NEXT_DROP[0]:
        _drop_compiled_programs()
        _NEXT_DROP[0] = min(max(MAX_MAPPINGS, _mapping_count() + MAPPINGS_MARGIN), HARD_MAPPINGS)


# ------------------------------------------------------------------ CPU seconds per test
# On the shared 2-core machine a test's wall time says as much about the other jobs as about the
# test; ``--cpu-durations=N`` lists the N tests that used the most CPU time instead (this process's
# threads, XLA's compiler threads among them, and its finished subprocesses: every phase, module
# fixtures counted in the test that first asks for them). Works with xdist: the workers' figures
# travel in the reports.


def pytest_addoption(parser):
    _addoption_ledger(parser)
    _addoption_file_durations(parser)
    parser.addoption("--cpu-durations", type=int, default=None, metavar="N",
                     help="list the N tests that used the most CPU seconds (this process and its children)")


def _cpu_seconds() -> float:
    import resource
    import time

    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    if item.config.getoption("cpu_durations") is not None:
        start = getattr(item, "_cpu_phase_start", None)
        if start is not None:
            outcome.get_result().user_properties.append(("cpu_s", _cpu_seconds() - start))


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_setup(item):
    if item.config.getoption("cpu_durations") is not None:
        item._cpu_phase_start = _cpu_seconds()
    yield


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_call(item):
    if item.config.getoption("cpu_durations") is not None:
        item._cpu_phase_start = _cpu_seconds()
    yield


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_teardown(item, nextitem):
    if item.config.getoption("cpu_durations") is not None:
        item._cpu_phase_start = _cpu_seconds()
    yield


_CPU_BY_TEST: dict = {}


def pytest_runtest_logreport(report):
    _record_file_seconds(report)
    for name, value in getattr(report, "user_properties", ()):
        if name == "cpu_s":
            _CPU_BY_TEST[(report.nodeid, report.when)] = value


def pytest_terminal_summary(terminalreporter, config):
    count = config.getoption("cpu_durations")
    if count is None or not _CPU_BY_TEST:
        return
    total = sum(_CPU_BY_TEST.values())
    terminalreporter.write_sep("=", f"{count or 'all'} most CPU seconds (total {total:.1f} s)")
    ranked = sorted(_CPU_BY_TEST.items(), key=lambda kv: -kv[1])
    for (nodeid, when), seconds in ranked[: count or None]:
        terminalreporter.write_line(f"{seconds:8.2f}s {when:8s} {nodeid}")


# ------------------------------------------------------------------ compiled programs per test
# ``--compile-ledger=DIR`` writes, per worker, one JSON line per test phase: the XLA programs it
# compiled (name, seconds), the ones it loaded from the persistent compilation cache, the cache keys
# it missed (a key missed in two workers: a program both compiled), its tracing seconds, and each
# program it lowered with its arguments' shapes ("lower": name, {shape: count}) (JAX's own compile
# log, turned on for the run), and each solve it traced ("solve": the problem's type, mode, solver
# and settings, which the shapes do not show, with the grid's size). The suite is bound by XLA
# compiles; the ledger shows
# which tests compile which programs, and which programs several tests compile again under another
# shape.

_LEDGER: dict = {"phase": None, "records": []}
_COMPILED = re.compile(r"Finished XLA compilation of (.+) in ([0-9.e-]+) sec")
_TRACED = re.compile(r"Finished tracing (.+) for jit in ([0-9.e-]+) sec")
_HIT = re.compile(r"Persistent compilation cache hit for '([^']+)'")
_MISS = re.compile(r"PERSISTENT COMPILATION CACHE MISS for '[^']+' with key '([^']+)'")


class _LedgerHandler(logging.Handler):
    def emit(self, record):
        if _LEDGER["phase"] is None:
            return
        if isinstance(record.msg, str) and record.msg.startswith("Compiling %s with global shapes"):
            # a program lowered: its name and its arguments' shapes (each shape and dtype with its
            # count), to tell programs that differ only by a shape (a grid size, a batch) apart
            name, avals = record.args[0], record.args[1]
            shapes = collections.Counter(getattr(a, "str_short", lambda a=a: str(a))() for a in avals)
            _LEDGER["records"].append(("lower", str(name), dict(sorted(shapes.items()))))
            return
        message = record.getMessage()
        for kind, pattern in (("compile", _COMPILED), ("trace", _TRACED), ("hit", _HIT), ("miss", _MISS)):
            match = pattern.search(message)
            if match:
                seconds = float(match.group(2)) if kind in ("compile", "trace") else 0.0
                _LEDGER["records"].append((kind, match.group(1), seconds))


def _addoption_ledger(parser):
    parser.addoption("--compile-ledger", default=None, metavar="DIR",
                     help="write each test's compiled programs to DIR/ledger-<worker>.jsonl")


def _ledger_start(config) -> None:
    folder = config.getoption("compile_ledger")
    if folder is None:
        return
    jax.config.update("jax_log_compiles", True)
    handler = _LedgerHandler(level=logging.DEBUG)
    logging.getLogger("jax").addHandler(handler)  # JAX's modules' records reach it by propagation
    logging.getLogger("jax._src.compiler").setLevel(logging.DEBUG)  # the cache misses (and keys)
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    Path(folder).mkdir(parents=True, exist_ok=True)
    _LEDGER["file"] = open(Path(folder) / f"ledger-{worker}.jsonl", "a")  # noqa: SIM115
    _ledger_solves()


def _ledger_solves() -> None:
    """Record each trace of :func:`camjax.solvers.base.search_one` (every solve program traces it
    once, under ``vmap`` or not) as ("solve", "<problem type> <mode> <solver> <settings digest>",
    {"n": the grid's size}): two solve programs of one label differ in sizes alone."""
    import hashlib

    from camjax.solvers import base

    original = base.search_one

    def search_one(problem, weights, key, **kwargs):
        if _LEDGER["phase"] is not None:
            settings = hashlib.sha256(repr(kwargs.get("settings")).encode()).hexdigest()[:8]
            label = f"{type(problem).__module__}.{type(problem).__name__} {kwargs.get('mode')} " \
                    f"{kwargs.get('solver')} {settings}"
            n = max((int(x.shape[-1]) for x in jax.tree.leaves(problem) if getattr(x, "shape", ())), default=0)
            _LEDGER["records"].append(("solve", label, {"n": n}))
        return original(problem, weights, key, **kwargs)

    base.search_one = search_one  # search_batch looks it up when it traces


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    if "file" in _LEDGER:
        _LEDGER["phase"] = item.nodeid
        _LEDGER["records"] = []
    yield
    if "file" in _LEDGER:
        records = _LEDGER["records"]
        _LEDGER["file"].write(json.dumps({"test": item.nodeid, "records": records}) + "\n")
        _LEDGER["file"].flush()
        _LEDGER["phase"] = None


# ------------------------------------------------------------------ the longest files first
# `-n auto --dist loadfile` hands whole files to the workers in the order of its queue, and xdist
# orders that queue by each file's number of tests: a file of three long tests (the cache matrix)
# started last and ran alone at the end of the run. Here the files are ordered by their seconds in
# a recorded run (tests/file_durations.json: one table for the whole suite, one for the quick
# loop, ``-m "not slow"``), the longest first, so that the short files fill the end, and xdist's
# reordering is turned off. A file not recorded counts 0.6 s a test. ``--file-durations=PATH``
# writes each file's seconds (every phase of every test) of this run into PATH's table for this
# run's ``-m`` expression, to refresh the record from a run of the whole suite or of the quick loop;
# every run also keeps its table in pytest's cache (.pytest_cache/v/camjax/file-durations/).

FILE_DURATIONS = Path(__file__).with_name("file_durations.json")
_SECONDS_BY_FILE: dict = {}


def _addoption_file_durations(parser):
    parser.addoption("--file-durations", default=None, metavar="PATH",
                     help="write each test file's seconds in this run to PATH (JSON)")


def _keep_file_order(config) -> None:
    if hasattr(config.option, "loadscopereorder"):  # pytest-xdist: keep the queue in collection order
        config.option.loadscopereorder = False


def _table_name(config) -> str:
    return "not slow" if (config.getoption("markexpr", "") or "").strip() == "not slow" else "full run"


def _read_durations(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


def pytest_collection_modifyitems(config, items):
    recorded = _read_durations(FILE_DURATIONS).get(_table_name(config), {})
    counts: dict = {}
    for item in items:
        path = item.nodeid.split("::")[0]
        counts[path] = counts.get(path, 0) + 1
    weight = {path: recorded.get(path, 0.6 * n) for path, n in counts.items()}
    rank = {path: k for k, path in enumerate(sorted(weight, key=lambda p: (-weight[p], p)))}
    order = {id(item): k for k, item in enumerate(items)}
    items.sort(key=lambda item: (rank[item.nodeid.split("::")[0]], order[id(item)]))


def _record_file_seconds(report) -> None:
    path = report.nodeid.split("::")[0]
    _SECONDS_BY_FILE[path] = _SECONDS_BY_FILE.get(path, 0.0) + report.duration


def pytest_sessionfinish(session, exitstatus):
    if not _SECONDS_BY_FILE or os.environ.get("PYTEST_XDIST_WORKER"):
        return
    table = {p: round(s, 1) for p, s in sorted(_SECONDS_BY_FILE.items())}
    cache = getattr(session.config, "cache", None)
    if cache is not None:  # every run's own figures, to refresh the record from (e.g. after CI)
        cache.set(f"camjax/file-durations/{_table_name(session.config)}", table)
    target = session.config.getoption("file_durations", None)
    if target:
        tables = _read_durations(Path(target))
        tables[_table_name(session.config)] = table
        Path(target).write_text(json.dumps(tables, indent=1) + "\n")
