"""Scene level: run what a scene's [dynamics] section lists and gather it in a typed report.

One function per ``compute`` entry (:func:`compensation`, :func:`robustness`,
:func:`time_domain`, :func:`drive`, :func:`nonlinear`, :func:`jump`, :func:`shaping`), each
returning a frozen dataclass with the numbers written to ``dynamics.json`` (``to_json``) and the
curves the figures draw. :func:`scene_dynamics` runs them in order into a :class:`DynamicsReport`.
None of this is traceable: it turns arrays into Python numbers for a report.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from camjax.dynamics.budget import tracked
from camjax.dynamics.compensation import (
    compensate_linear,
    compensate_nonlinear,
    compensate_time,
    robustness_grid,
)
from camjax.dynamics.context import (
    Context,
    as_float,
    closure_of,
    context,
    drive_of,
    finite_or_none,
    program_values,
    shaping_constraints,
)
from camjax.dynamics.harmonics import (
    TWO_PI,
    CamHarmonics,
    cam_grid,
    evaluate_cam,
    max_abs,
    mean_square,
    pad_harmonics,
    trim_harmonics,
)
from camjax.dynamics.integrate import Settling, integrate_train, settling, simulate_drive
from camjax.dynamics.jump import (
    contact_force,
    jump_speed,
    min_contact_force,
    min_preload,
    min_spring_rate,
)
from camjax.dynamics.plant import (
    damping_ratio,
    natural_frequency_rad_s,
    perturbed_plant,
    resonant_harmonic,
    steady_state,
    tracking_error_harmonics,
    transfer,
)
from camjax.dynamics.results import *  # noqa: F401,F403  (re-exported: the typed results)
from camjax.dynamics.results import (
    Compensation,
    DriveResult,
    DriveRun,
    Jump,
    Nominal,
    Nonlinear,
    Robustness,
    Shaping,
    TimeDomain,
    WnMisestimate,
)
from camjax.dynamics.shaping import band_tracking_ms, shape_law

# ------------------------------------------------------------------- one per compute entry


def nominal(ctx: Context) -> Nominal:
    """Plant figures and the nominal cam's steady-state tracking error."""
    plant, omega, phi, cam = ctx.plant, ctx.omega, ctx.phi, ctx.cam
    err = tracking_error_harmonics(cam, cam, plant, omega)
    n_res, r_res = resonant_harmonic(plant, omega)
    return Nominal(
        as_float(natural_frequency_rad_s(plant)) / TWO_PI, as_float(damping_ratio(plant)), n_res, r_res,
        as_float(jnp.abs(transfer(plant, n_res * omega))), as_float(max_abs(err, phi)),
        as_float(jnp.sqrt(mean_square(err))), np.rad2deg(np.asarray(phi)),
        np.asarray(evaluate_cam(cam, phi).f),
        np.asarray(evaluate_cam(steady_state(cam, plant, omega), phi).f))


def compensation(ctx: Context, nom: Nominal) -> Compensation:
    """Linear compensation: its error, its time form, and a 10 % misestimated omega_n."""
    plant, omega, phi, cam, comp = ctx.plant, ctx.omega, ctx.phi, ctx.cam, ctx.linear
    comp_err = tracking_error_harmonics(comp, cam, plant, omega)
    comp_time = compensate_time(program_values(ctx.scene, phi), plant, omega)
    comp_vals = np.asarray(evaluate_cam(comp, phi).f)
    mis = []
    for est in (0.9, 1.1):
        c_est = compensate_linear(cam, perturbed_plant(plant, 1.0, est), omega)
        e = as_float(max_abs(tracking_error_harmonics(c_est, cam, plant, omega), phi))
        mis.append(WnMisestimate(est, e, nom.max_tracking_error / e))
    return Compensation(
        as_float(max_abs(comp_err, phi)), as_float(jnp.sqrt(mean_square(comp_err))),
        float(np.max(np.abs(np.asarray(comp_time) - comp_vals))),
        float(np.max(np.abs(comp_vals - nom.cam))),
        trim_harmonics(comp), tuple(mis), comp_vals)


