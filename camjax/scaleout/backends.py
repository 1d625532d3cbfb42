"""Pluggable maps over block tasks: in-process, a spawn-context process pool, or a Ray cluster.

A backend has one method, ``map_unordered(fn, tasks)``, yielding ``(position, Outcome)`` as tasks
finish, in any order. A task that raises, or whose worker dies, yields a failed :class:`Outcome`
with the error text; it never stops the others. Retrying and storing are the driver's job
(:func:`camjax.scaleout.driver.run_blocks`), so every backend gets the same semantics. Scheduling,
placement and worker lifetime are the engine's (``concurrent.futures`` or Ray), not ours. Worker
set-up (the shared compilation cache) travels with the task: see
:func:`camjax.scaleout.blocks.configure_worker`.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any, NamedTuple

BACKENDS = ("sequential", "process", "ray")


class Outcome(NamedTuple):
    """Result of one attempt at one task."""

    ok: bool
    value: Any  # the function's return value when ok
    error: str  # traceback or reason when not ok ("" when ok)
    seconds: float  # wall time inside the worker (0 when unknown)
    worker: str  # "host:pid" of the worker ("" when unknown)


def run_task(fn: Callable, task) -> tuple[Any, float, str]:
    """Call ``fn(task)`` in a worker and time it (top level so it pickles by reference)."""
    start = time.perf_counter()
    value = fn(task)
    return value, time.perf_counter() - start, f"{socket.gethostname()}:{os.getpid()}"


def _failure(exc: BaseException) -> Outcome:
    text = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
    return Outcome(False, None, text.strip(), 0.0, "")


class SequentialMap:
    """Every task in this process, one after the other (the reference the others must match)."""

    name = "sequential"

    def map_unordered(self, fn: Callable, tasks: Sequence) -> Iterator[tuple[int, Outcome]]:
        for i, task in enumerate(tasks):
            try:
                value, seconds, worker = run_task(fn, task)
            except Exception as exc:  # a failed block is reported, not raised
                yield i, _failure(exc)
            else:
                yield i, Outcome(True, value, "", seconds, worker)

    def close(self) -> None:
        pass


class ProcessMap:
    """A ``spawn``-context process pool (no fork: JAX's threads do not survive a fork).

    The pool lives across calls; if a worker dies the pool breaks, every unfinished task of that
    call fails with the reason, and the next call starts a fresh pool.
    """

    name = "process"

    def __init__(self, workers: int | None = None):
        self.workers = workers or os.cpu_count() or 1
        self._pool: ProcessPoolExecutor | None = None

    def _executor(self) -> ProcessPoolExecutor:
        if self._pool is None:
            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"))
        return self._pool

    def map_unordered(self, fn: Callable, tasks: Sequence) -> Iterator[tuple[int, Outcome]]:
        pool = self._executor()
        futures = {pool.submit(run_task, fn, task): i for i, task in enumerate(tasks)}
        broken = False
        for future in as_completed(futures):
            try:
                value, seconds, worker = future.result()
            except BrokenProcessPool as exc:
                broken = True
                yield futures[future], _failure(exc)
            except Exception as exc:
                yield futures[future], _failure(exc)
            else:
                yield futures[future], Outcome(True, value, "", seconds, worker)
        if broken:
            self.close()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None


_RAY_SINGLE_NODE_ENV = "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER"


class RayMap:
    """Tasks on a Ray cluster: an existing one (``address``) or a local one started here.

    A local instance listens on loopback only, without the dashboard, with ``workers`` CPUs.
    Ray's own task retries are off (``max_retries=0``): a crashed worker or a raised error comes
    back as a failed outcome and the driver retries it, as with every other backend. ``runtime_env``
    is passed to ``ray.init`` (e.g. ``{"env_vars": {...}}`` or a ``working_dir``).
    """

    name = "ray"

    def __init__(self, address: str | None = None, workers: int | None = None,
                 runtime_env: dict | None = None):
        if address is None:
            # Ray turns 127.0.0.1 into the host's interface address unless it runs as a
            # single-node instance; this switch (read when ray is imported, and inherited by its
            # workers) keeps a local instance's traffic on loopback.
            os.environ.setdefault(_RAY_SINGLE_NODE_ENV, "0")
        try:
            import ray
        except ImportError:
            raise ImportError("the ray backend needs Ray: pip install 'camjax[ray]'") from None
        if address is None and not ray.is_initialized():
            constants = getattr(getattr(ray, "_private", None), "ray_constants", None)
            if constants is not None and hasattr(constants, "ENABLE_RAY_CLUSTER"):
                constants.ENABLE_RAY_CLUSTER = False  # ray was imported before the switch was set
        self._ray = ray
        self._started_here = False
        if not ray.is_initialized():
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                      "runtime_env": runtime_env}
            if address is None:
                # a private local instance: loopback only, our CPU count
                kwargs.update(num_cpus=workers or os.cpu_count() or 1, _node_ip_address="127.0.0.1")
                self._started_here = True
            ray.init(address=address, **kwargs)
        self._remote = ray.remote(run_task).options(max_retries=0, retry_exceptions=False, num_cpus=1)

    def map_unordered(self, fn: Callable, tasks: Sequence) -> Iterator[tuple[int, Outcome]]:
        ray = self._ray
        fn_ref = ray.put(fn)
        pending = {self._remote.remote(fn_ref, task): i for i, task in enumerate(tasks)}
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                i = pending.pop(ref)
                try:
                    value, seconds, worker = ray.get(ref)
                except Exception as exc:  # RayTaskError, WorkerCrashedError, ...
                    yield i, _failure(exc)
                else:
                    yield i, Outcome(True, value, "", seconds, worker)

    def close(self) -> None:
        if self._started_here:
            self._ray.shutdown()
            self._started_here = False


def make_backend(name: str, *, workers: int | None = None, address: str | None = None,
                 runtime_env: dict | None = None):
    """Backend by name: "sequential", "process" or "ray"."""
    if name == "sequential":
        return SequentialMap()
    if name == "process":
        return ProcessMap(workers)
    if name == "ray":
        return RayMap(address, workers, runtime_env)
    raise ValueError(f"backend: {name!r} is not allowed; use {', '.join(BACKENDS)}")
