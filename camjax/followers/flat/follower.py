"""The translating flat-face follower (SPEC 3 and 5): the source theses' reference case.

A face perpendicular to the stem touches the cam at s' off the axis; the cam's radius of
curvature is rho = R_b + s + s'' and must stay positive (a face cannot follow a concave cam). The
design variables are the base radius R_b and the face width L; the objective is the thesis' size
plus Hertz stress (:mod:`camjax.followers.flat.problem`), so a [design] needs [contact]. Only
this follower takes a [guide] (the stem's reactions, SPEC 4).
"""

from __future__ import annotations

from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, loads
from camjax.evaluate import curve_extremes
from camjax.followers._translating import (
    TRAIN_KEYS,
    DesignSolution,
    GeometryCurves,
    TranslatingFollower,
    read_train,
)
from camjax.followers.flat import geometry as flat_geo
from camjax.followers.flat.geometry import FLAT_MIN_CURVATURE_RADIUS_MM
from camjax.results import MinBaseRadius
from camjax.scene.reader import DEFAULT, build
from camjax.scene.spec import FollowerSpec

# the stem's reactions in the guide (camjax.loads.GuideReactions) whose extrema a report with a
# [guide] takes: N, N, N, mm
GUIDE_CURVES = ("cam_force", "reaction_1", "reaction_2", "gamma")


@dataclass(frozen=True, kw_only=True)
class FlatSpec(FollowerSpec):
    """[follower] of a flat face: the train and the margin of rho >= min_curvature_radius_mm."""

    type: str = "flat"
    # > 0: a flat face on rho = 0 rides a corner, where the contact stress is unbounded
    min_curvature_radius_mm: float = FLAT_MIN_CURVATURE_RADIUS_MM


def _f(x) -> float:
    return float(np.asarray(x))


@jax.jit
def _design_needs(problem, stress_coefficient, kin, base_radius_mm):
    """Peak stress at the design, per-angle stress need and R_b need, the face width need (one
    compiled call)."""
    from camjax.followers.flat import problem as P

    rho = flat_geo.flat_radius_of_curvature(base_radius_mm, kin)
    sigma_peak = jnp.max(contact.stress_from_coefficient(stress_coefficient, rho))
    need = P.rho_need(problem) - problem.q_mm  # max over angles: P.required_base_radius
    return sigma_peak, P.stress_rho_need(problem), need, P.required_face_width(problem)


class Flat(TranslatingFollower):
    name = "flat"
    title = "flat-face"
    keys = (*TRAIN_KEYS, "min_curvature_radius_mm")
    example_scene = "default"
    variables = ("base_radius_mm", "face_width_mm")
    design_needs_contact = True
    takes_guide = True

    def parse(self, r) -> FlatSpec:
        self.check_keys(r)
        train = read_train(r)
        rho_min = r.number("min_curvature_radius_mm", DEFAULT, low=0.0, low_open=True)
        return build(FlatSpec, type=self.name, train=train, min_curvature_radius_mm=rho_min)

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        return {"base_radius_mm": r.interval("base_radius_mm"), "face_width_mm": r.interval("face_width_mm")}

    def min_base_radius(self, scene, arrays) -> MinBaseRadius:
        """Smallest R_b with rho >= rho_min (``min_curvature_radius_mm``) at every angle:
        max_theta rho_min - (s + s''), refined off the grid with exact extrema (``[motion]
        extrema``), else on the samples. The same limit the design and the drawing's check use."""
        rho_min = float(scene.follower.min_curvature_radius_mm)
        if arrays.model is not None:
            q = curve_extremes(scene, arrays, ("q",))["q"]
            return MinBaseRadius(rho_min - q.min, q.min_deg, "curvature")
        t = np.asarray(arrays.theta_deg)
        r, i = jax.jit(flat_geo.flat_min_base_radius)(arrays.kin, rho_min)
        # + 0.0: -0.0 (s = s'' = 0 somewhere, e.g. uniform laws) reads as 0
        return MinBaseRadius(_f(r) + 0.0, _f(t[int(i)]), "curvature")

    def design_solution(self, scene, arrays, result, problem) -> DesignSolution:
        """The smallest R_b and L the design needs and which of curvature and stress binds (exact
        extrema: refined off the grid; else on the samples)."""
        from camjax.followers.flat import problem as P

        if problem.exact is not None:  # every figure refined off the grid
            e = problem.exact
            curvature = float(problem.rho_min_mm - e.q_min_mm)
            stress_need = float(e.stress_need_mm)
            binding = "stress" if stress_need >= curvature else "curvature"
            return DesignSolution(
                result, result["stress_max_MPa"], max(curvature, stress_need),
                _f(e.stress_need_deg if binding == "stress" else e.q_min_deg), binding,
                _f(P.required_face_width(problem)), float(problem.rho_min_mm))
        t = np.asarray(arrays.theta_deg)
        sigma_peak, stress_rho, need, width = jax.device_get(
            _design_needs(problem, arrays.stress_coefficient, arrays.kin, result["base_radius_mm"]))
        sigma_peak, width = float(sigma_peak), float(width)
        i = int(np.argmax(need))
        return DesignSolution(
            result, sigma_peak, float(need[i]), _f(t[i]),
            "stress" if stress_rho[i] >= float(problem.rho_min_mm) else "curvature",
            width, float(problem.rho_min_mm))

    def geometry(self, follower, rotation, arrays, base_radius_mm) -> GeometryCurves:
        kin = arrays.kin
        x, y = flat_geo.flat_profile(base_radius_mm, kin, rotation)
        rho = flat_geo.flat_radius_of_curvature(base_radius_mm, kin)
        stress = None
        if arrays.stress_coefficient is not None:
            stress = contact.stress_from_coefficient(arrays.stress_coefficient, rho)
        width = flat_geo.flat_face_width(kin, symmetric=True)
        return GeometryCurves(x, y, rho_mm=rho, stress_MPa=stress, face_width_mm=width)

    def design_face_width(self, result, extremes) -> float:
        """The design's L, else 2 max|s'| (the extremes': exact or the samples')."""
        width = result.get("face_width_mm")
        if width is None:
            width = 2.0 * max(extremes["ds"].max, -extremes["ds"].min, 0.0)
        return width

    def drawn_face_width(self, face_width_mm, geometry_width) -> float:
        return float(np.asarray(geometry_width)) if face_width_mm is None else face_width_mm

    def curve_names(self, scene, arrays) -> tuple[str, ...]:
        guide = GUIDE_CURVES if arrays.force_N is not None and scene.guide is not None else ()
        return (*guide, "q")

    def curve(self, name, p, consts, base_radius_mm):
        if name == "q":  # s + s'' (mm): rho = R_b + q
            return p.kin.s + p.kin.d2s
        if name == "stress":  # contact stress at base_radius_mm, MPa
            return contact.stress_from_coefficient(p.stress_coefficient, base_radius_mm + p.kin.s + p.kin.d2s)
        if name in GUIDE_CURVES:
            offset = flat_geo.flat_contact_offset(p.kin)
            return getattr(loads.guide_reactions(consts.guide, p.force_N, offset), name)
        return super().curve(name, p, consts, base_radius_mm)

    def summary(self, design) -> str:
        return f"L = {design['face_width_mm']:.4f} mm"

    def drawn_summary(self, data) -> str:
        width = data["evaluated_at"].get("face_width_mm")
        return f", L = {width:.4f} mm" if width is not None else ""


FOLLOWER = Flat()
