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

import hashlib
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field

SOLVERS = ("gradient", "ga")
MODES = ("global", "pointwise")


@dataclass(frozen=True)
class SweepSpec:
    """What every block of a sweep shares: solver, mode and its settings (results depend on it).

    ``ga_population`` / ``ga_generations`` of 0 keep the GA's defaults.
    """

    solver: str = "gradient"  # "gradient" or "ga"
    mode: str = "global"  # "global" or "pointwise"
    seed: int = 0  # GA seed; weighting i of the sweep uses fold_in(key(seed), i)
    samples: int = 0  # angle grid override; 0 keeps the scene's
    ga_population: int = 0
    ga_generations: int = 0

    def __post_init__(self):
        if self.solver not in SOLVERS:
            raise ValueError(f"solver: {self.solver!r} is not allowed; use {', '.join(SOLVERS)}")
        if self.mode not in MODES:
            raise ValueError(f"mode: {self.mode!r} is not allowed; use {', '.join(MODES)}")


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
                                    spec, cache_dir))
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
    import jax

    os.makedirs(cache_dir, exist_ok=True)
    jax.config.update("jax_compilation_cache_dir", cache_dir)
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    _CONFIGURED_CACHE.append(cache_dir)


def _float(x) -> float:
    return float(x)


def _records(task: BlockTask, problem, weights, result) -> list[dict]:
    """One JSON record per weighting. Pointwise mode: the source's design, max over angles."""
    import numpy as np

    spec = task.spec
    design = result.design
    out = []
    for i, (alpha, gamma) in enumerate(task.weightings):
        rec = {
            "scene": task.scene_name,
            "weighting": task.first_weighting + i,
            "alpha": alpha,
            "gamma": gamma,
            "solver": spec.solver,
            "mode": spec.mode,
        }
        if spec.mode == "global":
            rec.update(
                base_radius_mm=_float(design.base_radius_mm[i]),
                face_width_mm=_float(design.face_width_mm[i]),
                objective=_float(result.objective[i]),
                feasible=bool(result.feasible[i]),
                violated=[name for name, v in zip(result.violation._fields, result.violation, strict=True)
                          if float(v[i]) > 0],
            )
        else:
            r = np.asarray(design.base_radius_mm[i])
            length = np.asarray(design.face_width_mm[i])
            rec.update(
                base_radius_mm=float(r.max()),
                base_radius_deg=float(np.asarray(problem.theta_deg)[r.argmax()]),
                face_width_mm=float(length.max()),
                face_width_deg=float(np.asarray(problem.theta_deg)[length.argmax()]),
                feasible=bool(np.all(np.asarray(result.feasible[i]))),
            )
        rec["size_mm"] = rec["base_radius_mm"] + rec["face_width_mm"]
        out.append(rec)
    return out


def _stress_at(problem, records: list[dict]) -> None:
    """Peak contact stress (MPa) of each record's (R_b, L) over the whole grid (the Pareto y-axis)."""
    import jax.numpy as jnp

    from camjax import problem as P

    r = jnp.asarray([rec["base_radius_mm"] for rec in records])
    peak = jnp.max(P.stress(problem, P.Design(r[:, None], 0.0 * r[:, None])), axis=-1)
    for rec, s in zip(records, peak.tolist(), strict=True):
        rec["stress_max_MPa"] = s


def solve_block(task: BlockTask) -> list[dict]:
    """The pure block function: rebuild the scene's problem and solve every weighting of the block.

    Runs anywhere camjax is installed (top-level, picklable). Returns one record per weighting
    (plain dicts: scene, weighting index, alpha, gamma, solver, mode, base_radius_mm,
    face_width_mm, size_mm, stress_max_MPa, feasible, ...).
    """
    configure_worker(task.cache_dir)
    import jax
    import jax.numpy as jnp

    import camjax  # noqa: F401  (x64)
    from camjax.problem import problem_from_scene, weights_of
    from camjax.scene import parse_scene

    spec = task.spec
    scene = parse_scene(task.scene_text, task.scene_name, f"<sweep block {task.index}>")
    problem = problem_from_scene(scene, samples=spec.samples or None)
    pairs = jnp.asarray(task.weightings, problem.q_mm.dtype).reshape(-1, 2)
    weights = weights_of(pairs[:, 0], pairs[:, 1])
    mesh = None
    if task.shard and jax.local_device_count() > 1:
        from camjax.scaleout import sharding

        mesh = sharding.device_mesh()
    if spec.solver == "gradient":
        from camjax.solvers import gradient

        if mesh is None:
            result = gradient.solve_sweep(problem, weights, spec.mode)
        else:
            result = sharding.sharded_gradient_sweep(mesh, problem, weights, spec.mode)
    else:
        from camjax.solvers import ga

        settings = ga.DEFAULT_SETTINGS
        overrides = {k: v for k, v in (("population", spec.ga_population),
                                       ("generations", spec.ga_generations)) if v}
        if overrides:
            settings = ga.GASettings(**{**asdict(settings), **overrides})
        keys = ga.weighting_keys(spec.seed, len(task.weightings), task.first_weighting)
        if mesh is None:
            result = ga.solve(keys, problem, weights, spec.mode, settings)
        else:
            result = sharding.sharded_ga_solve(mesh, keys, problem, weights, spec.mode, settings)
    records = _records(task, problem, weights, result)
    _stress_at(problem, records)
    return records
