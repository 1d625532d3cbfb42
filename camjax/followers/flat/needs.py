"""What the flat face's constraints need of a design at each cam angle (SPEC 5): the design and
problem pytrees, the radius of curvature and contact stress, and the smallest R_b, rho and L
every angle needs -- the pieces both the problem family (:mod:`camjax.followers.flat.problem`)
and its closed-form optimum (:mod:`camjax.followers.flat.optimum`) are built from.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from camjax.contact import stress_from_coefficient
from camjax.extrema import ITERATIONS


class Design(NamedTuple):
    """One cam design (scalars), or a batch of them (arrays with leading axes)."""

    base_radius_mm: jax.Array  # R_b, mm
    face_width_mm: jax.Array  # L, mm


class Problem(NamedTuple):
    """Design-independent data of one optimal-design problem on an angle grid of n samples.

    A pytree of arrays only, so it can be passed through ``jit`` and ``vmap`` (a stack of
    problems, as :func:`per_angle` builds, has one more leading axis on every leaf).
    """

    theta_deg: jax.Array  # (n,) cam angle, degrees
    q_mm: jax.Array  # (n,) s + s'' (mm): rho = R_b + q
    ds_mm: jax.Array  # (n,) s' (mm/rad): contact offset from the follower axis
    stress_coefficient: jax.Array  # (n,) C, MPa mm^0.5: sigma = C / sqrt(rho)
    lower: Design  # lower bounds, mm
    upper: Design  # upper bounds, mm
    sigma_max_MPa: jax.Array  # () allowable contact stress
    size_norm_mm: jax.Array  # () N = R_b,max + L_max
    rho_min_mm: jax.Array  # () smallest admissible radius of curvature
    exact: ExactExtrema | None = None  # closed forms for extrema off the grid; None: the grid's


class ExactExtrema(NamedTuple):
    """What makes a problem's maxima over the angle exact (``[motion] extrema = "exact"``).

    The constraint maxima do not depend on the design: refined once per scene. The peak stress
    does (rho = R_b + q): :func:`exact_peak_stress` refines it per design from ``model``.
    """

    model: Any  # camjax.evaluate.SceneModel: the scene's closed forms
    q_min_mm: jax.Array  # () min_theta (s + s''), mm
    stress_need_mm: jax.Array  # () max_theta ((C / sigma_max)^2 - q), mm
    face_width_need_mm: jax.Array  # () 2 max_theta |s'|, mm
    q_min_deg: jax.Array  # () where q is smallest (the curvature constraint binds), deg
    stress_need_deg: jax.Array  # () where the stress need peaks, deg
    face_width_need_deg: jax.Array  # () where |s'| peaks, deg


def curvature_radius(problem: Problem, design: Design) -> jax.Array:
    """rho(theta) = R_b + s + s'' (mm), shape (n,)."""
    return design.base_radius_mm + problem.q_mm


def stress(problem: Problem, design: Design) -> jax.Array:
    """Hertz contact stress sigma(theta) (MPa), shape (n,); finite (saturated) where rho <= 0."""
    return stress_from_coefficient(problem.stress_coefficient, curvature_radius(problem, design))


def stress_rho_need(problem: Problem) -> jax.Array:
    """Smallest rho (mm) with sigma <= sigma_max at each angle, (C / sigma_max)^2, shape (n,)."""
    return (problem.stress_coefficient / problem.sigma_max_MPa) ** 2


def rho_need(problem: Problem) -> jax.Array:
    """Smallest admissible rho (mm) at each angle: curvature margin and stress, shape (n,)."""
    return jnp.maximum(problem.rho_min_mm, stress_rho_need(problem))


def face_width_need(problem: Problem) -> jax.Array:
    """Face width (mm) the contact offset needs at each angle, 2|s'|, shape (n,)."""
    return 2.0 * jnp.abs(problem.ds_mm)


def required_base_radius(problem: Problem) -> jax.Array:
    """Smallest R_b (mm) meeting curvature and stress at every angle (ignoring the box), shape ()."""
    if problem.exact is None:
        return jnp.max(rho_need(problem) - problem.q_mm)
    return jnp.maximum(problem.rho_min_mm - problem.exact.q_min_mm, problem.exact.stress_need_mm)


def required_face_width(problem: Problem) -> jax.Array:
    """Smallest L (mm) meeting the face-width constraint at every angle, 2 max|s'|, shape ()."""
    return jnp.max(face_width_need(problem)) if problem.exact is None else problem.exact.face_width_need_mm


def exact_peak_stress(problem: Problem, design: Design, iterations: int = ITERATIONS):
    """max_theta sigma (MPa) and its angle (deg), refined off the grid: an
    :class:`camjax.extrema.Extremum`. Needs ``problem.exact``. The gradient in the design is
    the envelope theorem's, -C / (2 rho^(3/2)) at the refined angle.
    """
    from camjax import extrema
    from camjax.contact import stress_from_coefficient as sigma_of
    from camjax.evaluate import model_at
    from camjax.program import segment_bounds_deg

    model = problem.exact.model

    def fn(segment, theta_deg, params):
        m, radius = params
        p = model_at(m, segment, theta_deg)
        return sigma_of(p.stress_coefficient, radius + p.kin.s + p.kin.d2s)

    return extrema.refine_max(fn, (model, design.base_radius_mm), segment_bounds_deg(model.program),
                              stress(problem, design), constant=extrema.dwells(model.program),
                              iterations=iterations)
