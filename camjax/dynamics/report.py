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

from camjax import program as prog
from camjax.dynamics.budget import tracked
from camjax.dynamics.compensation import (
    compensate_linear,
    compensate_nonlinear,
    compensate_time,
    robustness_grid,
)
from camjax.dynamics.harmonics import (
    TWO_PI,
    CamHarmonics,
    CamValues,
    cam_grid,
    evaluate_cam,
    harmonics_from_samples,
    max_abs,
    mean_square,
    pad_harmonics,
    trim_harmonics,
)
from camjax.dynamics.integrate import Drive, Settling, integrate_train, settling, simulate_drive
from camjax.dynamics.jump import (
    ForceClosure,
    contact_force,
    jump_speed,
    min_contact_force,
    min_preload,
    min_spring_rate,
)
from camjax.dynamics.plant import (
    Plant,
    damping_ratio,
    natural_frequency_rad_s,
    perturbed_plant,
    resonant_harmonic,
    steady_state,
    tracking_error_harmonics,
    transfer,
)
from camjax.dynamics.shaping import band_tracking_ms, shape_law

# ------------------------------------------------------------------------ scene -> models


def plant_of(spec) -> Plant:
    """The follower train of a :class:`~camjax.scene.DynamicsSpec`."""
    return Plant(jnp.asarray(spec.I3), jnp.asarray(spec.c3), jnp.asarray(spec.k23))


def drive_of(spec) -> Drive:
    """The drive of a DynamicsSpec with drive flexibility (I1, k01, c01 given)."""
    return Drive(jnp.asarray(spec.I1), jnp.asarray(spec.I2), jnp.asarray(spec.k01), jnp.asarray(spec.c01))


def closure_of(spec) -> ForceClosure:
    """The force closure of a DynamicsSpec with a spring."""
    return ForceClosure(jnp.asarray(spec.I2), jnp.asarray(spec.spring_rate),
                        jnp.asarray(spec.spring_preload), jnp.asarray(spec.follower_damping),
                        jnp.asarray(spec.weight))


def program_cam(scene, samples: int | None = None, n_harmonics: int | None = None) -> CamHarmonics:
    """The scene's motion program as CamHarmonics in SI (m or rad), from the FFT of its samples."""
    spec = scene.dynamics
    n = spec.samples if samples is None else samples
    kin = prog.evaluate(scene.motion.program, n)
    return harmonics_from_samples(kin.s * spec.motion_scale, spec.harmonics if n_harmonics is None
                                  else n_harmonics)


def program_values(scene, angles_rad: jax.Array) -> CamValues:
    """Exact program law (not its harmonics) at arbitrary cam angles, SI."""
    kin = prog.motion_at(scene.motion.program, jnp.rad2deg(angles_rad))
    k = scene.dynamics.motion_scale
    return CamValues(kin.s * k, kin.ds * k, kin.d2s * k)


