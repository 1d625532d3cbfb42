"""The translating roller follower with offset (SPEC 3): pressure angle, undercut, roller stress.

The roller's centre follows the pitch curve at R_p = R_b + R_f; the cam surface is that curve
offset inward by R_f. The limits are the pressure angle (|phi| <= ``max_pressure_angle_deg``) and
the undercut (the convex cam surface's radius >= ``min_curvature_radius_mm``); the design
variables are R_b, R_f and the offset e (:mod:`camjax.followers.roller.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import runtime
from camjax.evaluate import curve_extremes
from camjax.followers import _checks, _closure, _closure_design, _closure_problem
from camjax.followers._closure import POSITIVE_CLOSURES, closure_keys, read_closure
from camjax.followers._pitch import rotation_sign
from camjax.followers._translating import (
    TRAIN_KEYS,
    DesignSolution,
    GeometryCurves,
    TranslatingFollower,
    read_train,
)
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller.geometry import ROLLER_MAX_PRESSURE_ANGLE_DEG, ROLLER_MIN_CURVATURE_RADIUS_MM
from camjax.results import MinBaseRadius
from camjax.scene.reader import DEFAULT, build, fixed_or_free
from camjax.scene.spec import ClosureSpec, FollowerSpec

# the roller's curves at the drawing radius: pressure angle (rad), |pitch-curve rho| (mm), undercut
# margin rho_c - rho_min on convex parts (mm; the largest float on concave ones, as
# camjax.followers.roller.geometry.roller_undercut_margin)
ROLLER_CURVES = ("pressure_angle", "pitch_rho_abs", "undercut_margin")
# the pressure-angle sizing: |s' - e~| / tan(limit) - s (mm), whose max is the smallest
# d = sqrt(R_p^2 - e^2) (camjax.followers.roller.geometry.roller_min_prime_radius_for_pressure_angle)
PRESSURE_NEED = "pressure_angle_need"


# the sampled sizing, one compiled (and saved) program for every call
_grid_sizing = runtime.program_cache(roller_geo.roller_min_prime_radius, static_argnames=("rotation",))


def exact_prime_radius(arrays, grid_prime_radius_mm, pressure_need, roller_radius_mm, offset_mm,
                       min_curvature_radius_mm, rotation) -> tuple[float, float, bool]:
    """The smallest prime radius with the pressure angle and the undercut held at every cam angle
    (exact extrema): the larger of the pressure angle's (closed form at the refined max of the
    pressure-angle need, the :class:`camjax.results.Extremes` that ``pressure_need()`` returns) and
    the undercut's, the latter moved up from the grid's ``grid_prime_radius_mm`` to the root of the
    refined undercut peak (:func:`camjax.followers._sizing.exact_boundary`). Returns (R_p mm, angle
    deg, undercut binds).

    The need is asked for after the root: its program is the drawing's refined extrema, which a
    cold command compiles meanwhile in the thread ahead (:func:`camjax.runtime.ahead`)."""
    from camjax.followers import _sizing

    dtype = arrays.kin.s.dtype
    x0 = float(grid_prime_radius_mm)
    params = (jnp.asarray(rotation_sign(rotation) * offset_mm, dtype),
              jnp.asarray(roller_radius_mm + min_curvature_radius_mm, dtype))
    b = _sizing.exact_boundary(arrays.model.program, arrays.kin, jnp.asarray(x0, dtype),
                               jnp.asarray(1e6 * (1.0 + x0), dtype), params,
                               limits=roller_geo.undercut_limits)
    rp_uc, need = _f(b.x), pressure_need()
    rp_phi = math.hypot(offset_mm, max(need.max, 0.0))
    if rp_uc > rp_phi:
        return rp_uc, _f(b.angle_deg), True
    return rp_phi, need.max_deg, False


@partial(runtime.program_cache, static_argnames=("kind",))
def _second_prime_radius(kin, prime_radius_mm, high_mm, dims, kind: str):
    """The smallest prime radius >= ``prime_radius_mm`` (< ``high_mm``) at which a positive drive's
    second contact holds its limits at every sample (:func:`camjax.followers._closure_problem.second_limits`,
    :func:`camjax.followers._closure_problem.first_admissible_size`), whether one does, and the sample where
    they are tightest there. ``dims``: (sign e, R_f, rho_min, tan(limit), groove clearance, yoke span,
    second roller radius), arrays: one compiled program for every scene of a closure kind and grid."""
    offset, rf, rho_min, tan_lim, clearance, span, radius = dims
    closure = ClosureSpec(kind, clearance_mm=clearance, yoke_span_mm=span, second_roller_radius_mm=radius)

    def limits(rp):
        return _closure_problem.second_limits(closure, kin, prime_radius_mm=rp, signed_offset_mm=offset,
                                      roller_radius_mm=rf, min_curvature_radius_mm=rho_min, tan_limit=tan_lim)

    rp, found = _closure_problem.first_admissible_size(lambda rp: jnp.any(limits(rp) > 0.0), prime_radius_mm,
                                                       high_mm, kin.s.shape[-1])
    return rp, found, jnp.argmax(jnp.max(limits(rp), axis=0))


@partial(jax.jit, static_argnames=("closure", "rotation"))
def _groove_curves(closure, rotation: str, base_radius_mm, roller_radius_mm, offset_mm,
                   min_curvature_radius_mm, kin, pitch_x, pitch_y, inner_x, inner_y, path_force_N, hertz):
    """A groove's curves at one design (:func:`camjax.followers._closure.groove_curves` on the roller's
    geometry), one compiled program: the follower's numbers and the [contact]'s are data."""
    g = roller_geo.roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin, rotation,
                                   min_curvature_radius_mm)
    return _closure.groove_curves(closure, pitch_x, pitch_y, inner_x, inner_y, g.pitch_curvature,
                                  g.pressure_angle, roller_radius_mm, min_curvature_radius_mm, path_force_N,
                                  hertz)


@partial(jax.jit, static_argnames=("rotation",))
def _yoke_curves(second, rotation: str, base_radius_mm, roller_radius_mm, offset_mm, min_curvature_radius_mm,
                 kin, path_force_N, hertz):
    """A yoke's second cam at one design and the first roller's highest centre
    (:func:`camjax.followers._closure.yoke_curves` on the roller's geometry), one compiled program per
    grid and rotation. ``second``: (yoke span mm, second roller radius mm), data like the follower's
    other numbers."""
    span, radius = second
    closure = ClosureSpec("conjugate", yoke_span_mm=span, second_roller_radius_mm=radius)
    g = roller_geo.roller_geometry(base_radius_mm, roller_radius_mm, offset_mm, kin, rotation,
                                   min_curvature_radius_mm)
    return _closure.yoke_curves(closure, base_radius_mm, roller_radius_mm, offset_mm, kin, rotation,
                                min_curvature_radius_mm, g, path_force_N, hertz)


@dataclass(frozen=True, kw_only=True)
class RollerSpec(FollowerSpec):
    """[follower] of a roller: its radius, the axis' offset and the two limits."""

    type: str = "roller"
    roller_radius_mm: float = 0.0  # R_f (required by the scene)
    offset_mm: float = 0.0  # e, the follower axis' distance from the cam centre
    max_pressure_angle_deg: float = ROLLER_MAX_PRESSURE_ANGLE_DEG
    min_curvature_radius_mm: float = ROLLER_MIN_CURVATURE_RADIUS_MM  # 0 = just no undercut


class RollerCurveConstants(NamedTuple):
    """What the roller's curves need besides the motion. The offset is stored times the rotation
    sign (a cw cam is the mirror image of the ccw one with e -> -e), so the curves are the ccw
    formulas of :mod:`camjax.followers._pitch` with the pressure angle's sign restored by
    ``rotation_sign``."""

    roller_radius_mm: jax.Array
    offset_mm: jax.Array  # rotation_sign * e
    rotation_sign: jax.Array  # +1 ccw, -1 cw
    min_curvature_radius_mm: jax.Array  # the undercut margin's rho_min
    tan_pressure_limit: jax.Array  # tan(follower.max_pressure_angle_deg)


def _f(x) -> float:
    return float(np.asarray(x))


class Roller(TranslatingFollower):
    name = "roller"
    title = "roller"
    keys = (*TRAIN_KEYS, "roller_radius_mm", "offset_mm", "max_pressure_angle_deg", "min_curvature_radius_mm",
            *closure_keys(rocking=False))
    closures = POSITIVE_CLOSURES
    example_scene = "roller"
    variables = ("base_radius_mm", "roller_radius_mm", "offset_mm")
    optional_variables = (_closure_design.YOKE_SPAN,)
    sizing_curves = (PRESSURE_NEED,)

    def parse(self, r) -> RollerSpec:
        self.check_keys(r)
        train = read_train(r)
        limit = _checks.read_max_pressure_angle(r)
        roller = r.number("roller_radius_mm", low=0.0, low_open=True)
        return build(RollerSpec, type=self.name, train=train, closure=read_closure(r, False, roller),
                     roller_radius_mm=roller,
                     offset_mm=r.number("offset_mm", DEFAULT), max_pressure_angle_deg=limit,
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        roller = fixed_or_free(r, "roller_radius_mm", (follower.roller_radius_mm,) * 2)
        offset = fixed_or_free(r, "offset_mm", (follower.offset_mm,) * 2, positive=False)
        # refused only when no design in the bounds has |e| < R_p
        _checks.offset_cuts_prime_circle(r, offset, base[1] + roller[1], "R_b + R_f")
        return {"base_radius_mm": base, "roller_radius_mm": roller, "offset_mm": offset,
                **_closure_design.design_bounds(r, follower, False, roller[0])}

    def drawn_follower(self, scene, result):
        """The [follower] with a design's R_f and offset."""
        if "roller_radius_mm" not in result:
            return scene.follower
        return replace(scene.follower, roller_radius_mm=result["roller_radius_mm"],
                       offset_mm=result["offset_mm"], closure=scene.follower.closure.designed(result))

    def min_base_radius(self, scene, arrays) -> MinBaseRadius:
        """The smallest prime circle with |phi| <= max_pressure_angle_deg and no undercut (convex
        cam-surface radius >= min_curvature_radius_mm) at the follower's R_f and offset
        (:func:`camjax.followers.roller.geometry.roller_min_prime_radius`: closed form for the
        pressure angle, its max over the angle refined off the grid with exact extrema; bisection
        on the samples for the undercut, with exact extrema moved on to the root of its refined
        peak, :func:`exact_prime_radius`), minus R_f; the angle is where the binding limit is reached.
        """
        first = self._first_min_base_radius(scene, arrays)
        if not scene.follower.closure.positive:
            return first
        return self._second_min_base_radius(scene, arrays, first)

    def sampled_sizing(self, scene, arrays, roller_radius_mm, offset_mm) -> roller_geo.RollerSizing:
        """The smallest prime radius on the samples (:func:`camjax.followers.roller.geometry.
        roller_min_prime_radius`) for roller radius and offset (mm), the scene's limits and rotation:
        one compiled (and saved) program for every call, the design's check included."""
        f = scene.follower
        return _grid_sizing(arrays.kin, roller_radius_mm, offset_mm, math.radians(f.max_pressure_angle_deg),
                            f.min_curvature_radius_mm, scene.motion.rotation)

    def _first_min_base_radius(self, scene, arrays) -> MinBaseRadius:
        f, t = scene.follower, np.asarray(arrays.theta_deg)
        sizing = self.sampled_sizing(scene, arrays, f.roller_radius_mm, f.offset_mm)
        rp = _f(sizing.prime_radius_mm)
        if arrays.model is not None:
            # exact: the pressure angle's closed form at its refined max (>= the samples' max) and
            # the undercut's root of its refined peak, the larger of the two
            def need():
                return curve_extremes(scene, arrays, (PRESSURE_NEED,))[PRESSURE_NEED]

            rp, deg, undercut = exact_prime_radius(arrays, rp, need, f.roller_radius_mm, f.offset_mm,
                                                   f.min_curvature_radius_mm, scene.motion.rotation)
            binding = "undercut" if undercut else "pressure_angle"
            return MinBaseRadius(rp - f.roller_radius_mm, deg, binding, rp)
        return MinBaseRadius(rp - f.roller_radius_mm, _f(t[int(sizing.index)]),
                             "undercut" if bool(sizing.undercut_binds) else "pressure_angle", rp)

    def _second_min_base_radius(self, scene, arrays, first: MinBaseRadius) -> MinBaseRadius:
        """The first contact's smallest cam raised, where the positive drive's second contact (outer
        flank, yoke's cam) breaks its limits there, to the smallest prime radius where it holds them
        too (on the samples; the first's hold at every larger one). Where none does (a yoke's
        second cam shrinks as the first grows) the first's stays and the drawn cam reports it."""
        f, c, kin = scene.follower, scene.follower.closure, arrays.kin
        dt = kin.s.dtype
        dims = tuple(jnp.asarray(v, dt) for v in (
            rotation_sign(scene.motion.rotation) * f.offset_mm, f.roller_radius_mm, f.min_curvature_radius_mm,
            math.tan(math.radians(f.max_pressure_angle_deg)), c.clearance_mm, c.yoke_span_mm or 0.0,
            c.second_roller_radius_mm or 0.0))
        rp0 = jnp.asarray(first.prime_radius_mm, dt)
        high = 10.0 * rp0 + 10.0 * (f.roller_radius_mm + c.clearance_mm)
        rp, found, worst = _second_prime_radius(kin, rp0, high, dims, kind=c.kind)
        rp = _f(rp)
        if not bool(found) or rp <= first.prime_radius_mm:
            return first
        deg = _f(np.asarray(arrays.theta_deg)[int(worst)])
        binding = "outer_flank" if c.kind == "groove" else "conjugate"
        return MinBaseRadius(rp - f.roller_radius_mm, deg, binding, rp)

    def design_solution(self, scene, arrays, result, problem) -> DesignSolution:
        """A roller design's figures: its peak stress as the stress curve computes it, and the
        smallest R_b its R_f and offset admit (pressure angle and undercut; stress aside)."""
        f, t = scene.follower, np.asarray(arrays.theta_deg)
        rf, e = result["roller_radius_mm"], result["offset_mm"]
        drawn = self.drawn_follower(scene, result)
        curves = self.curves(scene, arrays, result["base_radius_mm"], drawn)
        sizing = self.sampled_sizing(scene, arrays, rf, e)
        peak_stress = None if curves.stress_MPa is None else _f(np.max(curves.stress_MPa))
        rp, deg, undercut = _f(sizing.prime_radius_mm), _f(t[int(sizing.index)]), bool(sizing.undercut_binds)
        if arrays.model is not None:  # exact, as min_base_radius
            def need():
                return curve_extremes(scene, arrays, (PRESSURE_NEED,), follower=drawn)[PRESSURE_NEED]

            rp, deg, undercut = exact_prime_radius(arrays, rp, need, rf, e, f.min_curvature_radius_mm,
                                                   scene.motion.rotation)
        return DesignSolution(result, peak_stress, rp - rf, deg, "undercut" if undercut else "pressure_angle",
                              None, f.min_curvature_radius_mm)

    def geometry(self, follower, rotation, arrays, base_radius_mm) -> GeometryCurves:
        kin, rf, e = arrays.kin, follower.roller_radius_mm, follower.offset_mm
        x, y = roller_geo.roller_profile(base_radius_mm, rf, e, kin, rotation)
        pitch_x, pitch_y = roller_geo.roller_pitch_curve(base_radius_mm, rf, e, kin, rotation)
        g = roller_geo.roller_geometry(base_radius_mm, rf, e, kin, rotation, follower.min_curvature_radius_mm)
        coefficient = arrays.stress_coefficient
        stress = roller_geo.roller_contact_stress(coefficient, g.pitch_curvature, g.pressure_angle, rf)
        return GeometryCurves(x, y, stress_MPa=stress, pitch_x_mm=pitch_x, pitch_y_mm=pitch_y,
                              pressure_angle_deg=jnp.rad2deg(g.pressure_angle),
                              pitch_rho_mm=g.pitch_radius_of_curvature, undercut_margin_mm=g.undercut_margin)

    def closure_curves(self, scene, arrays, base_radius_mm, follower, geometry):
        """Both flanks of a groove (or the second cam of a conjugate pair), their margins and loads."""
        rf, e, rot = float(follower.roller_radius_mm), float(follower.offset_mm), scene.motion.rotation
        min_rho = follower.min_curvature_radius_mm
        if follower.closure.kind == "groove":
            return _groove_curves(follower.closure, rot, base_radius_mm, rf, e, min_rho, arrays.kin,
                                  geometry.pitch_x_mm, geometry.pitch_y_mm, geometry.profile_x_mm,
                                  geometry.profile_y_mm, arrays.force_N, _closure.hertz_of(scene))
        c = follower.closure
        second = (c.yoke_span_mm, c.second_roller_radius_mm)
        out, top = _yoke_curves(second, rot, base_radius_mm, rf, e, min_rho, arrays.kin, arrays.force_N,
                                _closure.hertz_of(scene))
        _closure.check_yoke(follower.closure, base_radius_mm, e, top)
        return out

    def curve_dimensions(self, follower):
        return (float(follower.roller_radius_mm), float(follower.offset_mm),
                follower.max_pressure_angle_deg)

    def curve_names(self, scene, arrays) -> tuple[str, ...]:
        return ROLLER_CURVES

    def curve_constants(self, scene, follower) -> RollerCurveConstants:
        sign = rotation_sign(scene.motion.rotation)
        return RollerCurveConstants(float(follower.roller_radius_mm), sign * float(follower.offset_mm), sign,
                                    follower.min_curvature_radius_mm,
                                    math.tan(math.radians(follower.max_pressure_angle_deg)))

    def curve(self, name, p, consts, base_radius_mm):
        c = consts.follower
        if name == "stress":  # contact stress, MPa (even in phi)
            g = roller_geo.roller_geometry(base_radius_mm, c.roller_radius_mm, c.offset_mm, p.kin)
            return roller_geo.roller_contact_stress(p.stress_coefficient, g.pitch_curvature, g.pressure_angle,
                                                    c.roller_radius_mm)
        if name == PRESSURE_NEED:
            return roller_geo.roller_pressure_angle_need(p.kin.ds, p.kin.s, c.offset_mm, c.tan_pressure_limit)
        if name in ROLLER_CURVES:
            g = roller_geo.roller_geometry(base_radius_mm, c.roller_radius_mm, c.offset_mm, p.kin,
                                           "ccw", c.min_curvature_radius_mm)
            return {"pressure_angle": c.rotation_sign * g.pressure_angle,
                    "undercut_margin": g.undercut_margin,
                    "pitch_rho_abs": jnp.abs(g.pitch_radius_of_curvature)}[name]
        return super().curve(name, p, consts, base_radius_mm)

    def summary(self, design) -> str:
        return (f"R_f = {design['roller_radius_mm']:.4f} mm, offset {design['offset_mm']:.4f} mm, "
                f"R_p = {design['prime_radius_mm']:.4f} mm")

    def title_dimensions(self, data) -> list[str]:
        roller = data.get("roller")
        return [f"R_f = {roller['roller_radius_mm']:g} mm, e = {roller['offset_mm']:g} mm"] if roller else []

    def drawn_summary(self, data) -> str:
        roller = data["roller"]
        return f", R_f = {roller['roller_radius_mm']:.4f} mm, offset {roller['offset_mm']:.4f} mm"


FOLLOWER = Roller()