def robustness(ctx: Context) -> Robustness:
    """The compensated and nominal error over the scene's (mu, lambda, kappa) grid."""
    spec, plant, omega, phi, cam, comp = ctx.spec, ctx.plant, ctx.omega, ctx.phi, ctx.cam, ctx.linear
    mu, lam, kap = (np.asarray(v) for v in (spec.damping_factors, spec.speed_factors, spec.wn_factors))
    grid = np.asarray(robustness_grid(comp, cam, plant, omega, mu, lam, kap, phi))
    grid_nom = np.asarray(robustness_grid(cam, cam, plant, omega, mu, lam, kap, phi))
    ratios = (lam[:, None] / kap[None, :]).ravel()
    at_ratio = np.asarray(robustness_grid(comp, cam, plant, omega, np.array([1.0]), ratios,
                                          np.array([1.0]), phi))[0, :, 0]
    return Robustness(mu, lam, kap, grid, grid_nom, ratios, at_ratio)


def time_domain(ctx: Context, settle: Settling) -> TimeDomain:
    """RK4 from rest under the exact program law, nominal and linearly compensated."""
    plant, omega, cam, m = ctx.plant, ctx.omega, ctx.cam, ctx.spec.steps_per_cycle
    # the count is data, bounded by the scene's cap: another inertia or speed compiles nothing again
    cycles, bound = settle.cycles, ctx.spec.max_cycles
    exact = program_values(ctx.scene, cam_grid(2 * m))
    load = integrate_train(plant, exact.f, omega, cycles, max_cycles=bound).angle
    grid_m = cam_grid(m)
    harm = evaluate_cam(steady_state(cam, plant, omega), grid_m).f
    compensated = compensate_time(exact, plant, omega)
    load_c = integrate_train(plant, compensated, omega, cycles, max_cycles=bound).angle
    target = program_values(ctx.scene, grid_m).f
    decay = as_float(damping_ratio(plant) * natural_frequency_rad_s(plant))
    return TimeDomain(cycles, m, float(math.exp(-decay * cycles * TWO_PI / omega)),
                      as_float(jnp.max(jnp.abs(load - harm))), as_float(jnp.max(jnp.abs(load - target))),
                      as_float(jnp.max(jnp.abs(load_c - target))))


def nonlinear(ctx: Context, settle: Settling) -> Nonlinear:
    """Nonlinear compensation with drive flexibility, fitted to the scene's harmonics."""
    spec = ctx.spec
    nl = compensate_nonlinear(trim_harmonics(ctx.cam), drive_of(spec), ctx.plant, ctx.omega,
                              spec.harmonics, settle.cycles, spec.steps_per_cycle, spec.max_cycles)
    return Nonlinear(as_float(nl.fit_rms), spec.harmonics, nl.cam)


def drive(ctx: Context, settle: Settling,
          nonlinear_cam: Callable[[], CamHarmonics] | None = None) -> DriveResult:
    """The nominal, linear (and nonlinear, when given) cams on the flexible drive.

    ``nonlinear_cam`` is called after the other two runs: it may wait for the nonlinear
    compensation computed meanwhile in another thread.
    """
    spec, plant, omega, m = ctx.spec, ctx.plant, ctx.omega, ctx.spec.steps_per_cycle
    dr = drive_of(spec)
    grid_m = cam_grid(m)
    target = evaluate_cam(ctx.cam, grid_m).f
    cams = {"nominal": lambda: ctx.cam, "linear": lambda: ctx.linear}
    if nonlinear_cam is not None:
        cams["nonlinear"] = nonlinear_cam
    runs = {}
    for name, get_cam in cams.items():
        r = simulate_drive(trim_harmonics(get_cam()), dr, plant, omega, settle.cycles, m, spec.max_cycles)
        runs[name] = DriveRun(as_float(jnp.max(jnp.abs(r.cam_speed - omega)) / omega),
                              as_float(jnp.max(jnp.abs(r.load - target))), as_float(jnp.max(jnp.abs(r.cam_torque))),
                              np.asarray(r.cam_speed) / TWO_PI, np.asarray(r.load))
    return DriveResult(settle.cycles, math.sqrt(spec.k01 / spec.I1) / TWO_PI, runs,
                       np.rad2deg(np.asarray(grid_m)), np.asarray(target))


