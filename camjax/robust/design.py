"""Robust design: a design that keeps each constraint over a fraction of a fixed set of samples of
the scene's [tolerances] (``[design] robust = { probability, samples, seed }``).

The robust problem is a problem family of :mod:`camjax.solvers.base` that wraps the follower's
own: it holds the follower family's problem at the nominal values (``nominal``) and the same
family's problem of every sample (``samples``, leading axis S: each sample's scene with its drawn
values, the form error added to the lift, built by :func:`camjax.robust.evaluate.drawn` and the
follower's ``problem_from_scene``, exactly as ``camjax robust`` evaluates a sample). A toleranced
design variable (a roller's radius, an offset) is built as the design's value times ``factor``
plus ``shift`` (one per sample and variable: a spread in percent scales, one in mm shifts).

For a design x, sample s and constraint k of the follower's family, G_k,s = max over the grid of
g_k(sample s, x_s) (mm, <= 0 where the sample keeps the limit). The robust constraint row k is the
order statistic of the G_k,s that m samples may exceed, with d free design variables,

    m = floor((1 - p)(S + 1)) - d,

so that a fresh sample breaks the limit with probability at most (m + d) / (S + 1) <= 1 - p on
average (the scenario approach with sampling and discarding: each of the d variables can fit one
sample's value more), and no lower than the nominal's own row (the design keeps its limits at
the nominal values too). A scene with loads adds ``contact_lost``: the order statistic of
-min(contact load) / (peak nominal load) times the size norm; it does not depend on the
geometry (the follower force is the train's), so a scene that loses contact too often has no
robust design (reported infeasible, ``contact_lost`` violated). The objective is the nominal
one; every solver and mode run the problem unchanged. A global solve goes by rounds
(:func:`solve_robust`) from the nominal optimum (``origin``, when the problem holds it): each row
is kept over the samples left when its m largest at the current design are discarded (one row
per sample), until the order statistics agree. In pointwise mode
each angle keeps its own order statistic (the fraction of samples that keep a limit at every
angle can then be lower).

:func:`design_json` solves the nominal and the robust problem with the scene's solver and mode and
measures both designs on a fresh sample set (another seed) with :func:`camjax.robust.evaluate.batch`.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.family import FEASIBILITY_TOL_MM, all_within, violated
from camjax.numerics import finite_float, positive_part
from camjax.robust import evaluate as ev
from camjax.robust.tolerances import Tolerances, draw
from camjax.solvers.base import family_of, register_family

CHECK_SAMPLES_MIN = 20_000  # the fresh sample set: at least this many, and 10 x the design's
CHECK_SAMPLES_MAX = 200_000
LOAD_FLOOR = 1e-12  # N or N m: the contact row's scale when the nominal load is 0
# the family protocol's declaration (camjax.solvers.base): a row's max over its kept samples is not
# one design variable minus a fixed term, as a follower family's max over the grid is, so the
# gradient solver prices every row (angle and kept sample) by its own multiplier
ONE_MULTIPLIER_PER_CONSTRAINT = False


class Problem(NamedTuple):
    """A robust design problem: the follower family's problems, nominal and per sample."""

    nominal: Any  # the family's Problem at the nominal values, grid (n,)
    samples: Any  # the family's Problem of every sample, leading axis (S,); no closed-form model
    factor: Any  # the family's Design, (S,) each: a drawn variable is x * factor + shift
    shift: Any  # the family's Design, (S,) each, mm
    contact: jax.Array | None  # (S, n) -load / peak nominal load x size norm (mm); None without loads
    rank: jax.Array  # () int m: how many of the full sample set may exceed a robust row
    # (rows, S) bool: the samples each row is kept over (the m it may exceed discarded, a solve's
    # smooth form: a max over fixed samples); None: the order statistic itself
    keep: jax.Array | None = None
    # the family's Design a solve starts from (mm): the nominal optimum, whose basin the robust
    # optimum is in (the gradient solver also starts from the box's centre and keeps the better);
    # None: the family's own start
    origin: Any = None

    @property
    def theta_deg(self):
        return self.nominal.theta_deg

    @property
    def lower(self):
        return self.nominal.lower

    @property
    def upper(self):
        return self.nominal.upper

    @property
    def sigma_max_MPa(self):
        return self.nominal.sigma_max_MPa


