"""Three implementations of the same population fitness, for the scaling benchmark.

The fitness of a design (R_b, L) on an N-angle grid is the pair the GA ranks by
(:func:`camjax.solvers.ga.design_fitness`):

    objective  = [alpha (R_b + L)/N_size + gamma max_theta sigma(theta)/sigma_max] / (alpha + gamma)
    violation  = sum over constraints of max_theta max(0, g_i(theta)) / N_size

* :func:`library_fitness` -- camjax as users run it: ``camjax.solvers.ga.fitness``, one design
  written once and ``vmap``-ed over the population.
* :func:`fused_fitness` -- the hand-fused reference: one jnp expression over (population, N) with
  a single reduction over angles, max_theta C^2 / rho (one division per design-angle), and one
  square root per design. The constraints are linear in the design with unit slope, so
  max_theta g_i(theta) = a_i - x: the angle-dependent part a_i is computed once per scene
  (:class:`FusedScene`) and only the stress needs the (population, N) pass. (camjax's own
  fitness, ``camjax.followers.flat.problem.peak_stress`` and ``constraint_maxima``, uses the same algorithm.)
* :func:`numpy_fitness` -- the same algorithm in vectorized NumPy, with in-place operations (the
  best plain NumPy we could write; ``fitness.numpy_ratio`` uses it).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.family import Weights
from camjax.followers.flat.problem import Design, Problem
from camjax.numerics import RHO_FLOOR_MM


class FusedScene(NamedTuple):
    """Design-independent data of the fused kernel (arrays of one dtype)."""

    q_mm: jax.Array  # (N,) s + s''
    coefficient_sq: jax.Array  # (N,) C^2, so that max sigma = sqrt(max C^2 / rho)
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
        problem.stress_coefficient**2,
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


def _fitness_from_peak(scene: FusedScene, weights: Weights, designs: Design, peak: jax.Array):
    """(objective, violation) of a population given its peak stresses (population,)."""
    r, length = designs.base_radius_mm, designs.face_width_mm
    objective = (
        weights.alpha * (r + length) / scene.size_norm_mm + weights.gamma * peak / scene.sigma_max_MPa
    ) / (weights.alpha + weights.gamma)
    violation = (
        jnp.maximum(scene.curvature_need_mm - r, 0.0)
        + jnp.maximum(scene.stress_need_mm - r, 0.0)
        + jnp.maximum(scene.width_need_mm - length, 0.0)
    ) / scene.size_norm_mm
    return objective, violation


def fused_fitness(scene: FusedScene, weights: Weights, designs: Design) -> tuple[jax.Array, jax.Array]:
    """The hand-fused kernel: one pass over (population, N), one reduction (alpha > 0 assumed)."""
    rho = designs.base_radius_mm[:, None] + scene.q_mm[None, :]
    peak = jnp.sqrt(jnp.max(scene.coefficient_sq[None, :] / jnp.maximum(rho, RHO_FLOOR_MM), axis=1))
    return _fitness_from_peak(scene, weights, designs, peak)


TILE = 7200  # angles per tile of the tiled reference kernel


def tiled_fitness(scene: FusedScene, weights: Weights, designs: Design, tile: int = TILE):
    """The fused kernel with the angles reduced tile by tile (``lax.map``; N divisible by tile).

    Each tile is its own reduction of <= ``tile`` angles: this keeps XLA:CPU's YNNPACK reduce on
    its fast path for long grids (it slows ~10x once a row passes ~16k angles; see docs/benchmarks.md).
    """
    n = scene.q_mm.shape[0]
    tile = min(tile, n)
    q = scene.q_mm.reshape(n // tile, tile)
    c2 = scene.coefficient_sq.reshape(n // tile, tile)
    r = designs.base_radius_mm

    def tile_max(qc):
        return jnp.max(qc[1][None, :] / jnp.maximum(r[:, None] + qc[0][None, :], RHO_FLOOR_MM), axis=1)

    peak = jnp.sqrt(jnp.max(jax.lax.map(tile_max, (q, c2)), axis=0))
    return _fitness_from_peak(scene, weights, designs, peak)


def numpy_fitness(scene: dict, alpha: float, gamma: float, r: np.ndarray, length: np.ndarray):
    """The fused kernel's algorithm in NumPy (``scene``: :class:`FusedScene` fields as ndarrays)."""
    rho = np.add.outer(r, scene["q_mm"])
    np.maximum(rho, RHO_FLOOR_MM, out=rho)
    np.divide(scene["coefficient_sq"], rho, out=rho)
    peak = np.sqrt(rho.max(axis=1))
    objective = (alpha * (r + length) / scene["size_norm_mm"] + gamma * peak / scene["sigma_max_MPa"]) / (
        alpha + gamma
    )
    violation = (
        np.maximum(scene["curvature_need_mm"] - r, 0.0)
        + np.maximum(scene["stress_need_mm"] - r, 0.0)
        + np.maximum(scene["width_need_mm"] - length, 0.0)
    ) / scene["size_norm_mm"]
    return objective, violation


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
    "tiled_fitness",
    "fused_scene",
    "library_fitness",
    "max_disagreement",
    "numpy_fitness",
    "numpy_scene",
    "random_designs",
]
