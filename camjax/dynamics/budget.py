"""Work estimate, budget and progress of ``camjax dynamics``, known before any of the work runs.

:func:`estimate_work` counts, per analysis of the scene's ``compute`` (and the nominal part that
always runs), the elementary work it will do -- cos/sin tables of ``samples`` x ``harmonics + 1``
entries, batched evaluations over such a table (the robustness grid, the jump's speed scan),
RK4 steps (cycles x ``steps_per_cycle``, cycles from :func:`~camjax.dynamics.integrate.settling`
exactly as the run takes them), least-squares sizes and L-BFGS iterations -- and turns the counts
into seconds with the per-unit costs of :data:`COSTS`.

The costs were measured on the development machine (2 shared x86-64 cores, CPU, float64) by
:func:`camjax.dynamics.calibrate.calibrate` (``python -m camjax.dynamics.calibrate``),
which times each kernel warm at two sizes; :data:`COSTS` holds the largest of repeated
measurements, rounded up (they vary by up to 2x between repeats on a shared machine). The
compile of a new shape (seconds, on the first run only) and the figures (about a second) are not
counted. A faster machine finishes sooner than estimated; the progress bar's ETA follows the pace
measured.

:data:`BUDGET_S` is the budget: beyond it :func:`refusal` returns the one line ``camjax
dynamics`` refuses with (exit 2, nothing written) unless ``--force`` is given. None of this is
traceable: it turns a scene into Python numbers.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from dataclasses import dataclass

BUDGET_S = 120.0
"""Estimated seconds of work beyond which ``camjax dynamics`` refuses a scene without --force.
thesis-bench estimates at 4 s; with its train undamped (``c3 = 0``: every run takes
``max_cycles``) and the largest values a scene accepts, ``steps_per_cycle = 100000`` and
``max_cycles = 100000``, at 13 min for ``time_domain`` alone and 2.8 days for everything."""

TWO_PI = 2.0 * math.pi

SMALL_HARMONICS = 32
"""Up to this many coefficients (harmonics + 1) a drive step's cam evaluation is one small
single-threaded kernel; above it XLA's CPU runtime splits it over threads and a step costs
several times more (measured: 7 us per step at 21 coefficients, 36 us at 41)."""


@dataclass(frozen=True)
class Costs:
    """Seconds per unit of work (see the module docstring for how they were measured)."""

    table_ns: float = 110.0  # per entry of a samples x (harmonics + 1) cos/sin evaluation (f, f', f'')
    batch_ns: float = 0.3  # per entry and batched element over a table (robustness, jump scan)
    train_step_ns: float = 40.0  # one RK4 step of the follower train (time_domain)
    drive_step_us: tuple[float, float, float, float] = (1.0, 0.3, 28.0, 0.4)
    # one RK4 step of the drive: a + b (H+1) us up to SMALL_HARMONICS harmonics, c + d (H+1) above
    nonlinear_step_us: tuple[float, float, float, float] = (1.0, 0.6, 30.0, 0.8)
    # one RK4 step of the nonlinear compensation's drive equation, the same form
    lstsq_ns: float = 0.5  # per M (2H+1)^2 of the nonlinear fit
    shaping_step_us: tuple[float, float] = (30.0, 0.01)
    # one L-BFGS iteration: a + b (9 speeds + constraints) x (shaping_harmonics + 1) us

    def drive_step_s(self, hp: int) -> float:
        return _two_regimes(self.drive_step_us, hp) * 1e-6

    def nonlinear_step_s(self, hp: int) -> float:
        return _two_regimes(self.nonlinear_step_us, hp) * 1e-6


def _two_regimes(c: tuple[float, float, float, float], hp: int) -> float:
    return c[0] + c[1] * hp if hp <= SMALL_HARMONICS else c[2] + c[3] * hp


COSTS = Costs()


@dataclass(frozen=True)
class Piece:
    """The estimated work of one analysis."""

    name: str  # a [dynamics].compute entry, or "nominal" (always run)
    seconds: float
    what: str  # the counts, e.g. "2 runs x 214 cycles x 720 steps = 3.08e+05 RK4 steps"
    fields: tuple[str, ...]  # the [dynamics] fields that set its size


@dataclass(frozen=True)
class WorkEstimate:
    """What :func:`estimate_work` found: one :class:`Piece` per analysis, in the order they run."""

    pieces: tuple[Piece, ...]

    @property
    def seconds(self) -> float:
        return sum(p.seconds for p in self.pieces)

    def piece(self, name: str) -> Piece | None:
        return next((p for p in self.pieces if p.name == name), None)

    def drivers(self, share: float = 0.9) -> tuple[Piece, ...]:
        """The largest pieces that together make up ``share`` of the estimate."""
        out, acc = [], 0.0
        for p in sorted(self.pieces, key=lambda p: -p.seconds):
            out.append(p)
            acc += p.seconds
            if acc >= share * self.seconds:
                break
        return tuple(out)


def _count(x: float) -> str:
    return f"{x:.3g}"


def _duration(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:.3g} s"
    if seconds < 7200:
        return f"{seconds / 60:.3g} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.3g} h"
    return f"{seconds / 86400:.3g} days"


def shaping_constraint_count(program) -> int:
    """How many (angle, level) pairs law shaping pins (as
    :func:`camjax.dynamics.context.shaping_constraints` makes them), from the program alone."""
    return sum(max(2, int(width // 5) + 1) if kind == "dwell" else 1
               for kind, width in zip(program.kinds, program.angles_deg, strict=True))


def estimate_work(scene, costs: Costs = COSTS) -> WorkEstimate:
    """The work ``scene_dynamics(scene)`` will do, per analysis, in estimated seconds.

    Counts only, from the scene's [dynamics] section; the one computation is the FFT of the
    program's samples when a drive runs (the drive's step costs with the number of harmonics the
    cam really has, as the run trims them). Raises ValueError without a [dynamics] section.
    """
    from camjax.dynamics.context import plant_of, program_cam
    from camjax.dynamics.harmonics import trim_harmonics
    from camjax.dynamics.integrate import settling

    spec = scene.dynamics
    if spec is None:
        raise ValueError("scene has no [dynamics] section")
    compute = spec.compute
    n, h, m = spec.samples, spec.harmonics, spec.steps_per_cycle
    hp = h + 1
    table = n * hp
    on_grid = f"{n} samples x {hp} harmonics"
    grid_fields = ("samples", "harmonics")
    pieces = [Piece("nominal", 3 * table * costs.table_ns * 1e-9, f"3 evaluations of {on_grid}",
                    grid_fields)]
    if "compensation" in compute or "robustness" in compute:
        pieces.append(Piece("compensation", 4 * table * costs.table_ns * 1e-9,
                            f"4 evaluations of {on_grid}", grid_fields))
    needs_drive = spec.has_drive and ("drive" in compute or "nonlinear" in compute)
    if "time_domain" in compute or needs_drive:
        settle = settling(plant_of(spec), TWO_PI * spec.cam_speed_hz, spec.transient_tolerance,
                          spec.max_cycles)
        c = settle.cycles
        capped = settle.cycles_needed is None or c < settle.cycles_needed
        why = "max_cycles" if capped else "transient_tolerance"
        cycles = f"{c} cycles ({why}) x {m} steps_per_cycle"
        cycle_fields = ("steps_per_cycle", why)
        if "time_domain" in compute:
            steps = 2 * c * m
            pieces.append(Piece("time_domain", steps * costs.train_step_ns * 1e-9 + m * hp * costs.table_ns
                                * 1e-9, f"2 runs x {cycles} = {_count(steps)} RK4 steps", cycle_fields))
        if needs_drive:
            hp_cam = int(trim_harmonics(program_cam(scene)).cos.shape[-1])  # the cam's own harmonics
            with_nl = "nonlinear" in compute
            # the nonlinear cam is known only once fitted: its harmonics above about 3x the program
            # cam's fall to round-off and are trimmed (the bench's: 25 of 60, for 9)
            hp_nl = min(hp, 3 * (hp_cam - 1) + 1) if with_nl else hp_cam
            if with_nl:
                steps_s = c * m * costs.nonlinear_step_s(hp_cam)
                fit_s = m * (2 * h + 1) ** 2 * costs.lstsq_ns * 1e-9
                pieces.append(Piece("nonlinear", steps_s + fit_s,
                                    f"{cycles} = {_count(c * m)} RK4 steps, a fit of {2 * h + 1} terms",
                                    (*cycle_fields, "harmonics") if hp_cam == hp or fit_s > 0.1 * steps_s
                                    else cycle_fields))
            runs = 3 if with_nl else 2
            seconds = c * m * (2 * costs.drive_step_s(hp_cam) + (costs.drive_step_s(hp_nl) if with_nl else 0))
            pieces.append(Piece("drive", seconds + m * hp * costs.table_ns * 1e-9,
                                f"{runs} runs x {cycles} = {_count(runs * c * m)} RK4 steps",
                                (*cycle_fields, "harmonics") if hp in (hp_cam, hp_nl) else cycle_fields))
    if "jump" in compute:
        batched = (256 + h + 1) + 2 * 60 + (400 + 3 * h + 81)  # scan, bisection, plot speeds
        pieces.append(Piece("jump", (11 * table * costs.table_ns + batched * table * costs.batch_ns) * 1e-9,
                            f"{batched} speeds x {on_grid}", grid_fields))
    if "robustness" in compute:
        a, b, k = len(spec.damping_factors), len(spec.speed_factors), len(spec.wn_factors)
        batched = 2 * a * b * k + b * k
        pieces.append(Piece("robustness", (3 * table * costs.table_ns + batched * table * costs.batch_ns)
                            * 1e-9, f"{batched} plants x {on_grid}",
                            ("damping_factors", "speed_factors", "wn_factors", *grid_fields)))
    if "shaping" in compute:
        q = shaping_constraint_count(scene.motion.program)
        a, b = costs.shaping_step_us
        per_step_s = (a + b * (9 + q) * (spec.shaping_harmonics + 1)) * 1e-6
        pieces.append(Piece("shaping", spec.shaping_steps * per_step_s + 3 * table * costs.table_ns * 1e-9,
                            f"{spec.shaping_steps} L-BFGS steps over {spec.shaping_harmonics} harmonics",
                            ("shaping_steps", "shaping_harmonics")))
    return WorkEstimate(tuple(pieces))


def refusal(scene, work: WorkEstimate, force: bool = False, budget_s: float | None = None) -> str | None:
    """The one line ``camjax dynamics`` refuses ``scene`` with, or None to run it.

    None when ``force`` is set or the estimate is within the budget (:data:`BUDGET_S`, read at
    call time, or ``budget_s``). The line names the [dynamics] fields of the analyses that make
    up most of the estimate, with their values, and the estimate against the budget.
    """
    budget = BUDGET_S if budget_s is None else budget_s
    if force or work.seconds <= budget:
        return None
    spec = scene.dynamics
    drivers = work.drivers()
    fields = list(dict.fromkeys(f for p in drivers for f in p.fields))
    values = ", ".join(f"dynamics.{f} = {_field_value(getattr(spec, f))}" for f in fields)
    parts = "; ".join(f"{p.name}: {p.what}, {_duration(p.seconds)}" for p in drivers)
    less = ", ".join(_LESS_WORK.get(f, f"a smaller {f}") for f in fields)
    return (f"scene {scene.name}: {values}: the estimated work, {_duration(work.seconds)}, exceeds the "
            f"budget of {_duration(budget)} ({parts}) (allowed: {less}; or --force to run it anyway)")


_LESS_WORK = {"transient_tolerance": "a larger transient_tolerance (fewer cycles)",
              "damping_factors": "fewer damping_factors", "speed_factors": "fewer speed_factors",
              "wn_factors": "fewer wn_factors"}
"""How a field lowers the work, where it is not by being smaller."""


def _field_value(v) -> str:
    if isinstance(v, tuple):
        return f"[{', '.join(f'{x:g}' for x in v)}]"
    return f"{v:g}" if isinstance(v, float) else str(v)


# ------------------------------------------------------------------------------ progress


class WorkProgress:
    """A tqdm bar on stderr over the estimated seconds of work, with elapsed time and an ETA.

    The analyses call :meth:`start` and :meth:`finish` with their :class:`Piece` names (from any
    thread). A finished analysis counts its whole estimate; a running one counts the time since it
    started, up to 95 % of its estimate: XLA's loops report nothing while they run. tqdm's ETA is
    what is left over the pace measured so far, so a machine faster or slower than the calibration
    corrects it as analyses finish. :meth:`write` prints a line above the bar.
    """

    def __init__(self, work: WorkEstimate, file=None, interval_s: float = 0.5):
        from tqdm.auto import tqdm

        self._estimate = {p.name: max(p.seconds, 1e-3) for p in work.pieces}
        self._file = file if file is not None else sys.stderr
        total = sum(self._estimate.values())
        self._bar = tqdm(total=total, file=self._file, desc="camjax dynamics", leave=False,
                         bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed} elapsed, ETA {remaining}"
                                    f" (estimated {_duration(total)})")
        self._started: dict[str, float] = {}
        self._finished: set[str] = set()
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker = threading.Thread(target=self._tick, args=(interval_s,), daemon=True,
                                        name="camjax-progress")
        self._ticker.start()

    def credited(self, now: float | None = None) -> float:
        """Estimated seconds of work done: finished pieces whole, running ones by their time."""
        now = time.monotonic() if now is None else now
        with self._lock:
            done = 0.0
            for name, est in self._estimate.items():
                if name in self._finished:
                    done += est
                elif name in self._started:
                    done += min(now - self._started[name], 0.95 * est)
            return done

    def start(self, name: str) -> None:
        with self._lock:
            self._started.setdefault(name, time.monotonic())

    def finish(self, name: str) -> None:
        with self._lock:
            self._finished.add(name)
        self._refresh()

    def _refresh(self) -> None:
        n = self.credited()
        if n > self._bar.n:
            self._bar.update(n - self._bar.n)

    def _tick(self, interval_s: float) -> None:
        while not self._stop.wait(interval_s):
            self._refresh()

    def write(self, line: str) -> None:
        """``line`` on the bar's stream: above the bar while it shows, plainly after :meth:`close`."""
        if self._stop.is_set():
            self._file.write(line + "\n")
            self._file.flush()
        else:
            self._bar.write(line, file=self._file)

    def close(self) -> None:
        """Stop the bar and clear it (the run's lines stay)."""
        if not self._stop.is_set():
            self._stop.set()
            self._ticker.join()
            self._bar.close()


def tracked(tracker, name: str, fn, *args):
    """``fn(*args)`` with ``tracker.start(name)`` before and ``tracker.finish(name)`` after (when
    ``tracker`` is not None)."""
    if tracker is None:
        return fn(*args)
    tracker.start(name)
    try:
        return fn(*args)
    finally:
        tracker.finish(name)
