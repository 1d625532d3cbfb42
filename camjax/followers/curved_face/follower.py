"""The translating curved-face (mushroom) follower (SPEC 3): a crowned face of radius R_c.

The face's circle follows the pitch curve of a roller of radius R_c, so the pressure angle, the
undercut and the Hertz stress are the roller's with R_f = R_c; the face does not roll, so the
contact travels R_c sin phi across it (which the face width W must cover) and slides on the cam
(:mod:`camjax.followers.curved_face.geometry`). The design variables are R_b, R_c, W and the
offset e (:mod:`camjax.followers.curved_face.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import program, runtime
from camjax.evaluate import curve_extremes
from camjax.followers import _checks
from camjax.followers._pitch import rotation_sign
from camjax.followers._translating import (
    TRAIN_KEYS,
    DesignSolution,
    GeometryCurves,
    TranslatingFollower,
    read_train,
)
from camjax.followers.curved_face import geometry as curved_geo
from camjax.followers.curved_face.geometry import (
    CURVED_MAX_PRESSURE_ANGLE_DEG,
    CURVED_MIN_CURVATURE_RADIUS_MM,
)
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller.follower import exact_prime_radius
from camjax.results import MinBaseRadius
from camjax.scene.reader import DEFAULT, build, fixed_or_free
from camjax.scene.spec import FollowerSpec

# the curved face's curves at the drawing radius: the roller's (pressure angle, rad; |pitch-curve
# rho| and the undercut margin, mm), the contact's travel on the face R_c sin phi (mm) and the
# sliding speed (m/s)
CURVED_CURVES = ("pressure_angle", "pitch_rho_abs", "undercut_margin", "face_travel", "sliding_speed")
# the angle-limit sizing: |s' - e~| / tan(limit) - s (mm), limit = min(phi_max, asin(W / 2 R_c))
PRESSURE_NEED = "pressure_angle_need"


# the sampled sizing, one compiled (and saved) program for every call
_grid_sizing = runtime.program_cache(curved_geo.min_prime_radius, static_argnames=("rotation",))

@dataclass(frozen=True, kw_only=True)
class CurvedFaceSpec(FollowerSpec):
    """[follower] of a curved face: its crown radius and width, the axis' offset and the limits."""

    type: str = "curved_face"
    face_radius_mm: float = 0.0  # R_c (required by the scene)
    face_width_mm: float = 0.0  # W, <= 2 R_c (required by the scene)
    offset_mm: float = 0.0  # e, the follower axis' distance from the cam centre
    max_pressure_angle_deg: float = CURVED_MAX_PRESSURE_ANGLE_DEG
    min_curvature_radius_mm: float = CURVED_MIN_CURVATURE_RADIUS_MM  # 0 = just no undercut


class CurvedCurveConstants(NamedTuple):
    """What the curved face's curves need besides the motion (offset times the rotation sign, as
    :class:`camjax.followers.roller.follower.RollerCurveConstants`)."""

    face_radius_mm: jax.Array
    offset_mm: jax.Array  # rotation_sign * e
    rotation_sign: jax.Array  # +1 ccw, -1 cw
    min_curvature_radius_mm: jax.Array
    tan_angle_limit: jax.Array  # tan(min(phi_max, asin(W / 2 R_c))): the sizing's limit
    cam_speed_rad_s: jax.Array


def _f(x) -> float:
    return float(np.asarray(x))


def _angle_limit_rad(f) -> float:
    """min(phi_max, asin(W / 2 R_c)) (rad): where the pressure angle or the face's edge binds."""
    edge = math.asin(min(f.face_width_mm / (2 * f.face_radius_mm), 1.0))
    return min(math.radians(f.max_pressure_angle_deg), edge)