def jump(ctx: Context) -> Jump:
    """Jump speed in the scene's search range and the closure needed at the cam speed."""
    spec, plant, omega, phi, cam = ctx.spec, ctx.plant, ctx.omega, ctx.phi, ctx.cam
    closure = closure_of(spec)
    lo_hz, hi_hz = spec.jump_speed_range_hz or (0.05 * spec.cam_speed_hz, 10 * spec.cam_speed_hz)
    # the cam speed is scanned too: contact lost there is then found at or below it
    js = jump_speed(cam, plant, closure, phi, TWO_PI * lo_hz, TWO_PI * hi_hz,
                    include_rad_s=jnp.asarray([omega]))
    force = contact_force(cam, plant, closure, omega, phi)
    # plot grid: even steps plus every resonant speed and a close look around the jump
    res_hz = as_float(natural_frequency_rad_s(plant)) / TWO_PI / np.arange(1, spec.harmonics + 1)
    speeds = [np.linspace(lo_hz, hi_hz, 400), res_hz * 0.999, res_hz, res_hz * 1.001]
    found = bool(js.found)
    status = "found" if found else "lost_at_lowest_speed" if bool(js.lost_at_low) else "holds_in_range"
    if found:
        j_hz = as_float(js.speed_rad_s) / TWO_PI
        speeds.append(np.linspace(0.98 * j_hz, 1.02 * j_hz, 81))
    speeds = np.unique(np.clip(np.concatenate(speeds), lo_hz, hi_hz))
    fmins = np.asarray(jax.vmap(lambda w: min_contact_force(cam, plant, closure, w, phi))(
        jnp.asarray(speeds) * TWO_PI))
    return Jump((lo_hz, hi_hz), as_float(js.speed_rad_s) / TWO_PI if found else None, status, spec.cam_speed_hz,
                as_float(jnp.min(force)), as_float(min_preload(cam, plant, closure, omega, phi)),
                finite_or_none(min_spring_rate(cam, plant, closure, omega, phi)),
                speeds, fmins, np.asarray(force))


def shaping(ctx: Context) -> Shaping:
    """Law shaping over the scene's speed band, the lift and dwells pinned."""
    spec, plant, omega, phi = ctx.spec, ctx.plant, ctx.omega, ctx.phi
    c_phi, c_val = shaping_constraints(ctx.scene)
    band = omega * jnp.linspace(spec.shaping_band[0], spec.shaping_band[1], 9)
    cam0 = pad_harmonics(ctx.cam, spec.shaping_harmonics)
    lift = max(float(np.max(c_val) - np.min(c_val)), 1e-300)
    res = shape_law(cam0, plant, band, jnp.asarray(c_phi), jnp.asarray(c_val), lift, steps=spec.shaping_steps)
    shaped = pad_harmonics(res.cam, spec.harmonics)
    return Shaping(
        (spec.shaping_band[0] * spec.cam_speed_hz, spec.shaping_band[1] * spec.cam_speed_hz),
        spec.shaping_harmonics, as_float(jnp.sqrt(band_tracking_ms(cam0, plant, band))), as_float(res.tracking_rms),
        as_float(max_abs(tracking_error_harmonics(shaped, shaped, plant, omega), phi)),
        as_float(res.constraint_max), res.cam, np.asarray(evaluate_cam(shaped, phi).f),
        np.asarray(evaluate_cam(steady_state(shaped, plant, omega), phi).f))


# ------------------------------------------------------------------------------ the report


