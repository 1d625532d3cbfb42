"""Hybrid solver: the GA's global search, then the interior point (:mod:`camjax.solvers.newton`)
from its best design, kept only where it is no worse (the hybrid never returns a worse design than
the GA it starts from).

The solver protocol of :mod:`camjax.solvers.base`; settings are the GA's and the interior point's
(``settings.of("ga")``, ``settings.of("newton")``).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.family import Design, Weights
from camjax.solvers import ga, newton
from camjax.solvers.base import Raw, family_of
from camjax.solvers.certificate import certify_point
from camjax.solvers.certificate import certificate_json as certificate_json  # the final point's, in result.json

DEFAULT_SETTINGS = None  # the hybrid has no settings of its own


def run_one(problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """GA from ``init`` (if given), then Newton steps (:func:`camjax.solvers.newton.minimize`) from
    the GA's best design.

    The polished design is kept where it is feasible and its objective no larger than the GA's,
    or where it repairs an infeasible GA design; elsewhere the GA's design is the answer (a polish
    that ends elsewhere, on another local optimum or at its safeguard, never makes the answer
    worse). Iterations: generations + Newton steps; converged: the polished design was kept and
    its scaled KKT residual reached the stopping rule. The final point's KKT certificate
    (:func:`camjax.solvers.certificate.certify_point`) comes with it.
    """
    found = ga.run(key, problem, weights, settings.of("ga"), seed_design=init)
    polished = newton.minimize(problem, weights, found.design, settings.of("newton"))
    ev = family_of(problem).evaluate(problem, weights, polished.design)
    keep = ev.feasible & (~found.feasible | (ev.objective <= found.objective))
    design = jax.tree.map(lambda a, b: jnp.where(keep, a, b), polished.design, found.design)
    iterations = found.iterations + polished.iterations
    return Raw(design, iterations, keep & polished.converged,
               certify_point(problem, weights, design, iterations))
