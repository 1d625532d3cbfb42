"""The constraint checks both follower families apply to an evaluated geometry, each one sentence,
and the [follower] and [design] checks several follower types share.

Tolerances are the solvers' (:data:`camjax.family.FEASIBILITY_TOL_MM`, relative 1e-6 on the
stress, :data:`camjax.family.FEASIBILITY_TOL_RAD` on the pressure angle), so a design a solver
calls feasible is not flagged here.
"""

from __future__ import annotations

import math

from camjax.family import FEASIBILITY_RTOL_STRESS, FEASIBILITY_TOL_MM, FEASIBILITY_TOL_RAD
from camjax.results import GeometryViolation
from camjax.scene.reader import DEFAULT, fixed_or_free


def curvature(rho: float, deg: float, rho_min_mm: float) -> list[GeometryViolation]:
    """A radius of curvature (mm) at cam angle ``deg`` below the allowed one."""
    if rho >= rho_min_mm - FEASIBILITY_TOL_MM:
        return []
    why = "the profile crosses itself" if rho < 0 else "the flat face cannot follow it"
    return [GeometryViolation("curvature", f"min radius of curvature {rho:.4g} mm at {deg:g} deg < "
                              f"{rho_min_mm:g} mm: {why}")]


def stress(sigma: float, deg: float, sigma_max_MPa: float) -> list[GeometryViolation]:
    """A peak contact stress (MPa) above the allowed one."""
    if sigma <= sigma_max_MPa * (1.0 + FEASIBILITY_RTOL_STRESS):
        return []
    return [GeometryViolation("stress", f"peak contact stress {sigma:.4g} MPa at {deg:g} deg > sigma_max "
                              f"{sigma_max_MPa:g} MPa")]


def pressure_angle(phi: float, deg: float, limit_deg: float) -> list[GeometryViolation]:
    """A largest |pressure angle| (deg) above its limit."""
    if phi <= limit_deg + math.degrees(FEASIBILITY_TOL_RAD):
        return []
    return [GeometryViolation("pressure_angle", f"|pressure angle| {phi:.4g} deg at {deg:g} deg > "
                              f"{limit_deg:g} deg")]


def undercut(margin: float, deg: float) -> list[GeometryViolation]:
    """A negative undercut margin (mm): the roller (or the curved face) undercuts the cam."""
    if margin >= -FEASIBILITY_TOL_MM:
        return []
    return [GeometryViolation("undercut", f"undercut margin {margin:.4g} mm at {deg:g} deg <= 0: the roller "
                              "undercuts the cam")]


def outer_flank(margin: float, deg: float) -> list[GeometryViolation]:
    """A negative outer-flank margin (mm): a groove's outer flank is concave tighter than its roller
    (the pitch curve's concavity radius below R_f + clearance + the smallest radius allowed)."""
    if margin >= -FEASIBILITY_TOL_MM:
        return []
    return [GeometryViolation("outer_flank", f"outer-flank margin {margin:.4g} mm at {deg:g} deg <= 0: the "
                              "pitch curve's concavity radius is below R_f + clearance, the groove's outer "
                              "flank cannot be cut")]


def worst_of(theta_deg, extremes: dict | None = None):
    """The function ``(values, pick, name=None, sense="min") -> (value, deg)`` that finds a curve's
    worst value and its cam angle (deg): ``extremes[name]``'s min or max (``sense``) where the exact
    extrema (:class:`camjax.results.Extremes` by curve name) have the curve, else the sample that
    ``pick`` (``np.argmin``, ``np.argmax``) chooses among ``values`` on the grid ``theta_deg``."""
    ex = extremes or {}

    def at(values, pick, name=None, sense="min"):
        if name in ex:
            e = ex[name]
            return (e.min, e.min_deg) if sense == "min" else (e.max, e.max_deg)
        i = int(pick(values))
        return float(values[i]), float(theta_deg[i])

    return at