class Evaluation(NamedTuple):
    """A design judged on the nominal grid and the samples (shape () each)."""

    objective: jax.Array  # the nominal objective F
    violation: Any  # the robust rows' violations (mm) and the box's
    feasible: jax.Array  # bool: every robust row and the box within FEASIBILITY_TOL_MM
    nominal: Any  # the family's Evaluation at the nominal values
    rows: Any  # the robust rows (mm, <= 0 kept), one per constraint


_TYPES: dict = {}


def _named(kind: str, fields: tuple[str, ...]):
    """A NamedTuple type of ``fields`` (one per constraint set), defined in this module so that a
    pytree of it pickles (the program cache keys on the tree's structure)."""
    key = (kind, fields)
    if key not in _TYPES:
        name = f"_{kind}_" + "_".join(fields)
        cls = NamedTuple(name, [(f, jax.Array) for f in fields])
        cls.__module__ = __name__
        setattr(sys.modules[__name__], name, cls)
        _TYPES[key] = cls
    return _TYPES[key]


def _base(problem: Problem):
    return family_of(problem.nominal)


def _row_names(problem: Problem) -> tuple[str, ...]:
    base = _base(problem)
    names = base.Constraints._fields
    return (*names, "contact_lost") if problem.contact is not None else names


def rank_from_top(probability: float, count: int, free: int = 1) -> int:
    """m = floor((1 - p)(S + 1)) - d: how many of ``count`` samples may exceed a robust row, with
    d = ``free`` design variables (Python; at least 0). The scenario approach's bound
    (sampling and discarding): a design fitted to S samples with m of them discarded breaks a fresh
    sample with probability at most (m + d) / (S + 1) on average."""
    return max(0, min(count - 1, math.floor((1.0 - probability) * (count + 1) + 1e-9) - max(free, 1)))


def free_variables(bounds) -> int:
    """d: the design variables free in their box (low < high), of (name, (low, high)) pairs."""
    return sum(1 for _, (lo, hi) in bounds if hi > lo)


def _order_statistic(values, rank):
    """The (m + 1)-th largest of ``values`` (S,), m = ``rank``."""
    count = values.shape[-1]
    return jnp.sort(values)[count - 1 - jnp.minimum(rank, count - 1)]


def sample_maxima(problem: Problem, design) -> dict[str, jax.Array]:
    """G_k,s: each sample's max over the grid of each constraint (mm), (S,) per row name."""
    base = _base(problem)

    def one(p, a, b):
        return base.constraint_maxima(p, jax.tree.map(lambda x, ai, bi: x * ai + bi, design, a, b))

    g = jax.vmap(one)(problem.samples, problem.factor, problem.shift)
    out = dict(g._asdict())
    if problem.contact is not None:
        out["contact_lost"] = jnp.max(problem.contact, axis=-1)
    return out


def constraint_maxima(problem: Problem, design):
    """The robust rows (mm, () each): each constraint's order statistic over the samples (with
    ``keep``: its max over the kept samples), no lower than the nominal's own max over the grid."""
    base = _base(problem)
    nominal = base.constraint_maxima(problem.nominal, design)._asdict()
    rows = {}
    for r, (name, values) in enumerate(sample_maxima(problem, design).items()):
        if problem.keep is None:
            q = _order_statistic(values, problem.rank)
        else:
            q = jnp.max(jnp.where(problem.keep[..., r, :], values, -1e30), axis=-1)
        rows[name] = jnp.maximum(q, nominal[name]) if name in nominal else q
    return _named("Constraints", tuple(rows))(**rows)


