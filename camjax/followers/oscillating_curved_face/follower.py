"""The oscillating curved-face follower (SPEC 3): a crowned face of radius R_c on a swinging arm.

The face's circle (radius R_c, its centre at ``arm_length_mm`` l from a pivot at
``pivot_distance_mm`` d from the cam centre) follows the pitch curve of an oscillating roller of
radius R_c, so the pressure angle, the undercut, the contact force and the Hertz stress are that
roller's; the face does not roll, so the contact travels R_c sin phi across it (which the face
width W must cover) and slides on the cam
(:mod:`camjax.followers.oscillating_curved_face.geometry`). Design variables: R_b, R_c, W, d and l
(:mod:`camjax.followers.oscillating_curved_face.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import jax
import numpy as np

from camjax.family import FEASIBILITY_TOL_MM
from camjax.followers import _checks
from camjax.followers._rocking import (
    TRAIN_KEYS,
    RockerCurves,
    RockerGeometry,
    RockerSizing,
    RockingFollower,
    circle_arm_closure_problem,
    read_train,
)
from camjax.followers._swing import relative_rate
from camjax.followers.oscillating_curved_face import geometry as curved_geo
from camjax.followers.oscillating_curved_face.geometry import (
    CURVED_MAX_PRESSURE_ANGLE_DEG,
    CURVED_MIN_CURVATURE_RADIUS_MM,
)
from camjax.followers.oscillating_roller.follower import (
    arm_sizing,
    arm_sizing_result,
    check_rocker_closes,
    circle_contact,
    circle_geometry,
)
from camjax.results import GeometryViolation
from camjax.scene.reader import DEFAULT, build, fixed_or_free
from camjax.scene.spec import FollowerSpec


@dataclass(frozen=True, kw_only=True)
class OscillatingCurvedFaceSpec(FollowerSpec):
    """[follower] of a rocker with a crowned face: pivot, arm, the face's radius and width, limits."""

    type: str = "oscillating_curved_face"
    pivot_distance_mm: float = 0.0  # d, cam centre to pivot (required by the scene)
    arm_length_mm: float = 0.0  # l, pivot to the centre of the face's circle (required)
    face_radius_mm: float = 0.0  # R_c (required)
    face_width_mm: float = 0.0  # W, <= 2 R_c (required)
    max_pressure_angle_deg: float = CURVED_MAX_PRESSURE_ANGLE_DEG
    min_curvature_radius_mm: float = CURVED_MIN_CURVATURE_RADIUS_MM  # 0 = just no undercut


# the rocker's curves and the face's own: its width (mm), where the contact sits on it off its
# axis, R_c sin phi (mm), and the sliding speed of cam and face at the contact (m/s)
OscillatingCurvedCurves = NamedTuple("OscillatingCurvedCurves", [
    *RockerCurves.__annotations__.items(), ("face_width_mm", float), ("face_travel_mm", np.ndarray),
    ("sliding_speed_m_s", np.ndarray)])


def _f(x) -> float:
    return float(np.asarray(x))


def _face_curves(pivot_distance_mm, arm_length_mm, face_radius_mm, kin, cam_speed_rad_s, psi,
                 rotation) -> dict:
    rate = relative_rate(kin, rotation)
    legs = curved_geo.legs(pivot_distance_mm, arm_length_mm, psi, rate)
    return {"face_travel": curved_geo.face_travel_of(legs, face_radius_mm),
            "sliding_speed": curved_geo.sliding_speed_of(legs, rate, face_radius_mm, cam_speed_rad_s)}


# the drawn curves' (concrete values) in one compiled program: op by op its dozen operations would
# each compile on their own, and in the drawing compiled beside the solver (camjax.runtime.ahead)
# each could wait while the solver's program is exported and compiled (measured: one multiply
# waited 1.8 s)
_face_curves_program = jax.jit(_face_curves, static_argnames="rotation")


