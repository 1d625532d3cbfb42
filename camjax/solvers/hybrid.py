"""Hybrid solver: the GA's global search, then the interior point (:mod:`camjax.solvers.newton`)
from its best design, kept only where it is no worse (the hybrid never returns a worse design than
the GA it starts from).

The solver protocol of :mod:`camjax.solvers.base`; settings are the GA's and the interior point's
(``settings.of("ga")``, ``settings.of("newton")``) and the hybrid's own :class:`HybridSettings`
(the GA stage's generations).
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from camjax.family import Design, Weights
from camjax.solvers import ga, newton
from camjax.solvers.base import Raw, family_of
from camjax.solvers.certificate import certificate_json as certificate_json  # the final point's
from camjax.solvers.certificate import certify_point


@dataclasses.dataclass(frozen=True)
class HybridSettings:
    """The hybrid's own setting (hashable: a ``jit`` static argument).

    ``ga_generations``: the generations of the GA stage where the GA's settings are its defaults
    (``ga.DEFAULT_SETTINGS``, 200 generations); GA settings other than the defaults run as given,
    and None runs the GA's settings always. The GA stage's answer is only the polish's start: the
    interior point reaches the optimum of its basin from a coarser answer in a few more steps, where
    the GA's last generations cost as much as its first. On the seven types' 100-weighting sweeps
    (benchmarks/follower_sweep.py's problems) 50 generations gave the hybrid the same answers as 200
    (0 infeasible, every objective within 1.3e-8 of the best any method found) in 0.5 to 0.7 of the
    time of 100 (docs/optimization.md); 40 did not (the knife edge: 4 weightings of 100 up to 2.3e-6
    above the best).
    """

    ga_generations: int | None = 50

    def __post_init__(self):
        if self.ga_generations is not None and self.ga_generations < 1:
            raise ValueError(f"ga_generations: {self.ga_generations} must be >= 1 (or None: the GA's own)")


DEFAULT_SETTINGS = HybridSettings()


def ga_stage(settings) -> ga.GASettings:
    """The GA settings the hybrid's GA stage runs (:class:`HybridSettings`) under the solvers'
    ``settings`` (:class:`camjax.solvers.base.Settings`)."""
    own, found = settings.of("hybrid"), settings.of("ga")
    if own.ga_generations is None or found != ga.DEFAULT_SETTINGS:
        return found
    return dataclasses.replace(found, generations=own.ga_generations)


POLISH_MU = 1e-2
"""The polish's first barrier parameter is newton's ``mu0`` times this: the GA's design is near an
optimum, where a barrier started high only walks back to it (the seven types' 100-weighting sweeps:
the knife edge's polish 30 steps at the median, 200 at most, with mu0 0.1; 9 and 10 with 1e-3)."""


def polish(problem, weights: Weights, found: ga.GAResult,
           settings: newton.NewtonSettings = newton.DEFAULT_SETTINGS):
    """The interior point from the GA's answer ``found``: (design, Newton steps, kept & converged).

    :func:`camjax.solvers.newton.minimize` from ``found.design`` with its barrier started at
    ``settings.mu0`` x :data:`POLISH_MU`; the polished design is kept where it is feasible and its
    objective no larger than the GA's, or where it repairs an infeasible GA design; elsewhere the
    GA's design is the answer (a polish that ends elsewhere, on another local optimum or at its
    safeguard, never makes the answer worse). The hybrid solver and the joint co-design's hybrid
    (:mod:`camjax.codesign.joint`) both polish here. Traceable, vmappable."""
    low_barrier = dataclasses.replace(settings, mu0=settings.mu0 * POLISH_MU)
    polished = newton.minimize(problem, weights, found.design, low_barrier)
    ev = family_of(problem).evaluate(problem, weights, polished.design)
    keep = ev.feasible & (~found.feasible | (ev.objective <= found.objective))
    design = jax.tree.map(lambda a, b: jnp.where(keep, a, b), polished.design, found.design)
    return design, polished.iterations, keep & polished.converged


def run_one(problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """GA (:func:`ga_stage`'s settings) from ``init`` (if given), then :func:`polish` from the GA's
    best design.

    Iterations: generations + Newton steps; converged: the polished design was kept and its scaled
    KKT residual reached the stopping rule. The final point's KKT certificate
    (:func:`camjax.solvers.certificate.certify_point`) comes with it.
    """
    found = ga.run(key, problem, weights, ga_stage(settings), seed_design=init)
    design, steps, converged = polish(problem, weights, found, settings.of("newton"))
    iterations = found.iterations + steps
    return Raw(design, iterations, converged, certify_point(problem, weights, design, iterations))
