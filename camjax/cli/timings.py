"""``--timings``: where a command's wall time went, phase by phase, and what JAX spent of it.

A command marks each phase as it starts (:meth:`PhaseClock.mark`, the same phases its progress
lines name); :meth:`PhaseClock.lines` gives, once it is done, each phase's wall seconds (a phase
lasts until the next one starts), their total, and the seconds JAX spent tracing Python into
programs, lowering them and handing them to XLA (compiling each, or loading it from the
persistent compilation cache: a scene's first run compiles its programs, later runs load them),
with how many programs were compiled and how many loaded. JAX's seconds are summed over threads
(the command line compiles the drawing's programs in a second thread while the design solves),
so they may exceed a phase's wall time.

The first phase, ``start-up``, runs from the command's entry (:func:`mark_entry`: Python's own
start before it is not counted, ~0.02 s) until the command reads its scene: Python, JAX and
camjax imported. Called as a function (:func:`camjax.cli.app.main` with arguments, e.g. from a
test), it starts at that call.

Not traceable (wall clocks and Python callbacks): the command line only.
"""

from __future__ import annotations

import time

_ENTRY: list = [None]  # perf_counter() at the command's entry (camjax.cli.entry)
_ACTIVE: list = []  # the clock JAX's events are counted into (one command at a time)
_LISTENING: list = [False]

# JAX's monitoring events (jax._src.dispatch, jax._src.compilation_cache): durations and counts
_DURATIONS = {"/jax/core/compile/jaxpr_trace_duration": "trace",
              "/jax/core/compile/jaxpr_to_mlir_module_duration": "lower",
              "/jax/core/compile/backend_compile_duration": "compile"}
_CACHE_HIT = "/jax/compilation_cache/cache_hits"


def mark_entry() -> None:
    """Remember now as the command's start (the ``camjax`` entry point calls it first)."""
    _ENTRY[0] = time.perf_counter()


def entry_time() -> float | None:
    """perf_counter() at the command's entry, or None when no entry point ran (a library call)."""
    return _ENTRY[0]


class PhaseClock:
    """The phases of one command run (see the module docstring); ``start``: perf_counter() of the
    first phase's start (default: now); ``count_jax``: count JAX's tracing and compiling too (its
    listeners are registered, and called on every compile, only when asked)."""

    def __init__(self, start: float | None = None, count_jax: bool = False):
        self.marks: list[tuple[str, float]] = [("start-up", time.perf_counter() if start is None else start)]
        self.jax = {"trace": 0.0, "lower": 0.0, "compile": 0.0, "compiles": 0, "loaded": 0}
        self.end: float | None = None
        if count_jax:
            _listen()
            _ACTIVE[:] = [self]

    def mark(self, phase: str) -> None:
        """Phase ``phase`` starts now (the one before ends)."""
        self.marks.append((phase, time.perf_counter()))

    def stop(self) -> None:
        """The run is done: the last phase ends now, and JAX's events are no longer counted."""
        self.end = time.perf_counter()
        if _ACTIVE and _ACTIVE[0] is self:
            _ACTIVE.clear()

    def lines(self, prog: str) -> list[str]:
        """Two lines for stderr, once :meth:`stop` was called: each phase's wall seconds with the
        run's (from the first phase's start to the stop), and JAX's work."""
        ends = [t for _, t in self.marks[1:]] + [self.end]
        wall = ", ".join(f"{name} {t1 - t0:.2f}" for (name, t0), t1 in zip(self.marks, ends, strict=True))
        j = self.jax
        return [f"{prog}: timings (wall s): {wall}; total {self.end - self.marks[0][1]:.2f}",
                f"{prog}: JAX (s, summed over threads): tracing {j['trace']:.2f}, lowering {j['lower']:.2f}, "
                f"XLA {j['compile']:.2f} for {j['compiles']} programs "
                f"({j['compiles'] - j['loaded']} compiled, {j['loaded']} loaded from the compilation cache)"]


def _on_duration(event: str, seconds: float, **_) -> None:
    kind = _DURATIONS.get(event)
    if kind is None or not _ACTIVE:
        return
    clock = _ACTIVE[0]
    clock.jax[kind] += seconds
    if kind == "compile":
        clock.jax["compiles"] += 1


def _on_event(event: str, **_) -> None:
    if event == _CACHE_HIT and _ACTIVE:
        _ACTIVE[0].jax["loaded"] += 1


def _listen() -> None:
    """Register the JAX listeners once per process (JAX keeps them for its lifetime)."""
    if _LISTENING[0]:
        return
    import jax.monitoring

    jax.monitoring.register_event_duration_secs_listener(_on_duration)
    jax.monitoring.register_event_listener(_on_event)
    _LISTENING[0] = True
