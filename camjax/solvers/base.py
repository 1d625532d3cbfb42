"""One result type and one entry point for every solver, mode and problem family.

:func:`solve` (one weighting, Python) and :func:`solve_batch` (a batch of weightings: one compiled
search, one compiled judgement shared by every solver) run any registered solver (:data:`camjax.solvers.registry.SOLVERS`) in either mode
(:data:`~camjax.solvers.registry.MODES`) on any registered problem family and return a
:class:`Solution`. The choice between the global and the pointwise problem is made here only
(:func:`in_mode`, :func:`judge`): a solver is written for one problem on its angle grid.

Solver protocol (a module named in :data:`camjax.solvers.registry.SOLVER_MODULES`):

- ``DEFAULT_SETTINGS``: a hashable settings object (a ``jit`` static argument);
- ``run_one(problem, weights, key, settings, init=None) -> Raw``: solve one problem for one
  weighting, traceable and vmappable; ``settings`` is a :class:`Settings` (``settings.of(name)``
  gives a solver's own settings), ``key`` a PRNG key (ignored by deterministic solvers),
  ``init`` an optional start design. It must reach the problem only through its family module
  (:func:`family_of`) and treat the design as a pytree (``jax.tree.map``);
- where ``run_one`` gives a ``Raw.certificate``: ``certificate_json(problem, certificate, mode=,
  solver=) -> dict``, result.json's ``certificate`` block (:mod:`camjax.solvers.certificate`'s).

Problem-family protocol (a follower folder's ``problem.py``, :mod:`camjax.followers`; the
flat-face one is :mod:`camjax.followers.flat.problem`). It provides:

- ``Problem``: the problem's pytree type (NamedTuple of arrays, the key :func:`family_of`
  dispatches on); ``Design``: the design pytree of named variables (mm);
- ``bounds(problem) -> (lower: Design, upper: Design)`` box bounds, mm (lo == hi fixes a variable);
- ``size_norm(problem) -> ()`` the length (mm) the constraints are divided by (g / N);
- ``objective(problem, weights, design) -> ()`` the dimensionless objective F (true max over angles);
- ``size_term(problem, design) -> ()`` the normalized size (the alpha = 0 tie-break);
- ``constraints(problem, design) -> NamedTuple`` of (n,) arrays g <= 0 (mm), one per angle;
- ``constraint_maxima(problem, design) -> NamedTuple`` of () arrays: their maxima over angles;
- ``evaluate(problem, weights, design) -> Evaluation`` with at least ``objective``,
  ``violation`` (a NamedTuple of worst violations) and ``feasible`` (bool), plus anything the
  report needs (peak stress, ...);
- ``per_angle(problem) -> Problem`` the n one-angle problems stacked on a leading axis;
- ``condense_pointwise(problem, per_angle_design) -> (Design, dict)`` the whole-cam design of a
  pointwise solve and extra arrays to report (e.g. the angles where each variable peaks);
- ``violated_constraints(problem, violation) -> list[str]`` (Python) names of violated constraints;
- ``solution_json(problem, solution) -> dict`` (Python) the family's keys of result.json's design
  block (design variables, constraint violations, evaluation figures, bounds, pointwise arrays);
- ``record(solution) -> dict`` (Python) the family's keys of a pareto.json row; it must contain
  ``size_mm`` and ``stress_max_MPa`` (the two objectives of the Pareto front).
- optionally ``polish(problem, weights, design) -> Design``: the exact optimum near a solver's
  global-mode design (the solvers may search on the sample grid; :func:`judge` polishes),
  and ``polish_pointwise(problem, weights, design, extras) -> (Design, dict)``: the condensed
  pointwise design taken as a continuous max over the angle; and
  ``ONE_MULTIPLIER_PER_CONSTRAINT = False`` where a constraint's max over the angles is not one
  design variable minus a fixed term (the gradient solver then prices every angle's row by its
  own multiplier; the robust problem, :mod:`camjax.robust.design`); and
  ``SMOOTH_OBJECTIVE = True`` where ``objective`` is smooth already, not a max over one-angle
  problems (the interior point then takes it as one row, :func:`camjax.solvers.epigraph.smooth_form`,
  and needs no ``per_angle``; the co-design's joint program, :mod:`camjax.codesign.joint`); and
  ``EXCHANGE_ANGLES = k``: the angles of each of the interior point's exchange rounds where the
  default's 16 take more rounds (:func:`camjax.solvers.exchange.exchange_angles`); and
  ``angle_stress(problem, design) -> (n,)``: the stress (MPa) per angle whose max is the
  objective's peak stress, where ``objective`` is ``alpha size_term + gamma peak / sigma_max``
  (the interior point's epigraph rows then come from the grid at once, sharing the constraint
  rows' terms, instead of from the n one-angle problems: :func:`camjax.solvers.epigraph.epigraph_form`);
  and ``smooth_constraints(problem, design) -> NamedTuple``: ``constraints`` with a row's kink
  taken out (a pressure angle's |lean| - reach as :func:`camjax.family.excess` with ``smooth``:
  the same sign at every design, and the same value and gradient where the row is 0), the rows
  the interior point takes (its Newton steps zig-zagged across such a kink at a dwell).

Weights (:class:`camjax.followers.flat.Weights`: alpha for size, gamma for stress) are shared by every
family, and so are the pieces of the protocol that do not depend on a family's physics (the box,
the per-angle split, the feasibility tolerances, the result keys: :mod:`camjax.family`). Starts
come from the bounds (the gradient solver: the centre of the box; the GA: uniform in it), so a
family needs no initial design; the solvers map every variable to the unit box, so a family needs
no scaling of its variables either.
"""

