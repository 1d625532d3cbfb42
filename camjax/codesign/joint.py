"""The co-design as one program in the laws and the geometry together: a problem family of its own.

The bilevel search (:mod:`camjax.codesign.problem`) solves the geometry anew for every law it
tries. Here the laws' free coordinates z, the follower family's design d and an epigraph
variable t are the design of one problem,

    minimize   t + law(z)
    subject to f_i(z, d) - t <= 0          at every angle i (the peak of the objective),
               g(P(z), d) <= 0             the family's constraints at every angle,
               d in [design]'s box, z in a box around the start, t in [0, t_max],

f_i the family's objective on the one-angle problem i (alpha size / N + gamma sigma_i / sigma_max),
P(z) its problem on the kinematics of z (:meth:`camjax.codesign.Codesign.problem`), law(z) the
[synthesis] terms that are quadratics in z. The epigraph makes every function smooth, so the
interior-point solver (:func:`camjax.solvers.newton.minimize`, exact second derivatives, stopping
on its scaled KKT residual; the family declares ``SMOOTH_OBJECTIVE``) or the gradient solver's
augmented-Lagrangian BFGS (:func:`camjax.solvers.gradient.refine_bfgs`, one multiplier per row)
solves it in one jitted loop, and a batch of co-designs (weightings, lifts, durations: problems of
one follower family on one grid) in one ``vmap``. On the built-in `codesign` scene (360 samples,
23 variables) the interior point ends in 42 Newton steps at F = 0.418834; the BFGS runs to its cap
of 24,000 evaluations and ends at 0.419483 from the same start.

This module is that problem family (the protocol of :mod:`camjax.solvers.base`): ``bounds``,
``size_norm``, ``objective`` (t + law(z): what the solver minimizes), ``size_term``,
``constraints``, ``constraint_maxima`` and ``evaluate`` (its ``objective`` the true F: the
family's objective with the true max over the angles, + law(z)). It takes the co-design's
quadratic law terms only: peak terms and a designed spring stay with the bilevel search
(:func:`supports`).
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.family import Weights
from camjax.solvers import gradient
from camjax.solvers.base import family_of, register_family

# half-width of the laws' box around the start, at least (each coordinate; normalized control
# units): max(Z_HALF_WIDTH, 2 |z_start|_inf). On the benchmark's 20 co-designs the optimum moves
# z by at most 0.2 from the start and its box is 1.9 wide; a 4-wide box gives the same optima
# with about 2x the solver's steps (the box maps onto the unit cube: a wider box, a worse scaling)
Z_HALF_WIDTH = 1.0
T_HEADROOM = 2.0  # t's box: [0, T_HEADROOM x the start's peak of f_i]
AT_BOX_RTOL = 1e-6  # a coordinate within this fraction of its box's width of a bound is at the box
# the solver's settings: its augmented-Lagrangian BFGS alone (the epigraph is smooth: no Rprop
# phase); 30 rounds of at most 800 evaluations. benchmarks/codesign.py (120 samples): every problem
# stops by itself within 2,700 evaluations, at SLSQP's optimum to 6e-10; rounds of 200-300 ended up
# to 0.9 % higher there. The `codesign` scene at 360 samples needs more: with 15 rounds of 400 it
# stopped at the cap, 6 % above (alpha = 2: 0.7458 against 0.6928 with this setting)
SETTINGS = gradient.GradientSettings(max_steps=0, refine_rounds=30, refine_steps=800, refine_gtol=1e-11)


class JointDesign(NamedTuple):
    """One point of the joint program (a pytree)."""

    laws: jax.Array  # (m,) the designed laws' free coordinates z
    geometry: Any  # the follower family's Design, mm
    peak: jax.Array  # () t, the epigraph variable (dimensionless)


class JointConstraints(NamedTuple):
    """Every row g <= 0, in mm (the epigraph rows times the size norm N)."""

    peak: jax.Array  # (n,) N (f_i - t)
    geometry: Any  # the family's Constraints, (n,) each


class JointEvaluation(NamedTuple):
    objective: jax.Array  # F = family objective (true max over angles) + law(z)
    violation: Any  # the family's Violation at (P(z), d)
    feasible: jax.Array  # bool
    peak_gap: jax.Array  # t - max_i f_i (>= 0 at a feasible point)
    geometry: Any  # the family's Evaluation


@partial(jax.tree_util.register_dataclass,
         data_fields=["kin0", "jacobian", "z0", "lower", "upper", "law_P", "law_q", "law_c", "weights",
                      "size_norm_mm"],
         meta_fields=["build"])
@dataclasses.dataclass(frozen=True)
class JointProblem:
    """The data of one joint co-design (arrays; a stack of them has a leading axis on every leaf).

    ``build(kin4) -> Problem``: the follower family's problem on kinematics (4, n) (static: one
    for a whole batch, :func:`stack`).
    """

    kin0: jax.Array  # (4, n) s, s', s'', s''' of the laws at z0 (mm, per rad^k)
    jacobian: jax.Array  # (4, n, m) their derivative in z
    z0: jax.Array  # (m,)
    lower: JointDesign
    upper: JointDesign
    law_P: jax.Array  # (m, m) law(z) = 0.5 z P z + q z + c
    law_q: jax.Array  # (m,)
    law_c: jax.Array  # ()
    weights: Weights  # the geometry objective's alpha, gamma
    size_norm_mm: jax.Array  # () N of the family's problem
    build: Callable = dataclasses.field(compare=False)


register_family(JointProblem, sys.modules[__name__])
# the objective t + law(z) is smooth (this family holds its own epigraph variable): the interior
# point takes it as it is (:func:`camjax.solvers.epigraph.smooth_form`), not split over angles
SMOOTH_OBJECTIVE = True


def supports(cd) -> bool:
    """Whether a co-design (:class:`camjax.codesign.Codesign`) fits this program: :func:`takes` its scene."""
    return takes(cd.scene)


def takes(scene) -> bool:
    """Whether the joint program takes a co-design scene: no peak terms and no designed spring (its
    preload is eliminated per law by the bilevel search; Python, reads the scene only). Peak terms
    as epigraph rows (+-v_j(z) <= p_k, w_k p_k in the objective) were tried: on the `codesign`
    scene at 180 samples with peak_accel 1e-3 the solve ran to its cap and ended at 0.45165 (rows
    weighted by w_k) or 0.46552 (rows divided by the start's peak), against 0.45060 for the bilevel
    search's continuation, so they stay there."""
    import camjax.codesign.spring as spring_mod
    from camjax.synthesis.problem import PEAK_TERMS

    terms = dict(scene.synthesis.objective) if scene.synthesis is not None else {}
    peaks = any(terms.get(name, 0.0) > 0.0 for name in PEAK_TERMS)
    return not peaks and spring_mod.spring_box(scene, ValueError) is None


def joint_solver(solver: str) -> str:
    """The solver the joint program runs for a [design] ``solver``: each registered one as named
    (``gradient``: its augmented-Lagrangian BFGS alone, the epigraph being smooth); any other name
    the gradient solver's BFGS."""
    return solver if solver in ("ga", "hybrid", "newton") else "gradient"


def search_solver(scene) -> str:
    """The solver that searches a co-design scene's laws: the joint program's
    (:func:`joint_solver` of its [design] solver) where it :func:`takes` the scene, else the
    bilevel search's gradient solver."""
    return joint_solver(scene.design.solver) if takes(scene) else "gradient"


# ------------------------------------------------------------------------------ construction


def joint_problem(cd, z_start, design_start) -> tuple[JointProblem, JointDesign]:
    """The joint program of co-design ``cd`` (a :class:`camjax.codesign.Codesign` that
    :func:`supports`) and its start: laws ``z_start``, geometry ``design_start`` (the inner optimum
    there), t the peak of f_i there. The laws' box is centred on the start, half-width
    max(:data:`Z_HALF_WIDTH`, 2 |z_start|_inf) in each coordinate."""
    if not supports(cd):
        raise ValueError("the joint program takes quadratic law terms only "
                         "(no peak terms, no designed spring)")
    z_start = np.asarray(z_start, dtype=np.float64)
    problem0 = cd.problem(cd.kinematics(z_start))
    family = family_of(problem0)
    lo, hi = family.bounds(problem0)
    half = max(Z_HALF_WIDTH, 2.0 * float(np.max(np.abs(z_start), initial=0.0)))
    build = cd.builder  # equal for every co-design of one shape and grid: one compiled solve
    f_start = float(jnp.max(_peak_rows(problem0, cd.weights, design_start)))
    lower = JointDesign(jnp.asarray(z_start - half), lo, jnp.asarray(0.0))
    upper = JointDesign(jnp.asarray(z_start + half), hi, jnp.asarray(T_HEADROOM * max(f_start, 1e-3)))
    P, q, c = (jnp.asarray(v, dtype=jnp.float64) for v in (cd.law_P, cd.law_q, cd.law_c))
    jp = JointProblem(jnp.asarray(cd.kin0), jnp.asarray(cd.jacobian), jnp.asarray(cd.lin.z0), lower, upper,
                      P, q, c, cd.weights, jnp.asarray(family.size_norm(problem0)), build)
    start = JointDesign(jnp.asarray(z_start), jax.tree.map(jnp.asarray, design_start), jnp.asarray(f_start))
    return jp, start


def stack(problems: list[JointProblem]) -> JointProblem:
    """One batch of joint programs (a leading axis on every leaf), built with the first one's
    ``build``: every problem's own ``build`` must give the same problem on its start kinematics
    (co-designs of one scene whose motion differs: the family's problem reads the grid, the
    [design], the follower and the loads' data, not the segments), checked here."""
    first = problems[0]
    for p in problems[1:]:
        kin = p.kin0
        a, b = first.build(kin), p.build(kin)
        same = jax.tree.all(jax.tree.map(lambda x, y: bool(np.array_equal(np.asarray(x), np.asarray(y))),
                                         a, b))
        if not same:
            raise ValueError("stack: the problems' families differ beyond their kinematics (not one batch)")
    rebuilt = [dataclasses.replace(p, build=first.build) for p in problems]
    return jax.tree.map(lambda *xs: jnp.stack(xs), *rebuilt)


# ------------------------------------------------------------------------------ the family


def kinematics(problem: JointProblem, z) -> jax.Array:
    """(4, n) kinematics of the laws z."""
    return problem.kin0 + jnp.tensordot(problem.jacobian, z - problem.z0, axes=1)


def base_problem(problem: JointProblem, design: JointDesign):
    """The follower family's problem on the kinematics of ``design.laws``."""
    return problem.build(kinematics(problem, design.laws))


def law_value(problem: JointProblem, z) -> jax.Array:
    return 0.5 * z @ problem.law_P @ z + problem.law_q @ z + problem.law_c


def _peak_rows(base, weights: Weights, geometry) -> jax.Array:
    """f_i: the family's objective on each one-angle problem, (n,)."""
    family = family_of(base)
    return jax.vmap(lambda p: family.objective(p, weights, geometry))(family.per_angle(base))


def bounds(problem: JointProblem):
    return problem.lower, problem.upper


def size_norm(problem: JointProblem) -> jax.Array:
    return problem.size_norm_mm


def objective(problem: JointProblem, weights: Weights, design: JointDesign) -> jax.Array:
    """t + law(z): the epigraph's objective (what the solver minimizes; ``weights`` are the
    problem's own, which the rows carry)."""
    del weights
    return design.peak + law_value(problem, design.laws)


def size_term(problem: JointProblem, design: JointDesign) -> jax.Array:
    base = base_problem(problem, design)
    return family_of(base).size_term(base, design.geometry)


def constraints(problem: JointProblem, design: JointDesign) -> JointConstraints:
    base = base_problem(problem, design)
    rows = _peak_rows(base, problem.weights, design.geometry) - design.peak
    return JointConstraints(problem.size_norm_mm * rows, family_of(base).constraints(base, design.geometry))


def constraint_maxima(problem: JointProblem, design: JointDesign) -> JointConstraints:
    return jax.tree.map(jnp.max, constraints(problem, design))


def evaluate(problem: JointProblem, weights: Weights, design: JointDesign) -> JointEvaluation:
    """The true F at ``design`` (the family's evaluation of its geometry on P(z), + law(z)), its
    violations and feasibility (the family's), and how far t is above the peak of f_i."""
    del weights
    base = base_problem(problem, design)
    family = family_of(base)
    ev = family.evaluate(base, problem.weights, design.geometry)
    gap = design.peak - jnp.max(_peak_rows(base, problem.weights, design.geometry))
    return JointEvaluation(ev.objective + law_value(problem, design.laws), ev.violation, ev.feasible, gap, ev)


# ------------------------------------------------------------------------------ solves


class JointResult(NamedTuple):
    """One joint co-design (shape () each; a batch: a leading axis)."""

    laws: jax.Array  # (m,) z at the end of the joint solve
    at_box: jax.Array  # bool: some coordinate of z ended at its box (the box, not the optimum, stopped it)
    design: Any  # the family's Design: the geometry optimum of those laws (the inner solve's)
    objective: jax.Array  # F(z): the family's objective at that optimum + law(z)
    feasible: jax.Array  # bool: that geometry's feasibility
    iterations: jax.Array  # int: the joint solve's evaluations


def solve(problem: JointProblem, start: JointDesign, settings=SETTINGS, solver: str = "gradient",
          key: jax.Array | None = None, ga_settings=None) -> JointResult:
    """One joint co-design from ``start`` by a registered solver, then the geometry of its laws
    solved as the bilevel search solves it (:func:`camjax.codesign.problem.inner_solve` on P(z):
    what :meth:`camjax.codesign.Codesign.value` gives), so that F(z) is the co-design's own value
    of those laws and the geometry meets the family's tolerances. Traceable; vmap it over a stack.

    ``solver`` (:func:`joint_solver` of it) runs as the registry's ``run_one`` runs it
    (:func:`camjax.solvers.base.solver_module`), from ``start``: ``newton`` (the interior point
    with its default settings, :func:`camjax.solvers.epigraph.smooth_form`), ``gradient`` (the
    gradient solver with ``settings``: :data:`SETTINGS`, its augmented-Lagrangian BFGS alone,
    the start kept where the BFGS ends no better), ``ga`` (the GA, ``ga_settings`` (default its
    own), PRNG ``key``, its population seeded with the start: by elitism never worse than it) or
    ``hybrid`` (the hybrid solver: its GA stage so seeded, then its interior-point polish).
    Iterations: the solver's own count (the GA's generations plus the polish's Newton steps; the
    gradient solver's evaluations)."""
    from camjax.codesign.problem import JOINT_INNER_SOLVER, inner_solve
    from camjax.solvers.base import Settings, solver_module

    solver = joint_solver(solver)
    settings_of = Settings.of_solvers(gradient=settings, ga=ga_settings)
    raw = solver_module(solver).run_one(problem, problem.weights, jax.random.key(0) if key is None else key,
                                        settings_of, init=start)
    design, steps = raw.design, raw.iterations
    base = base_problem(problem, design)
    objective, geometry, feasible = inner_solve(base, problem.weights, solver=JOINT_INNER_SOLVER)
    f = objective + law_value(problem, design.laws)
    width = problem.upper.laws - problem.lower.laws
    at_box = jnp.any((design.laws - problem.lower.laws <= AT_BOX_RTOL * width)
                     | (problem.upper.laws - design.laws <= AT_BOX_RTOL * width))
    return JointResult(design.laws, at_box, geometry, f, feasible, steps)


@partial(jax.jit, static_argnames=("settings", "solver"))
def solve_batch(problems: JointProblem, starts: JointDesign, settings=SETTINGS, solver: str = "gradient"
                ) -> JointResult:
    """A stack of joint co-designs (:func:`stack`) in one vmapped, jitted solve (``gradient`` or
    ``newton``, see :func:`solve`)."""
    return jax.vmap(lambda p, s: solve(p, s, settings, solver))(problems, starts)


_solve_one = jax.jit(solve, static_argnames=("settings", "solver", "ga_settings"))


def search(cd, z0, f0: float, inner0, settings=SETTINGS):
    """The co-design ``cd`` (a :class:`camjax.codesign.Codesign` that :func:`supports`) from laws
    ``z0`` with F(z0) = ``f0`` and inner optimum ``inner0``: one joint solve by the scene's [design]
    solver and seed (:func:`solve`; the key of the seed's first weighting, as ``camjax design``
    draws it), then F and the inner
    optimum at its laws by ``cd`` itself (:meth:`~camjax.codesign.Codesign.value`, the solve that
    ends :func:`solve`, so the two agree). Returns what :func:`camjax.codesign.search.bfgs`
    returns: z, F, the inner optimum, the joint solve's evaluations and [F(z0), F(z)]; the start
    where the joint solve did not improve on it (Python: a driver of the jitted solve)."""
    import warnings

    from camjax.solvers.base import weighting_keys

    problem, start = joint_problem(cd, z0, inner0.design)
    design = cd.scene.design
    res = jax.device_get(_solve_one(problem, start, settings, joint_solver(design.solver),
                                    weighting_keys(design.seed, 1)[0]))
    z = np.asarray(res.laws, dtype=np.float64)
    if bool(res.at_box):
        warnings.warn("co-design: the laws' box of the joint solve stopped it (a coordinate at its bound); "
                      "the design is the best inside that box", RuntimeWarning, stacklevel=2)
    f, inner = cd.value(z)
    if not f < f0:
        return np.asarray(z0, dtype=np.float64), f0, inner0, int(res.iterations), [f0]
    return z, f, inner, int(res.iterations), [f0, f]
