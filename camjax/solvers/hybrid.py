"""Hybrid solver: the GA's global search, then a gradient polish from its best design, kept only
where it is no worse (the hybrid never returns a worse design than the GA it starts from).

The solver protocol of :mod:`camjax.solvers.base`; settings are the GA's and the gradient
solver's (``settings.of("ga")``, ``settings.of("gradient")``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.family import Design, Weights
from camjax.solvers import ga, gradient, newton
from camjax.solvers.base import Raw
from camjax.solvers.newton import certificate_json as certificate_json  # the final point's, in result.json

DEFAULT_SETTINGS = None  # the hybrid has no settings of its own


def run_one(problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """GA from ``init`` (if given), then the gradient solver from the GA's best design.

    The polished design is kept where it is feasible and its objective no larger than the GA's,
    or where it repairs an infeasible GA design; elsewhere the GA's design is the answer (a polish
    that stalls on a kink of the max over angles can end above its start). Iterations:
    generations + gradient steps; converged: the polished design was kept and the gradient
    stopping rule was met. The final point's KKT certificate
    (:func:`camjax.solvers.newton.certify_point`) comes with it.
    """
    found = ga.run(key, problem, weights, settings.of("ga"), seed_design=init)
    polished = gradient.minimize(problem, weights, found.design, settings.of("gradient"))
    keep = polished.feasible & (~found.feasible | (polished.objective <= found.objective))
    design = jax.tree.map(lambda a, b: jnp.where(keep, a, b), polished.design, found.design)
    iterations = found.iterations + polished.iterations
    return Raw(design, iterations, keep & polished.converged,
               newton.certify_point(problem, weights, design, iterations))
