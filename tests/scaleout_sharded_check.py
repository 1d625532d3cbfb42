"""Run in a fresh process by tests/test_distributed.py: sharded vs unsharded on 4 CPU host devices.

JAX fixes its device count when the backend starts, so this cannot run inside the pytest
process (which has one device and must keep it). Prints one JSON object on the last line.
"""

import json
import sys
import time

import jax

jax.config.update("jax_num_cpu_devices", 4)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

import camjax  # noqa: E402, F401  (x64)
from camjax.family import weights_of  # noqa: E402
from camjax.followers.flat.problem import problem_from_scene  # noqa: E402
from camjax.scaleout import sharding  # noqa: E402
from camjax.scaleout.blocks import BlockTask, SweepSpec, solve_block  # noqa: E402
from camjax.scene import builtin_scene_text  # noqa: E402
from camjax.solvers import ga  # noqa: E402
from camjax.solvers.base import solve_batch, weighting_keys  # noqa: E402


def _numbers_differ(a: list[dict], b: list[dict]) -> float:
    """Largest relative difference of any numeric field of two record lists (inf if keys differ)."""
    worst = 0.0
    for ra, rb in zip(a, b, strict=True):
        if ra.keys() != rb.keys():
            return float("inf")
        for k, va in ra.items():
            vb = rb[k]
            if isinstance(va, float):
                worst = max(worst, abs(va - vb) / max(1.0, abs(va)))
            elif va != vb:
                return float("inf")
    return worst


def _leaves_differ(a, b) -> float:
    """Largest difference of two solutions' floating-point leaves relative to max(1, |a|) (inf if
    shapes, NaNs or other leaves differ)."""
    worst = 0.0
    for x, y in zip(jax.tree.leaves(a), jax.tree.leaves(b), strict=True):
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape:
            return float("inf")
        if np.issubdtype(x.dtype, np.floating):
            worst = max(worst, float(np.nanmax(np.abs(x - y) / np.maximum(1.0, np.abs(x)), initial=0.0)))
            if not np.array_equal(np.isnan(x), np.isnan(y)):
                return float("inf")
        elif not np.array_equal(x, y):
            return float("inf")
    return worst


def main() -> dict:
    out = {"devices": jax.local_device_count()}
    start = time.perf_counter()
    lap = lambda name: print(f"{name}: {time.perf_counter() - start:.1f} s", file=sys.stderr)  # noqa: E731
    problem = problem_from_scene(camjax.load_scene())
    w = 6  # does not divide 4: exercises the padding
    weights = weights_of(jnp.logspace(-1, 1, w), jnp.ones(w))
    genes = jax.random.uniform(jax.random.key(1), (w, 64, 2), dtype=problem.q_mm.dtype)
    unsharded = sharding._batched_fitness(problem, weights, genes)
    for pd in (1, 2):
        mesh = sharding.device_mesh(pd)
        got = sharding.sharded_fitness(mesh, problem, weights, genes)
        out[f"fitness_bitwise_{pd}"] = all(bool(jnp.array_equal(a, b)) for a, b in zip(unsharded, got, strict=True))
        out[f"fitness_shards_{pd}"] = len(got[0].sharding.device_set) if pd > 1 else None

    lap("fitness")
    settings = ga.GASettings(population=32, generations=30)
    keys = ga.weighting_keys(0, w)
    ref = ga.solve(keys, problem, weights, "global", settings)
    got = sharding.sharded_ga_solve(sharding.device_mesh(2), keys, problem, weights, settings)
    out["ga_population_sharded_max_diff_mm"] = max(
        float(jnp.max(jnp.abs(a - b))) for a, b in zip(ref.design, got.design, strict=True))

    lap("ga population")
    # pointwise mode through sharded_solve (any registered solver: the gradient solver here; the
    # GA and the gradient solver in global mode through solve_block below): 2 weightings padded
    # to the 4 devices
    coarse = problem_from_scene(camjax.load_scene(), samples=90)  # pointwise: 90 problems per weighting
    two = weights_of(jnp.asarray([0.3, 3.0]), jnp.ones(2))
    keys = weighting_keys(0, 2)
    ref = solve_batch(coarse, two, keys, "pointwise", "gradient")
    got = sharding.sharded_solve(coarse, two, keys, "pointwise", "gradient", mesh=sharding.device_mesh(2))
    out["gradient_pointwise_sharded_max_diff"] = _leaves_differ(ref, got)
    out["gradient_pointwise_per_angle_shape"] = list(got.pointwise.base_radius_mm.shape)
    placed, _ = sharding.spread_weightings((two, keys), sharding.device_mesh(2))
    out["gradient_pointwise_devices"] = len(placed[0].alpha.sharding.device_set)
    lap("gradient pointwise")
    text = builtin_scene_text("default")
    pairs = tuple((float(a), 1.0) for a in jnp.logspace(-1, 1.5, w).tolist())
    for solver, mode in (("gradient", "global"), ("ga", "global")):
        spec = SweepSpec(solver=solver, mode=mode, ga_population=32, ga_generations=40)
        task = BlockTask(0, "default", text, pairs, 0, spec)
        plain = solve_block(BlockTask(**{**task.__dict__, "shard": False}))
        spread = solve_block(task)
        out[f"records_{solver}_{mode}_rel_diff"] = _numbers_differ(plain, spread)
        out[f"records_{solver}_{mode}_count"] = len(spread)
        lap(f"{solver} {mode}")
    return out


if __name__ == "__main__":
    print(json.dumps(main()))
    sys.stdout.flush()