from __future__ import annotations

import dataclasses
import importlib
import time
from dataclasses import dataclass
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import runtime
from camjax.family import Weights, weights_of
from camjax.numerics import finite_float
from camjax.results import Status
from camjax.solvers.registry import (
    DEFAULT_SOLVER,
    MODES,
    SOLVER_MODULES,
    SOLVERS,
    check_choice,
    check_weights,
)

__all__ = [
    "Raw", "Settings", "Solution", "Timings", "family_of", "register_family",
    "in_mode", "problem_from_scene", "solve", "solve_batch", "solver_module", "weighting_keys",
]


# ------------------------------------------------------------------------------ registry


_FAMILIES: dict[type, Any] = {}


def register_family(problem_type: type, module) -> None:
    """Register a problem family that is not a follower's (its ``Problem`` type and module): the
    co-design's joint program of laws and geometry, :mod:`camjax.codesign.joint`."""
    _FAMILIES[problem_type] = module


def family_of(problem):
    """The family module of a problem, found by its type among the registered followers' problem
    modules (Python, at trace time)."""
    from camjax import followers

    family = _FAMILIES.get(type(problem))
    if family is None:
        modules = [f.problem_module() for f in followers.all_followers()]
        _FAMILIES.update({module.Problem: module for module in modules})
        family = _FAMILIES.get(type(problem))
    if family is None:
        raise TypeError(f"problem: {type(problem).__name__} is not the problem of a registered follower "
                        f"({', '.join(followers.names())})")
    return family


def problem_from_scene(scene, arrays=None, *, samples: int | None = None, dtype=None):
    """The design problem of a scene's [design] section, built by its follower type's problem module.

    (Python, not traceable.) ``arrays``: the scene's :class:`camjax.evaluate.SceneArrays` if
    already computed; ``samples``, ``dtype``: grid size and floating dtype otherwise.
    """
    from camjax import followers

    module = followers.of(scene).problem_module()
    return module.problem_from_scene(scene, arrays, samples=samples, dtype=dtype)


def solver_module(name: str):
    """The module of a registered solver."""
    check_choice("solver", name, SOLVERS)
    return importlib.import_module(SOLVER_MODULES[name])


