"""The scene limits a design problem carries, as functions of the problem: what the solvers'
certificates differentiate the optimal objective by (``dF*/d limit``, in the scene's units)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.solvers.base import family_of


def limit_setters(problem) -> dict:
    """The scene's limits a problem carries: scene key -> (problem, value) -> problem with that
    limit set to ``value`` (in the scene's units), every field derived from it moved with it. A
    problem that is not a NamedTuple of such fields (the co-design's joint program, whose limits
    live in the problems it builds) carries none here."""
    fields = set(getattr(problem, "_fields", ()))
    if not fields:
        return {}
    has_stress = "stress" in jax.eval_shape(
        lambda: family_of(problem).constraints(problem, family_of(problem).bounds(problem)[0]))._fields
    out = {}
    if "sigma_max_MPa" in fields and has_stress:
        out["sigma_max_MPa"] = lambda p, v: p._replace(sigma_max_MPa=v)
    if "tan_max_pressure_angle" in fields:
        def pressure(p, v):
            extra = {"max_pressure_angle_deg": v} if "max_pressure_angle_deg" in fields else {}
            return p._replace(tan_max_pressure_angle=jnp.tan(jnp.radians(v)), **extra)
        out["max_pressure_angle_deg"] = pressure
    for name in ("min_curvature_radius_mm", "rho_min_mm"):
        if name in fields:
            out["min_curvature_radius_mm"] = lambda p, v, name=name: p._replace(**{name: v})
    return out


def limit_values(problem) -> dict:
    """The current value of each limit of :func:`limit_setters` (scene units), () arrays."""
    values = {}
    for key in limit_setters(problem):
        if key == "max_pressure_angle_deg":
            values[key] = (problem.max_pressure_angle_deg if "max_pressure_angle_deg" in problem._fields
                           else jnp.degrees(jnp.arctan(problem.tan_max_pressure_angle)))
        elif key == "min_curvature_radius_mm":
            values[key] = getattr(problem, "min_curvature_radius_mm", getattr(problem, "rho_min_mm", None))
        else:
            values[key] = getattr(problem, key)
    return values