def constraints(problem: Problem, design):
    """The robust rows as the protocol's constraint arrays. With ``keep``: one row per sample, shape
    (1 + S,) (the nominal's max over the grid, then each sample's; a discarded sample's row repeats
    the nominal's, or for a row without one (contact) the least sample's: never above the others,
    and no huge constant for the solver's multipliers to see), whose max is
    :func:`constraint_maxima`; without: the order statistic, shape (1,)."""
    if problem.keep is None:
        m = constraint_maxima(problem, design)
        return type(m)(*(jnp.reshape(v, (1,)) for v in m))
    nominal = _base(problem).constraint_maxima(problem.nominal, design)._asdict()
    rows = {}
    for r, (name, values) in enumerate(sample_maxima(problem, design).items()):
        first = nominal[name] if name in nominal else jnp.min(values, axis=-1)
        kept = jnp.where(problem.keep[..., r, :], values, first[..., None])
        rows[name] = jnp.concatenate([first[..., None], kept], axis=-1)
    return _named("Constraints", tuple(rows))(**rows)


# ---------------------------------------------------------- the family's own, at the nominal


def bounds(problem: Problem):
    return _base(problem).bounds(problem.nominal)


def size_norm(problem: Problem):
    return _base(problem).size_norm(problem.nominal)


def size_term(problem: Problem, design):
    return _base(problem).size_term(problem.nominal, design)


def objective(problem: Problem, weights, design):
    return _base(problem).objective(problem.nominal, weights, design)


def _span(problem: Problem):
    return jax.tree.map(lambda lo, hi: jnp.where(hi > lo, hi - lo, 1.0), problem.lower, problem.upper)


def to_unit(problem: Problem, design):
    """The family's unit-box coordinates (its own ``to_unit`` where it has one)."""
    base = _base(problem)
    if hasattr(base, "to_unit"):
        return base.to_unit(problem.nominal, design)
    return jax.tree.map(lambda x, lo, w: (x - lo) / w, design, problem.lower, _span(problem))


def from_unit(problem: Problem, u):
    base = _base(problem)
    if hasattr(base, "from_unit"):
        return base.from_unit(problem.nominal, u)
    return jax.tree.map(lambda v, lo, w: lo + v * w, u, problem.lower, _span(problem))


def start(problem: Problem):
    """The nominal optimum (``origin``) where the problem holds one, else the family's start."""
    if problem.origin is not None:
        return problem.origin
    base = _base(problem)
    if hasattr(base, "start"):
        return base.start(problem.nominal)
    return jax.tree.map(lambda lo, hi: 0.5 * (lo + hi), problem.lower, problem.upper)


def per_angle(problem: Problem) -> Problem:
    """The n one-angle robust problems: the nominal's and every sample's grid split by angle."""
    base = _base(problem)
    nominal = base.per_angle(problem.nominal)
    n = problem.nominal.theta_deg.shape[-1]
    samples = jax.tree.map(lambda x: jnp.moveaxis(x, 0, 1), jax.vmap(base.per_angle)(problem.samples))
    spread = lambda x: jnp.broadcast_to(x, (n, *x.shape))  # noqa: E731
    contact = None if problem.contact is None else jnp.moveaxis(problem.contact, -1, 0)[..., None]
    return Problem(nominal, samples, jax.tree.map(spread, problem.factor),
                   jax.tree.map(spread, problem.shift), contact, jnp.broadcast_to(problem.rank, (n,)),
                   None if problem.keep is None else spread(problem.keep))


def condense_pointwise(problem: Problem, per_angle_design):
    return _base(problem).condense_pointwise(problem.nominal, per_angle_design)


def polish(problem: Problem, weights, design):
    """The family's polish at the nominal (the nominal's limits kept between the samples too)."""
    hook = getattr(_base(problem), "polish", None)
    return design if hook is None else hook(problem.nominal, weights, design)


def polish_pointwise(problem: Problem, weights, design, extras):
    hook = getattr(_base(problem), "polish_pointwise", None)
    return (design, extras) if hook is None else hook(problem.nominal, weights, design, extras)


def evaluate(problem: Problem, weights, design) -> Evaluation:
    """The nominal objective and evaluation, the robust rows and their violations (mm)."""
    base = _base(problem)
    nominal = base.evaluate(problem.nominal, weights, design)
    rows = constraint_maxima(problem, design)
    names = (*rows._fields, "bounds")
    v = _named("Violation", names)(*(positive_part(x) for x in rows), nominal.violation.bounds)
    feasible = all_within(v, dict.fromkeys(names, FEASIBILITY_TOL_MM))
    return Evaluation(nominal.objective, v, feasible, nominal, rows)