@dataclass(frozen=True)
class DynamicsReport:
    """What :func:`scene_dynamics` computed; an analysis the scene did not list is None."""

    scene: str
    follower: str  # "translating" or "oscillating"
    cam_speed_hz: float
    samples: int
    harmonics: int
    nominal: Nominal
    compensation: Compensation | None = None
    robustness: Robustness | None = None
    time_domain: TimeDomain | None = None
    nonlinear: Nonlinear | None = None
    drive: DriveResult | None = None
    jump: Jump | None = None
    shaping: Shaping | None = None
    settling: Settling | None = None  # of the time-domain runs (time_domain, drive, nonlinear)
    max_cycles: int = 0
    transient_tolerance: float = 0.0

    @property
    def unit(self) -> str:
        """Motion unit: m (translating) or rad (oscillating)."""
        return "m" if self.follower == "translating" else "rad"

    @property
    def summary(self) -> dict:
        """The content of dynamics.json (floats, ints, bools, lists, None)."""
        n = self.nominal
        out: dict = {
            "scene": self.scene, "follower": self.follower,
            "units": {"motion": self.unit, "force": "N" if self.unit == "m" else "N m",
                      "speed": "Hz (cam revolutions per second)"},
            "cam_speed_hz": self.cam_speed_hz,
            "natural_frequency_hz": n.natural_frequency_hz, "damping_ratio": n.damping_ratio,
            "resonant_harmonic": {"n": n.resonant_n, "frequency_ratio": n.resonant_ratio,
                                  "amplification": n.resonant_amplification},
            "samples": self.samples, "harmonics": self.harmonics,
            "nominal": {"max_tracking_error": n.max_tracking_error,
                        "rms_tracking_error": n.rms_tracking_error},
        }
        if self.compensation is not None:
            out["compensated"] = self.compensation.to_json()
        if self.robustness is not None:
            out["robustness"] = self.robustness.to_json()
            out["speed_wn_equivalence"] = self.robustness.equivalence_json()
        if self.time_domain is not None:
            out["time_domain"] = self.time_domain.to_json()
        if self.nonlinear is not None:
            out["nonlinear"] = self.nonlinear.to_json(
                self.drive.runs["nonlinear"].max_tracking_error if self.drive is not None else None)
        if self.drive is not None:
            out["drive"] = self.drive.to_json()
        if self.jump is not None:
            out["jump"] = self.jump.to_json()
        if self.shaping is not None:
            out["shaping"] = self.shaping.to_json()
        if self.settling is not None:
            out["settling"] = {"settled": self.settling.settled, "cycles": self.settling.cycles,
                               "cycles_needed": self.settling.cycles_needed, "max_cycles": self.max_cycles,
                               "transient_tolerance": self.transient_tolerance,
                               "residual_factor": self.settling.residual_factor}
        return out

    @property
    def curves(self) -> dict:
        """name -> NumPy curve, for the figures (:mod:`camjax.output.plots_dynamics`)."""
        n = self.nominal
        c = {"phi_deg": n.phi_deg, "nominal": n.cam, "nominal_load": n.load}
        if self.compensation is not None:
            c["compensated"] = self.compensation.curve
        if (r := self.robustness) is not None:
            c.update(rob_mu=r.damping_factors, rob_lam=r.speed_factors, rob_kap=r.wn_factors,
                     rob=r.compensated, rob_nominal=r.nominal, rob_ratio=r.ratios, rob_at_ratio=r.at_ratio)
        if (d := self.drive) is not None:
            c["drive_phi_deg"], c["drive_target"] = d.phi_deg, d.target
            for name, run in d.runs.items():
                c[f"drive_{name}_speed"], c[f"drive_{name}_load"] = run.speed_hz, run.load
        if (j := self.jump) is not None:
            c.update(jump_speeds_hz=j.speeds_hz, jump_fmin=j.min_force, contact_force=j.contact_force)
        if (s := self.shaping) is not None:
            c["shaped"], c["shaped_load"] = s.curve, s.load
        return c


def _start(fn, *args) -> Future:
    """``fn(*args)`` in a thread of its own: XLA releases the GIL while it computes, so a long
    XLA loop there overlaps the tracing, the other analyses and the figures in the caller."""
    pool = ThreadPoolExecutor(1, thread_name_prefix="camjax-dynamics")
    future = pool.submit(fn, *args)
    pool.shutdown(wait=False)
    return future


