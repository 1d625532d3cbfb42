"""The solvers' batch axes laid out over the devices of one host (CPU cores or GPUs).

A sweep's arrays have a **weighting** axis (one independent problem per (alpha, gamma)) and,
inside it for the GA, a **population** axis. :func:`device_mesh` arranges the local devices as
a 2-D :class:`jax.sharding.Mesh` with those two axis names; the functions here place their
inputs with ``NamedSharding`` and call the same jitted solvers, and XLA's SPMD partitioner
splits the work. Nothing in the solvers changes, so the results equal the unsharded ones: the
fitness bit for bit (each device runs the single-device program on its block, see
:func:`sharded_fitness`), the solvers to rounding (1e-12 in float64; a partitioned program may
round a few operations differently; measured: identical records).

- :func:`sharded_solve`: any registered solver and mode (the registry's
  :func:`~camjax.solvers.base.solve_batch`), the weightings over every device. No communication.
- :func:`sharded_ga_solve`: the GA's own layout, each population over the "population" axis
  too: one all-gather of the (population,) objective and violation per generation (selection
  ranks the whole population); pays off for populations of thousands.

Axes that do not divide by the mesh are padded by repeating the last weighting (results
trimmed); a population must divide.

On CPU, XLA gives one device per process unless told otherwise: set
``jax.config.update("jax_num_cpu_devices", N)`` (or
``XLA_FLAGS=--xla_force_host_platform_device_count=N``) before JAX starts its backend.
"""

from __future__ import annotations

from functools import partial

import jax
import jax.numpy as jnp
from jax.sharding import AxisType, Mesh, NamedSharding
from jax.sharding import PartitionSpec as PS

from camjax.family import Problem, Weights
from camjax.solvers import ga
from camjax.solvers.base import DEFAULT_SETTINGS, Settings, Solution, solve_batch
from camjax.solvers.registry import DEFAULT_SOLVER

WEIGHTINGS = "weightings"
POPULATION = "population"


