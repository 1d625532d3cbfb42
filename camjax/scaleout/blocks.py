"""A weight sweep cut into independent blocks of (scene, weightings), and the pure block function.

A sweep is embarrassingly parallel over (scene, weighting): every weighting's optimum depends on
its scene and its own (alpha, gamma) only (the GA's random key is ``fold_in(seed, index)`` of the
weighting's index in the whole sweep, so it does not depend on how the sweep is cut). A
:class:`BlockTask` carries everything a worker needs as plain data (the scene's TOML *text*, not
a parsed object), so that :func:`solve_block` can run in another process or on another machine
and rebuild the problem there. Its output is a list of Pareto records: plain JSON dicts, one per
weighting.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

from camjax.solvers.registry import DEFAULT_SOLVER, MODES, SOLVERS, check_choice


@dataclass(frozen=True)
class SweepSpec:
    """What every block of a sweep shares: solver, mode and its settings (results depend on it).

    ``ga_population`` / ``ga_generations`` of 0 keep the preset's.
    """

    solver: str = DEFAULT_SOLVER  # a name of camjax.solvers.registry.SOLVERS
    mode: str = "global"  # "global" or "pointwise"
    seed: int = 0  # GA seed; weighting i of the sweep uses fold_in(key(seed), i)
    samples: int = 0  # angle grid override; 0 keeps the scene's
    ga_preset: str = "default"  # a key of camjax.solvers.ga.PRESETS
    ga_population: int = 0
    ga_generations: int = 0

    def __post_init__(self):
        check_choice("solver", self.solver, SOLVERS)
        check_choice("mode", self.mode, MODES)


@dataclass(frozen=True)
class BlockTask:
    """One unit of work: a scene and a run of consecutive weightings of the sweep.

    Picklable plain data. ``first_weighting`` is the index of ``weightings[0]`` in the sweep's
    weighting list (it seeds the GA); ``cache_dir`` is the persistent JAX compilation cache the
    worker should use (None: leave the worker's JAX configuration alone).
    """

    index: int  # block number in the sweep (also its file name)
    scene_name: str
    scene_text: str  # TOML
    weightings: tuple[tuple[float, float], ...]  # (alpha, gamma) pairs
    first_weighting: int
    spec: SweepSpec = field(default_factory=SweepSpec)
    cache_dir: str | None = None
    shard: bool = True
    pad_to: int = 0  # solve this many weightings (the last repeated) so every block compiles alike


def scene_digest(text: str) -> str:
    """Short SHA-256 of a scene's TOML text (identifies it in a manifest)."""
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def make_blocks(scenes: Sequence[tuple[str, str]], weightings: Sequence[tuple[float, float]],
                block_size: int, spec: SweepSpec, cache_dir: str | None = None) -> list[BlockTask]:
    """Cut scenes x weightings into blocks of at most ``block_size`` weightings of one scene.

    Args:
      scenes: (name, TOML text) pairs.
      weightings: (alpha, gamma) pairs, shared by every scene.
      block_size: weightings per block (>= 1).
    Returns blocks numbered 0, 1, ... scene by scene, weightings in order.
    """
    if block_size < 1:
        raise ValueError(f"block_size: {block_size} must be >= 1")
    pairs = tuple((float(a), float(g)) for a, g in weightings)
    blocks = []
    for name, text in scenes:
        for start in range(0, len(pairs), block_size):
            blocks.append(BlockTask(len(blocks), name, text, pairs[start:start + block_size], start,
                                    spec, cache_dir, pad_to=block_size))
    return blocks


# ------------------------------------------------------------------------------ worker

_CONFIGURED_CACHE: list[str] = []


def configure_worker(cache_dir: str | None) -> None:
    """Point this process's JAX at the shared persistent compilation cache (once per process).

    Must run before the process compiles anything to take effect; every block function calls it
    first, so a fresh worker (process pool, Ray) compiles a block's solver once for the whole
    cluster and loads it from the cache afterwards.
    """
    if cache_dir is None or cache_dir in _CONFIGURED_CACHE:
        return
    from camjax.runtime import use_compilation_cache

    use_compilation_cache(cache_dir)
    _CONFIGURED_CACHE.append(cache_dir)


@functools.lru_cache(maxsize=8)
def _problem(scene_text: str, scene_name: str, samples: int):
    """The scene's problem, built once per worker process and scene (blocks of a scene share it)."""
    from camjax.scene import parse_scene
    from camjax.solvers.base import problem_from_scene

    scene = parse_scene(scene_text, scene_name, f"<sweep scene {scene_name}>")
    return problem_from_scene(scene, samples=samples or None)


def solve_block(task: BlockTask) -> list[dict]:
    """The pure block function: rebuild the scene's problem and solve every weighting of the block.

    Runs anywhere camjax is installed (top level, picklable). One compiled call of
    :func:`camjax.solvers.base.solve_batch` for the block; weighting i of the sweep uses the key
    fold_in(key(seed), i), as :func:`camjax.solvers.sweep.sweep` does, so the records equal that
    sweep's whatever the block size (a block size of one runs the design's own program, traced
    without vmap: the same numbers but in the last bits, see
    :func:`~camjax.solvers.base.solve_batch`). Returns one record per weighting: the fields of
    :meth:`camjax.solvers.sweep.SweepResult.records` except "pareto" (a property of the whole
    sweep, decided by :func:`pareto_records`), plus scene, weighting index, solver and mode.
    The solver and mode are checked against :mod:`camjax.solvers.registry` by :class:`SweepSpec`.
    """
    configure_worker(task.cache_dir)
    import jax
    import jax.numpy as jnp
    import numpy as np

    import camjax  # noqa: F401  (x64)
    from camjax.family import Weights
    from camjax.solvers.base import solve_batch, weighting_keys
    from camjax.solvers.sweep import records_of

    spec = task.spec
    problem = _problem(task.scene_text, task.scene_name, spec.samples)
    dtype = jax.tree.leaves(problem.lower)[0].dtype
    count = len(task.weightings)
    # the short last block is padded by repeating its last weighting: one compiled program for all
    idx = np.minimum(np.arange(max(count, task.pad_to)), count - 1)
    pairs = np.asarray(task.weightings, float).reshape(-1, 2)[idx]
    weights = Weights(jnp.asarray(pairs[:, 0], dtype), jnp.asarray(pairs[:, 1], dtype))
    keys = weighting_keys(spec.seed, count, task.first_weighting)[idx]
    solve = solve_batch
    if task.shard and jax.local_device_count() > 1:  # the weightings over every local device
        from camjax.scaleout.sharding import sharded_solve as solve
    result = solve(problem, weights, keys, spec.mode, spec.solver, solver_settings(spec))
    result = jax.tree.map(lambda x: np.asarray(x)[:count], result)
    records = records_of(problem, result)
    for i, rec in enumerate(records):
        rec.update(scene=task.scene_name, weighting=task.first_weighting + i, solver=spec.solver,
                   mode=spec.mode)
    return records


def solver_settings(spec: SweepSpec):
    """The solvers' settings of a sweep's blocks: the GA's as an override unless they are its defaults,
    so that a block's program (settings are a static argument) is the one an in-process sweep of the
    same weightings compiles (:func:`camjax.solvers.sweep.sweep` passes no override)."""
    from camjax.solvers import ga
    from camjax.solvers.base import Settings

    settings = ga_settings(spec)
    return Settings.of_solvers(ga=None if settings == ga.DEFAULT_SETTINGS else settings)


def ga_settings(spec: SweepSpec):
    """The GA settings of a sweep: the preset with the spec's population / generations."""
    from camjax.solvers import ga

    settings = ga.PRESETS[spec.ga_preset]
    overrides = {k: v for k, v in (("population", spec.ga_population),
                                   ("generations", spec.ga_generations)) if v}
    return ga.GASettings(**{**asdict(settings), **overrides}) if overrides else settings


def pareto_records(records: list[dict]) -> list[dict]:
    """Records of a whole sweep with "pareto": non-dominated in (size, peak stress) within its scene."""
    import numpy as np

    from camjax.solvers.sweep import pareto_mask

    out = [dict(r) for r in records]
    for scene in dict.fromkeys(r["scene"] for r in out):
        rows = [r for r in out if r["scene"] == scene]
        column = lambda key, rows=rows: np.array([r[key] for r in rows])  # noqa: E731
        mask = pareto_mask(column("size_mm"), column("stress_max_MPa"), column("feasible"))
        for r, on_front in zip(rows, mask.tolist(), strict=True):
            r["pareto"] = on_front
    return out