def _time_domain_runs(ctx: Context, settle: Settling, train: bool, with_drive: bool,
                      say: Callable[[str], None], tracker=None) -> dict:
    """The time-domain entries (time_domain, nonlinear, drive) in their order of dependence."""
    runs = f"{settle.cycles} cycles x {ctx.spec.steps_per_cycle} RK4 steps"
    parts: dict = {}
    nl = None
    if with_drive and "nonlinear" in ctx.spec.compute:
        # the nonlinear compensation runs beside the train and the first two drive runs
        say(f"nonlinear ({runs})")
        nl = _start(tracked, tracker, "nonlinear", nonlinear, ctx, settle)
    if train:
        say(f"time_domain ({runs})")
        parts["time_domain"] = tracked(tracker, "time_domain", time_domain, ctx, settle)
    if with_drive:
        say(f"drive ({runs} per cam)")
        parts["drive"] = tracked(tracker, "drive", drive, ctx, settle,
                                 None if nl is None else lambda: nl.result().cam)
    if nl is not None:
        parts["nonlinear"] = nl.result()
    return parts


def _context_and_nominal(scene) -> tuple[Context, Nominal]:
    ctx = context(scene)
    return ctx, nominal(ctx)


def scene_dynamics(scene, progress: Callable[[str], None] | None = None,
                   meanwhile: Callable[[DynamicsReport], None] | None = None,
                   tracker=None) -> DynamicsReport:
    """Run every analysis the scene's [dynamics] section lists. Not traceable (a report).

    The long XLA loops (the time-domain runs, the jump search) run in threads of their own.
    ``progress``, when given, is called with one line as each analysis starts. ``meanwhile``,
    when given, is called with the report of the analyses done so far while the threads finish:
    first with those of this thread (compensation, robustness, shaping; the others still None),
    then again as each thread but the last finishes, so that work needing only those (figures)
    overlaps the long loops. ``tracker``, when given (a
    :class:`~camjax.dynamics.budget.WorkProgress`), is told as each analysis of
    :func:`~camjax.dynamics.budget.estimate_work` starts and finishes (from any thread).
    Raises ValueError if the scene has no [dynamics] section.
    """
    spec = scene.dynamics
    if spec is None:
        raise ValueError("scene has no [dynamics] section")
    say = progress or (lambda _line: None)
    compute = spec.compute
    ctx, nom = tracked(tracker, "nominal", _context_and_nominal, scene)
    parts: dict = {}
    threads: list[Future] = []
    needs_drive = spec.has_drive and ("drive" in compute or "nonlinear" in compute)
    if "time_domain" in compute or needs_drive:
        settle = settling(ctx.plant, ctx.omega, spec.transient_tolerance, spec.max_cycles)
        parts.update(settling=settle, max_cycles=spec.max_cycles,
                     transient_tolerance=spec.transient_tolerance)
        threads.append(_start(_time_domain_runs, ctx, settle, "time_domain" in compute, needs_drive, say,
                              tracker))
    if "jump" in compute:
        say("jump")
        threads.append(_start(lambda: {"jump": tracked(tracker, "jump", jump, ctx)}))
    if "compensation" in compute or "robustness" in compute:
        say("compensation")
        parts["compensation"] = tracked(tracker, "compensation", compensation, ctx, nom)
    if "robustness" in compute:
        say("robustness")
        parts["robustness"] = tracked(tracker, "robustness", robustness, ctx)
    if "shaping" in compute:
        say(f"shaping ({spec.shaping_steps} L-BFGS steps)")
        parts["shaping"] = tracked(tracker, "shaping", shaping, ctx)

    def report() -> DynamicsReport:
        return DynamicsReport(scene.name, spec.follower, spec.cam_speed_hz, spec.samples, spec.harmonics,
                              nom, **parts)

    if meanwhile is not None:
        meanwhile(report())
    for k, thread in enumerate(as_completed(threads)):
        parts.update(thread.result())
        if meanwhile is not None and k < len(threads) - 1:
            meanwhile(report())
    return report()
