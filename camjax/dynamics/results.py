"""The typed results of the analyses a scene's [dynamics] lists: one frozen dataclass per
``compute`` entry, each with the numbers dynamics.json holds (``to_json``) and the curves the
figures draw (:mod:`camjax.dynamics.report` fills them in)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from camjax.dynamics.context import coefficients_json
from camjax.dynamics.harmonics import (
    CamHarmonics,
)
from camjax.dynamics.integrate import Settling

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
                "coefficients": coefficients_json(self.cam),
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
        out = {"fit_rms": self.fit_rms, "harmonics": self.harmonics, "coefficients": coefficients_json(self.cam)}
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
                "coefficients": coefficients_json(self.cam)}


def settling_json(s: Settling, spec) -> dict:
    """The ``settling`` entry of dynamics.json: did ``max_cycles`` cut the time-domain runs short?"""
    return {"settled": s.settled, "cycles": s.cycles, "cycles_needed": s.cycles_needed,
            "max_cycles": spec.max_cycles, "transient_tolerance": spec.transient_tolerance,
            "residual_factor": s.residual_factor}


