"""The smooth epigraph form of a design problem: what :mod:`camjax.solvers.newton` solves and certifies.

For one problem and weighting (every registered problem family, through its protocol only,
:mod:`camjax.solvers.base`), with the design mapped to the unit box u
(:func:`camjax.solvers.box.to_unit` with ``own=False``: each variable over its bounds) and an epigraph variable t, z = (u, t):

    minimize    phi(z) = t  (+ 1e-9 size_term when alpha = 0, the gradient solver's tie-break)
    subject to  rows(z) <= 0: f_i(u) - t at every angle i (f_i the one-angle problem's objective
                divided by alpha + gamma), every constraint row g / N, and the unit box

:func:`epigraph_form` builds phi, rows and their row blocks (``kinds``: the names and counts the
certificate labels its multipliers by). With gamma = 0 the first objective row alone holds t (n
equal rows would leave the multipliers' split free); a constraint block that is not one row per
angle (a robust problem's row per sample, a max over the grid) is taken from the n one-angle
problems, one row per angle and sample; rows below -ROW_FLOOR are floored there. A family whose
objective is smooth already (it declares ``SMOOTH_OBJECTIVE = True``) takes :func:`smooth_form`:
one objective row, objective(u) - t. A family with an ``angle_stress`` hook gives the f_i from its
grid at once (alpha size_term + gamma sigma_i / sigma_max): the same numbers, with the terms the
constraint rows compute shared (the oscillating curved face's 100-weighting sweep ran in 0.35 s
instead of 0.44 s on 2 cores). A family with a ``smooth_constraints`` hook gives its constraint rows
without their kinks (:func:`camjax.family.excess`: the same feasible set, and the same values and
gradients where a row binds): the roller's 100-weighting sweep took at most 36 Newton steps with
them and 64 with |s' - e~| - tan(phi_max) w, whose kink at a dwell (s' = 0, the offset near 0)
held the steps zig-zagging across offset 0.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax.flatten_util import ravel_pytree

from camjax.family import Weights, weighted_objective
from camjax.solvers.base import family_of
from camjax.solvers.box import TIE_BREAK, from_unit, u_max_of

ROW_FLOOR = 1e3  # the normalized rows' floor (a row below it is inactive; see :func:`epigraph_form`)


class EpigraphForm(NamedTuple):
    """A problem's epigraph form (see the module docstring): its functions of z = (u, t) and row blocks."""


    phi: Any  # z -> () objective
    rows: Any  # z -> (M,) c(z) <= 0, every row
    unravel: Any  # (m,) -> unit-box Design
    free: jax.Array  # (m + 1,) 1 free, 0 fixed (t free)
    u_max: jax.Array  # (m,)
    n_angles: int
    kinds: tuple  # ((name, count), ...) the row blocks in order: "objective", each constraint, bounds
    epigraph: jax.Array  # (n,) bool: the objective rows that hold t (all, or the first alone: gamma = 0)
    mu_scale: float  # 1 / the most rows per angle of a split block (1 without one): scales mu0
    split: bool  # a block was split by angle and sample (a robust problem): the feasible-slack path
    t_column: jax.Array  # (M,) d rows / d t: -1 on the rows that hold t, 0 elsewhere (phi = t + a
    # function of u: phi and every row are affine in t)


def _unit_box(u_max_tree):
    """The unit box's flat upper corner, its unravel, its size m and dtype, which variables are
    free (u_max > 0) and the same with t (always free) appended."""
    u_max, unravel = ravel_pytree(u_max_tree)
    dtype = u_max.dtype
    free_u = (u_max > 0).astype(dtype)
    return u_max, unravel, u_max.shape[0], dtype, free_u, jnp.concatenate([free_u, jnp.ones(1, dtype)])