def device_mesh(population_devices: int = 1, devices=None) -> Mesh:
    """Mesh (weightings x population) over ``devices`` (default: every local device).

    Args:
      population_devices: devices along the population axis (must divide the device count);
        the rest go to the weighting axis. 1 (default): weightings only, no communication.
    """
    devices = list(jax.local_devices() if devices is None else devices)
    if population_devices < 1 or len(devices) % population_devices:
        raise ValueError(f"population_devices: {population_devices} must divide the {len(devices)} devices")
    shape = (len(devices) // population_devices, population_devices)
    return jax.make_mesh(shape, (WEIGHTINGS, POPULATION), axis_types=(AxisType.Auto, AxisType.Auto),
                         devices=devices)


def _pad_leading(tree, multiple: int):
    """Pad every leaf's axis 0 to a multiple by repeating its last entry; returns (tree, size)."""
    n = jax.tree.leaves(tree)[0].shape[0]
    extra = -n % multiple
    if extra == 0:
        return tree, n
    return jax.tree.map(lambda x: jnp.concatenate([x, jnp.repeat(x[-1:], extra, axis=0)]), tree), n


def _trim(tree, n: int):
    return jax.tree.map(lambda x: x[:n], tree)


def _place(mesh: Mesh, tree, *spec):
    return jax.device_put(tree, NamedSharding(mesh, PS(*spec)))


def spread_weightings(tree, mesh: Mesh | None = None):
    """Place arrays with a leading weighting axis (weights, keys) over every device of the mesh.

    Returns (placed tree, w): the axis is padded to a multiple of the device count by repeating
    its last entry; keep ``[:w]`` of the results. A jitted solver called with these inputs (e.g.
    :func:`camjax.solvers.sweep.solve_batch`) runs its weightings spread over the devices.
    """
    mesh = device_mesh() if mesh is None else mesh
    tree, w = _pad_leading(tree, mesh.size)
    return _place(mesh, tree, (WEIGHTINGS, POPULATION)), w


# ----------------------------------------------------------------------------- fitness


@jax.jit
def _batched_fitness(problem: Problem, weights: Weights, genes: jax.Array):
    return jax.vmap(ga.fitness, in_axes=(None, 0, 0))(problem, weights, genes)


def sharded_fitness(mesh: Mesh, problem: Problem, weights: Weights, genes: jax.Array):
    """GA fitness of populations for many weightings, over the mesh, bit for bit as on one device.

    Every device runs the *single-device* fitness program on its own block of (weightings x
    population) — dispatched asynchronously, so the devices work at once — and the blocks are
    assembled into globally sharded arrays (``NamedSharding(mesh, P("weightings",
    "population"))``). Not a partitioned program, on purpose: XLA:CPU compiles a multi-partition
    program with other arithmetic rewrites (a division by a replicated scalar becomes a multiply
    by its reciprocal), which moves 1 ulp in ~10 % of the objectives; the per-device program
    does not, and the fitness is per member (no reduction crosses a block), so the result is
    exactly that of one device.

    Args:
      weights: leaves of shape (w,).
      genes: (w, p, d) unit-box genes; w split over "weightings", p over "population" (p must
        divide by the population axis size).
    Returns (objective, violation), each (w, p), equal bit for bit to the unsharded
    ``vmap(ga.fitness)`` under ``jit``.
    """
    n_w, n_p = mesh.shape[WEIGHTINGS], mesh.shape[POPULATION]
    if genes.shape[1] % n_p:
        raise ValueError(f"population {genes.shape[1]} must divide by the mesh's {n_p} population devices")
    (weights, genes), w = _pad_leading((weights, genes), n_w)
    rows, cols = genes.shape[0] // n_w, genes.shape[1] // n_p
    sharding = NamedSharding(mesh, PS(WEIGHTINGS, POPULATION))
    blocks = {}
    for i in range(n_w):
        for j in range(n_p):
            device = mesh.devices[i, j]
            r, c = slice(i * rows, (i + 1) * rows), slice(j * cols, (j + 1) * cols)
            blocks[device] = _batched_fitness(*jax.device_put(
                (problem, jax.tree.map(lambda x, r=r: x[r], weights), genes[r, c]), device))
    shape = genes.shape[:2]
    order = list(sharding.addressable_devices_indices_map(shape))
    out = tuple(jax.make_array_from_single_device_arrays(shape, sharding, [blocks[d][k] for d in order])
                for k in range(2))
    return _trim(out, w)


# ------------------------------------------------------------------------- any solver


def sharded_solve(problem, weights: Weights, keys: jax.Array, mode: str = "global", solver: str = DEFAULT_SOLVER,
                  settings: Settings = DEFAULT_SETTINGS, mesh: Mesh | None = None) -> Solution:
    """:func:`camjax.solvers.base.solve_batch` with its weightings spread over the devices.

    Any registered solver and mode, through the registry: the same jitted solve, its (w,) weights
    and keys placed over every device of ``mesh`` (default: :func:`device_mesh` over every local
    device; padded by repeating the last weighting, trimmed again). A weighting's problem never
    crosses a device, so no device waits for another. Returns the unsharded :class:`Solution`
    (leading axis w) to rounding (tested: the same records).
    """
    (weights, keys), w = spread_weightings((weights, keys), mesh)
    return _trim(solve_batch(problem, weights, keys, mode, solver, settings), w)


# -------------------------------------------------------------------------------- GA


def _run_on_mesh(key, problem: Problem, weights: Weights, settings: ga.GASettings, mesh: Mesh) -> ga.GAResult:
    """:func:`camjax.solvers.ga.run` with the population pinned to the mesh's population axis.

    Only sharding constraints are added, so the random stream and every arithmetic step are those
    of the unsharded run.
    """
    members = NamedSharding(mesh, PS(POPULATION))

    def pin(state: ga.GAState) -> ga.GAState:
        return state._replace(
            genes=jax.lax.with_sharding_constraint(state.genes, NamedSharding(mesh, PS(POPULATION, None))),
            objective=jax.lax.with_sharding_constraint(state.objective, members),
            violation=jax.lax.with_sharding_constraint(state.violation, members))

    return ga.run(key, problem, weights, settings, constrain=pin)


@partial(jax.jit, static_argnames=("settings", "mesh"))
def _ga_on_mesh(keys, problem: Problem, weights: Weights, settings: ga.GASettings, mesh: Mesh):
    one = partial(_run_on_mesh, settings=settings, mesh=mesh)
    return jax.vmap(one, in_axes=(0, None, 0), spmd_axis_name=WEIGHTINGS)(keys, problem, weights)


def sharded_ga_solve(mesh: Mesh, keys: jax.Array, problem: Problem, weights: Weights,
                     settings: ga.GASettings = ga.DEFAULT_SETTINGS) -> ga.GAResult:
    """The GA (global mode) with each population split over the mesh's "population" axis.

    The one layout that is a solver's own: only the GA has a population. ``keys`` and ``weights``
    (w,) go over "weightings", each population over "population" (``settings.population`` must
    divide by its size; a population axis of size 1 is :func:`sharded_solve`'s layout). Leaves
    (w,) as :func:`camjax.solvers.ga.solve`'s, equal to them to rounding. Pays off for
    populations of thousands: one all-gather of the objective and violation per generation.
    """
    if settings.population % mesh.shape[POPULATION]:
        raise ValueError(f"population {settings.population} must divide by the mesh's "
                         f"{mesh.shape[POPULATION]} population devices")
    (keys, weights), w = _pad_leading((keys, weights), mesh.shape[WEIGHTINGS])
    out = _ga_on_mesh(_place(mesh, keys, WEIGHTINGS), problem, _place(mesh, weights, WEIGHTINGS),
                      settings, mesh)
    return _trim(out, w)