@dataclass(frozen=True)
class Settings:
    """Static settings of every solver (hashable): per-solver overrides of their DEFAULT_SETTINGS.

    ``Settings.of_solvers(ga=GASettings(...))``; ``settings.of("ga")`` gives the GA's settings.
    """

    overrides: tuple[tuple[str, Any], ...] = ()

    @classmethod
    def of_solvers(cls, **by_solver) -> Settings:
        for name in by_solver:
            check_choice("settings", name, SOLVERS)
        return cls(tuple(sorted((k, v) for k, v in by_solver.items() if v is not None)))

    def of(self, name: str):
        return dict(self.overrides).get(name, solver_module(name).DEFAULT_SETTINGS)


DEFAULT_SETTINGS = Settings()


INTERIOR_POINT_SOLVERS = ("newton", "hybrid")  # the solvers that run the interior point (its settings)


def for_problem(problem, solver: str, settings: Settings) -> Settings:
    """``settings`` with what the interior point (the newton solver, the hybrid's polish) takes from
    a problem whose box is concrete: the count of its free variables
    (:func:`camjax.solvers.newton.for_problem`), a static of the search program, so that its
    derivatives take only the free variables' directions. Under a trace, and for the solvers that
    do not run the interior point (their programs then serve every box), ``settings`` as given."""
    if solver not in INTERIOR_POINT_SOLVERS:
        return settings
    newton = solver_module("newton")
    own = settings.of("newton")
    fitted = newton.for_problem(problem, own)
    if fitted == own:
        return settings
    return Settings(tuple(sorted({**dict(settings.overrides), "newton": fitted}.items())))


class Raw(NamedTuple):
    """What a solver's ``run_one`` returns for one problem and weighting (shape () each)."""

    design: Any  # the family's Design, mm
    iterations: jax.Array  # int: steps or generations
    converged: jax.Array | None  # bool: the stopping rule was met; None for a fixed-budget solver
    certificate: Any = None  # the answer's KKT certificate (camjax.solvers.certificate.Certificate), if any


# ------------------------------------------------------------------------------ result


@dataclass(frozen=True)
class Timings:
    """Wall-clock seconds of a :func:`solve` call (Python floats; never traced)."""

    compile_s: float  # tracing and compilation (0 when the program was already compiled)
    run_s: float  # the compiled program, to the results on the host


@partial(jax.tree_util.register_dataclass,
         data_fields=["alpha", "gamma", "design", "objective", "violation", "feasible", "status",
                      "iterations", "converged", "evaluation", "pointwise", "extras", "certificate"],
         meta_fields=["mode", "solver", "timings"])