class CurvedFace(TranslatingFollower):
    name = "curved_face"
    title = "curved-face"
    keys = (*TRAIN_KEYS, "face_radius_mm", "face_width_mm", "offset_mm", "max_pressure_angle_deg",
            "min_curvature_radius_mm")
    example_scene = "curved-face"
    variables = ("base_radius_mm", "face_radius_mm", "face_width_mm", "offset_mm")
    sizing_curves = (PRESSURE_NEED,)

    def parse(self, r) -> CurvedFaceSpec:
        self.check_keys(r)
        train = read_train(r)
        limit = _checks.read_max_pressure_angle(r)
        radius, width = _checks.read_face(r)
        return build(CurvedFaceSpec, type=self.name, train=train, face_radius_mm=radius, face_width_mm=width,
                     offset_mm=r.number("offset_mm", DEFAULT), max_pressure_angle_deg=limit,
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        radius, width = _checks.face_bounds(r, follower)
        offset = fixed_or_free(r, "offset_mm", (follower.offset_mm,) * 2, positive=False)
        # refused only when no design in the bounds has |e| < R_p
        _checks.offset_cuts_prime_circle(r, offset, base[1] + radius[1], "R_b + R_c")
        _checks.face_fits_circle(r, radius, width)
        return {"base_radius_mm": base, "face_radius_mm": radius, "face_width_mm": width, "offset_mm": offset}

    def drawn_follower(self, scene, result):
        """The [follower] with a design's R_c, W and offset."""
        if "face_radius_mm" not in result:
            return scene.follower
        return replace(scene.follower, face_radius_mm=result["face_radius_mm"],
                       face_width_mm=result["face_width_mm"], offset_mm=result["offset_mm"])

    def _sizing(self, scene, arrays, follower) -> MinBaseRadius:
        f, t = follower, np.asarray(arrays.theta_deg)
        sizing, face = _grid_sizing(arrays.kin, f.face_radius_mm, f.face_width_mm, f.offset_mm,
                                    math.radians(f.max_pressure_angle_deg), f.min_curvature_radius_mm,
                                    scene.motion.rotation)
        angle = "face_travel" if bool(face) else "pressure_angle"
        if arrays.model is not None:  # exact: the pressure angle's and the undercut's limits refined
            def need():
                return curve_extremes(scene, arrays, (PRESSURE_NEED,), follower=follower)[PRESSURE_NEED]

            rp, deg, undercut = exact_prime_radius(arrays, sizing.prime_radius_mm, need, f.face_radius_mm,
                                                   f.offset_mm, f.min_curvature_radius_mm,
                                                   scene.motion.rotation)
            return MinBaseRadius(rp - f.face_radius_mm, deg, "undercut" if undercut else angle, rp)
        if bool(sizing.undercut_binds):
            return MinBaseRadius(_f(sizing.prime_radius_mm) - f.face_radius_mm, _f(t[int(sizing.index)]),
                                 "undercut", _f(sizing.prime_radius_mm))
        return MinBaseRadius(_f(sizing.prime_radius_mm) - f.face_radius_mm, _f(t[int(sizing.index)]), angle,
                             _f(sizing.prime_radius_mm))

    def min_base_radius(self, scene, arrays) -> MinBaseRadius:
        """The smallest prime circle with |phi| <= max_pressure_angle_deg, the contact on the face
        (|phi| <= asin(W / 2 R_c)) and no undercut at the follower's R_c, W and offset, minus R_c:
        the roller's sizing with the smaller angle limit
        (:func:`camjax.followers.curved_face.geometry.min_prime_radius`)."""
        return self._sizing(scene, arrays, scene.follower)

    def design_solution(self, scene, arrays, result, problem) -> DesignSolution:
        """A design's figures: its peak stress as the stress curve computes it, and the smallest R_b
        its R_c, W and offset admit (pressure angle, face travel and undercut; stress aside)."""
        drawn = self.drawn_follower(scene, result)
        curves = self.curves(scene, arrays, result["base_radius_mm"], drawn)
        minimum = self._sizing(scene, arrays, drawn)
        peak_stress = None if curves.stress_MPa is None else _f(np.max(curves.stress_MPa))
        return DesignSolution(result, peak_stress, minimum.radius_mm, minimum.angle_deg, minimum.binding,
                              None,
                              scene.follower.min_curvature_radius_mm)

    def geometry(self, follower, rotation, arrays, base_radius_mm) -> GeometryCurves:
        kin, rc, e = arrays.kin, follower.face_radius_mm, follower.offset_mm
        x, y = curved_geo.profile(base_radius_mm, rc, e, kin, rotation)
        pitch_x, pitch_y = roller_geo.roller_pitch_curve(base_radius_mm, rc, e, kin, rotation)
        g = curved_geo.geometry(base_radius_mm, rc, e, kin, rotation, follower.min_curvature_radius_mm)
        coefficient = arrays.stress_coefficient
        stress = roller_geo.roller_contact_stress(coefficient, g.pitch_curvature, g.pressure_angle, rc)
        own = {"face_travel_mm": curved_geo.face_travel(base_radius_mm, rc, e, kin, rotation),
               "sliding_speed_m_s": curved_geo.sliding_speed_m_s(base_radius_mm, rc, e, kin,
                                                                 arrays.cam_speed_rad_s, rotation)}
        width = jnp.asarray(follower.face_width_mm)
        return GeometryCurves(x, y, stress_MPa=stress, face_width_mm=width,
                              pitch_x_mm=pitch_x, pitch_y_mm=pitch_y,
                              pressure_angle_deg=jnp.rad2deg(g.pressure_angle),
                              pitch_rho_mm=g.pitch_radius_of_curvature, undercut_margin_mm=g.undercut_margin,
                              own_curves=own)

    def drawn_face_width(self, face_width_mm, geometry_width) -> float:
        """The drawn follower's W (the geometry carries it)."""
        return float(np.asarray(geometry_width)) if face_width_mm is None else face_width_mm

    def curve_dimensions(self, follower):
        """(R_c, offset, pressure-angle limit): the circle that touches the cam is the face's."""
        return (float(follower.face_radius_mm), float(follower.offset_mm), follower.max_pressure_angle_deg)

    def curve_names(self, scene, arrays) -> tuple[str, ...]:
        return CURVED_CURVES

    def curve_constants(self, scene, follower) -> CurvedCurveConstants:
        sign = rotation_sign(scene.motion.rotation)
        return CurvedCurveConstants(float(follower.face_radius_mm), sign * float(follower.offset_mm), sign,
                                    follower.min_curvature_radius_mm, math.tan(_angle_limit_rad(follower)),
                                    program.rpm_to_rad_s(scene.motion.rpm))

    def curve(self, name, p, consts, base_radius_mm):
        c = consts.follower
        if name == PRESSURE_NEED:
            return roller_geo.roller_pressure_angle_need(p.kin.ds, p.kin.s, c.offset_mm, c.tan_angle_limit)
        g = roller_geo.roller_geometry(base_radius_mm, c.face_radius_mm, c.offset_mm, p.kin, "ccw",
                                       c.min_curvature_radius_mm)
        if name == "stress":  # contact stress, MPa (even in phi)
            return roller_geo.roller_contact_stress(p.stress_coefficient, g.pitch_curvature, g.pressure_angle,
                                                    c.face_radius_mm)
        if name in CURVED_CURVES:
            w = roller_geo.roller_pitch_height(base_radius_mm, c.face_radius_mm, c.offset_mm, p.kin)
            u = p.kin.ds - c.offset_mm
            return {"pressure_angle": c.rotation_sign * g.pressure_angle,
                    "undercut_margin": g.undercut_margin,
                    "pitch_rho_abs": jnp.abs(g.pitch_radius_of_curvature),
                    "face_travel": c.rotation_sign * curved_geo.face_travel_of(w, u, c.face_radius_mm),
                    "sliding_speed": curved_geo.sliding_speed_of(w, u, c.face_radius_mm, c.cam_speed_rad_s),
                    }[name]
        return super().curve(name, p, consts, base_radius_mm)

    def summary(self, design) -> str:
        return (f"R_c = {design['face_radius_mm']:.4f} mm, W = {design['face_width_mm']:.4f} mm, "
                f"offset {design['offset_mm']:.4f} mm, R_p = {design['prime_radius_mm']:.4f} mm")

    def title_dimensions(self, data) -> list[str]:
        face = data.get("curved_face")  # W: the shared line's L
        return [f"R_c = {face['face_radius_mm']:g} mm, e = {face['offset_mm']:g} mm"] if face else []

    def drawn_summary(self, data) -> str:
        face = data["curved_face"]
        return (f", R_c = {face['face_radius_mm']:.4f} mm, W = {face['face_width_mm']:.4f} mm, "
                f"offset {face['offset_mm']:.4f} mm")


FOLLOWER = CurvedFace()