def epigraph_form(problem, weights: Weights) -> EpigraphForm:
    """The epigraph form of ``problem`` for one weighting (traceable; the functions close over it).
    A family that declares ``SMOOTH_OBJECTIVE = True`` gets :func:`smooth_form`."""
    family = family_of(problem)
    if getattr(family, "SMOOTH_OBJECTIVE", False):
        return smooth_form(problem, weights)
    u_max_tree = u_max_of(problem)
    u_max, unravel, m, dtype, free_u, free = _unit_box(u_max_tree)
    per = family.per_angle(problem)
    total = weights.alpha + weights.gamma
    scale = jnp.where(total > 0, total, 1.0)
    tie = jnp.where(weights.alpha > 0, 0.0, TIE_BREAK)
    norm = family.size_norm(problem)

    def design_of(z):
        return from_unit(problem, unravel(z[:m]), own=False)

    def phi(z):
        return z[m] + tie * family.size_term(problem, design_of(z))

    n = problem.theta_deg.shape[-1]
    shapes = jax.eval_shape(lambda: family.constraints(problem, from_unit(problem, u_max_tree, own=False)))
    # a block with one row per angle is smooth; any other (a robust problem's row per sample, each
    # a max over the grid) is taken from the n one-angle problems instead, one row per angle and
    # sample: the same feasible set (max_i g_i <= 0 iff every g_i <= 0) without a kink in a row
    split = tuple(tuple(v.shape) != (n,) for v in shapes)

    # the rows without the kinks of their |.| where the family gives them (the same zero sets)
    constraints = getattr(family, "smooth_constraints", family.constraints)  # optional hook

    def constraint_rows(design):
        g = constraints(problem, design)
        if any(split):
            at = jax.vmap(lambda p: constraints(p, design))(per)  # (n, ...) each
            g = [jnp.moveaxis(a, 0, -1) if cut else v for v, a, cut in zip(g, at, split, strict=True)]
        return [jnp.ravel(v) for v in g]

    epigraph = (weights.gamma != 0) | (jnp.arange(n) == 0)
    angle_stress = getattr(family, "angle_stress", None)  # optional hook

    def objective_rows(design):  # (n,) f_i: the one-angle problems' objectives
        if angle_stress is None:
            return jax.vmap(lambda p: family.objective(p, weights, design))(per)
        # the same numbers from the grid at once (a family's objective is alpha size_term + gamma
        # peak / sigma_max, the peak the max of angle_stress): the rows share their terms with the
        # constraint rows' (one evaluation of the geometry instead of two)
        return weighted_objective(weights, family.size_term(problem, design), angle_stress(problem, design),
                                  problem.sigma_max_MPa)

    def rows(z):
        design = design_of(z)
        f = objective_rows(design) / scale - z[m]
        # without a stress weight every f_i is the same size term: n equal rows make the epigraph
        # degenerate (the multipliers' split among them is free, and the path stalls on it), so
        # the first row alone carries it and the others are a constant -1 (never active)
        f = jnp.where(epigraph, f, -1.0)
        g = jnp.concatenate(constraint_rows(design)) / norm
        # a row far inside its limit (a never-active row: a robust problem's discarded sample is
        # -1e30) floored at -ROW_FLOOR: the same feasible set (max(g, -F) <= 0 iff g <= 0), and
        # slacks of O(F), whose rounding cannot swamp the infeasibility measure
        g = jnp.maximum(g, -ROW_FLOOR)
        u = z[:m]
        box_lo = jnp.where(free_u > 0, -u, -1.0)
        box_hi = jnp.where(free_u > 0, u - u_max, -1.0)
        return jnp.concatenate([f.astype(dtype), g, box_lo, box_hi])

    counts = [v.shape[0] for v in jax.eval_shape(lambda: constraint_rows(from_unit(problem, u_max_tree, own=False)))]
    blocks = zip(shapes._fields, counts, strict=True)
    kinds = (("objective", n), *blocks, ("lower_bound", m), ("upper_bound", m))
    # a split block has k rows per angle (a robust problem's 1 + S): its barrier term is k times a
    # grid block's, so the first barrier parameters are divided by k (the path starts as near the
    # objective as on a grid problem; with mu0 the barrier pushed the design to the box's far side)
    mu_scale = 1.0 / max([c // n for c, cut in zip(counts, split, strict=True) if cut] or [1])
    total = n + sum(counts) + 2 * m
    t_column = jnp.zeros(total, dtype).at[:n].set(-epigraph.astype(dtype))
    return EpigraphForm(phi, rows, unravel, free, u_max, n, kinds, epigraph, mu_scale, any(split), t_column)


def smooth_form(problem, weights: Weights) -> EpigraphForm:
    """The form of a family whose objective is smooth already (it declares ``SMOOTH_OBJECTIVE =
    True``: the co-design's joint program, :mod:`camjax.codesign.joint`, which holds its own
    epigraph variable). There is no max over angles to take apart: one objective row,
    objective(u) - t <= 0, the constraint rows g / N of every leaf of ``family.constraints`` (a
    nested tuple of blocks: ``kinds`` names each by its path), and the unit box."""
    family = family_of(problem)
    u_max, unravel, m, dtype, free_u, free = _unit_box(u_max_of(problem))
    norm = family.size_norm(problem)

    def design_of(z):
        return from_unit(problem, unravel(z[:m]), own=False)

    def phi(z):
        return z[m]

    def constraint_rows(design):
        return [jnp.ravel(v) for v in jax.tree.leaves(family.constraints(problem, design))]

    def rows(z):
        design = design_of(z)
        f = jnp.reshape(family.objective(problem, weights, design), (1,)) - z[m]
        g = jnp.maximum(jnp.concatenate(constraint_rows(design)) / norm, -ROW_FLOOR)
        u = z[:m]
        box_lo = jnp.where(free_u > 0, -u, -1.0)
        box_hi = jnp.where(free_u > 0, u - u_max, -1.0)
        return jnp.concatenate([f.astype(dtype), g, box_lo, box_hi])

    shapes = jax.eval_shape(lambda: family.constraints(problem, design_of(jnp.zeros(m + 1, dtype))))
    paths = jax.tree_util.tree_flatten_with_path(shapes)[0]
    blocks = tuple((jax.tree_util.keystr(path, simple=True, separator="."), int(math.prod(leaf.shape)))
                   for path, leaf in paths)
    kinds = (("objective", 1), *blocks, ("lower_bound", m), ("upper_bound", m))
    t_column = jnp.zeros(1 + sum(count for _, count in blocks) + 2 * m, dtype).at[0].set(-1.0)
    return EpigraphForm(phi, rows, unravel, free, u_max, 1, kinds, jnp.ones(1, bool), 1.0, False, t_column)