@dataclass(frozen=True)
class Solution:
    """A solved design (scalars), or a batch of them (leading axis w on every array).

    The family's design variables and evaluation figures read as attributes too
    (``solution.base_radius_mm`` is ``solution.design.base_radius_mm``, ``solution.stress_max_MPa``
    is ``solution.evaluation.stress_max_MPa``; pointwise extras likewise).
    """

    mode: str
    solver: str
    alpha: jax.Array
    gamma: jax.Array
    design: Any  # the family's Design, mm (pointwise: the condensed whole-cam design)
    objective: jax.Array  # F of the design (true max over angles)
    violation: Any  # the family's Violation: worst violation per constraint
    feasible: jax.Array  # bool
    status: jax.Array  # int32: a camjax.results.Status code (CONVERGED, MAX_STEPS or INFEASIBLE)
    iterations: jax.Array  # int: steps, generations, or their sum (hybrid); max over angles (pointwise)
    converged: jax.Array | None  # bool (every angle), None for a fixed-budget solver
    evaluation: Any  # the family's Evaluation of ``design`` on the whole grid
    pointwise: Any = None  # pointwise mode: the per-angle designs, (n,) each
    extras: dict | None = None  # pointwise mode: the family's extra arrays (angles of the peaks, ...)
    certificate: Any = None  # the solver's KKT certificate of its answer (pointwise: one per angle)
    timings: Timings | None = None  # filled in by :func:`solve`

    def __getattr__(self, name: str):
        if name.startswith("_"):
            raise AttributeError(name)
        for part in (self.__dict__.get("design"), self.__dict__.get("evaluation")):
            if part is not None and name in getattr(part, "_fields", ()):
                return getattr(part, name)
        extras = self.__dict__.get("extras")
        if extras and name in extras:
            return extras[name]
        raise AttributeError(f"Solution has no field {name!r}")

    def __getitem__(self, i) -> Solution:
        """Entry i of a batch."""
        return jax.tree.map(lambda x: x[i], self)

    @property
    def batch_size(self) -> int | None:
        """w for a batch, None for a single result."""
        return None if np.ndim(self.objective) == 0 else int(np.shape(self.objective)[0])

    @property
    def status_name(self) -> str:
        """"converged", "max_steps" or "infeasible" (single result)."""
        return Status.name_of(self.status)

    def violated(self, problem) -> list[str]:
        """Names of the violated constraints (single result)."""
        return family_of(problem).violated_constraints(problem, self.violation)

    def to_json(self, problem) -> dict[str, Any]:
        """Plain dict (floats, bools, lists) of a single result; strict JSON (no NaN/inf)."""
        out = {"mode": self.mode, "solver": self.solver, "alpha": _f(self.alpha), "gamma": _f(self.gamma),
               "objective": _f(self.objective), "feasible": bool(self.feasible),
               "status": self.status_name, "violated": self.violated(problem),
               "iterations": int(self.iterations),
               "converged": None if self.converged is None else bool(self.converged)}
        out.update(family_of(problem).solution_json(problem, self))
        if self.certificate is not None:
            out["certificate"] = self.certificate_json(problem)
        return out

    def certificate_json(self, problem) -> dict[str, Any]:
        """The certificate's result.json block, rendered by the solver module against ``problem``:
        the problem the solver solved (its rows are the multipliers' rows)."""
        return solver_module(self.solver).certificate_json(problem, self.certificate, mode=self.mode,
                                                           solver=self.solver)

    def record(self, problem) -> dict[str, Any]:
        """One pareto.json row of a single result (without "pareto")."""
        return {"alpha": _f(self.alpha), "gamma": _f(self.gamma),
                **family_of(problem).record(self),
                "objective": _f(self.objective), "feasible": bool(self.feasible),
                "status": self.status_name}


def _f(x) -> float:
    return finite_float(x)


# --------------------------------------------------------------------------------- modes


def in_mode(run_one, mode: str):
    """``run_one(problem, weights, key, init)`` solved in ``mode``: the one place modes differ.

    "global": ``run_one`` itself (one design for the whole grid). "pointwise": ``run_one`` vmapped
    over the family's :func:`per_angle` problems, angle i with the key fold_in(key, i) and
    ``init`` (if any) holding one start per angle; results get a leading axis n.
    """
    check_choice("mode", mode, MODES)
    if mode == "global":
        return run_one

    def pointwise(problem, weights, key, init=None):
        per = family_of(problem).per_angle(problem)
        n = jax.tree.leaves(per)[0].shape[0]
        keys = jax.vmap(lambda i: jax.random.fold_in(key, i))(jnp.arange(n))
        return jax.vmap(run_one, in_axes=(0, None, 0, None if init is None else 0))(per, weights, keys, init)

    return pointwise


def _status(feasible, done) -> jax.Array:
    return jnp.where(~feasible, int(Status.INFEASIBLE),
                     jnp.where(done, int(Status.CONVERGED), int(Status.MAX_STEPS))).astype(jnp.int32)


