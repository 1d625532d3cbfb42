"""GA-style global search: a population of designs evaluated in one vectorized call per generation.

Real-coded genetic algorithm on the unit box (every design variable mapped to [0, 1] as in
:mod:`camjax.solvers.gradient`), written for **one** problem and one weighting and batched with
``vmap`` over weightings (and, in pointwise mode, angles). Arrays are laid out
``(weightings, [angles,] population, genes)``, so the leading axes can be sharded across devices.

One generation (:func:`ga_step`):

1. rank the population by Deb's feasibility rules: a smaller total constraint violation wins;
   among equally (in)feasible designs the smaller objective wins (no penalty weight to tune);
2. elitism: the ``elite`` best designs pass unchanged;
3. tournament selection (size ``tournament``) of two parents per child;
4. crossover with probability ``crossover``: extended intermediate recombination,
   child = p1 + r (p2 - p1), r ~ U(-blend, 1 + blend) per gene; otherwise the child is p1;
5. mutation: each gene with probability ``mutation_rate`` gets a Gaussian kick whose scale decays
   geometrically from ``mutation_start`` to ``mutation_end`` (unit-box lengths) over the run;
6. clip to the box (so optima on a bound are reached exactly) and evaluate the new population.

The fitness is the problem's true objective and violation; it broadcasts (population, angles)
with no gather and no Python loop, so XLA fuses it into one pass. Randomness is threaded
explicitly: ``ga_init(key, ...)`` draws the seed of a counter-based stream kept in
:class:`GAState` (see :func:`random_words` for why not threefry per step); a weighting's key is
``fold_in(key(seed), index)``, so a result does not depend on how a sweep is chunked.

Settings: :data:`DEFAULT_SETTINGS` reach 0.05 mm of the closed-form per-angle optimum on the
reference case (tests); :data:`SOURCE_SETTINGS` are the source's MATLAB run (population 20,
crossover 0.8, elite 2, MATLAB's default 100 x (number of variables) generations).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.family import Design, Problem, Violation, Weights
from camjax.solvers.base import Raw, family_of, in_mode
from camjax.solvers.base import weighting_keys as weighting_keys
from camjax.solvers.box import from_unit, problem_dtype, solver_objective, to_unit
from camjax.solvers.certificate import certificate_json as certificate_json  # the final point's
from camjax.solvers.certificate import certify_point


@dataclass(frozen=True)
class GASettings:
    """Static configuration of the GA (hashable: a ``jit`` static argument)."""

    population: int = 32
    generations: int = 200
    crossover: float = 0.8  # probability that a child is a recombination of two parents
    elite: int = 2  # best designs copied unchanged into the next generation
    tournament: int = 2  # contestants per tournament
    blend: float = 0.25  # extended intermediate recombination range
    mutation_rate: float = 0.5  # probability that a gene mutates
    mutation_start: float = 0.1  # Gaussian mutation scale at generation 0 (unit box)
    mutation_end: float = 1e-4  # ... at the last generation (geometric decay)


DEFAULT_SETTINGS = GASettings()
SOURCE_SETTINGS = GASettings(population=20, generations=200, crossover=0.8, elite=2)
PRESETS = {"default": DEFAULT_SETTINGS, "source": SOURCE_SETTINGS}


class GAState(NamedTuple):
    """One population (shapes for one problem and weighting; batching adds leading axes)."""

    genes: jax.Array  # (population, genes) unit-box coordinates
    objective: jax.Array  # (population,) F / (alpha + gamma) (+ tie-break), as minimized
    violation: jax.Array  # (population,) total scaled constraint violation, 0 when feasible
    stream: jax.Array  # () uint64 seed of the counter-based random stream (from the jax key)
    generation: jax.Array  # () int


class GAResult(NamedTuple):
    """Best design found (shape () each for one problem and weighting)."""

    design: Design  # mm
    objective: jax.Array  # F (true max over angles)
    violation: Violation  # worst violation per constraint, mm / MPa
    feasible: jax.Array  # bool
    iterations: jax.Array  # int, generations
    best_history: jax.Array  # (generations,) best minimized objective after each generation


def check_settings(settings: GASettings) -> None:
    """Raise ValueError naming the field of an impossible configuration."""
    s = settings
    if not (2 <= s.population < 65536):
        raise ValueError(f"population: {s.population} must be in [2, 65535]")
    if not 0 <= s.elite < s.population:
        raise ValueError(f"elite: {s.elite} must be in [0, population = {s.population})")
    if s.generations < 1 or s.tournament < 1:
        raise ValueError("generations and tournament must be >= 1")
    if not (0 <= s.crossover <= 1 and 0 <= s.mutation_rate <= 1):
        raise ValueError("crossover and mutation_rate are probabilities in [0, 1]")
    if not (s.mutation_start > 0 and s.mutation_end > 0):
        raise ValueError("mutation_start and mutation_end must be > 0")


# ------------------------------------------------------------------------------ genes


def _to_genes(problem: Problem, design: Design) -> jax.Array:
    """Design (one design, mm) -> genes (d,) in the unit box: its leaves raveled in order (a
    family's design is scalars; the co-design's joint program has an array of the laws' coordinates)."""
    return jnp.concatenate([jnp.ravel(v) for v in jax.tree.leaves(to_unit(problem, design))])


def _from_genes(problem: Problem, genes: jax.Array) -> Design:
    """Genes (..., d) -> design in mm (leaves of shape (...) + the leaf's own shape)."""
    lower = family_of(problem).bounds(problem)[0]
    leaves, start = [], 0
    for leaf in jax.tree.leaves(lower):
        shape = jnp.shape(leaf)
        size = math.prod(shape)
        leaves.append(genes[..., start:start + size].reshape(genes.shape[:-1] + shape))
        start += size
    return from_unit(problem, jax.tree.unflatten(jax.tree.structure(lower), leaves))


def _gene_max(problem: Problem) -> jax.Array:
    """(d,) upper end of each gene: 1, or 0 for a variable fixed by lo == hi."""
    lower, upper = family_of(problem).bounds(problem)
    return jnp.concatenate([jnp.ravel(jnp.where(hi > lo, 1.0, 0.0)) for lo, hi in
                            zip(jax.tree.leaves(lower), jax.tree.leaves(upper), strict=True)])


# ----------------------------------------------------------------------------- fitness


def design_fitness(problem: Problem, weights: Weights, design: Design) -> tuple[jax.Array, jax.Array]:
    """(objective as minimized, total scaled violation) of one design; shape () each.

    One pass over the angles (flat face: the peak stress, :func:`camjax.followers.flat.problem.peak_stress`);
    the constraints' maxima over angles come from the family's ``constraint_maxima``.
    """
    family = family_of(problem)
    g = family.constraint_maxima(problem, design)
    total = sum(jnp.maximum(gi, 0.0) for gi in jax.tree.leaves(g)) / family.size_norm(problem)
    return solver_objective(problem, weights, design), total


def fitness(problem: Problem, weights: Weights, genes: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Objective and violation of a population, genes (p, d) -> (p,), (p,): one fused call."""
    return jax.vmap(design_fitness, in_axes=(None, None, 0))(problem, weights, _from_genes(problem, genes))


def deb_key(objective: jax.Array, violation: jax.Array) -> jax.Array:
    """Scalar sort key of Deb's rules, (p,) -> (p,): smaller is better.

    Feasible members keep their objective; infeasible ones get (largest feasible objective + 1)
    + violation, so any feasible design beats any infeasible one and infeasible designs compare
    by violation alone. No sort is needed: tournaments and elitism take minima of this key.
    """
    feasible = violation <= 0
    worst = jnp.max(jnp.where(feasible, objective, -jnp.inf))
    offset = jnp.where(jnp.isfinite(worst), worst + 1.0, 0.0)
    return jnp.where(feasible, objective, offset + violation)


def _smallest(key: jax.Array, count: int) -> jax.Array:
    """Indices of the ``count`` smallest entries (count small and static; no sort)."""
    out = []
    for _ in range(count):
        i = jnp.argmin(key)
        out.append(i)
        key = key.at[i].set(jnp.inf)
    return jnp.stack(out) if out else jnp.zeros((0,), dtype=int)


_GOLDEN = 0x9E3779B97F4A7C15
_GOLDEN_2 = 0xD1B54A32D192ED03


def _splitmix64(x: jax.Array) -> jax.Array:
    """SplitMix64 finalizer (uint64 -> uint64), a counter-based generator's output function."""
    x = x ^ (x >> 30)
    x = x * jnp.uint64(0xBF58476D1CE4E5B9)
    x = x ^ (x >> 27)
    x = x * jnp.uint64(0x94D049BB133111EB)
    return x ^ (x >> 31)


def random_words(stream: jax.Array, generation: jax.Array, shape: tuple[int, ...]) -> jax.Array:
    """uint32 random words of a generation: SplitMix64 over (stream, generation, index) counters.

    Counter-based and elementwise, so it fuses and vectorizes; on a CPU it is ~25x cheaper than
    ``jax.random.bits`` (threefry), which was most of the cost of a generation. The stream itself
    is drawn from a jax key in :func:`ga_init`.
    """
    n = math.prod(shape)
    half = (n + 1) // 2
    # a sub-stream per generation (hashed, so generations never share counters), then counters
    sub = _splitmix64(stream + (generation.astype(jnp.uint64) + jnp.uint64(1)) * jnp.uint64(_GOLDEN_2))
    z = _splitmix64(sub + (jnp.arange(half, dtype=jnp.uint64) + jnp.uint64(1)) * jnp.uint64(_GOLDEN))
    words = jnp.concatenate([(z >> 32).astype(jnp.uint32), z.astype(jnp.uint32)])
    return words[:n].reshape(shape)


def _uniform(bits: jax.Array, dtype) -> jax.Array:
    """uint32 -> uniform in the open interval (0, 1)."""
    return (bits.astype(dtype) + 0.5) * (2.0 ** -32)


# --------------------------------------------------------------------------- init/step


def ga_init(key: jax.Array, problem: Problem, weights: Weights, settings: GASettings = DEFAULT_SETTINGS,
            seed_design: Design | None = None) -> GAState:
    """Uniform random population in the box (member 0 = ``seed_design`` when given)."""
    stream = jax.random.bits(key, (), jnp.uint64)
    top = _gene_max(problem)
    # the steps use counters 0 .. generations - 1; the initial population takes the next one
    first = random_words(stream, jnp.asarray(settings.generations), (settings.population, top.shape[0]))
    genes = _uniform(first, problem_dtype(problem)) * top
    if seed_design is not None:
        genes = genes.at[0].set(jnp.clip(_to_genes(problem, seed_design), 0.0, top))
    obj, vio = fitness(problem, weights, genes)
    return GAState(genes, obj, vio, stream, jnp.asarray(0))


def mutation_scale(settings: GASettings, generation: jax.Array) -> jax.Array:
    """Geometric decay from mutation_start (generation 0) to mutation_end (last generation)."""
    frac = generation / max(settings.generations - 1, 1)
    return settings.mutation_start * (settings.mutation_end / settings.mutation_start) ** frac


def ga_step(state: GAState, problem: Problem, weights: Weights,
            settings: GASettings = DEFAULT_SETTINGS) -> GAState:
    """One generation: elitism, tournaments, crossover, mutation, evaluation.

    All random numbers of a generation are one block of k + 4d + 1 words per child
    (:func:`random_words`).
    """
    p, d = state.genes.shape
    k, n_child = settings.tournament, p - settings.elite
    dtype = state.genes.dtype
    bits = random_words(state.stream, state.generation, (n_child, k + 4 * d + 1))
    rank_key = deb_key(state.objective, state.violation)
    elites = state.genes[_smallest(rank_key, settings.elite)]

    # tournaments: two 16-bit contestant indices per word, k contestants for each of 2 parents
    halves = jnp.concatenate([bits[:, :k] >> 16, bits[:, :k] & 0xFFFF], axis=1).reshape(n_child, 2, k)
    contestants = ((halves * p) >> 16).astype(jnp.int32)
    winner = jnp.take_along_axis(contestants, jnp.argmin(rank_key[contestants], axis=-1)[..., None], -1)
    parents = state.genes[winner[..., 0]]  # (n_child, 2, d)

    u = _uniform(bits[:, k:], dtype)
    blend, cross_u, mut_u = u[:, :d], u[:, d], u[:, d + 1: 2 * d + 1]
    radius_u, angle_u = u[:, 2 * d + 1: 3 * d + 1], u[:, 3 * d + 1:]
    r = -settings.blend + (1.0 + 2.0 * settings.blend) * blend
    mixed = parents[:, 0] + r * (parents[:, 1] - parents[:, 0])
    children = jnp.where((cross_u < settings.crossover)[:, None], mixed, parents[:, 0])

    normal = jnp.sqrt(-2.0 * jnp.log(radius_u)) * jnp.cos(2.0 * jnp.pi * angle_u)  # Box-Muller
    kick = mutation_scale(settings, state.generation) * normal
    children = children + jnp.where(mut_u < settings.mutation_rate, kick, 0.0)
    children = jnp.clip(children, 0.0, _gene_max(problem))

    genes = jnp.concatenate([elites, children.astype(dtype)], axis=0)
    obj, vio = fitness(problem, weights, genes)
    return GAState(genes, obj, vio, state.stream, state.generation + 1)


def best(state: GAState) -> tuple[jax.Array, jax.Array, jax.Array]:
    """(genes (d,), objective, violation) of the best member."""
    i = jnp.argmin(deb_key(state.objective, state.violation))
    return state.genes[i], state.objective[i], state.violation[i]


# ------------------------------------------------------------------------------ solves


def run(key: jax.Array, problem: Problem, weights: Weights, settings: GASettings = DEFAULT_SETTINGS,
        seed_design: Design | None = None,
        constrain: Callable[[GAState], GAState] | None = None) -> GAResult:
    """The whole GA for one problem and weighting as one ``lax.scan``; traceable, vmappable.

    ``constrain`` is applied to the state after ``ga_init`` and after every ``ga_step`` (the
    sharded solve pins the population to devices with it); it must not change values.
    """
    check_settings(settings)
    constrain = constrain or (lambda state: state)

    def body(state, _):
        state = constrain(ga_step(state, problem, weights, settings))
        return state, best(state)[1]

    state = constrain(ga_init(key, problem, weights, settings, seed_design))
    state, history = jax.lax.scan(body, state, None, length=settings.generations)
    genes, _, _ = best(state)
    design = _from_genes(problem, genes)
    ev = family_of(problem).evaluate(problem, weights, design)
    return GAResult(design, ev.objective, ev.violation, ev.feasible, state.generation, history)


def run_pointwise(key: jax.Array, problem: Problem, weights: Weights,
                  settings: GASettings = DEFAULT_SETTINGS) -> GAResult:
    """Pointwise mode for one weighting: one population per angle (vmap), leaves of shape (n,).

    Angle i uses the key fold_in(key, i) (:func:`camjax.solvers.base.in_mode`).
    """
    return in_mode(lambda p, w, k, init=None: run(k, p, w, settings), "pointwise")(problem, weights, key)


@partial(jax.jit, static_argnames=("mode", "settings"))
def solve(keys: jax.Array, problem: Problem, weights: Weights, mode: str = "global",
          settings: GASettings = DEFAULT_SETTINGS) -> GAResult:
    """All weightings at once: ``weights`` leaves (w,), ``keys`` (w,) -> results with leading axis w.

    mode "global": leaves (w,); "pointwise": leaves (w, n). Layout (w, [n,] population, genes).
    The GA's raw results; :func:`camjax.solvers.base.solve_batch` gives
    :class:`~camjax.solvers.base.Solution` s.
    """
    one = in_mode(lambda p, w, k, init=None: run(k, p, w, settings), mode)
    return jax.vmap(one, in_axes=(None, 0, 0))(problem, weights, keys)


def run_one(problem: Problem, weights: Weights, key: jax.Array, settings, init: Design | None = None) -> Raw:
    """The solver protocol of :mod:`camjax.solvers.base`: :func:`run` with ``settings.of("ga")``.

    ``init`` (optional) seeds member 0 of the population. A fixed budget of generations: no
    convergence flag (status max_steps when feasible). The final point's KKT certificate
    (:func:`camjax.solvers.certificate.certify_point`) comes with it.
    """
    res = run(key, problem, weights, settings.of("ga"), seed_design=init)
    return Raw(res.design, res.iterations, None, certify_point(problem, weights, res.design, res.iterations))
