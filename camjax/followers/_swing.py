"""What every rocking (oscillating) follower shares: the layout, the arm's relative turning rate,
and the scan-and-bisect search of the sizing functions.

Layout (follower frame, fixed; mm). The cam centre O is the origin and the pivot A = (d, 0) lies
on +X at the pivot distance d. The arm angle psi is measured at the pivot from the line of
centres A -> O; the arm's unit vector is u(psi) = (-cos psi, sin psi), so the arm points at the
cam centre for psi = 0 and swings up (+Y) as psi grows. The motion program gives psi = psi0 + s
with s in rad (``lift_deg`` in the scene), psi0 its value at s = 0.

Kinematic inversion. The cam frame turns with the cam as in :mod:`camjax.followers._pitch`: a
follower-frame point x appears at P = R(-sigma theta) x in cam coordinates (sigma = +1 ccw, -1
cw; :func:`camjax.followers._pitch.to_cam_frame`). The same physical layout serves both rotations;
the rotation enters every closed form only through Q = 1 + sigma s', the rate at which the arm
turns relative to the cam (per rad of cam angle). The followers' own closed forms are in
:mod:`camjax.followers.oscillating_roller.geometry` and :mod:`camjax.followers.oscillating_flat.geometry`.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign
from camjax.program import Kinematics

# Arm start angles scanned by the sizing functions before the bisection (see first_admissible).
SIZING_SCAN = 2048
SIZING_BISECTIONS = 80
SIZING_BATCH_VALUES = 1 << 22  # arm angles x samples evaluated at once by the scan (~32 MB of float64)




def relative_rate(kin: Kinematics, rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Q = 1 + sigma s' (rad/rad): the arm's turning rate relative to the cam, per rad of cam angle.

    In the cam frame the follower frame turns at +sigma per rad of cam angle (P = R(-sigma theta)
    x), so an arm at psi(theta) = psi0 + s turns at s' + sigma relative to the cam, sigma Q.
    """
    return 1.0 + rotation_sign(rotation) * kin.ds


def arm_angle(psi0, kin: Kinematics) -> jax.Array:
    """psi = psi0 + s (rad) at every sample."""
    return psi0 + kin.s


class ArmTrig(NamedTuple):
    """cos psi and sin psi of the arm angle at every sample (shape (n,) each)."""

    c: jax.Array  # cos psi
    sn: jax.Array  # sin psi


def arm_trig(cos_psi0, sin_psi0, s_rad) -> ArmTrig:
    """cos and sin of psi = psi0 + s at every sample from psi0's (scalars) and the swing s (rad),
    by the angle-addition formulas. A design problem's per-angle terms then take no trigonometric
    function of the design: cos s and sin s are the scene's data. The oscillating roller's
    100-weighting sweep with the interior point (benchmarks.follower_sweep's problem, 2 cores) took
    0.12-0.16 s instead of 0.34-0.36 s with cos(psi0 + s) of the design."""
    cs, ss = jnp.cos(s_rad), jnp.sin(s_rad)
    return ArmTrig(cos_psi0 * cs - sin_psi0 * ss, sin_psi0 * cs + cos_psi0 * ss)


def of_angle(psi) -> ArmTrig:
    """:class:`ArmTrig` of the arm angles ``psi`` (rad)."""
    return ArmTrig(jnp.cos(psi), jnp.sin(psi))