class Judged(NamedTuple):
    """What :func:`judge` makes of a solver's raw result (one weighting): the design on the whole
    grid and its evaluation."""

    design: Any  # the family's Design, mm (pointwise: the condensed, polished whole-cam design)
    pointwise: Any  # pointwise mode: the per-angle designs, (n,) each; None in global mode
    extras: dict | None  # pointwise mode: the family's extra arrays; None in global mode
    evaluation: Any  # the family's Evaluation of ``design``
    status: jax.Array  # int32 Status code
    iterations: jax.Array  # int32 (pointwise: the max over the angles)
    converged: jax.Array  # bool (pointwise: every angle)


def _design_form(problem):
    """The family's design as shapes and dtypes (its lower bounds', ``jax.eval_shape``: nothing is
    computed or compiled, traced or not)."""
    return jax.eval_shape(lambda p: family_of(p).bounds(p)[0], problem)


def search_one(problem, weights: Weights, key: jax.Array, *, mode: str, solver: str,
               settings: Settings) -> tuple[Raw, jax.Array]:
    """The solver's search in ``mode`` for one weighting: its :class:`Raw` result, with the
    iterations as int32, the design in the bounds' dtype and ``done`` (bool: the stopping rule was
    met; False for a fixed-budget solver), so that :func:`judge`'s arguments have one form
    whatever the solver. Traceable, vmappable."""
    module = solver_module(solver)
    run = in_mode(lambda p, w, k, init=None: module.run_one(p, w, k, settings, init), mode)
    raw = run(problem, weights, key)
    design = jax.tree.map(lambda x, b: jnp.asarray(x, b.dtype), raw.design, _design_form(problem))
    iterations = jnp.asarray(raw.iterations, jnp.int32)
    done = jnp.zeros(iterations.shape, bool) if raw.converged is None else jnp.asarray(raw.converged, bool)
    return raw._replace(design=design, iterations=iterations), done


def judge(problem, weights: Weights, design, iterations: jax.Array, done: jax.Array, mode: str) -> Judged:
    """Judge a solver's raw design on the whole grid (a pointwise one condensed first, the family's
    polish onto its exact extrema where it has one); traceable, vmappable. It depends on the mode
    but not on the solver: one program serves every solver of a problem."""
    family = family_of(problem)
    per_angle, extras = None, None
    if mode == "pointwise":
        per_angle = design
        design, extras = family.condense_pointwise(problem, per_angle)
        polish_pointwise = getattr(family, "polish_pointwise", None)  # optional hook (flat face)
        if polish_pointwise is not None:  # exact extrema: the continuous max over angles
            design, extras = polish_pointwise(problem, weights, design, extras)
        iterations, done = jnp.max(iterations), jnp.all(done)
    elif (polish := getattr(family, "polish", None)) is not None:  # optional hook (flat face)
        design = polish(problem, weights, design)  # exact extrema: the continuous optimum
    ev = family.evaluate(problem, weights, design)
    return Judged(design, per_angle, extras, ev, _status(ev.feasible, done), iterations, done)


def _solution(weights: Weights, raw: Raw, judged: Judged, mode: str, solver: str) -> Solution:
    """The :class:`Solution` of a search's raw result and its judgement (any leading axes)."""
    converged = None if raw.converged is None else judged.converged
    return Solution(mode, solver, weights.alpha, weights.gamma, judged.design, judged.evaluation.objective,
                    judged.evaluation.violation, judged.evaluation.feasible, judged.status, judged.iterations,
                    converged, judged.evaluation, judged.pointwise, judged.extras, raw.certificate)


def solve_one(problem, weights: Weights, key: jax.Array, *, mode: str = "global", solver: str = DEFAULT_SOLVER,
              settings: Settings = DEFAULT_SETTINGS) -> Solution:
    """One weighting (scalar alpha, gamma), any registered solver and mode; traceable, vmappable."""
    raw, done = search_one(problem, weights, key, mode=mode, solver=solver, settings=settings)
    judged = judge(problem, weights, raw.design, raw.iterations, done, mode)
    return _solution(weights, raw, judged, mode, solver)


