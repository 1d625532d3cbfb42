"""Timing and provenance: compile time apart from steady state, medians after warm-up.

Every figure the benchmarks report comes from :func:`time_jit` (JAX: lower + compile timed
alone, then the compiled executable called after warm-up) or :func:`time_python` (SciPy, NumPy:
plain calls after warm-up). Both return a :class:`Timing` whose ``median_s`` is the figure used.
"""

from __future__ import annotations

import datetime as _dt
import os
import platform
import statistics
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import numpy as np


class Timing(NamedTuple):
    """Wall-clock times of one benchmarked call, seconds."""

    compile_s: float  # jit lower + compile (0 for non-JAX code)
    median_s: float  # median of the steady-state repeats (the reported figure)
    min_s: float
    repeats: int
    samples_s: tuple  # every steady-state repeat


def block(tree: Any) -> Any:
    """Wait for every array of a pytree (JAX dispatch is asynchronous)."""
    return jax.block_until_ready(tree)


def _repeat(call: Callable[[], Any], repeats: int, min_time_s: float) -> list[float]:
    """At least ``repeats`` timed calls, more (up to 50) while their total is under min_time_s."""
    times: list[float] = []
    while len(times) < repeats or (sum(times) < min_time_s and len(times) < 50):
        t0 = time.perf_counter()
        block(call())
        times.append(time.perf_counter() - t0)
    return times


def _timing(compile_s: float, times: list[float]) -> Timing:
    return Timing(compile_s, statistics.median(times), min(times), len(times), tuple(times))


def time_jit(
    fn: Callable, *args, repeats: int = 5, warmup: int = 1, min_time_s: float = 0.2,
    slow_s: float | None = None,
) -> tuple[Timing, Any]:
    """Time ``jax.jit(fn)``: compile (lower + compile) alone, then the median of steady calls.

    Returns the timing and the output of the last call. ``args`` are passed as traced arguments
    (never closed over), so XLA cannot constant-fold the benchmark away. ``slow_s``: a first
    warm-up call longer than this many seconds is the one sample (a call of tens of seconds, whose
    repeats would buy little; its first-call overhead is small beside it).
    """
    t0 = time.perf_counter()
    compiled = compile_for(fn, *args)
    compile_s = time.perf_counter() - t0
    out = None
    for k in range(warmup):
        t1 = time.perf_counter()
        out = block(compiled(*args))
        first = time.perf_counter() - t1
        if k == 0 and slow_s is not None and first > slow_s:
            return _timing(compile_s, [first]), out
    times = _repeat(lambda: compiled(*args), repeats, min_time_s)
    out = block(compiled(*args))
    return _timing(compile_s, times), out


def time_python(
    call: Callable[[], Any], repeats: int = 3, warmup: int = 1, min_time_s: float = 0.0
) -> tuple[Timing, Any]:
    """Median of ``repeats`` calls of a plain Python callable after ``warmup`` calls."""
    outputs = []

    def keep():
        outputs.append(call())
        return outputs[-1]

    for _ in range(warmup):
        keep()
    times = _repeat(keep, repeats, min_time_s)
    return _timing(0.0, times), outputs[-1]


def compile_for(fn: Callable, *args):
    """``jax.jit(fn)`` lowered and compiled for ``args``: the executable the helpers below inspect."""
    return jax.jit(fn).lower(*args).compile()


def compiled_cost(compiled) -> dict:
    """XLA's static cost estimate of a compiled program (flops, transcendentals, bytes)."""
    cost = compiled.cost_analysis()
    if isinstance(cost, list):  # older jax returned one dict per computation
        cost = cost[0] if cost else {}
    keep = ("flops", "transcendentals", "bytes accessed")
    return {k.replace(" ", "_"): float(cost[k]) for k in keep if k in (cost or {})}


def fusion_count(compiled) -> int:
    """Number of XLA fusions in a compiled program's optimized HLO (kernel launches)."""
    text = compiled.as_text()
    return sum(1 for line in text.splitlines() if " fusion(" in line or "= fusion" in line)


def environment(dtype: str) -> dict:
    """Provenance recorded in the JSON: versions, machine, CPU count, dtype, backend, date."""
    import jaxlib
    import scipy

    try:
        load = os.getloadavg()
    except OSError:
        load = None
    return {
        "date_utc": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "jax": jax.__version__,
        "jaxlib": jaxlib.__version__,
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "python": platform.python_version(),
        "machine": f"{platform.system()} {platform.machine()} {_cpu_model()}".strip(),
        "cpu_count": os.cpu_count(),
        "backend": jax.default_backend(),
        "devices": [str(d) for d in jax.devices()],
        "dtype": dtype,
        "x64": bool(jax.config.jax_enable_x64),
        "load_average_at_start": load,
        **_git_state(),
    }


def _git_state() -> dict:
    """Commit of the working tree the run measured, and whether camjax/ had local changes."""
    import subprocess

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    def git(*args):
        return subprocess.run(
            ["git", "-C", root, *args], capture_output=True, text=True, timeout=10
        ).stdout.strip()

    try:
        return {
            "git_commit": git("rev-parse", "HEAD"),
            "camjax_locally_modified": bool(git("status", "--porcelain", "camjax")),
        }
    except (OSError, subprocess.SubprocessError):
        return {}


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def loglog_slope(x, y) -> float:
    """Least-squares exponent b of y ~ a x^b."""
    x, y = np.log(np.asarray(x, float)), np.log(np.asarray(y, float))
    return float(np.polyfit(x, y, 1)[0])


def profile_thunks(compiled, *args, calls: int = 3, top: int = 8) -> list[dict]:
    """Where the time goes: a ``jax.profiler`` trace of ``calls`` steady calls of ``compiled``,
    summarized as the ``top`` XLA:CPU thunks/fusions by time per call (ms) on any thread.

    Python-side and bookkeeping events are left out; ``threads`` counts the distinct threads a
    thunk ran on (the 2 CPUs' worker pool shows as several).
    """
    import collections
    import glob
    import tempfile

    block(compiled(*args))
    total: collections.Counter = collections.Counter()
    threads: dict = collections.defaultdict(set)
    skip = ("python", "block_until_ready", "ThunkExecutor", "Await", "trace", "PjitFunction")
    with tempfile.TemporaryDirectory() as tmp:
        with jax.profiler.trace(tmp):
            for _ in range(calls):
                block(compiled(*args))
        paths = sorted(glob.glob(f"{tmp}/**/*.xplane.pb", recursive=True))
        if not paths:
            return []
        data = jax.profiler.ProfileData.from_file(paths[-1])
        for plane in data.planes:
            for line in plane.lines:
                if line.name == "python":
                    continue
                for ev in line.events:
                    if ev.name.startswith("end:") or any(s in ev.name for s in skip):
                        continue
                    total[ev.name] += ev.duration_ns
                    threads[ev.name].add(line.name)
    return [
        {"thunk": name, "ms_per_call": ns / calls / 1e6, "threads": len(threads[name])}
        for name, ns in total.most_common(top)
    ]