def first_admissible(bad, lo, hi, samples: int, scan: int = SIZING_SCAN,
                      bisections: int = SIZING_BISECTIONS):
    """Smallest x in (lo, hi) with bad(x) False: a scan of ``scan`` points, then a bisection.

    The scan finds the first admissible grid point x_k; bisecting [x_{k-1}, x_k] moves to the
    boundary (80 halvings: below float64 resolution for brackets < 1e5). Returns (x, found);
    x = hi where nothing on the scan is admissible. ``bad`` maps one x (shape ()) to a bool over
    the whole grid of ``samples`` angles; the scan evaluates it in batches of ~SIZING_BATCH_VALUES
    / samples points, so memory stays bounded on dense grids. jit/vmap-safe; not differentiable
    (a search), nor meant to be.
    """
    xs = lo + (hi - lo) * (jnp.arange(1, scan + 1) / (scan + 1))
    ok = ~jax.lax.map(bad, xs, batch_size=max(1, min(scan, SIZING_BATCH_VALUES // max(samples, 1))))
    found = jnp.any(ok)
    k = jnp.argmax(ok)
    a = jnp.where(k > 0, xs[jnp.maximum(k - 1, 0)], lo)
    b = xs[k]

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        is_bad = bad(m)
        return jnp.where(is_bad, m, a), jnp.where(is_bad, b, m)

    a, b = jax.lax.fori_loop(0, bisections, halve, (a, b))
    return jnp.where(found, b, hi), found


class MomentModel(NamedTuple):
    """What the Hertz coefficient of a rocker's contact is made of (SI and MPa; arrays)."""

    train: Any  # camjax.loads.RockerTrain
    cam_speed_rad_s: jax.Array
    width_compliance: jax.Array  # w K: cam width (mm) times the pair's compliance (1/MPa)


def moment_model(scene, arrays) -> MomentModel | None:
    """The scene's :class:`MomentModel` (None without a follower train or a [contact] section)."""
    from camjax.contact import compliance

    if scene.follower.train is None or scene.contact is None:
        return None
    c, dtype = scene.contact, arrays.kin.s.dtype
    as_ = lambda v: jnp.asarray(v, dtype)  # noqa: E731
    return MomentModel(jax.tree.map(as_, scene.follower.train), as_(arrays.cam_speed_rad_s),
                       as_(c.cam_width_mm * compliance(c.cam, c.follower)))


def second_moment_coefficient_at(model: MomentModel, kin: Kinematics) -> jax.Array:
    """:func:`moment_coefficient_at` of max(-M, 0): the pivot torque a positive drive's second contact
    carries (camjax.followers._closure)."""
    from camjax.contact import HERTZ_FACTOR
    from camjax.loads import rocker_torque
    from camjax.numerics import safe_sqrt

    moment = rocker_torque(model.train, kin, model.cam_speed_rad_s)
    return HERTZ_FACTOR * safe_sqrt(jnp.maximum(-moment, 0.0) / model.width_compliance)


@jax.jit
def moment_coefficient_at(model: MomentModel, kin: Kinematics) -> jax.Array:
    """C_M = 0.564 sqrt(M / (w K)) at the angles of ``kin`` (MPa mm^0.5 m^0.5), M (N m) the torque
    about the pivot (:func:`camjax.loads.rocker_torque`); divided by the root of the contact
    force's lever arm (m) it is the Hertz coefficient C of :func:`camjax.contact.stress_coefficient`.
    One compiled call where it is evaluated on a grid outside a program."""
    from camjax.contact import HERTZ_FACTOR
    from camjax.loads import rocker_torque
    from camjax.numerics import safe_sqrt

    moment = rocker_torque(model.train, kin, model.cam_speed_rad_s)
    return HERTZ_FACTOR * safe_sqrt(moment / model.width_compliance)


def moment_coefficient(scene, arrays) -> jax.Array:
    """C_M = 0.564 sqrt(M / (w K)) per angle, shape (n,), of a rocker scene: M (N m) the torque about
    the pivot (:func:`camjax.loads.rocker_torque`), w the cam width (mm), K the compliance (1/MPa);
    zeros without a follower train or [contact]. Divided by the root of the lever arm of the contact
    force (m) it is the Hertz coefficient C (MPa mm^0.5); every rocking family uses it
    (:func:`moment_coefficient_at`).
    """
    model = moment_model(scene, arrays)
    return jnp.zeros_like(arrays.kin.s) if model is None else moment_coefficient_at(model, arrays.kin)


# the (n,) leaves of every rocking family's Problem
GRID_FIELDS = frozenset({"theta_deg", "s_rad", "ds", "d2s", "moment_coefficient"})


def scene_fields(scene, arrays, as_) -> dict:
    """The Problem fields every rocking family takes from the scene alone: the grid (theta, the
    swing s (rad), s', s'', C_M of :func:`moment_coefficient`), sigma_max (1 without one),
    rho_min, the rotation's sign, and the motion program and :class:`MomentModel` behind the grid
    when extrema are exact (None otherwise); ``as_`` casts to the problem's dtype (Python: reads
    the scene)."""
    d, f, kin = scene.design, scene.follower, arrays.kin
    return dict(
        theta_deg=as_(arrays.theta_deg), s_rad=kin.s, ds=kin.ds, d2s=kin.d2s,
        moment_coefficient=as_(moment_coefficient(scene, arrays)),
        sigma_max_MPa=as_(d.sigma_max_MPa if d.sigma_max_MPa is not None else 1.0),
        min_curvature_radius_mm=as_(f.min_curvature_radius_mm),
        rotation_sign=as_(rotation_sign(scene.motion.rotation)),
        program=None if arrays.model is None else arrays.model.program,
        moment_model=None if arrays.model is None else moment_model(scene, arrays),
    )


def per_angle(problem):
    """The n pointwise problems of a rocking family: every grid leaf (n,) -> (n, 1), every scalar
    leaf -> (n,); one angle's problem has no program or moment model (its sample is all there is)."""
    from camjax import family

    return family.per_angle(problem._replace(program=None, moment_model=None), GRID_FIELDS)


def polish_design(problem, design, constraints, names: tuple[str, ...]):
    """The solver's design moved, where it is short, the least distance that keeps the named
    constraints at every cam angle, not only at the grid's samples
    (:func:`camjax.followers._polish.polish_design`, with the rocking problem at the angles of one
    segment of ``problem.program``: its motion, and its moment coefficient from
    ``problem.moment_model``). Without a program (grid extrema) the design is returned unchanged.
    Traceable and vmappable; the result carries no gradient."""
    from camjax import program as program_mod
    from camjax.followers import _polish

    program = getattr(problem, "program", None)

    def at(segment, theta_deg):  # the problem at one segment's angles
        kin = program_mod.segment_motion(program, segment, theta_deg)
        model = getattr(problem, "moment_model", None)
        coefficient = jnp.zeros_like(kin.s) if model is None else moment_coefficient_at(model, kin)
        at = problem._replace(theta_deg=jnp.degrees(kin.theta), s_rad=kin.s, ds=kin.ds, d2s=kin.d2s,
                              moment_coefficient=coefficient)
        closure = getattr(problem, "closure", None)
        if closure is not None:  # a positive drive's second contact: the load it carries, max(-M, 0)
            second = jnp.zeros_like(kin.s) if model is None else second_moment_coefficient_at(model, kin)
            at = at._replace(closure=closure._replace(second_coefficient=second))
        return at

    return _polish.polish_design(problem, design, constraints, names, program=program, at=at)
