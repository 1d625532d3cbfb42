"""The oscillating (rocker) roller follower (SPEC 3): a roller on an arm swinging about a pivot.

The pivot sits at ``pivot_distance_mm`` d from the cam centre and the roller's centre at
``arm_length_mm`` l from the pivot; the limits are the pressure angle and the undercut, as for the
translating roller (:mod:`camjax.followers.oscillating_roller.geometry` for the closed forms).
Design variables: R_b, R_f, d and l (:mod:`camjax.followers.oscillating_roller.problem`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np

from camjax import contact, loads, runtime
from camjax.errors import SceneError
from camjax.followers import _checks, _closure, _closure_design, _closure_problem
from camjax.followers._closure import POSITIVE_CLOSURES, closure_keys, read_closure
from camjax.followers._rocking import (
    TRAIN_KEYS,
    RockerGeometry,
    RockerSizing,
    RockingFollower,
    circle_arm_closure_problem,
    read_train,
)
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller.geometry import ROLLER_MAX_PRESSURE_ANGLE_DEG, ROLLER_MIN_CURVATURE_RADIUS_MM
from camjax.scene.reader import DEFAULT, build, fixed_or_free
from camjax.scene.spec import ClosureSpec, FollowerSpec


@partial(runtime.program_cache, static_argnames=("kind",))
def _second_start_angle(kin, prime_first, sizing, second, kind: str):
    """The smallest arm start angle psi0 (rad) at which both contacts of a positive drive hold their
    limits at every sample (:func:`camjax.followers._closure_problem.first_admissible_size`), no
    smaller than the first contact's smallest cam's (prime radius ``prime_first``, mm), whether one
    does, the sample where the limits are tightest there, and its prime radius (mm). ``sizing``:
    (d, l, rotation sign, tan(limit), R_f + rho_min); ``second``: (groove clearance, second arm
    length, its angle (deg), second roller radius, R_f, rho_min), arrays: one compiled program for
    every scene of a closure kind and grid (the scene's values are its data)."""
    d, l, sign, tan_lim, _ = sizing
    clearance, arm, angle, radius, rf, rho_min = second
    closure = ClosureSpec(kind, clearance_mm=clearance, second_roller_radius_mm=radius,
                          second_arm_length_mm=arm, second_arm_angle_deg=angle)

    def limits(psi0):
        g = _closure_problem.second_limits(closure, kin, psi0=psi0, pivot_distance_mm=d, arm_length_mm=l, sign=sign,
                                   roller_radius_mm=rf, min_curvature_radius_mm=rho_min, tan_limit=tan_lim)
        return jnp.concatenate([rocker_roller_geo.sizing_limits(kin, psi0, sizing), g])

    hi = jnp.pi - jnp.max(kin.s)
    psi_first = rocker_roller_geo.arm_start_angle(prime_first, d, l)
    psi0, found = _closure_problem.first_admissible_size(lambda p: jnp.any(limits(p) > 0.0), psi_first, hi,
                                                 kin.s.shape[-1])
    return (psi0, found, jnp.argmax(jnp.max(limits(psi0), axis=0)),
            rocker_roller_geo.roller_centre_distance(d, l, psi0))


@jax.jit
def _groove_curves(clearance_mm, pitch_x, pitch_y, inner_x, inner_y, pitch_curvature, pressure_angle_rad,
                   roller_radius_mm, min_curvature_radius_mm, path_force_N, hertz):
    """A rocker groove's curves at one design (:func:`camjax.followers._closure.groove_curves`), one
    compiled program per grid: the clearance and the follower's numbers are data."""
    return _closure.groove_curves(ClosureSpec("groove", clearance_mm=clearance_mm), pitch_x, pitch_y, inner_x,
                                  inner_y, pitch_curvature, pressure_angle_rad, roller_radius_mm,
                                  min_curvature_radius_mm, path_force_N, hertz)


@partial(jax.jit, static_argnames=("rotation",))
def _arm_curves(second, pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm, kin,
                rotation: str, min_curvature_radius_mm, moment_Nm, hertz):
    """A conjugate rocker's second cam and where its arms go
    (:func:`camjax.followers._closure.arm_curves`), one compiled program per grid and rotation.
    ``second``: (second arm length mm, its angle from the first deg, second roller radius mm), data
    like the follower's other numbers."""
    length, angle, radius = second
    closure = ClosureSpec("conjugate", second_arm_length_mm=length, second_arm_angle_deg=angle,
                          second_roller_radius_mm=radius)
    return _closure.arm_curves(closure, pivot_distance_mm, arm_length_mm, roller_radius_mm, prime_radius_mm,
                               kin, rotation, min_curvature_radius_mm, moment_Nm, hertz)


@dataclass(frozen=True, kw_only=True)
class OscillatingRollerSpec(FollowerSpec):
    """[follower] of a rocker with a roller: pivot, arm, roller and the two limits."""

    type: str = "oscillating_roller"
    pivot_distance_mm: float = 0.0  # d, cam centre to pivot (required by the scene)
    arm_length_mm: float = 0.0  # l, pivot to roller centre (required)
    roller_radius_mm: float = 0.0  # R_f (required)
    max_pressure_angle_deg: float = ROLLER_MAX_PRESSURE_ANGLE_DEG
    min_curvature_radius_mm: float = ROLLER_MIN_CURVATURE_RADIUS_MM  # as for a roller: 0 = just no undercut


def _f(x) -> float:
    return float(np.asarray(x))


def check_rocker_closes(r, base, roller, pivot_distance_mm, arm_length_mm) -> None:
    """Refuse bounds in which no design closes: |d - l| < R_p < d + l nowhere.

    Designs of the box that do not close are left to the solver's reach constraint; a box with
    none that does is a scene error naming pivot_distance_mm (the pivot cannot be placed).
    """
    (d0, d1), (l0, l1) = pivot_distance_mm, arm_length_mm
    rp0, rp1 = base[0] + roller[0], base[1] + roller[1]
    gap = max(d0 - l1, l0 - d1, 0.0)  # smallest |d - l| in the box
    if rp1 <= gap or rp0 >= d1 + l1:
        value = list(pivot_distance_mm) if d0 != d1 else d0
        raise r.error("pivot_distance_mm", value,
                      f"no design in the bounds closes: the prime radius R_b + R_f ({rp0:g}..{rp1:g} mm) "
                      f"must lie between |d - l| (>= {gap:g} mm) and d + l (<= {d1 + l1:g} mm)",
                      "a pivot distance closer to the arm length, or a larger base radius")


@runtime.program_cache(static_argnames=("rotation",))
def arm_sizing(kin, program, pivot_distance_mm, arm_length_mm, roller_radius_mm, max_pressure_angle_rad,
               min_curvature_radius_mm, rotation):
    """The sizing of a roller (or a curved face of radius ``roller_radius_mm``) on an arm, in one
    compiled (and saved) program: the samples' (:func:`camjax.followers.oscillating_roller.geometry.
    oscillating_roller_min_prime_radius`) and, with ``program`` (exact extrema; None: grid), the
    smallest psi0 from the samples' up with |phi| <= the limit and no undercut at every cam angle
    (:func:`camjax.followers._sizing.exact_boundary` on
    :func:`camjax.followers.oscillating_roller.geometry.sizing_limits`). Returns (sampled sizing,
    :class:`camjax.followers._sizing.Boundary` or None)."""
    from camjax.followers import _sizing
    from camjax.followers._pitch import rotation_sign

    s = rocker_roller_geo.oscillating_roller_min_prime_radius(
        kin, pivot_distance_mm, arm_length_mm, roller_radius_mm, max_pressure_angle_rad,
        min_curvature_radius_mm, rotation)
    if program is None:
        return s, None
    as_ = lambda v: jnp.asarray(v, kin.s.dtype)  # noqa: E731
    params = (as_(pivot_distance_mm), as_(arm_length_mm), as_(rotation_sign(rotation)),
              jnp.tan(as_(max_pressure_angle_rad)), as_(roller_radius_mm) + min_curvature_radius_mm)
    return s, _sizing.exact_boundary(program, kin, s.arm_start_angle, jnp.pi - jnp.max(kin.s), params,
                                     limits=rocker_roller_geo.sizing_limits)


def _centre_distance(d: float, l: float, psi: float) -> float:
    """:func:`camjax.followers.oscillating_roller.geometry.roller_centre_distance` (mm) in Python
    floats, operation for operation, so the same number as its evaluation op by op (XLA's cosine on
    the CPU is the C library's): no small compiles in the drawing compiled beside the solver
    (:func:`camjax.runtime.ahead`), where each could wait while the solver's program is exported and
    compiled."""
    q = d**2 + l**2 - 2.0 * d * l * math.cos(psi)
    return math.sqrt(q) if q > 0 else 0.0


def arm_sizing_result(kin, sampled, boundary, follower, max_pressure_angle_deg: float,
                      roller_radius_mm: float, angle_binding: str, what: str) -> RockerSizing:
    """The :class:`RockerSizing` of :func:`arm_sizing`'s result (the follower's [follower] spec;
    ``what`` names the limits in messages): a SceneError where no arm start angle is admissible,
    on the samples or (exact) at every cam angle (a narrow window of admissible psi0 that only the
    samples see)."""
    f = follower
    advice = "a longer arm, another pivot distance or a larger max_pressure_angle_deg"
    if not bool(sampled.found) or (boundary is not None and not bool(boundary.refined)):
        where = "" if not bool(sampled.found) else (f" at every cam angle (the {kin.s.shape[-1]} samples "
                                                    'alone admit one: extrema = "grid" sizes on them)')
        raise SceneError("follower.arm_length_mm", f.arm_length_mm,
                         f"with pivot_distance_mm = {f.pivot_distance_mm:g} no prime radius keeps "
                         f"|pressure angle| <= {max_pressure_angle_deg:g} deg {what}{where}", advice)
    if boundary is None:
        t = np.degrees(np.asarray(kin.theta))
        binding = "undercut" if bool(sampled.undercut_binds) else angle_binding
        return RockerSizing(_f(sampled.base_radius_mm), _f(sampled.prime_radius_mm),
                            _f(t[int(sampled.index)]), binding)
    rp = _centre_distance(f.pivot_distance_mm, f.arm_length_mm, _f(boundary.x))
    binding = "undercut" if int(boundary.row) == 1 else angle_binding
    return RockerSizing(rp - roller_radius_mm, rp, _f(boundary.angle_deg), binding)


def circle_geometry(scene, kin, base_radius_mm, radius_mm: float, geometry, profile) -> RockerGeometry:
    """The :class:`camjax.followers._rocking.RockerGeometry` of a circle of radius ``radius_mm`` at
    the arm's end (the roller, the oscillating curved face's crown) on a cam of base radius
    ``base_radius_mm``: its pitch curve is the oscillating roller's of R_p = R_b + R; ``geometry``
    and ``profile`` are the follower's closed forms, called as ``geometry(d, l, R, R_p, kin,
    rotation, rho_min)`` and ``profile(d, l, R, R_p, kin, rotation)``."""
    f, rotation = scene.follower, scene.motion.rotation
    d, l = f.pivot_distance_mm, f.arm_length_mm
    rp = base_radius_mm + radius_mm
    g = geometry(d, l, radius_mm, rp, kin, rotation, f.min_curvature_radius_mm)
    x, y = profile(d, l, radius_mm, rp, kin, rotation)
    pitch_x, pitch_y = rocker_roller_geo.oscillating_roller_pitch_curve(d, l, rp, kin, rotation)
    return RockerGeometry(
        x, y, g.arm_angle, rocker_roller_geo.arm_start_angle(rp, d, l), g.pressure_angle,
        g.cam_radius_of_curvature, pitch_x, pitch_y, g.pitch_radius_of_curvature, g.pitch_curvature,
        g.undercut_margin, arm_length_mm=l, roller_radius_mm=radius_mm, prime_radius_mm=rp,
        pressure_angle_limit_deg=float(f.max_pressure_angle_deg))


def circle_contact(scene, moment, g, radius_mm: float):
    """The contact force (N) and Hertz stress (MPa, None without [contact]) of a circle of radius
    ``radius_mm`` (the roller, the oscillating curved face's crown) at the arm's end, from the pivot
    torque ``moment`` (N m) and the rocker geometry ``g``: the normal runs through the circle's
    centre, so P = M / (l cos phi); the force along the centre's path, M / l, is the roller
    formula's "axial" force."""
    force = loads.rocker_roller_contact_force(moment, g.arm_length_mm, g.pressure_angle)
    stress = None
    if scene.contact is not None:
        c = scene.contact
        along = moment / (g.arm_length_mm * 1e-3)  # N
        coeff = contact.stress_coefficient(along, c.cam_width_mm, c.cam, c.follower)
        stress = roller_geo.roller_contact_stress(coeff, g.pitch_curvature, g.pressure_angle, radius_mm)
    return force, stress


class OscillatingRoller(RockingFollower):
    name = "oscillating_roller"
    title = "oscillating roller"
    keys = ("pivot_distance_mm", "arm_length_mm", "roller_radius_mm", "max_pressure_angle_deg",
            "min_curvature_radius_mm", *TRAIN_KEYS, *closure_keys(rocking=True))
    closures = POSITIVE_CLOSURES
    example_scene = "oscillating-roller"
    variables = ("base_radius_mm", "roller_radius_mm", "pivot_distance_mm", "arm_length_mm")
    optional_variables = (_closure_design.ARM_ANGLE,)

    def parse(self, r) -> OscillatingRollerSpec:
        """Whether the geometry closes for the prime (base) radius the cam gets is checked where that
        radius is known (the design or the sizing); here d > 0, l > 0 and R_f > 0."""
        self.check_keys(r)
        train = read_train(r)
        pivot = r.number("pivot_distance_mm", low=0.0, low_open=True)
        limit = _checks.read_max_pressure_angle(r)
        arm = r.number("arm_length_mm", low=0.0, low_open=True)
        roller = r.number("roller_radius_mm", low=0.0, low_open=True)
        return build(OscillatingRollerSpec, type=self.name, train=train, pivot_distance_mm=pivot,
                     arm_length_mm=arm, roller_radius_mm=roller, closure=read_closure(r, True, roller),
                     max_pressure_angle_deg=limit,
                     min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0))

    def design_bounds(self, r, follower) -> dict[str, tuple[float, float]]:
        base = fixed_or_free(r, "base_radius_mm")
        roller = fixed_or_free(r, "roller_radius_mm", (follower.roller_radius_mm,) * 2)
        variables = dict(
            pivot_distance_mm=fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2),
            arm_length_mm=fixed_or_free(r, "arm_length_mm", (follower.arm_length_mm,) * 2))
        check_rocker_closes(r, base, roller, **variables)
        return {"base_radius_mm": base, "roller_radius_mm": roller, **variables,
                **_closure_design.design_bounds(r, follower, True, roller[0])}

    def sizing(self, scene, kin, program=None) -> RockerSizing:
        f = scene.follower
        sampled, boundary = arm_sizing(kin, program, f.pivot_distance_mm, f.arm_length_mm, f.roller_radius_mm,
                                       math.radians(f.max_pressure_angle_deg), f.min_curvature_radius_mm,
                                       scene.motion.rotation)
        first = arm_sizing_result(kin, sampled, boundary, f, f.max_pressure_angle_deg, f.roller_radius_mm,
                                  "pressure_angle", "without undercut")
        return first if not f.closure.positive else self._second_sizing(scene, kin, first)

    def _second_sizing(self, scene, kin, first: RockerSizing) -> RockerSizing:
        """The first contact's smallest cam raised, where the positive drive's second contact (outer
        flank, second arm's cam) breaks its limits there, to the smallest arm start angle (prime
        radius) where both contacts hold theirs (on the samples). Where none does the first's stays
        and the drawn cam reports it."""
        from camjax.followers._pitch import rotation_sign

        f, c, dt = scene.follower, scene.follower.closure, kin.s.dtype
        d, l, rf = f.pivot_distance_mm, f.arm_length_mm, f.roller_radius_mm
        as_ = lambda *v: tuple(jnp.asarray(x, dt) for x in v)  # noqa: E731
        tan_lim = math.tan(math.radians(f.max_pressure_angle_deg))
        sizing = as_(d, l, rotation_sign(scene.motion.rotation), tan_lim, rf + f.min_curvature_radius_mm)
        arm = (c.second_arm_length_mm, c.second_arm_angle_deg, c.second_roller_radius_mm)
        second = as_(c.clearance_mm, *(arm if c.kind == "conjugate" else (0.0,) * 3), rf, f.min_curvature_radius_mm)
        prime_first = jnp.asarray(first.min_prime_radius_mm, dt)
        sized = _second_start_angle(kin, prime_first, sizing, second, kind=c.kind)
        _, found, worst, rp = jax.device_get(sized)
        rp = _f(rp)
        if not bool(found) or rp <= first.min_prime_radius_mm * (1.0 + 1e-12):
            return first
        deg = float(np.degrees(np.asarray(kin.theta))[int(worst)])
        return RockerSizing(rp - rf, rp, deg, "outer_flank" if c.kind == "groove" else "conjugate")

    def closure_problem(self, scene, kin, base_radius_mm) -> str | None:
        """The prime radius R_p = R_b + R_f must lie strictly between |d - l| and d + l (the roller
        reaches the prime circle) and the arm must stay off the line of centres while it swings
        (psi0 + max s < pi)."""
        return circle_arm_closure_problem(scene, kin, base_radius_mm, scene.follower.roller_radius_mm,
                                          "the roller cannot reach the prime circle R_p")

    def geometry(self, scene, kin, base_radius_mm) -> RockerGeometry:
        return circle_geometry(scene, kin, base_radius_mm, scene.follower.roller_radius_mm,
                               rocker_roller_geo.oscillating_roller_geometry,
                               rocker_roller_geo.oscillating_roller_profile)

    def contact(self, scene, moment, g):
        return circle_contact(scene, moment, g, scene.follower.roller_radius_mm)

    def closure_curves(self, scene, kin, base_radius_mm, g, moment):
        """Both flanks of a groove (or the second cam of a conjugate pair), their margins and loads."""
        f = scene.follower
        path_force = None if moment is None else moment / (g.arm_length_mm * 1e-3)  # N along the path
        if f.closure.kind == "groove":
            return _groove_curves(f.closure.clearance_mm, g.pitch_x_mm, g.pitch_y_mm, g.profile_x_mm,
                                  g.profile_y_mm, g.pitch_curvature, g.pressure_angle, f.roller_radius_mm,
                                  f.min_curvature_radius_mm, path_force, _closure.hertz_of(scene))
        c = f.closure
        second = (c.second_arm_length_mm, c.second_arm_angle_deg, c.second_roller_radius_mm)
        out, reach = _arm_curves(second, f.pivot_distance_mm, f.arm_length_mm, f.roller_radius_mm,
                                 base_radius_mm + f.roller_radius_mm, kin, scene.motion.rotation,
                                 f.min_curvature_radius_mm, moment, _closure.hertz_of(scene))
        _closure.check_arm(f.closure, jax.device_get(reach))
        return out

    def summary(self, design) -> str:
        return (f"R_f = {design['roller_radius_mm']:.4f} mm, pivot {design['pivot_distance_mm']:.4f} mm, "
                f"arm {design['arm_length_mm']:.4f} mm, R_p = {design['prime_radius_mm']:.4f} mm")

    def title_dimensions(self, data) -> list[str]:
        rocker = data.get("oscillating_follower", {})
        return [f"d = {rocker['pivot_distance_mm']:g} mm, l = {rocker['arm_length_mm']:g} mm, "
                f"R_f = {rocker['roller_radius_mm']:g} mm"] if rocker else []


FOLLOWER = OscillatingRoller()