def violated_constraints(problem: Problem, v) -> list[str]:
    return violated(v._fields, v, dict.fromkeys(v._fields, FEASIBILITY_TOL_MM))


def _nominal_solution(solution):
    ev_ = solution.evaluation
    return dataclasses.replace(solution, evaluation=ev_.nominal, violation=ev_.nominal.violation,
                               feasible=ev_.nominal.feasible)


def solution_json(problem: Problem, solution) -> dict:
    """The family's keys of the design at the nominal values, and ``robust_rows_mm``: each robust
    row (<= 0: kept by the fraction asked of the samples)."""
    out = _base(problem).solution_json(problem.nominal, _nominal_solution(solution))
    out["robust_rows_mm"] = {k: finite_float(v) for k, v in solution.evaluation.rows._asdict().items()}
    return out


def record(solution) -> dict:
    """The family's pareto.json keys of the design at the nominal values."""
    from camjax import followers

    nominal = solution.evaluation.nominal
    base = next(f.problem_module() for f in followers.all_followers()
                if isinstance(nominal, f.problem_module().Evaluation))
    return base.record(_nominal_solution(solution))


register_family(Problem, sys.modules[__name__])


# ------------------------------------------------------------------------------ building


def _split(tol: Tolerances, variables) -> tuple[Tolerances, list[int], list[int]]:
    """The tolerances of the scene's values (not design variables), and the columns of each kind."""
    scene_cols = [i for i, t in enumerate(tol.values) if t.section != "design"]
    design_cols = [i for i, t in enumerate(tol.values) if t.section == "design" and t.name in variables]
    return tol._replace(values=tuple(tol.values[i] for i in scene_cols)), scene_cols, design_cols


def robust_problem(scene, nominal_problem, *, samples: int | None = None, seed: int | None = None,
                   probability: float | None = None, origin=None) -> Problem:
    """The robust problem of a scene with [design] robust (``samples``, ``seed``, ``probability``
    override the scene's), around ``nominal_problem`` (the follower's problem of the scene);
    ``origin``: the nominal optimum (the family's Design, mm) the solves start from, or None.
    Python: draws the samples and builds their problems in one compiled call."""
    spec = scene.design.robust
    samples = spec.samples if samples is None else int(samples)
    seed = spec.seed if seed is None else int(seed)
    p = spec.probability if probability is None else float(probability)
    base = family_of(nominal_problem)
    variables = base.Design._fields
    tol = scene.tolerances
    scene_tol, scene_cols, design_cols = _split(tol, variables)
    draws = draw(tol, samples, seed)
    unit = np.asarray(draws.unit)
    nom = ev.nominal(scene, scene_tol, {})
    dtype = jax.tree.leaves(nominal_problem.lower)[0].dtype
    build = ev._cached("robust-problems", nom, lambda: _problems_program(nom, base))
    g = ev._cached("grid", nom, lambda: ev._grid_program(nom))()
    probs, loads = build(jnp.asarray(unit[:, scene_cols].reshape(samples, len(scene_cols))),
                         jnp.asarray(draws.phases), g, ev.numbers(nom))
    factor = {v: np.ones(samples) for v in variables}
    shift = {v: np.zeros(samples) for v in variables}
    for j in design_cols:
        t = tol.values[j]
        if t.relative:
            factor[t.name] = 1.0 + t.spread / 100.0 * unit[:, j]
        else:
            shift[t.name] = t.spread * unit[:, j]
    # the rows' tuple types exist before a saved program's output tree is read back (a fresh process)
    names = (*base.Constraints._fields, *(("contact_lost",) if scene.follower.train is not None else ()))
    _named("Constraints", names)
    _named("Violation", (*names, "bounds"))
    contact = None
    if scene.follower.train is not None:
        scale = max(float(np.max(np.abs(np.asarray(nominal_load(scene))))), LOAD_FLOOR)
        contact = -loads / scale * base.size_norm(nominal_problem)
    as_design = lambda d: base.Design(**{k: jnp.asarray(d[k], dtype) for k in variables})  # noqa: E731
    return Problem(nominal_problem, probs, as_design(factor), as_design(shift), contact,
                   jnp.asarray(rank_from_top(p, samples, free_variables(scene.design.variables)), jnp.int32),
                   origin=None if origin is None else as_design(origin._asdict()))


