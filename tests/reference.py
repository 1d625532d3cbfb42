"""The reference case (SPEC 5) in closed form, NumPy float64, independent of camjax.

Cycloidal dwell-rise-dwell-return: dwell to 100 deg, rise of 5 mm over 80 deg, dwell to 300 deg,
return over 60 deg; 240 rpm, m = 1 kg, k = 3004 N/m, x0 = 13 mm, c = 0.345 N s/m, g = 9.81 m/s^2;
a 10 mm steel cam on a bronze flat face; sigma_max = 1230 MPa, size norm 65 mm.

Every test that checks camjax against the reference case compares with these functions; nothing
here imports camjax or reads its scene file, so a wrong constant in either shows up as a failure.
The cycloid p(x) = x - sin(2 pi x)/(2 pi) is the textbook law (SPEC 2), written out again here.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

LIFT_MM = 5.0
RISE_DEG = (100.0, 80.0)  # start, span
RETURN_DEG = (300.0, 60.0)
CAM_SPEED_RAD_S = 240.0 * 2 * math.pi / 60  # 240 rpm
MASS_KG = 1.0
SPRING_N_PER_M = 3004.0
PRELOAD_MM = 13.0
DAMPING_NS_PER_M = 0.345
GRAVITY_M_S2 = 9.81
CAM_WIDTH_MM = 10.0
CAM_E_MPA, CAM_POISSON = 2.1e5, 0.3  # steel
FOLLOWER_E_MPA, FOLLOWER_POISSON = 1.15e5, 0.26  # bronze
SIGMA_MAX_MPA = 1230.0
SIZE_NORM_MM = 65.0
BASE_RADIUS_BOUNDS_MM = (5.0, 40.0)
FACE_WIDTH_BOUNDS_MM = (5.0, 25.0)


def reference_motion(theta_deg, lift_mm: float = LIFT_MM, rise_deg: tuple[float, float] = RISE_DEG,
                     return_deg: tuple[float, float] = RETURN_DEG):
    """s (mm), s' (mm/rad), s'' (mm/rad^2) of a cycloidal rise and return, any array shape.

    ``rise_deg`` and ``return_deg`` are (start, span) in degrees; s = 0 before the rise and after
    the return, ``lift_mm`` between them. Angles are taken modulo 360; a sample exactly on a joint
    belongs to the segment that starts there. The defaults are the reference case; a dwell-free
    program is ``rise_deg=(0, r), return_deg=(r, 360 - r)``.
    """
    t = np.asarray(theta_deg, dtype=np.float64) % 360.0
    s = np.where((t >= sum(rise_deg)) & (t < return_deg[0]), lift_mm, 0.0)
    ds, d2s = np.zeros_like(t), np.zeros_like(t)
    for (start, span), sign in ((rise_deg, 1.0), (return_deg, -1.0)):
        beta = math.radians(span)
        inside = (t >= start) & (t < start + span)
        x = np.where(inside, (t - start) / span, 0.0)
        p = x - np.sin(2 * np.pi * x) / (2 * np.pi)
        s = np.where(inside, lift_mm * p if sign > 0 else lift_mm * (1 - p), s)
        ds = np.where(inside, sign * lift_mm * (1 - np.cos(2 * np.pi * x)) / beta, ds)
        d2s = np.where(inside, sign * lift_mm * 2 * np.pi * np.sin(2 * np.pi * x) / beta**2, d2s)
    return s, ds, d2s


def reference_force(theta_deg, spring_N_per_m: float = SPRING_N_PER_M):
    """Kinetostatic cam force (N): m y'' + c y' + k (y + x0) + m g at the reference speed."""
    s, ds, d2s = reference_motion(theta_deg)
    w = CAM_SPEED_RAD_S
    y, v, a = s * 1e-3, ds * w * 1e-3, d2s * w**2 * 1e-3  # SI
    return MASS_KG * a + DAMPING_NS_PER_M * v + spring_N_per_m * (y + PRELOAD_MM * 1e-3) + MASS_KG * GRAVITY_M_S2


def stress_coefficient(force_N):
    """C (MPa mm^0.5) of the Hertz line contact, sigma = C / sqrt(rho): 0.564 sqrt(F / (w k))."""
    k = (1 - CAM_POISSON**2) / CAM_E_MPA + (1 - FOLLOWER_POISSON**2) / FOLLOWER_E_MPA  # 1/MPa
    return 0.564 * np.sqrt(np.asarray(force_N) / (CAM_WIDTH_MM * k))


def hertz_stress_MPa(force_N, rho_mm):
    """Hertz line-contact stress (MPa) at contact force ``force_N`` and curvature radius ``rho_mm``."""
    return stress_coefficient(force_N) / np.sqrt(rho_mm)


class ReferenceCase(NamedTuple):
    """The reference case on a grid of N samples from 0 deg (shape (N,) each)."""

    theta_deg: np.ndarray
    s_mm: np.ndarray
    ds_mm: np.ndarray  # s', mm/rad
    d2s_mm: np.ndarray  # s'', mm/rad^2
    force_N: np.ndarray
    stress_coefficient: np.ndarray  # MPa mm^0.5


def reference_case(samples: int = 360) -> ReferenceCase:
    """Every per-angle array of the reference case on ``samples`` angles k 360/N deg."""
    theta = np.arange(samples) * 360.0 / samples
    force = reference_force(theta)
    return ReferenceCase(theta, *reference_motion(theta), force, stress_coefficient(force))


def numpy_reference_optimum(alpha: float = 1.0, gamma: float = 1.0) -> tuple[float, float, float, float]:
    """Largest per-angle optimum (R_b, its angle, L, its angle) of the reference case (mm, deg).

    Per angle, L = max(2|s'|, 5) and R = -q + max((gamma N C / (2 alpha sigma_max))^(2/3),
    (C / sigma_max)^2), clipped to the bounds, where q = s + s'', sigma = C / sqrt(R + q) and N the
    size norm: the stationary point of alpha R / N + gamma sigma / sigma_max, or the smallest R
    with sigma <= sigma_max if that is larger.
    """
    ref = reference_case(360)
    q = ref.s_mm + ref.d2s_mm
    c = ref.stress_coefficient
    rho = np.maximum((gamma * SIZE_NORM_MM * c / (2 * alpha * SIGMA_MAX_MPA)) ** (2 / 3),
                     (c / SIGMA_MAX_MPA) ** 2)
    radius = np.clip(-q + rho, *BASE_RADIUS_BOUNDS_MM)
    width = np.clip(2 * np.abs(ref.ds_mm), *FACE_WIDTH_BOUNDS_MM)
    i, j = int(np.argmax(radius)), int(np.argmax(width))
    return float(radius[i]), float(ref.theta_deg[i]), float(width[j]), float(ref.theta_deg[j])
