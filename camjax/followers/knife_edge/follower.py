"""The translating knife-edge follower with offset (SPEC 3): the roller with R_f = 0.

The edge's tip follows the pitch curve, which is the cam profile itself (R_p = R_b). The limits
are the pressure angle (|phi| <= ``max_pressure_angle_deg``) and the profile's convex radius of
curvature (>= ``min_curvature_radius_mm``: a sharp crest wears the edge; no undercut, nothing is
offset from the pitch curve); the design variables are R_b and the offset e
(:mod:`camjax.followers.knife_edge.problem`). No contact stress: the Hertz stress of a point
contact of zero radius is unbounded, so a scene with [contact] is refused (``takes_contact``).

The run is the roller's (:class:`camjax.followers.roller.follower.Roller`) with R_f = 0: its
sizing, curves and exact extrema hold at R_f = 0 (the roller's curve named ``undercut_margin`` is,
here, the convex-radius margin rho - rho_min, named ``curvature`` in what the knife edge reports).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import jax.numpy as jnp
import numpy as np

from camjax.followers import _checks
from camjax.followers._translating import (
    TRAIN_KEYS,
    DesignSolution,
    GeometryCurves,
    least_abs_offset,
    read_train,
)
from camjax.followers.knife_edge import geometry as knife_geo
from camjax.followers.roller.follower import Roller, RollerSpec
from camjax.results import GeometryViolation, MinBaseRadius
from camjax.scene.reader import DEFAULT, build, fixed_or_free

_BINDING = {"undercut": "curvature"}  # the roller's name of a limit -> the knife edge's


@dataclass(frozen=True, kw_only=True)
class KnifeEdgeSpec(RollerSpec):
    """[follower] of a knife edge: the axis' offset and the two limits (a roller of radius 0)."""

    type: str = "knife_edge"
    roller_radius_mm: float = 0.0  # always 0 (not a scene key): the roller's run reads it
    max_pressure_angle_deg: float = knife_geo.KNIFE_EDGE_MAX_PRESSURE_ANGLE_DEG
    min_curvature_radius_mm: float = knife_geo.KNIFE_EDGE_MIN_CURVATURE_RADIUS_MM  # 0 = no limit


def _f(x) -> float:
    return float(np.asarray(x))


class KnifeEdge(Roller):
    name = "knife_edge"
    title = "knife-edge"
    keys = (*TRAIN_KEYS, "offset_mm", "max_pressure_angle_deg", "min_curvature_radius_mm")
    example_scene = "knife-edge"
    variables = ("base_radius_mm", "offset_mm")
    takes_contact = False  # a point contact of zero radius: the Hertz stress is unbounded
    closures = ("spring",)  # a groove or a second cam needs a roller of some radius

    def parse(self, r) -> KnifeEdgeSpec:
        self.check_keys(r)
        train = read_train(r)
        limit = _checks.read_max_pressure_angle(r)
        return build(KnifeEdgeSpec, type=self.name, train=train, offset_mm=r.number("offset_mm", DEFAULT),
                     max_pressure_angle_deg=limit,
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        offset = fixed_or_free(r, "offset_mm", (follower.offset_mm,) * 2, positive=False)
        # |e| < R_b is a constraint of the problem (its pressure-angle constraint holds only there):
        # refused here only when no design in the bounds meets it
        if least_abs_offset(offset) >= base[1]:
            raise r.error("offset_mm", list(offset) if offset[0] != offset[1] else offset[0],
                          f"gives |e| >= R_b for every design in the bounds (largest R_b: {base[1]:g} mm): "
                          "the follower axis must cut the base circle",
                          f"|e| < {base[1]:g} somewhere in the bounds")
        return {"base_radius_mm": base, "offset_mm": offset}

    def drawn_follower(self, scene, result):
        """The [follower] with a design's offset."""
        if "offset_mm" not in result:
            return scene.follower
        return replace(scene.follower, offset_mm=result["offset_mm"])

    def min_base_radius(self, scene, arrays) -> MinBaseRadius:
        """The roller's sizing at R_f = 0: the smallest base circle with |phi| <= the limit and a
        convex profile radius >= ``min_curvature_radius_mm`` at the follower's offset."""
        m = super().min_base_radius(scene, arrays)
        return m._replace(binding=_BINDING.get(m.binding, m.binding))

    def design_solution(self, scene, arrays, result, problem) -> DesignSolution:
        """A knife-edge design's figures: the smallest R_b its offset admits and the limit there."""
        f, t = scene.follower, np.asarray(arrays.theta_deg)
        # knife_geo.knife_edge_min_base_radius through the roller's compiled program (R_f = 0), the
        # one min_base_radius ran: evaluated operation by operation it compiled ~40 small programs
        sizing = self.sampled_sizing(scene, arrays, 0.0, result["offset_mm"])
        return DesignSolution(result, None, _f(sizing.prime_radius_mm), _f(t[int(sizing.index)]),
                              "curvature" if bool(sizing.undercut_binds) else "pressure_angle", None,
                              f.min_curvature_radius_mm)

    def geometry(self, follower, rotation, arrays, base_radius_mm) -> GeometryCurves:
        kin, e = arrays.kin, follower.offset_mm
        x, y = knife_geo.knife_edge_profile(base_radius_mm, e, kin, rotation)
        g = knife_geo.knife_edge_geometry(base_radius_mm, e, kin, rotation, follower.min_curvature_radius_mm)
        # the tip is the pitch point: the pitch curve is the outline
        return GeometryCurves(x, y, pitch_x_mm=x, pitch_y_mm=y,
                              pressure_angle_deg=jnp.rad2deg(g.pressure_angle),
                              pitch_rho_mm=g.radius_of_curvature, undercut_margin_mm=g.curvature_margin)

    def run(self, scene, arrays=None, *, base_radius_mm=None, dtype=None):
        """The roller's run at R_f = 0, its undercut check told as the profile's curvature limit."""
        run = super().run(scene, arrays, base_radius_mm=base_radius_mm, dtype=dtype)
        return run._replace(violations=tuple(_curvature(v, scene.follower.min_curvature_radius_mm, run)
                                             for v in run.violations))

    def summary(self, design) -> str:
        return f"offset {design['offset_mm']:.4f} mm"

    def title_dimensions(self, data) -> list[str]:
        knife = data.get("knife_edge")
        return [f"knife edge, e = {knife['offset_mm']:g} mm"] if knife else []

    def drawn_summary(self, data) -> str:
        return f", offset {data['knife_edge']['offset_mm']:.4f} mm"


def _curvature(v: GeometryViolation, rho_min_mm: float, run) -> GeometryViolation:
    """The roller's undercut violation (margin rho - rho_min < 0 on a convex part) in the knife
    edge's words; any other violation as it is."""
    if v.constraint != "undercut":
        return v
    margin = run.extremes.get("undercut_margin") if run.extremes else None
    if margin is not None:
        at, deg = margin.min, margin.min_deg
    else:
        i = int(np.argmin(run.curves.undercut_margin_mm))
        at, deg = float(run.curves.undercut_margin_mm[i]), float(run.curves.theta_deg[i])
    return GeometryViolation("curvature", f"smallest convex profile radius {at + rho_min_mm:.4g} mm at "
                             f"{deg:g} deg < min_curvature_radius_mm = {rho_min_mm:g} mm: the crest is too "
                             "sharp for the knife edge")


FOLLOWER = KnifeEdge()