class OscillatingCurvedFace(RockingFollower):
    name = "oscillating_curved_face"
    title = "oscillating curved-face"
    keys = ("pivot_distance_mm", "arm_length_mm", "face_radius_mm", "face_width_mm", "max_pressure_angle_deg",
            "min_curvature_radius_mm", *TRAIN_KEYS)
    example_scene = "oscillating-curved-face"
    variables = ("base_radius_mm", "face_radius_mm", "face_width_mm", "pivot_distance_mm", "arm_length_mm")

    def parse(self, r) -> OscillatingCurvedFaceSpec:
        """d, l, R_c > 0 and 0 < W <= 2 R_c; whether the geometry closes is checked where the base
        radius is known (the design or the sizing)."""
        self.check_keys(r)
        train = read_train(r)
        pivot = r.number("pivot_distance_mm", low=0.0, low_open=True)
        limit = _checks.read_max_pressure_angle(r)
        radius, width = _checks.read_face(r)
        return build(OscillatingCurvedFaceSpec, type=self.name, train=train, pivot_distance_mm=pivot,
                     arm_length_mm=r.number("arm_length_mm", low=0.0, low_open=True),
                     face_radius_mm=radius, face_width_mm=width, max_pressure_angle_deg=limit,
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        radius, width = _checks.face_bounds(r, follower)
        variables = dict(
            pivot_distance_mm=fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2),
            arm_length_mm=fixed_or_free(r, "arm_length_mm", (follower.arm_length_mm,) * 2))
        _checks.face_fits_circle(r, radius, width)
        check_rocker_closes(r, base, radius, **variables)
        return {"base_radius_mm": base, "face_radius_mm": radius, "face_width_mm": width, **variables}

    # ---- hooks of the rocking family

    def sizing(self, scene, kin, program=None) -> RockerSizing:
        """The smallest prime circle with |phi| <= max_pressure_angle_deg, the contact on the face
        (|phi| <= asin(W / 2 R_c)) and no undercut, minus R_c: the oscillating roller's sizing
        (:func:`camjax.followers.oscillating_roller.follower.arm_sizing`) with R_f = R_c and the
        limit min(phi_max, asin(W / 2 R_c)), as
        :func:`camjax.followers.oscillating_curved_face.geometry.min_prime_radius`."""
        f = scene.follower
        face = _f(curved_geo.face_travel_limit_rad(f.face_radius_mm, f.face_width_mm))
        limit = min(math.radians(f.max_pressure_angle_deg), face)
        sampled, boundary = arm_sizing(kin, program, f.pivot_distance_mm, f.arm_length_mm, f.face_radius_mm,
                                       limit, f.min_curvature_radius_mm, scene.motion.rotation)
        angle = "face_travel" if face < math.radians(f.max_pressure_angle_deg) else "pressure_angle"
        return arm_sizing_result(kin, sampled, boundary, f, f.max_pressure_angle_deg, f.face_radius_mm, angle,
                                 f"and the contact on the face (W = {f.face_width_mm:g} mm) without undercut")

    def closure_problem(self, scene, kin, base_radius_mm) -> str | None:
        """As the oscillating roller's with R_f = R_c: |d - l| < R_b + R_c < d + l and the arm stays
        off the line of centres while it swings."""
        return circle_arm_closure_problem(scene, kin, base_radius_mm, scene.follower.face_radius_mm,
                                          "the face cannot reach the prime circle R_p = R_b + R_c")

    def geometry(self, scene, kin, base_radius_mm) -> RockerGeometry:
        return circle_geometry(scene, kin, base_radius_mm, scene.follower.face_radius_mm, curved_geo.geometry,
                               curved_geo.profile)

    def contact(self, scene, moment, g):
        """The oscillating roller's with R_f = R_c: the normal runs through the face's centre, so
        P = M / (l cos phi); Hertz line contact of the cam and the crowned face."""
        return circle_contact(scene, moment, g, scene.follower.face_radius_mm)

    def face_curves(self, scene, kin, cam_speed_rad_s, psi) -> dict:
        """The face's own curves at arm angles psi (rad): ``face_travel`` (mm, R_c sin phi) and
        ``sliding_speed`` (m/s); pointwise in the motion."""
        f = scene.follower
        return _face_curves(f.pivot_distance_mm, f.arm_length_mm, f.face_radius_mm, kin, cam_speed_rad_s, psi,
                            scene.motion.rotation)

    def point_curves(self, scene, kin, cam_speed_rad_s, base_radius_mm) -> dict:
        """The rocking family's curves and the face's (:meth:`face_curves`)."""
        out = super().point_curves(scene, kin, cam_speed_rad_s, base_radius_mm)
        return {**out, **self.face_curves(scene, kin, cam_speed_rad_s, out["arm_angle"])}

    def evaluate(self, scene, kin, cam_speed_rad_s, base_radius_mm) -> OscillatingCurvedCurves:
        """The rocker's curves with the face's width, the contact's travel on it and the sliding speed."""
        curves = super().evaluate(scene, kin, cam_speed_rad_s, base_radius_mm)
        f, psi = scene.follower, np.radians(curves.arm_angle_deg)
        face = _face_curves_program(f.pivot_distance_mm, f.arm_length_mm, f.face_radius_mm, kin,
                                    cam_speed_rad_s, psi, scene.motion.rotation)
        return OscillatingCurvedCurves(
            **curves._asdict(), face_width_mm=float(f.face_width_mm),
            face_travel_mm=np.asarray(face["face_travel"]),
            sliding_speed_m_s=np.asarray(face["sliding_speed"]))

    def run(self, scene, arrays=None, *, base_radius_mm=None, dtype=None):
        """The rocking family's run, with the face-width check added to the violations."""
        out = super().run(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)
        return out._replace(violations=out.violations + tuple(face_violations(out.curves, out.extremes)))

    def summary(self, design) -> str:
        return (f"R_c = {design['face_radius_mm']:.4f} mm, W = {design['face_width_mm']:.4f} mm, "
                f"pivot {design['pivot_distance_mm']:.4f} mm, arm {design['arm_length_mm']:.4f} mm, "
                f"R_p = {design['prime_radius_mm']:.4f} mm")

    def title_dimensions(self, data) -> list[str]:
        rocker = data.get("oscillating_follower", {})
        if not rocker:
            return []
        return [f"d = {rocker['pivot_distance_mm']:g} mm, l = {rocker['arm_length_mm']:g} mm, "
                f"R_c = {rocker['face_radius_mm']:g} mm, W = {rocker['face_width_mm']:.4g} mm"]


def face_violations(curves, extremes=None) -> list[GeometryViolation]:
    """The contact running off the face: max |R_c sin phi| > W / 2 (the solvers' tolerance), on the
    exact extrema where ``extremes`` has them, else on the samples."""
    e = (extremes or {}).get("face_travel")
    if e is None:
        travel = np.abs(np.asarray(curves.face_travel_mm))
        worst = (float(np.max(travel)), float(curves.theta_deg[int(np.argmax(travel))]))
    else:
        worst = max((e.max, e.max_deg), (-e.min, e.min_deg))
    need, deg = 2.0 * worst[0], worst[1]
    if curves.face_width_mm >= need - FEASIBILITY_TOL_MM:
        return []
    return [GeometryViolation("face_width", f"face width {curves.face_width_mm:.4g} mm < "
                              f"2 max|R_c sin phi| = "
                              f"{need:.4g} mm (at {deg:g} deg): the contact runs off the face")]


FOLLOWER = OscillatingCurvedFace()