def nominal_load(scene) -> jax.Array:
    """(n,) the nominal contact load (:func:`camjax.robust.evaluate.contact_load`)."""
    from camjax.evaluate import scene_arrays

    return ev.contact_load(scene, scene_arrays(scene))


def _problems_program(nom: ev.Nominal, base):
    """The jitted, vmapped family problem and contact load of a batch of samples, of the nominal's
    :class:`camjax.robust.evaluate.Numbers` (one program for every spread of a scene's tolerances)."""
    def one(u, p, g, n):
        at = ev.with_numbers(nom, n)
        d = ev.drawn(at, ev.values_of(at, u), p, g)
        problem = base.problem_from_scene(d.scene, d.arrays)
        return problem, ev.contact_load(d.scene, d.arrays)
    return jax.jit(jax.vmap(one, in_axes=(0, 0, None, None)))


def refuse_sweep(scene) -> None:
    """A sweep of a scene with [design] robust is refused (SceneError naming ``design.robust``):
    a sweep solves every weighting in one batched program of the nominal problem, and a robust
    design is a solve by rounds over its sample set, one weighting at a time (``camjax design``)."""
    from camjax.errors import SceneError

    spec = None if scene.design is None else scene.design.robust
    if spec is not None:
        raise SceneError("design.robust", {"probability": spec.probability, "samples": spec.samples},
                         "camjax sweep solves the nominal problem of every weighting; a robust design is "
                         "solved one weighting at a time by camjax design (--alpha, --gamma)",
                         "no robust key in [design] for a sweep of the nominal problem")


# ------------------------------------------------------------------------------ result


def check_samples(samples: int) -> int:
    """Size of the fresh sample set the designs are measured on."""
    return int(min(max(CHECK_SAMPLES_MIN, 10 * samples), CHECK_SAMPLES_MAX))


def kept(scene, design: dict[str, float], samples: int, seed: int) -> dict[str, Any]:
    """Each limit's probability kept by ``design`` (mm) over ``samples`` fresh draws of ``seed``,
    measured by ``camjax robust``'s evaluator (:func:`camjax.robust.evaluate.batch`)."""
    tol = scene.tolerances
    nom = ev.nominal(scene, tol, design)
    draws = draw(tol, samples, seed)
    res = ev.batch(nom, draws.unit, draws.phases, curves=0)
    broken = np.asarray(res.broken)
    lims = ev.limit_names(scene)
    return {"limits": {lim: 1.0 - float(broken[:, i].mean()) for i, lim in enumerate(lims)},
            "all": 1.0 - float(broken.any(axis=1).mean()) if lims else 1.0}