def shaping_constraints(scene) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) and levels (SI) pinned by law shaping: every joint and dwell samples."""
    p = scene.motion.program
    angles = []
    for kind, start, width in zip(p.kinds, p.start_deg, p.angles_deg, strict=True):
        angles.extend(np.linspace(start, start + width, max(2, int(width // 5) + 1)) if kind == "dwell"
                      else [start])
    angles_deg = np.mod(np.asarray(angles), 360.0)
    levels = np.asarray(prog.motion_at(p, angles_deg).s) * scene.dynamics.motion_scale
    return np.deg2rad(angles_deg), levels


def _f(x) -> float:
    return float(np.asarray(x))


def _finite_or_none(x) -> float | None:
    v = _f(x)
    return v if math.isfinite(v) else None


def _coefficients(cam: CamHarmonics) -> dict:
    return {"cos": np.asarray(cam.cos).tolist(), "sin": np.asarray(cam.sin).tolist()}


@dataclass(frozen=True)
class Context:
    """What every analysis of one scene shares: models, the cam and its linear compensation."""

    scene: object  # camjax.scene.Scene with a [dynamics] section
    plant: Plant
    omega: float  # cam speed Omega, rad/s
    phi: jax.Array  # (N,) cam-angle grid, rad
    cam: CamHarmonics  # the program's harmonics, SI
    linear: CamHarmonics  # its linear compensation at Omega

    @property
    def spec(self):
        return self.scene.dynamics


def context(scene) -> Context:
    """The shared models of a scene with a [dynamics] section."""
    spec = scene.dynamics
    plant = plant_of(spec)
    omega = TWO_PI * spec.cam_speed_hz
    cam = program_cam(scene)
    return Context(scene, plant, omega, cam_grid(spec.samples), cam, compensate_linear(cam, plant, omega))


# ------------------------------------------------------------------------ typed results


@dataclass(frozen=True)
class Nominal:
    """The uncompensated cam: plant figures and the steady-state tracking error (always run)."""

    natural_frequency_hz: float
    damping_ratio: float
    resonant_n: int  # harmonic of the cam nearest the resonance
    resonant_ratio: float  # n Omega / omega_n
    resonant_amplification: float  # |G(i n Omega)|
    max_tracking_error: float  # motion units
    rms_tracking_error: float
    phi_deg: np.ndarray  # (N,) grid, deg
    cam: np.ndarray  # (N,) theta2 on the grid
    load: np.ndarray  # (N,) steady-state theta3 on the grid


@dataclass(frozen=True)
class WnMisestimate:
    wn_estimate_factor: float
    compensated_max_tracking_error: float
    nominal_over_compensated: float


@dataclass(frozen=True)
class Compensation:
    """Linear feedforward at the cam speed."""

    max_tracking_error: float
    rms_tracking_error: float
    time_form_max_difference: float  # time form vs harmonic inverse, on the grid
    max_cam_change: float  # max |compensated - nominal cam|
    cam: CamHarmonics  # the compensated law, trailing negligible harmonics trimmed
    wn_misestimate: tuple[WnMisestimate, ...]
    curve: np.ndarray  # (N,) compensated cam on the grid

    def to_json(self) -> dict:
        return {"max_tracking_error": self.max_tracking_error,
                "rms_tracking_error": self.rms_tracking_error,
                "time_form_max_difference": self.time_form_max_difference,
                "max_cam_change": self.max_cam_change,
                "coefficients": _coefficients(self.cam),
                "wn_misestimate": [vars(m).copy() for m in self.wn_misestimate]}


@dataclass(frozen=True)
class Robustness:
    """Compensated vs nominal error over the (mu, lambda, kappa) grid of the scene."""

    damping_factors: np.ndarray  # (A,) mu
    speed_factors: np.ndarray  # (B,) lambda
    wn_factors: np.ndarray  # (C,) kappa
    compensated: np.ndarray  # (A, B, C) max tracking error of the compensated cam
    nominal: np.ndarray  # (A, B, C) same for the nominal cam
    ratios: np.ndarray  # (B C,) lambda / kappa
    at_ratio: np.ndarray  # (B C,) compensated error at mu = 1, lambda / kappa, kappa = 1

    def to_json(self) -> list:
        mu, lam, kap = self.damping_factors, self.speed_factors, self.wn_factors
        return [{"damping_factor": float(mu[i]), "speed_factor": float(lam[j]), "wn_factor": float(kap[k]),
                 "max_tracking_error": float(self.compensated[i, j, k]),
                 "nominal_max_tracking_error": float(self.nominal[i, j, k])}
                for i in range(mu.size) for j in range(lam.size) for k in range(kap.size)]

    def equivalence_json(self) -> dict:
        """error(mu=1, lambda, kappa) vs error(mu=1, lambda/kappa, 1): speed and omega_n enter
        the compensated error only through their ratio."""
        mu, lam, kap, grid = self.damping_factors, self.speed_factors, self.wn_factors, self.compensated
        i1 = int(np.argmin(np.abs(mu - 1.0)))
        diff = np.abs(grid[i1].ravel() - self.at_ratio)
        return {
            "max_abs_difference": float(diff.max()),
            "max_error_where_speed_equals_wn_factor": float(max(
                [grid[i1, j, k] for j in range(lam.size) for k in range(kap.size)
                 if abs(lam[j] - kap[k]) < 1e-12] or [0.0])),
            "note": "error(mu=1, lambda, kappa) vs error(mu=1, lambda/kappa, 1)",
        }


@dataclass(frozen=True)
class TimeDomain:
    """RK4 from rest of the train under the exact program law, nominal and compensated."""

    cycles: int
    steps_per_cycle: int
    transients_decayed_to: float
    nominal_max_difference_vs_harmonic: float
    nominal_max_tracking_error: float
    compensated_max_tracking_error: float

    def to_json(self) -> dict:
        return {"method": "RK4, lax.scan, from rest", **vars(self)}


@dataclass(frozen=True)
class DriveRun:
    """One cam on the flexible drive, last simulated revolution."""

    max_speed_ripple: float  # max |theta1' - Omega| / Omega
    max_tracking_error: float
    max_cam_torque: float  # N m
    speed_hz: np.ndarray  # (M,) cam speed, rev/s
    load: np.ndarray  # (M,) theta3

    def to_json(self) -> dict:
        return {"max_speed_ripple": self.max_speed_ripple, "max_tracking_error": self.max_tracking_error,
                "max_cam_torque": self.max_cam_torque}


@dataclass(frozen=True)
class DriveResult:
    """Cams ("nominal", "linear", and "nonlinear" when computed) on the flexible drive."""

    cycles: int
    drive_natural_frequency_hz: float  # sqrt(k01 / I1) / 2 pi
    runs: dict[str, DriveRun]
    phi_deg: np.ndarray  # (M,) motor angle grid, deg
    target: np.ndarray  # (M,) the nominal law on that grid

    def to_json(self) -> dict:
        return {"cycles": self.cycles, "drive_natural_frequency_hz": self.drive_natural_frequency_hz,
                **{name: run.to_json() for name, run in self.runs.items()}}


@dataclass(frozen=True)
class Nonlinear:
    """Nonlinear feedforward with drive flexibility, fitted to ``harmonics`` harmonics."""

    fit_rms: float
    harmonics: int
    cam: CamHarmonics

    def to_json(self, max_tracking_error: float | None = None) -> dict:
        out = {"fit_rms": self.fit_rms, "harmonics": self.harmonics, "coefficients": _coefficients(self.cam)}
        if max_tracking_error is not None:  # from the drive run of this cam
            out["max_tracking_error"] = max_tracking_error
        return out


JUMP_STATUSES = ("found", "lost_at_lowest_speed", "holds_in_range")
"""``jump_speed_status``: contact held below ``jump_speed_hz`` and is lost there; contact already
lost at the lowest speed scanned (no jump speed: no speed of the range keeps it); contact held at
every speed scanned."""


@dataclass(frozen=True)
class Jump:
    """Force closure: jump speed, contact margin at the cam speed, preload and rate needed.

    ``jump_speed_hz`` is the lowest speed of ``search_range_hz`` at which contact is lost, or None
    with ``status`` saying why (:data:`JUMP_STATUSES`); :meth:`note` says it in a sentence.
    """

    search_range_hz: tuple[float, float]
    jump_speed_hz: float | None  # None unless status == "found"
    status: str  # one of JUMP_STATUSES
    cam_speed_hz: float
    min_contact_force: float  # N or N m, at the cam speed
    min_spring_preload: float  # m or rad
    min_spring_rate: float | None  # None: no rate helps (the spring is slack somewhere)
    speeds_hz: np.ndarray  # (S,) plot grid
    min_force: np.ndarray  # (S,) min contact force at each speed
    contact_force: np.ndarray  # (N,) contact force over the cycle at the cam speed

    @property
    def cam_speed_in_range(self) -> bool:
        lo, hi = self.search_range_hz
        return lo <= self.cam_speed_hz <= hi

    @property
    def contact_lost_at_cam_speed(self) -> bool:
        return self.min_contact_force <= 0

    def note(self) -> str:
        """One sentence: where contact is lost in the scanned range, or why no speed is given."""
        lo, hi = self.search_range_hz
        scanned = f"{lo:.6g} .. {hi:.6g} Hz"
        if self.status == "found":
            text = (f"contact holds from {lo:.6g} Hz and is first lost at {self.jump_speed_hz:.6g} Hz "
                    f"(scanned {scanned})")
        elif self.status == "lost_at_lowest_speed":
            text = (f"no jump speed: contact is already lost at the lowest speed scanned, {lo:.6g} Hz "
                    f"(min contact force there {float(self.min_force[0]):.4g}; scanned {scanned}), so no "
                    "speed of the range keeps it: a stronger spring_rate or spring_preload, or a lower "
                    "jump_speed_range_hz")
        else:
            text = f"no jump speed: contact holds at every speed scanned, {scanned}"
        state = "lost" if self.contact_lost_at_cam_speed else "holds"
        if self.cam_speed_in_range:
            return f"{text}; at the cam speed {self.cam_speed_hz:.6g} Hz contact {state}"
        return (f"{text}; the cam speed {self.cam_speed_hz:.6g} Hz lies outside jump_speed_range_hz, "
                f"and there contact {state}")

    def to_json(self) -> dict:
        return {"search_range_hz": list(self.search_range_hz), "jump_speed_hz": self.jump_speed_hz,
                "jump_speed_status": self.status, "note": self.note(),
                "cam_speed_in_range": self.cam_speed_in_range,
                "min_contact_force": self.min_contact_force,
                "contact_lost_at_cam_speed": self.contact_lost_at_cam_speed,
                "min_spring_preload": self.min_spring_preload,
                # inf (no rate helps) is written as null
                "min_spring_rate": self.min_spring_rate}


@dataclass(frozen=True)
class Shaping:
    """Gradient-shaped law over the speed band."""

    speed_band_hz: tuple[float, float]
    harmonics: int
    initial_band_rms_tracking_error: float
    band_rms_tracking_error: float
    max_tracking_error: float  # at the cam speed
    constraint_max_violation: float
    cam: CamHarmonics
    curve: np.ndarray  # (N,) shaped law on the grid
    load: np.ndarray  # (N,) its steady-state load

    def to_json(self) -> dict:
        return {"speed_band_hz": list(self.speed_band_hz), "harmonics": self.harmonics,
                "initial_band_rms_tracking_error": self.initial_band_rms_tracking_error,
                "band_rms_tracking_error": self.band_rms_tracking_error,
                "max_tracking_error": self.max_tracking_error,
                "constraint_max_violation": self.constraint_max_violation,
                "coefficients": _coefficients(self.cam)}


def settling_json(s: Settling, spec) -> dict:
    """The ``settling`` entry of dynamics.json: did ``max_cycles`` cut the time-domain runs short?"""
    return {"settled": s.settled, "cycles": s.cycles, "cycles_needed": s.cycles_needed,
            "max_cycles": spec.max_cycles, "transient_tolerance": spec.transient_tolerance,
            "residual_factor": s.residual_factor}


# ------------------------------------------------------------------- one per compute entry


def nominal(ctx: Context) -> Nominal:
    """Plant figures and the nominal cam's steady-state tracking error."""
    plant, omega, phi, cam = ctx.plant, ctx.omega, ctx.phi, ctx.cam
    err = tracking_error_harmonics(cam, cam, plant, omega)
    n_res, r_res = resonant_harmonic(plant, omega)
    return Nominal(
        _f(natural_frequency_rad_s(plant)) / TWO_PI, _f(damping_ratio(plant)), n_res, r_res,
        _f(jnp.abs(transfer(plant, n_res * omega))), _f(max_abs(err, phi)),
        _f(jnp.sqrt(mean_square(err))), np.rad2deg(np.asarray(phi)),
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
        e = _f(max_abs(tracking_error_harmonics(c_est, cam, plant, omega), phi))
        mis.append(WnMisestimate(est, e, nom.max_tracking_error / e))
    return Compensation(
        _f(max_abs(comp_err, phi)), _f(jnp.sqrt(mean_square(comp_err))),
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
    cycles = settle.cycles
    exact = program_values(ctx.scene, cam_grid(2 * m))
    load = integrate_train(plant, exact.f, omega, cycles).angle
    grid_m = cam_grid(m)
    harm = evaluate_cam(steady_state(cam, plant, omega), grid_m).f
    load_c = integrate_train(plant, compensate_time(exact, plant, omega), omega, cycles).angle
    target = program_values(ctx.scene, grid_m).f
    decay = _f(damping_ratio(plant) * natural_frequency_rad_s(plant))
    return TimeDomain(cycles, m, float(math.exp(-decay * cycles * TWO_PI / omega)),
                      _f(jnp.max(jnp.abs(load - harm))), _f(jnp.max(jnp.abs(load - target))),
                      _f(jnp.max(jnp.abs(load_c - target))))


def nonlinear(ctx: Context, settle: Settling) -> Nonlinear:
    """Nonlinear compensation with drive flexibility, fitted to the scene's harmonics."""
    spec = ctx.spec
    nl = compensate_nonlinear(trim_harmonics(ctx.cam), drive_of(spec), ctx.plant, ctx.omega,
                              spec.harmonics, settle.cycles, spec.steps_per_cycle)
    return Nonlinear(_f(nl.fit_rms), spec.harmonics, nl.cam)


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
        r = simulate_drive(trim_harmonics(get_cam()), dr, plant, omega, settle.cycles, m)
        runs[name] = DriveRun(_f(jnp.max(jnp.abs(r.cam_speed - omega)) / omega),
                              _f(jnp.max(jnp.abs(r.load - target))), _f(jnp.max(jnp.abs(r.cam_torque))),
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
    res_hz = _f(natural_frequency_rad_s(plant)) / TWO_PI / np.arange(1, spec.harmonics + 1)
    speeds = [np.linspace(lo_hz, hi_hz, 400), res_hz * 0.999, res_hz, res_hz * 1.001]
    found = bool(js.found)
    status = "found" if found else "lost_at_lowest_speed" if bool(js.lost_at_low) else "holds_in_range"
    if found:
        j_hz = _f(js.speed_rad_s) / TWO_PI
        speeds.append(np.linspace(0.98 * j_hz, 1.02 * j_hz, 81))
    speeds = np.unique(np.clip(np.concatenate(speeds), lo_hz, hi_hz))
    fmins = np.asarray(jax.vmap(lambda w: min_contact_force(cam, plant, closure, w, phi))(
        jnp.asarray(speeds) * TWO_PI))
    return Jump((lo_hz, hi_hz), _f(js.speed_rad_s) / TWO_PI if found else None, status, spec.cam_speed_hz,
                _f(jnp.min(force)), _f(min_preload(cam, plant, closure, omega, phi)),
                _finite_or_none(min_spring_rate(cam, plant, closure, omega, phi)),
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
        spec.shaping_harmonics, _f(jnp.sqrt(band_tracking_ms(cam0, plant, band))), _f(res.tracking_rms),
        _f(max_abs(tracking_error_harmonics(shaped, shaped, plant, omega), phi)),
        _f(res.constraint_max), res.cam, np.asarray(evaluate_cam(shaped, phi).f),
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