def _per_weighting(one, problem, weights: Weights, *rest):
    """``one(problem, weights, *rest)`` for each weighting of a batch (leading axis w on weights
    and ``rest``). A batch of one weighting is traced without ``vmap``, its axis added back: a
    solve traced under ``vmap`` takes twice as long to trace (its loops batched) and ~10 % longer
    to compile."""
    if jnp.shape(weights.alpha)[0] == 1:
        first = jax.tree.map(lambda a: a[0], (weights, *rest))
        return jax.tree.map(lambda x: x[None], one(problem, *first))
    return jax.vmap(one, in_axes=(None, 0, *[0] * len(rest)))(problem, weights, *rest)


SEARCH_CHUNK = 10
"""Weightings searched side by side on the CPU (:func:`search_batch`'s ``chunk``). A ``vmap``'d
while loop runs every weighting to the step count of the slowest, and on the CPU a weighting costs
nearly its full price whether it is still moving or done: chunks of this many, one after another,
keep one slow weighting from holding up the whole batch. Measured on the seven types'
100-weighting sweeps (benchmarks/follower_sweep.py's problems, 2 cores, best of 3, chunked time
over whole-batch time): the interior point 0.40 (oscillating curved face, where one weighting
of 100 takes 111 steps and the median 38), 0.63 to 0.92 for five types and 1.09 to 1.17 for the
curved face (its steps are few and even); the hybrid 0.86 (oscillating roller) and 0.93
(oscillating flat); chunks of 5 or 25 were no faster. The designs are the same to the bit where
compared. On an accelerator the lanes of a ``vmap`` cost little: the whole batch is one chunk
there."""


def search_chunk(weights: Weights) -> int:
    """The ``chunk`` :func:`solve_batch` searches ``weights`` in: :data:`SEARCH_CHUNK` on the CPU,
    0 (the whole batch in one ``vmap``) on an accelerator or where the weightings are spread over
    several devices (:mod:`camjax.scaleout.sharding`: a ``vmap`` axis the partitioner can split)."""
    sharding = getattr(weights.alpha, "sharding", None)
    if sharding is not None and len(sharding.device_set) > 1:
        return 0
    return SEARCH_CHUNK if jax.default_backend() == "cpu" else 0