def design_json(scene, nominal_problem) -> dict:
    """result.json's design block of a scene with [design] robust: the robust design solved with the
    scene's solver and mode (its JSON, as a plain design's), and ``robust``: the nominal-optimal
    and the robust-optimal designs side by side, with each limit's probability kept measured on a
    fresh sample set (seed + 1)."""
    from camjax.solvers.base import solve
    from camjax.solvers.certificate import point_certificate_json

    d = scene.design
    spec = d.robust
    t0 = time.perf_counter()
    nominal = solve(nominal_problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver, seed=d.seed)
    t1 = time.perf_counter()
    problem = robust_problem(scene, nominal_problem, origin=nominal.design)
    t2 = time.perf_counter()
    robust, rounds, solved = solve_rounds(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver,
                                          seed=d.seed)
    t3 = time.perf_counter()
    out = robust.to_json(problem)
    if robust.certificate is not None:  # its multipliers are the rows of the last round's subset
        out["certificate"] = robust.certificate_json(solved)
    elif d.mode == "global":  # the gradient solver's answer, certified as the GA's final point is
        out["certificate"] = point_certificate_json(solved, robust)
    fresh, fresh_seed = check_samples(spec.samples), (spec.seed + 1) % 2**32
    variables = family_of(nominal_problem).Design._fields
    side = {}
    for name, sol in (("nominal", nominal), ("robust", robust)):
        design = {k: float(getattr(sol.design, k)) for k in variables}
        rows = (sol.evaluation.rows._asdict() if name == "robust" else dict(zip(
            _row_names(problem), _rows_of(*jax.device_get(_maxima(problem, sol.design)), int(problem.rank)),
            strict=True)))
        at_nominal = sol.evaluation.nominal if name == "robust" else sol.evaluation
        side[name] = {"design": design, "size_mm": finite_float(at_nominal.size_mm),
                      "objective": finite_float(sol.objective), "feasible": bool(sol.feasible),
                      "status": sol.status_name,
                      "robust_rows_mm": {k: finite_float(v) for k, v in rows.items()},
                      "probability_kept": kept(scene, design, fresh, fresh_seed)}
    t4 = time.perf_counter()
    size0, size1 = side["nominal"]["size_mm"], side["robust"]["size_mm"]
    free = free_variables(d.variables)
    m = rank_from_top(spec.probability, spec.samples, free)
    out["robust"] = {
        "probability": spec.probability, "samples": spec.samples, "seed": spec.seed,
        "samples_allowed_over": m, "free_variables": free, "rounds": rounds,
        "probability_bound": 1.0 - (m + free) / (spec.samples + 1),
        "check": {"samples": fresh, "seed": fresh_seed},
        **side,
        "violations": [("a design variable is outside its bounds" if name == "bounds" else
                        f"{name.replace('_', ' ')}: kept in fewer than {spec.probability:g} of the "
                        f"{spec.samples} samples") for name in out["violated"]],
        "size_increase_percent": finite_float(100.0 * (size1 - size0) / size0) if size0 else None,
        "timings_s": {"nominal": t1 - t0, "samples": t2 - t1, "robust": t3 - t2, "check": t4 - t3},
    }
    return out


SUBSET = 256  # samples a solve of a larger set works on: those nearest to breaking a limit
# ... and the interior point's: its path lengthens with the near-parallel split rows of many samples
# (the `robust` scene: 16 samples 76 Newton steps, 64 122, 256 its 200-step safeguard). With m >= 1
# the rounds' path decides which samples are discarded (docs/robust.md#robust-design)
SOLVER_SUBSET = {"newton": 16}


def take(problem: Problem, index) -> Problem:
    """The robust problem of the samples ``index`` (the full set's rank kept)."""
    pick = lambda x: x[index]  # noqa: E731
    return problem._replace(samples=jax.tree.map(pick, problem.samples),
                            factor=jax.tree.map(pick, problem.factor),
                            shift=jax.tree.map(pick, problem.shift),
                            contact=None if problem.contact is None else problem.contact[index],
                            keep=None if problem.keep is None else problem.keep[:, index])


@jax.jit
def _maxima(problem: Problem, design) -> tuple[jax.Array, jax.Array]:
    """At ``design``, all a round judges in one program: (rows,) the nominal's max over the grid of
    each robust row's constraint (mm; -inf without one: contact) and (rows, S) every sample's."""
    nominal = _base(problem).constraint_maxima(problem.nominal, design)._asdict()
    g = sample_maxima(problem, design)
    low = jnp.asarray(-jnp.inf, problem.lower[0].dtype)
    return jnp.stack([nominal.get(k, low) for k in g]), jnp.stack(list(g.values()))


def _rows_of(nominal: np.ndarray, g: np.ndarray, rank: int, keep: np.ndarray | None = None) -> np.ndarray:
    """(rows,) the robust rows of :func:`constraint_maxima` from :func:`_maxima`'s arrays, in NumPy."""
    if keep is None:
        q = np.sort(g, axis=-1)[:, g.shape[-1] - 1 - min(rank, g.shape[-1] - 1)]
    else:
        q = np.max(np.where(keep, g, -1e30), axis=-1)
    return np.maximum(q, nominal)


