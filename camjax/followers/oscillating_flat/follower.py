"""The oscillating (rocker) flat-face follower (SPEC 3): a face on an arm swinging about a pivot.

The face is a line at ``face_offset_mm`` f from the pivot, which sits at ``pivot_distance_mm`` d
from the cam centre; the cam's radius of curvature must stay above ``min_curvature_radius_mm``
(:mod:`camjax.followers.oscillating_flat.geometry` for the closed forms). Design variables: R_b, d
and f (:mod:`camjax.followers.oscillating_flat.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from camjax import contact, loads, runtime
from camjax.errors import SceneError
from camjax.followers._rocking import TRAIN_KEYS, RockerGeometry, RockerSizing, RockingFollower, read_train
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_flat.geometry import OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM
from camjax.scene.reader import DEFAULT, build, fixed_or_free
from camjax.scene.spec import FollowerSpec


@runtime.program_cache(static_argnames=("rotation",))
def flat_sizing(kin, program, pivot_distance_mm, face_offset_mm, min_curvature_radius_mm, rotation):
    """The sizing in one compiled (and saved) program: the samples'
    (:func:`camjax.followers.oscillating_flat.geometry.oscillating_flat_min_base_radius`) and, with
    ``program`` (exact extrema; None: grid), the smallest psi0 from the samples' up with
    rho >= rho_min at every cam angle (:func:`camjax.followers._sizing.exact_boundary`). Returns
    (sampled sizing, :class:`camjax.followers._sizing.Boundary` or None)."""
    from camjax.followers import _sizing
    from camjax.followers._pitch import rotation_sign

    s = rocker_flat_geo.oscillating_flat_min_base_radius(kin, pivot_distance_mm, face_offset_mm,
                                                         min_curvature_radius_mm, rotation)
    if program is None:
        return s, None
    values = (pivot_distance_mm, face_offset_mm, rotation_sign(rotation), min_curvature_radius_mm)
    params = tuple(jnp.asarray(v, kin.s.dtype) for v in values)
    return s, _sizing.exact_boundary(program, kin, s.arm_start_angle, 0.5 * jnp.pi - jnp.max(kin.s), params,
                                     limits=rocker_flat_geo.sizing_limits)

@dataclass(frozen=True, kw_only=True)
class OscillatingFlatSpec(FollowerSpec):
    """[follower] of a rocker with a flat face: pivot, face offset and the curvature limit."""

    type: str = "oscillating_flat"
    pivot_distance_mm: float = 0.0  # d, cam centre to pivot (required by the scene)
    face_offset_mm: float = 0.0  # f, the face line's distance from the pivot
    # a flat face's own default (rho > 0: a face on rho = 0 rides a corner)
    min_curvature_radius_mm: float = OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM


def _f(x) -> float:
    return float(np.asarray(x))


class OscillatingFlat(RockingFollower):
    name = "oscillating_flat"
    title = "oscillating flat-face"
    keys = ("pivot_distance_mm", "face_offset_mm", "min_curvature_radius_mm", *TRAIN_KEYS)
    example_scene = "oscillating-flat"
    variables = ("base_radius_mm", "pivot_distance_mm", "face_offset_mm")

    def parse(self, r) -> OscillatingFlatSpec:
        self.check_keys(r)
        train = read_train(r)
        pivot = r.number("pivot_distance_mm", low=0.0, low_open=True)
        return build(OscillatingFlatSpec, type=self.name, train=train, pivot_distance_mm=pivot,
                     face_offset_mm=r.number("face_offset_mm", DEFAULT),
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0,
                                                      low_open=True))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        pivot = fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2)
        offset = fixed_or_free(r, "face_offset_mm", (follower.face_offset_mm,) * 2, positive=False)
        if base[0] + offset[0] >= pivot[1] or base[1] + offset[1] <= 0:
            raise r.error("pivot_distance_mm", list(pivot) if pivot[0] != pivot[1] else pivot[0],
                          f"no design in the bounds closes: R_b + face_offset ({base[0] + offset[0]:g}.."
                          f"{base[1] + offset[1]:g} mm) must lie between 0 and the pivot distance",
                          "a larger pivot distance")
        return {"base_radius_mm": base, "pivot_distance_mm": pivot, "face_offset_mm": offset}

    def sizing(self, scene, kin, program=None) -> RockerSizing:
        f = scene.follower
        s, b = flat_sizing(kin, program, f.pivot_distance_mm, f.face_offset_mm, f.min_curvature_radius_mm,
                           scene.motion.rotation)
        if not bool(s.found) or (b is not None and not bool(b.refined)):
            where = "" if not bool(s.found) else (f" at every cam angle (the {kin.s.shape[-1]} samples "
                                                  'alone admit one: extrema = "grid" sizes on them)')
            raise SceneError("follower.pivot_distance_mm", f.pivot_distance_mm,
                             f"with face_offset_mm = {f.face_offset_mm:g} no base radius keeps the cam's "
                             f"radius of curvature >= {f.min_curvature_radius_mm:g} mm{where}",
                             "a larger pivot distance")
        if b is not None:  # exact: rho >= rho_min between the samples too
            rb = f.pivot_distance_mm * math.sin(_f(b.x)) - f.face_offset_mm
            return RockerSizing(rb, None, _f(b.angle_deg), "curvature")
        t = np.degrees(np.asarray(kin.theta))
        return RockerSizing(_f(s.base_radius_mm), None, _f(t[int(s.index)]), "curvature")

    def closure_problem(self, scene, kin, base_radius_mm) -> str | None:
        """0 < R_b + f < d and the face keeps rising (psi0 + max s < pi/2)."""
        f = scene.follower
        swing = float(np.max(np.asarray(kin.s)))
        if base_radius_mm <= 0:
            return "the base radius must be > 0"
        d, off = f.pivot_distance_mm, f.face_offset_mm
        if not 0 < base_radius_mm + off < d:
            return (f"the face cannot touch the base circle: needs 0 < R_b + face_offset = "
                    f"{base_radius_mm + off:g} < d = {d:g}")
        psi0 = math.asin((base_radius_mm + off) / d)
        if psi0 + swing >= 0.5 * math.pi:
            return (f"the face starts {math.degrees(psi0):g} deg from the line of centres and the lift "
                    f"({math.degrees(swing):g} deg) turns it past 90 deg, where a rise no longer lifts it")
        return None

    def geometry(self, scene, kin, base_radius_mm) -> RockerGeometry:
        f, rotation = scene.follower, scene.motion.rotation
        d = f.pivot_distance_mm
        g = rocker_flat_geo.oscillating_flat_geometry(d, f.face_offset_mm, base_radius_mm, kin, rotation)
        x, y = rocker_flat_geo.oscillating_flat_profile(d, f.face_offset_mm, base_radius_mm, kin, rotation)
        return RockerGeometry(
            x, y, g.arm_angle, rocker_flat_geo.face_start_angle(base_radius_mm, d, f.face_offset_mm),
            g.pressure_angle, g.radius_of_curvature, contact_distance_mm=g.contact_distance,
            face_offset_mm=f.face_offset_mm)

    def contact(self, scene, moment, g):
        force = loads.rocker_flat_contact_force(moment, g.contact_distance_mm)
        stress = None
        if scene.contact is not None:
            c = scene.contact
            stress = contact.hertz_line_stress(force, g.rho_mm, c.cam_width_mm, c.cam, c.follower)
        return force, stress

    def summary(self, design) -> str:
        return (f"pivot {design['pivot_distance_mm']:.4f} mm, face offset {design['face_offset_mm']:.4f} mm, "
                f"face {design['face_length_mm']:.4f} mm")

    def title_dimensions(self, data) -> list[str]:
        rocker = data.get("oscillating_follower", {})
        if not rocker:
            return []
        return [f"d = {rocker['pivot_distance_mm']:g} mm, f = {rocker['face_offset_mm']:g} mm"]


FOLLOWER = OscillatingFlat()
