"""The KKT certificate of an answer: its scaled residuals, its multipliers and what they price.

The answer of :mod:`camjax.solvers.newton` is a point z = (u, t) of the epigraph form
(:func:`camjax.solvers.epigraph.epigraph_form`: the unit-box variables u, the epigraph variable t,
one row c_i per angle and constraint, the box) with a multiplier y_i >= 0 per row. Its scaled KKT
residuals (IPOPT's, :func:`kkt_residuals`): stationarity ||grad phi + J^T y||_inf / s_d, primal
infeasibility max(c, 0), complementarity max |c_i| y_i / s_d, with s_d = max(100, ||y||_1 / rows) / 100
(:data:`S_MAX`); the interior point stops when the largest is <= :data:`TOL` (its ``tol``).

:func:`certificate_of` prices the scene's limits at an answer with its multipliers (the envelope
theorem: dF*/d limit = (alpha + gamma) sum_i y_i dc_i/d limit, the derivative of the Lagrangian in
the problem's limit fields; bounds through the unit box), in the solve's own program (no second
solve). :func:`certify_point` certifies any design (the GA's and the hybrid's final points, the
gradient solver's): the same residuals with multipliers fitted on the active rows by least
squares. :func:`certificate_json` writes result.json's ``certificate`` block from either, naming
the binding constraints (:func:`limited_by`: the text summary's line).
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.flatten_util import ravel_pytree

from camjax.family import Design, Problem, Weights, weights_of
from camjax.solvers.base import family_of
from camjax.solvers.box import to_unit, u_max_of
from camjax.solvers.epigraph import EpigraphForm, epigraph_form
from camjax.solvers.limits import limit_setters as _limits
from camjax.solvers.limits import limit_values

TOL = 1e-9  # the scaled KKT residual of a converged answer (the interior point's default ``tol``)
S_MAX = 100.0  # IPOPT's s_max: multipliers larger than this on average scale the dual residuals


class KKT(NamedTuple):
    """Scaled KKT residuals (dimensionless; the solver's normalized objective and rows)."""

    stationarity: jax.Array  # ||grad phi + J^T y||_inf / s_d (free variables)
    primal: jax.Array  # max(max_i c_i, 0): the largest violated row (g / N, f_i - t)
    complementarity: jax.Array  # max_i |c_i| y_i / s_d at the answer (slack-free: c, not s)
    error: jax.Array  # the largest of the three


def dual_scale(y, count):
    return jnp.maximum(S_MAX, jnp.sum(y) / count) / S_MAX


def residuals(grad, c, jac, y, free) -> KKT:
    """:class:`KKT` from the objective's gradient, the rows c and their Jacobian at one point."""
    sd = dual_scale(y, y.shape[0])
    stat = jnp.max(jnp.abs((grad + jac.T @ y) * free)) / sd
    primal = jnp.maximum(jnp.max(c), 0.0)
    comp = jnp.max(jnp.abs(jnp.minimum(c, 0.0)) * y) / sd
    return KKT(stat, primal, comp, jnp.maximum(jnp.maximum(stat, primal), comp))


def rows_and_jacobian(fns: EpigraphForm, z, point=None):
    """c(z) and its Jacobian from one forward-mode pass (the rows traced once: c is its primal);
    with ``point``, c(point(z)) and its Jacobian in z."""

    def rows(v):
        c = fns.rows(v if point is None else point(v))
        return c, c

    jac, c = jax.jacfwd(rows, has_aux=True)(z)
    return c, jac


def kkt_residuals(fns: EpigraphForm, z, y) -> KKT:
    """The scaled KKT residuals of the epigraph form at z = (u, t) with multipliers y (one per row)."""
    c, jac = rows_and_jacobian(fns, z)
    return residuals(jax.grad(fns.phi)(z), c, jac, y, fns.free)


class KKTPoint(NamedTuple):
    """An answer with its multipliers: the interior point's, or any design certified (shape () each
    for one problem, except the arrays noted)."""

    design: Design  # mm
    iterations: jax.Array  # int: the solver's steps
    converged: jax.Array  # bool: the KKT residual reached ``tol``
    z: jax.Array  # (m + 1,) unit-box variables and t at the answer
    multipliers: jax.Array  # (M,) y, one per row of the epigraph form
    kkt: KKT  # scaled residuals at the answer


class Certificate(NamedTuple):
    """The KKT certificate of one answer (traceable; arrays): what a solver's ``run_one`` hands to
    result.json."""

    result: KKTPoint  # the answer, its multipliers and scaled residuals
    scale: jax.Array  # () alpha + gamma: F = scale * (solver objective)
    sensitivity: dict  # limit key -> (M,) per-row dF*/d limit (scene units); the sum is the total
    bound_sensitivity: jax.Array  # (2m,) dF*/d bound (mm) of each bound row (lower, then upper)
    gamma: jax.Array  # () the stress weight (0: the epigraph rows carry the size only)


def certificate_of(problem: Problem, weights: Weights, res: KKTPoint) -> Certificate:
    """The sensitivities of the optimal objective F* to each limit of the scene at an answer with
    its multipliers, by the envelope theorem, dF*/dp = (alpha + gamma) sum_i y_i dc_i/dp at the
    answer (u, t fixed), split by row. Bounds: dF*/d lo_j = (alpha + gamma) y_j du_j/dx_j (and
    minus that for an upper bound), with the normalization N fixed. No solve: traceable, vmappable."""
    total = weights.alpha + weights.gamma
    scale = jnp.where(total > 0, total, 1.0)
    setters = _limits(problem)

    def rows_at(values):  # the rows at the answer with every limit set to ``values`` (one trace)
        moved = problem
        for key, setter in setters.items():
            moved = setter(moved, values[key])
        return epigraph_form(moved, weights).rows(res.z)

    # limit key -> (M,) dc/d limit (a problem without limits, e.g. a robust one: none)
    moved = jax.jacfwd(rows_at)(limit_values(problem)) if setters else {}
    sens = {key: scale * res.multipliers * moved[key] for key in setters}
    m = ravel_pytree(u_max_of(problem))[0].shape[0]
    x, unravel = ravel_pytree(res.design)
    diag = jnp.diagonal(jax.jacfwd(lambda v: ravel_pytree(to_unit(problem, unravel(v), own=False))[0])(x))
    y_box = res.multipliers[-2 * m:]
    bound = scale * y_box * jnp.concatenate([diag, -diag])
    return Certificate(res, scale, sens, bound, weights.gamma)


def certify_point(problem: Problem, weights: Weights, design: Design, iterations=0, *,
                  active_tol: float = 1e-6, tol: float = TOL) -> Certificate:
    """The certificate of any design (a GA's or a hybrid's final point): the epigraph form at
    t = max_i f_i, the rows within ``active_tol`` of their limit taken as active, their multipliers
    the least-squares fit of stationarity grad phi + J_A^T y_A = 0 (negative ones set to 0, which
    leaves their share in the stationarity residual), the KKT residuals and sensitivities from
    those. ``converged``: the residuals are within ``tol``. Traceable, vmappable."""
    fns = epigraph_form(problem, weights)
    dtype = fns.u_max.dtype
    u = ravel_pytree(jax.tree.map(lambda x: jnp.asarray(x, dtype), to_unit(problem, design, own=False)))[0]
    u = jnp.where(fns.u_max > 0, u, 0.0)
    n = fns.n_angles
    rows0 = fns.rows(jnp.concatenate([u, jnp.zeros(1, dtype)]))
    t = jnp.max(jnp.where(fns.epigraph, rows0[:n], -jnp.inf))
    z = jnp.concatenate([u, t[None]])
    c, jac = rows_and_jacobian(fns, z)
    grad = jax.grad(fns.phi)(z)
    active = (c >= -active_tol).astype(dtype)
    fit = jnp.linalg.lstsq((jac * fns.free).T * active, -grad * fns.free)[0]
    y = jnp.maximum(fit, 0.0) * active
    kkt = residuals(grad, c, jac, y, fns.free)
    res = KKTPoint(design, jnp.asarray(iterations), kkt.error <= tol, z, y, kkt)
    return certificate_of(problem, weights, res)


def point_certificate_json(problem: Problem, solution) -> dict:
    """result.json's certificate block of a :class:`camjax.solvers.base.Solution` that came without
    one (the gradient solver's): its final point certified on ``problem`` by :func:`certify_point`
    (one compiled program per problem form); in pointwise mode each angle's design on that angle's
    problem (one program for every angle), the block the critical angle's (:func:`certificate_json`)."""
    w = weights_of(solution.alpha, solution.gamma, problem.lower[0].dtype)
    if solution.mode == "pointwise":  # the per-angle designs, each on its angle's problem
        designs = jax.tree.map(jnp.asarray, solution.pointwise)
        cert = _certify_angles(family_of(problem).per_angle(problem), w, designs, solution.iterations)
    else:
        cert = _certify_point(problem, w, jax.tree.map(jnp.asarray, solution.design), solution.iterations)
    return certificate_json(problem, cert, mode=solution.mode, solver=solution.solver)


def solution_json(problem, solution, solved=None) -> dict:
    """A solution's JSON (:meth:`camjax.solvers.base.Solution.to_json` on ``problem``) with its
    certificate: the solver's own, of the rows of ``solved`` (the problem it solved; ``problem``
    when None), or, for a solver whose answer comes without one (the gradient solver's), its final
    point certified (:func:`point_certificate_json`)."""
    solved = problem if solved is None else solved
    out = dataclasses.replace(solution, certificate=None).to_json(problem)
    if solution.certificate is not None:
        out["certificate"] = solution.certificate_json(solved)
    else:
        out["certificate"] = point_certificate_json(solved, solution)
    return out


_certify_point = jax.jit(certify_point)
_certify_angles = jax.jit(jax.vmap(certify_point, in_axes=(0, None, 0, None)))


def _block(problem, cert: Certificate, *, active_tol: float = 1e-6) -> dict:
    """The residuals, sensitivities and merged active rows of :func:`certificate_json` (one answer)."""
    res = cert.result
    y = np.asarray(res.multipliers, float)
    scale = float(cert.scale)
    row_kinds = []  # the form's row blocks: static, read off a trace (nothing compiled or run)

    def blocks(p):
        row_kinds.append(epigraph_form(p, Weights(jnp.asarray(1.0), jnp.asarray(1.0))).kinds)
        return jnp.zeros(())

    jax.eval_shape(blocks, problem)
    theta = np.asarray(problem.theta_deg, float).reshape(-1)
    lower = family_of(problem).bounds(problem)[0]
    variables = list(lower._fields)
    keys = {"pressure_angle": "max_pressure_angle_deg", "stress": "sigma_max_MPa",
            "undercut": "min_curvature_radius_mm", "curvature": "min_curvature_radius_mm",
            # the face's own width (a design variable) is what these rows bind against
            "face_width": "face_width_mm (design)", "face_travel": "face_width_mm (design)"}
    # a problem with two contacts (a positive drive) names each row's kind and contact
    labels = getattr(family_of(problem), "row_labels", lambda p: {})(problem)
    sens = {k: np.asarray(v, float) for k, v in cert.sensitivity.items()}
    bound_sens = np.asarray(cert.bound_sensitivity, float)
    active = []
    start = 0
    m = len(variables)
    for kind, count in row_kinds[0]:
        for j in range(count):
            i = start + j
            if scale * y[i] <= active_tol:
                continue
            if kind in ("lower_bound", "upper_bound"):
                k = j + (m if kind == "upper_bound" else 0)
                side = "lower" if kind == "lower_bound" else "upper"
                active.append({"kind": "bound", "limit": f"{variables[j][:-3]}_bounds_mm ({side})",
                               "variable": variables[j], "theta_deg": None,
                               "multiplier": float(scale * y[i]), "dF_dlimit": float(bound_sens[k])})
                continue
            if kind == "objective" and float(cert.gamma) == 0.0:
                continue  # without a stress weight the epigraph rows are the size term's, not a limit
            name, contact = labels.get("stress" if kind == "objective" else kind,
                                       ("stress" if kind == "objective" else kind, None))
            key = keys.get(name)
            entry = {"kind": name, "limit": key, "theta_deg": float(theta[j % theta.size]),
                     "multiplier": float(scale * y[i])}
            if contact is not None:
                entry["contact"] = contact
            if key in sens:
                entry["dF_dlimit"] = float(sens[key][i])
            active.append(entry)
        start += count
    # merge the rows of one kind and contact at one angle (the stress in the objective and as a
    # constraint; a pressure angle's two rows, + and - the limit)
    merged: dict = {}
    for e in active:
        k = (e["kind"], e["theta_deg"], e.get("variable"), e.get("contact"))
        if k in merged:
            merged[k]["multiplier"] += e["multiplier"]
            if "dF_dlimit" in e:
                merged[k]["dF_dlimit"] = merged[k].get("dF_dlimit", 0.0) + e["dF_dlimit"]
        else:
            merged[k] = dict(e)
    kkt = res.kkt
    return {
        "stationarity": float(kkt.stationarity), "primal_feasibility": float(kkt.primal),
        "complementarity": float(kkt.complementarity), "iterations": int(res.iterations),
        "converged": bool(res.converged),
        "dF_dlimit": {k: float(np.sum(v)) for k, v in sens.items()},
        "active": sorted(merged.values(), key=lambda e: -e["multiplier"]),
    }


def limited_by(certificate: dict, top: int = 3) -> str:
    """The text summary's "limited by ..." line of a certificate block (its largest multipliers)."""
    parts = []
    for e in certificate["active"][:top]:
        if e["kind"] == "bound":
            parts.append(f"the {e['limit']}")
        else:
            of = f" of the {e['contact']}" if "contact" in e else ""
            parts.append(f"the {e['kind'].replace('_', ' ')}{of} at {e['theta_deg']:.1f} deg")
    return "limited by " + (" and ".join(parts) if parts else "nothing (an interior optimum)")


_POINT = "the final point's KKT residuals, multipliers fitted on its active rows (least squares)"
METHODS = {"newton": "primal-dual interior point on the epigraph form (scaled KKT residuals)",
           "ga": _POINT, "hybrid": _POINT, "gradient": _POINT}


def certificate_json(problem, cert: Certificate, *, mode: str = "global", solver: str = "newton",
                     active_tol: float = 1e-6) -> dict:
    """result.json's ``certificate`` block (Python, concrete values) of a solution's certificate.

    ``kkt``: the scaled residuals (``stationarity``, ``primal_feasibility``, ``complementarity``);
    ``iterations``, ``converged`` (the residuals within the stopping rule); ``dF_dlimit``: the
    optimal objective's sensitivity to each scene limit; ``active``: every row whose multiplier
    times (alpha + gamma) exceeds ``active_tol`` (the rows of one kind and angle merged), each with
    its kind (a constraint's field name, ``stress`` for the objective's stress rows, ``bound``; a
    positive drive's rows by the family's ``row_labels``: the kind of the limit and, under
    ``contact``, the flank or cam, e.g. "outer flank"), the scene key of its limit, the cam angle
    (deg; None for a bound), the variable (bounds), its multiplier and dF*/d limit (scene units);
    ``limited_by``: the summary's line. Pointwise mode: the certificate of the critical angle's
    one-angle problem (the one whose optimum is the largest), its angle under ``critical_angle_deg``.
    """
    extra = {}
    if mode == "pointwise":
        i = int(np.argmax(np.asarray(cert.result.z)[:, -1]))
        cert = jax.tree.map(lambda x: np.asarray(x)[i], cert)
        problem = jax.tree.map(lambda x: x[i], family_of(problem).per_angle(problem))
        extra["critical_angle_deg"] = float(np.reshape(np.asarray(problem.theta_deg), -1)[0])
    block = {"method": METHODS.get(solver, solver), **extra, **_block(problem, cert, active_tol=active_tol)}
    block["limited_by"] = limited_by(block)
    return block