def solve_robust(problem: Problem, weights, *, mode: str, solver: str, seed: int, subset: int | None = None,
                 rounds: int = 8):
    """The robust design of ``problem`` and the rounds it took (:func:`solve_rounds`)."""
    solution, done, _ = solve_rounds(problem, weights, mode=mode, solver=solver, seed=seed, subset=subset,
                                     rounds=rounds)
    return solution, done


def solve_rounds(problem: Problem, weights, *, mode: str, solver: str, seed: int, subset: int | None = None,
                 rounds: int = 8):
    """The robust design of ``problem`` (:func:`camjax.solvers.base.solve`), the rounds it took,
    and the problem the last round solved (a solution's certificate is of that problem's rows).

    Global mode, by rounds: at the current design (at first :func:`start`: the nominal optimum,
    or the family's start) each row's m largest samples are discarded and the row is the max over
    the others (a max over fixed samples, as smooth as each family's max over the grid, where the
    order statistic switches samples); a set larger than ``subset`` is solved on its ``subset``
    samples nearest to breaking a limit (None: :data:`SOLVER_SUBSET` or :data:`SUBSET`; at least
    4 (m + 1) + subset / 4). The design is solved, and the rounds end when every row's
    order statistic over the full set equals the row the solver kept (the discarded samples are
    the m largest at the design, and the subset holds the rest of the top). The solution is judged
    on the full set's order statistics. Pointwise mode solves the order statistics of the full set
    directly (each angle its own)."""
    from camjax.family import weights_of
    from camjax.results import Status
    from camjax.solvers.base import solve

    count = problem.factor[0].shape[0]
    m = int(problem.rank)
    subset = SOLVER_SUBSET.get(solver, SUBSET) if subset is None else int(subset)
    subset = max(subset, 4 * (m + 1) + subset // 4)
    if mode != "global":
        return solve(problem, weights, mode=mode, solver=solver, seed=seed), 1, problem
    design, index, done = start(problem), None, 0
    nominal, g = jax.device_get(_maxima(problem, design))
    while done < rounds:
        done += 1
        keep = np.ones(g.shape, bool)
        for r in range(g.shape[0]):
            keep[r, np.argsort(-g[r], kind="stable")[:m]] = False
        if count <= subset:
            index = np.arange(count)
        else:
            # each sample's best rank from the top over the rows (0: the largest of some row)
            best = np.min(np.argsort(np.argsort(-g, axis=-1, kind="stable"), axis=-1, kind="stable"), axis=0)
            order = np.argsort(best, kind="stable")
            index = order[:subset] if index is None else _merge(index, order, subset)
        at = np.sort(index)
        sub = take(problem._replace(keep=jnp.asarray(keep)), jnp.asarray(at))
        sol = solve(sub, weights, mode=mode, solver=solver, seed=seed)
        design = sol.design
        nominal, g = jax.device_get(_maxima(problem, design))  # the full set's rows against the kept
        full, kept_rows = _rows_of(nominal, g, m), _rows_of(nominal, g[:, at], m, keep[:, at])
        if np.allclose(full, kept_rows, rtol=0.0, atol=1e-12):
            break
    w = weights_of(sol.alpha, sol.gamma, problem.lower[0].dtype)
    full = jax.device_get(_evaluate(problem, w, jax.tree.map(jnp.asarray, design)))
    converged = sol.converged
    status = np.int32(Status.INFEASIBLE if not full.feasible else
                      Status.CONVERGED if converged is not None and bool(converged) else Status.MAX_STEPS)
    return dataclasses.replace(sol, objective=full.objective, violation=full.violation,
                               feasible=full.feasible, evaluation=full, status=status), done, sub


def _merge(previous: np.ndarray, order: np.ndarray, subset: int) -> np.ndarray:
    """The most critical samples of ``order`` first, then the previous subset's, ``subset`` in all."""
    keep = list(dict.fromkeys([*order[: subset // 2].tolist(), *previous.tolist(), *order.tolist()]))
    return np.asarray(keep[:subset])


_evaluate = jax.jit(evaluate)

