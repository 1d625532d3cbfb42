"""Three implementations of the same population fitness, for the scaling benchmark.

The fitness of a design (R_b, L) on an N-angle grid is the pair the GA ranks by
(:func:`camjax.solvers.ga.design_fitness`):

    objective  = [alpha (R_b + L)/N_size + gamma max_theta sigma(theta)/sigma_max] / (alpha + gamma)
    violation  = sum over constraints of max_theta max(0, g_i(theta)) / N_size

* :func:`library_fitness` -- camjax as users run it: ``camjax.solvers.ga.fitness``, one design
  written once and ``vmap``-ed over the population.
* :func:`fused_fitness` -- the hand-fused reference: one jnp expression over (population, N) with
  a single reduction over angles. The constraints are linear in the design with unit slope, so
  max_theta g_i(theta) = a_i - x: the angle-dependent part a_i is computed once per scene
  (:class:`FusedScene`) and only the stress needs the (population, N) pass.
* :func:`numpy_fitness` -- the same algorithm as the fused kernel in vectorized NumPy, with
  in-place operations (the best plain NumPy we could write; ``fitness.numpy_ratio`` uses it);
  :func:`numpy_fitness_per_angle` is the library's algorithm (every constraint per angle) in NumPy.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import problem as P
from camjax.numerics import RHO_FLOOR_MM
from camjax.problem import Design, Problem, Weights


class FusedScene(NamedTuple):
    """Design-independent data of the fused kernel (arrays of one dtype)."""

    q_mm: jax.Array  # (N,) s + s''
    coefficient: jax.Array  # (N,) C, sigma = C / sqrt(rho)
    curvature_need_mm: jax.Array  # () rho_min - min q: the curvature violation is this - R_b
    stress_need_mm: jax.Array  # () max (C/sigma_max)^2 - q: stress violation is this - R_b
    width_need_mm: jax.Array  # () 2 max |s'|: face-width violation is this - L
    sigma_max_MPa: jax.Array
    size_norm_mm: jax.Array


def fused_scene(problem: Problem) -> FusedScene:
    """Precompute the per-scene reductions of the constraints."""
    c2 = (problem.stress_coefficient / problem.sigma_max_MPa) ** 2
    return FusedScene(
        problem.q_mm,
        problem.stress_coefficient,
        problem.rho_min_mm - jnp.min(problem.q_mm),
        jnp.max(c2 - problem.q_mm),
        jnp.max(2.0 * jnp.abs(problem.ds_mm)),
        problem.sigma_max_MPa,
        problem.size_norm_mm,
    )


def library_fitness(problem: Problem, weights: Weights, designs: Design) -> tuple[jax.Array, jax.Array]:
    """camjax's own population fitness: ``vmap`` of the one-design fitness the GA uses."""
    from camjax.solvers.ga import design_fitness

    return jax.vmap(design_fitness, in_axes=(None, None, 0))(problem, weights, designs)


def fused_fitness(scene: FusedScene, weights: Weights, designs: Design) -> tuple[jax.Array, jax.Array]:
    """The hand-fused kernel: one pass over (population, N), one reduction (alpha > 0 assumed)."""
    r, length = designs.base_radius_mm, designs.face_width_mm
    rho = r[:, None] + scene.q_mm[None, :]
    sigma = scene.coefficient[None, :] / jnp.sqrt(jnp.maximum(rho, RHO_FLOOR_MM))
    peak = jnp.max(sigma, axis=1)
    objective = (
        weights.alpha * (r + length) / scene.size_norm_mm + weights.gamma * peak / scene.sigma_max_MPa
    ) / (weights.alpha + weights.gamma)
    violation = (
        jnp.maximum(scene.curvature_need_mm - r, 0.0)
        + jnp.maximum(scene.stress_need_mm - r, 0.0)
        + jnp.maximum(scene.width_need_mm - length, 0.0)
    ) / scene.size_norm_mm
    return objective, violation


def numpy_fitness(scene: dict, alpha: float, gamma: float, r: np.ndarray, length: np.ndarray):
    """The fused kernel's algorithm in NumPy (``scene``: :class:`FusedScene` fields as ndarrays)."""
    rho = np.add.outer(r, scene["q_mm"])
    np.maximum(rho, RHO_FLOOR_MM, out=rho)
    np.sqrt(rho, out=rho)
    np.divide(scene["coefficient"], rho, out=rho)
    peak = rho.max(axis=1)
    objective = (alpha * (r + length) / scene["size_norm_mm"] + gamma * peak / scene["sigma_max_MPa"]) / (
        alpha + gamma
    )
    violation = (
        np.maximum(scene["curvature_need_mm"] - r, 0.0)
        + np.maximum(scene["stress_need_mm"] - r, 0.0)
        + np.maximum(scene["width_need_mm"] - length, 0.0)
    ) / scene["size_norm_mm"]
    return objective, violation


def numpy_fitness_per_angle(problem_np: dict, alpha: float, gamma: float, r: np.ndarray, length: np.ndarray):
    """The library's algorithm in NumPy: every constraint evaluated and reduced per angle.

    ``problem_np``: the :class:`camjax.problem.Problem` grid arrays and scalars as NumPy.
    """
    p = problem_np
    rho = np.add.outer(r, p["q_mm"])
    sigma = p["stress_coefficient"] / np.sqrt(np.maximum(rho, RHO_FLOOR_MM))
    objective = (
        alpha * (r + length) / p["size_norm_mm"] + gamma * sigma.max(axis=1) / p["sigma_max_MPa"]
    ) / (alpha + gamma)
    curvature = np.maximum(p["rho_min_mm"] - rho, 0.0).max(axis=1)
    stress = np.maximum((p["stress_coefficient"] / p["sigma_max_MPa"]) ** 2 - rho, 0.0).max(axis=1)
    width = np.maximum(2.0 * np.abs(p["ds_mm"])[None, :] - length[:, None], 0.0).max(axis=1)
    return objective, (curvature + stress + width) / p["size_norm_mm"]


def numpy_problem(problem: Problem) -> dict:
    """The grid arrays and scalars of a problem as NumPy (bounds left out)."""
    keys = ("q_mm", "ds_mm", "stress_coefficient", "sigma_max_MPa", "size_norm_mm", "rho_min_mm")
    return {k: np.asarray(getattr(problem, k)) for k in keys}


def numpy_scene(scene: FusedScene) -> dict:
    """A :class:`FusedScene` as a dict of NumPy arrays / floats."""
    return {k: np.asarray(v) for k, v in scene._asdict().items()}


def random_designs(problem: Problem, population: int, seed: int = 0) -> Design:
    """Uniform designs in the box (mm), leaves of shape (population,)."""
    kr, kl = jax.random.split(jax.random.PRNGKey(seed))
    dt = problem.q_mm.dtype
    sample = lambda k, lo, hi: jax.random.uniform(k, (population,), dt, lo, hi)  # noqa: E731
    return Design(
        sample(kr, problem.lower.base_radius_mm, problem.upper.base_radius_mm),
        sample(kl, problem.lower.face_width_mm, problem.upper.face_width_mm),
    )


def max_disagreement(a: tuple, b: tuple) -> float:
    """Largest absolute difference between two (objective, violation) pairs."""
    return max(float(np.max(np.abs(np.asarray(x) - np.asarray(y)))) for x, y in zip(a, b, strict=True))


__all__ = [
    "FusedScene",
    "fused_fitness",
    "fused_scene",
    "library_fitness",
    "max_disagreement",
    "numpy_fitness",
    "numpy_fitness_per_angle",
    "numpy_problem",
    "numpy_scene",
    "random_designs",
    "P",
]