def _in_chunks(one, problem, weights: Weights, keys: jax.Array, chunk: int):
    """:func:`_per_weighting` in chunks of at most ``chunk`` weightings, one ``vmap`` each, the
    chunks one after another (``lax.map``); the batch is padded by repeating its last weighting to
    equal chunks and cut back. ``chunk`` 0, or a batch no larger: the whole batch at once."""
    count = int(jnp.shape(weights.alpha)[0])
    if chunk <= 0 or count <= chunk:
        return _per_weighting(one, problem, weights, keys)
    chunks = -(-count // chunk)
    size = -(-count // chunks)  # equal chunks, the least padding

    def split(x):
        x = jnp.concatenate([x, jnp.repeat(x[-1:], chunks * size - count, axis=0)])
        return x.reshape(chunks, size, *x.shape[1:])

    out = jax.lax.map(lambda wk: jax.vmap(one, in_axes=(None, 0, 0))(problem, *wk),
                      jax.tree.map(split, (weights, keys)))
    return jax.tree.map(lambda x: x.reshape(chunks * size, *x.shape[2:])[:count], out)


@partial(jax.jit, static_argnames=("mode", "solver", "settings", "chunk"))
def search_batch(problem, weights: Weights, keys: jax.Array, mode: str = "global",
                 solver: str = DEFAULT_SOLVER, settings: Settings = DEFAULT_SETTINGS,
                 chunk: int = 0) -> tuple[Raw, jax.Array]:
    """The solver's search of every weighting of a batch in one compiled program: :func:`search_one`
    with leading axis w (see :func:`solve_batch`), in chunks of ``chunk`` weightings
    (:func:`search_chunk`; 0: all at once)."""
    # search_one is looked up when traced (the suite's compile ledger records each solve by it)
    return _in_chunks(lambda p, w, k: search_one(p, w, k, mode=mode, solver=solver, settings=settings),
                      problem, weights, keys, chunk)


@partial(jax.jit, static_argnames="mode")
def judge_batch(problem, weights: Weights, design, iterations: jax.Array, done: jax.Array,
                mode: str = "global") -> Judged:
    """The judgement of every weighting of a batch in one compiled program, the same for every
    solver: :func:`judge` with leading axis w (see :func:`solve_batch`)."""
    return _per_weighting(lambda p, w, d, i, c: judge(p, w, d, i, c, mode), problem, weights, design,
                          iterations, done)


def solve_batch(problem, weights: Weights, keys: jax.Array, mode: str = "global", solver: str = DEFAULT_SOLVER,
                settings: Settings = DEFAULT_SETTINGS) -> Solution:
    """Every weighting of a batch in two compiled programs: the solver's search
    (:data:`search_batch`) and the judgement of its answers on the whole grid (:data:`judge_batch`:
    the family's polish and evaluation, one program whatever the solver, so that the solvers of one
    problem share it).

    Args:
      problem: a registered family's problem (grid arrays (n,)).
      weights: alpha, gamma of shape (w,).
      keys: (w,) PRNG keys (used by the GA and hybrid solvers), e.g. :func:`weighting_keys`.
      mode: a name of :data:`camjax.solvers.registry.MODES`.
      solver: a name of :data:`camjax.solvers.registry.SOLVERS`.
      settings: :class:`Settings` (per-solver overrides).
    Returns:
      a :class:`Solution` with leading axis w.

    Traceable (under ``jit`` the two programs are one). A batch of one weighting is traced without
    ``vmap``, its axis added back (:func:`_per_weighting`); its numbers are the batched program's
    but in the last bits where XLA's code for the two differs (measured on the built-in scenes'
    designs: the same for six of the seven follower types; the oscillating curved face's optimum,
    on a ridge, moved 1e-5 mm along it). A sweep in chunks of one weighting therefore runs the
    design's own programs. On the CPU a larger batch is searched :data:`SEARCH_CHUNK` weightings at
    a time (:func:`search_chunk`), each weighting's numbers those of its chunk's ``vmap``.
    """
    check_choice("mode", mode, MODES)
    check_choice("solver", solver, SOLVERS)
    settings = for_problem(problem, solver, settings)
    raw, done = search_batch(problem, weights, keys, mode, solver, settings, search_chunk(weights))
    return _solution(weights, raw, judge_batch(problem, weights, raw.design, raw.iterations, done, mode),
                     mode, solver)


_search_program = runtime.program_cache(search_batch, static_argnames=("mode", "solver", "settings", "chunk"))
_judge_program = runtime.program_cache(judge_batch, static_argnames="mode")


@partial(jax.jit, static_argnames="count")
def weighting_keys(seed: int, count: int, offset: int = 0) -> jax.Array:
    """One key per weighting, fold_in(key(seed), offset + i): independent of chunking.

    One compiled call: run eagerly, key, fold_in and arange would each be compiled on their own.
    """
    base = jax.random.key(seed)
    return jax.vmap(lambda i: jax.random.fold_in(base, i))(offset + jnp.arange(count))


_COMPILED: dict = {}


def _signature(tree):
    leaves, treedef = jax.tree.flatten(tree)
    return treedef, tuple((np.shape(x), str(jnp.result_type(x))) for x in leaves)


def solve(problem, weights: Weights | tuple[float, float] = (1.0, 1.0), *, mode: str = "global",
          solver: str = DEFAULT_SOLVER, seed: int = 0, settings: Settings = DEFAULT_SETTINGS) -> Solution:
    """Solve one weighting; returns a single :class:`Solution` with its :class:`Timings`.

    ``weights``: a scalar :class:`~camjax.followers.flat.Weights` or an (alpha, gamma) pair. A Python
    entry point (it checks the weights on concrete values and times compile and run); trace
    :func:`solve_one` or :func:`solve_batch` instead.
    """
    check_choice("mode", mode, MODES)
    check_choice("solver", solver, SOLVERS)
    alpha, gamma = (float(weights[0]), float(weights[1]))
    check_weights([alpha], [gamma])
    dtype = jax.tree.leaves(_design_form(problem))[0].dtype
    args = (problem, weights_of([alpha], [gamma], dtype), weighting_keys(seed, 1))
    t0 = time.perf_counter()
    compiled, fresh = compiled_batch(*args, mode=mode, solver=solver, settings=settings)
    t1 = time.perf_counter()
    res = jax.device_get(compiled(*args))  # NumPy leaves: indexing them dispatches nothing
    t2 = time.perf_counter()
    return dataclasses.replace(res[0], timings=Timings(t1 - t0 if fresh else 0.0, t2 - t1))


def compiled_batch(problem, weights: Weights, keys: jax.Array, *, mode: str = "global",
                   solver: str = DEFAULT_SOLVER, settings: Settings = DEFAULT_SETTINGS):
    """``(run, fresh)``: ``run(problem, weights, keys) -> Solution`` for arguments of the shapes and
    dtypes of these (a batch of ``w`` weightings: :func:`solve_batch`'s numbers), compiled once per
    process and kept (``fresh``: compiled by this call). With the program cache on (the command
    line) its search and judgement are saved programs, loaded without tracing; else the two jitted
    programs compiled ahead of time. Python: not traceable (call :func:`solve_batch` under a trace)."""
    settings = for_problem(problem, solver, settings)
    args = (problem, weights, keys)
    cache_key = (_signature(args), mode, solver, settings)
    compiled = _COMPILED.get(cache_key)
    if compiled is not None:
        return compiled, False
    compiled = _COMPILED[cache_key] = _compiled_solve(args, mode, solver, settings)
    return compiled, True


def _judge_specs(problem, mode: str, batch: int):
    """The shapes and dtypes of :data:`judge_batch`'s design, iterations and done for a batch of
    ``batch`` weightings (what :func:`search_one` gives, known without tracing the search)."""
    lead = (batch,)
    if mode == "pointwise":
        lead += (jax.tree.leaves(jax.eval_shape(family_of(problem).per_angle, problem))[0].shape[0],)
    design = jax.tree.map(lambda b: jax.ShapeDtypeStruct(lead + b.shape, b.dtype), _design_form(problem))
    return design, jax.ShapeDtypeStruct(lead, jnp.int32), jax.ShapeDtypeStruct(lead, jnp.bool_)


def _compiled_solve(args, mode: str, solver: str, settings: Settings):
    """``args -> Solution``: the search and judgement programs compiled for these arguments (with
    the program cache on, saved programs, no tracing: the command line; the judgement then
    compiles beside the search where compiling ahead is on, its arguments' shapes known first)."""
    problem, weights, _ = args
    specs = _judge_specs(problem, mode, int(jnp.shape(weights.alpha)[0]))
    if runtime.program_cache_on():
        def load_judge():
            return _judge_program.load(problem, weights, *specs, mode=mode)

        with runtime.ahead(load_judge):
            search = _search_program.load(*args, mode=mode, solver=solver, settings=settings)
        judged = load_judge()  # compiled by now where compiling ahead is on
    else:
        search = search_batch.lower(*args, mode, solver, settings).compile()
        judged = judge_batch.lower(problem, weights, *specs, mode).compile()

    def run(problem, weights, keys):
        raw, done = search(problem, weights, keys)
        judgement = judged(problem, weights, raw.design, raw.iterations, done)
        return _solution(weights, raw, judgement, mode, solver)

    return run