def closure(own: dict, theta_deg, pressure_angle_limit_deg: float | None) -> list[GeometryViolation]:
    """The second contact of a positive drive (:mod:`camjax.followers._closure`), on its samples: a
    groove's outer flank that cannot be cut; a conjugate cam's pressure angle over the limit and its
    undercut."""
    import numpy as np

    out: list[GeometryViolation] = []
    worst = worst_of(theta_deg)

    if "outer_margin_mm" in own:
        out += outer_flank(*worst(own["outer_margin_mm"], np.argmin))
    if "conjugate_margin_mm" in own:
        for v in undercut(*worst(own["conjugate_margin_mm"], np.argmin)):
            out.append(GeometryViolation("conjugate_undercut", v.message.replace("the roller undercuts the cam",
                                                                                 "the second roller undercuts its cam")))
    if "conjugate_pressure_angle_deg" in own and pressure_angle_limit_deg is not None:
        for v in pressure_angle(*worst(np.abs(own["conjugate_pressure_angle_deg"]), np.argmax), pressure_angle_limit_deg):
            out.append(GeometryViolation("conjugate_pressure_angle", "second cam: " + v.message))
    return out


# ------------------------------------------------------------------------------ scene checks


def read_max_pressure_angle(r):
    """[follower] max_pressure_angle_deg (deg, > 0 and < 90), or DEFAULT when the scene leaves it out."""
    limit = r.number("max_pressure_angle_deg", DEFAULT, low=0.0, low_open=True)
    if limit is not DEFAULT and limit >= 90.0:
        raise r.error("max_pressure_angle_deg", limit, "out of range", "> 0 and < 90")
    return limit


def read_face(r) -> tuple[float, float]:
    """[follower] face_radius_mm R_c > 0 and face_width_mm W of a curved face (mm, either
    family): 0 < W <= 2 R_c, the face a chord of its circle."""
    radius = r.number("face_radius_mm", low=0.0, low_open=True)
    width = r.number("face_width_mm", low=0.0, low_open=True)
    if width > 2.0 * radius:
        raise r.error("face_width_mm", width, f"is wider than the face's circle (2 face_radius_mm = "
                      f"{2.0 * radius:g} mm)", f"<= {2.0 * radius:g}")
    return radius, width


def face_bounds(r, follower) -> tuple[tuple[float, float], tuple[float, float]]:
    """[design] bounds (mm) of a curved face's R_c and W, fixed at the [follower]'s by default
    (checked by :func:`face_fits_circle`)."""
    return (fixed_or_free(r, "face_radius_mm", (follower.face_radius_mm,) * 2),
            fixed_or_free(r, "face_width_mm", (follower.face_width_mm,) * 2))


def face_fits_circle(r, radius: tuple[float, float], width: tuple[float, float]) -> None:
    """Refuses [design] bounds that allow a face wider than its circle: W_max > 2 R_c,min."""
    if width[1] > 2.0 * radius[0]:
        raise r.error("face_width_mm", list(width) if width[0] != width[1] else width[0],
                      f"allows a face wider than its circle (2 R_c = {2.0 * radius[0]:g} mm at the "
                      "smallest face_radius_mm)", f"<= {2.0 * radius[0]:g}")


def offset_cuts_prime_circle(r, offset: tuple[float, float], reach: float, prime: str) -> None:
    """Refuses [design] offset bounds (mm) with |e| >= R_p for every design in the bounds: ``reach``
    the largest prime radius the bounds allow (mm), ``prime`` its formula ("R_b + R_f"). |e| < R_p
    is a constraint of the problem (its pressure-angle constraint holds only there)."""
    if least_abs_offset(offset) >= reach:
        raise r.error("offset_mm", list(offset) if offset[0] != offset[1] else offset[0],
                      f"gives |e| >= R_p = {prime} for every design in the bounds (largest R_p: "
                      f"{reach:g} mm): the follower axis must cut the prime circle",
                      f"|e| < {reach:g} somewhere in the bounds")


def least_abs_offset(bounds: tuple[float, float]) -> float:
    """The smallest |e| (mm) in the offset's bounds (lo, hi): 0 when they straddle 0."""
    lo, hi = bounds
    return 0.0 if lo <= 0.0 <= hi else min(abs(lo), abs(hi))
