"""Benchmark 4: cost of the population fitness vs population size and grid size N.

Rates are design-angle evaluations per second (population x N / time). Three implementations of
the same fitness (:mod:`benchmarks.fitness`): camjax's GA fitness as the library runs it, the
hand-fused single-reduction kernel (the ~1e9/s reference of STYLE.md, measured here in the same
run) and vectorized NumPy.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks import fitness as fz
from benchmarks.harness import (
    compile_for,
    compiled_cost,
    fusion_count,
    loglog_slope,
    profile_thunks,
    time_jit,
    time_python,
)
from camjax.family import weights_of
from camjax.followers.flat import problem as P

FUSED_BLOCK = 2048  # designs per block of the fused kernel (see blocked())


def blocked(fn, block: int = FUSED_BLOCK):
    """Evaluate a population fitness ``fn(scene, weights, designs)`` in blocks with ``lax.map``.

    XLA:CPU's YNNPACK reduce fusion slows down ~10x when elementwise work follows the reduction
    and the population exceeds ~1e4 rows (measured; see docs/benchmarks.md); blocks of ~2k designs keep
    it on its fast path. Pads the population to a multiple of the block with copies of design 0.
    """

    def run(scene, weights, designs):
        pop = designs.base_radius_mm.shape[0]
        b = min(block, pop)
        chunks = -(-pop // b)
        pad = chunks * b - pop
        padded = jax.tree.map(
            lambda x: jnp.concatenate([x, jnp.broadcast_to(x[:1], (pad,))]).reshape(chunks, b), designs
        )
        out = jax.lax.map(lambda d: fn(scene, weights, type(designs)(*d)), tuple(padded))
        return jax.tree.map(lambda x: x.reshape(-1)[:pop], out)

    return run


def _rate(pop: int, n: int, seconds: float) -> float:
    return pop * n / seconds


def measure_population(problem, weights, populations, numpy_max_pop: int, repeats: int) -> list[dict]:
    """Library, fused and NumPy fitness at each population size on the problem's grid."""
    n = problem.q_mm.shape[0]
    scene = fz.fused_scene(problem)
    np_scene = fz.numpy_scene(scene)
    a, g = float(weights.alpha), float(weights.gamma)
    fused = blocked(fz.fused_fitness)
    library_blocked = blocked(fz.library_fitness)
    rows = []
    for pop in populations:
        designs = fz.random_designs(problem, pop)
        reps = repeats if pop < 10**6 else 1
        t_lib, out_lib = time_jit(fz.library_fitness, problem, weights, designs, repeats=reps)
        # the reference is the faster of the fused kernel as written and in blocks (see blocked())
        t_fused, out_fused = min(
            time_jit(fused, scene, weights, designs, repeats=reps),
            time_jit(fz.fused_fitness, scene, weights, designs, repeats=reps),
            key=lambda t_out: t_out[0].median_s,
        )
        t_blk, _ = time_jit(library_blocked, problem, weights, designs, repeats=reps)
        row = {
            "population": pop,
            "samples": n,
            "library_s": t_lib.median_s,
            "library_compile_s": t_lib.compile_s,
            "library_evals_per_s": _rate(pop, n, t_lib.median_s),
            "fused_s": t_fused.median_s,
            "fused_compile_s": t_fused.compile_s,
            "fused_evals_per_s": _rate(pop, n, t_fused.median_s),
            "library_blocked_s": t_blk.median_s,
            "library_blocked_evals_per_s": _rate(pop, n, t_blk.median_s),
            "fused_vs_library_max_abs_diff": fz.max_disagreement(out_lib, out_fused),
        }
        if pop <= numpy_max_pop:
            r, length = np.asarray(designs.base_radius_mm), np.asarray(designs.face_width_mm)
            t_np, out_np = time_python(
                lambda r=r, length=length: fz.numpy_fitness(np_scene, a, g, r, length), repeats=reps
            )
            row.update(
                numpy_s=t_np.median_s,
                numpy_evals_per_s=_rate(pop, n, t_np.median_s),
                numpy_vs_library_max_abs_diff=fz.max_disagreement(out_lib, out_np),
            )
        rows.append(row)
    return rows


def measure_samples(scene_obj, weights, sample_sizes, population: int, repeats: int, dtype) -> list[dict]:
    """Library and fused fitness at a fixed population for each grid size N."""
    rows = []
    fused = blocked(fz.fused_fitness)
    for n in sample_sizes:
        problem = P.problem_from_scene(scene_obj, samples=n, dtype=dtype, extrema="grid")
        w = weights_of(float(weights.alpha), float(weights.gamma), dtype)
        designs = fz.random_designs(problem, population)
        t_lib, _ = time_jit(fz.library_fitness, problem, w, designs, repeats=repeats)
        t_fused, _ = time_jit(fused, fz.fused_scene(problem), w, designs, repeats=repeats)
        rows.append(
            {
                "population": population,
                "samples": n,
                "dtype": jnp.dtype(dtype).name,
                "library_s": t_lib.median_s,
                "library_evals_per_s": _rate(population, n, t_lib.median_s),
                "fused_s": t_fused.median_s,
                "fused_evals_per_s": _rate(population, n, t_fused.median_s),
            }
        )
    return rows


def profile(problem, weights, population: int) -> dict:
    """XLA's static cost analysis and fusion count of each kernel at one population size."""
    designs = fz.random_designs(problem, population)
    scene = fz.fused_scene(problem)
    kernels = {
        "library": (fz.library_fitness, problem),
        "library_blocked": (blocked(fz.library_fitness), problem),
        "fused": (fz.fused_fitness, scene),
        "fused_blocked": (blocked(fz.fused_fitness), scene),
    }
    out = {"population": population, "samples": int(problem.q_mm.shape[0])}
    for name, (fn, data) in kernels.items():
        compiled = compile_for(fn, data, weights, designs)
        out[name] = {
            **compiled_cost(compiled),
            "fusions": fusion_count(compiled),
            "thunks": profile_thunks(compiled, data, weights, designs),
        }
    return out


def angle_cliff(
    scene_obj, weights, population: int = 1000, sizes=(14400, 18000), tiled_n: int = 36000
) -> dict:
    """The same fitness HLO just below and above ~16k angles (thunk times), and the angle-tiled
    kernel (:func:`benchmarks.fitness.tiled_fitness`) that avoids the cliff, at ``tiled_n``."""
    out = {"population": population}
    for n in sizes:
        problem = P.problem_from_scene(scene_obj, samples=n, extrema="grid")
        designs = fz.random_designs(problem, population)
        t, _ = time_jit(fz.library_fitness, problem, weights, designs, repeats=3)
        out[str(n)] = {
            "library_evals_per_s": _rate(population, n, t.median_s),
            "thunks": profile_thunks(compile_for(fz.library_fitness, problem, weights, designs), problem,
                                     weights, designs, top=2),
        }
    problem = P.problem_from_scene(scene_obj, samples=tiled_n, extrema="grid")
    designs = fz.random_designs(problem, population)
    t_lib, out_lib = time_jit(fz.library_fitness, problem, weights, designs, repeats=3)
    t_tiled, out_tiled = time_jit(fz.tiled_fitness, fz.fused_scene(problem), weights, designs, repeats=3)
    out["tiled"] = {
        "samples": tiled_n,
        "tile": fz.TILE,
        "library_evals_per_s": _rate(population, tiled_n, t_lib.median_s),
        "tiled_evals_per_s": _rate(population, tiled_n, t_tiled.median_s),
        "tiled_vs_library_max_abs_diff": fz.max_disagreement(out_lib, out_tiled),
    }
    return out


def paired_numpy_ratio(problem, weights, population: int, rounds: int) -> dict:
    """camjax / NumPy rate from interleaved rounds (camjax median of 5 calls, then NumPy median of
    3), the median of the per-round ratios: a load change on a shared machine hits both sides."""
    designs = fz.random_designs(problem, population)
    np_scene = fz.numpy_scene(fz.fused_scene(problem))
    r, length = np.asarray(designs.base_radius_mm), np.asarray(designs.face_width_mm)
    a, g = float(weights.alpha), float(weights.gamma)
    ratios, lib_s, np_s = [], [], []
    for _ in range(rounds):
        t_lib, _ = time_jit(fz.library_fitness, problem, weights, designs, repeats=5, min_time_s=0.0)
        t_np, _ = time_python(lambda: fz.numpy_fitness(np_scene, a, g, r, length), repeats=3)
        lib_s.append(t_lib.median_s)
        np_s.append(t_np.median_s)
        ratios.append(t_np.median_s / t_lib.median_s)
    return {
        "population": population,
        "ratio": float(np.median(ratios)),
        "round_ratios": ratios,
        "library_s": lib_s,
        "numpy_s": np_s,
    }


def _exponent(rows, key_x, key_t, x_min) -> float | None:
    pts = [(r[key_x], r[key_t]) for r in rows if r[key_x] >= x_min and key_t in r]
    if len(pts) < 2:
        return None
    return loglog_slope(*zip(*pts, strict=True))


def run(scene_obj, quick: bool) -> dict:
    """Benchmark 4 and the fitness targets (``fitness.evaluations_per_s``, ``fitness.numpy_ratio``)."""
    problem = P.problem_from_scene(scene_obj, extrema="grid")
    weights = weights_of(1.0, 1.0)
    pops = [10, 1000, 10**4] if quick else [10, 100, 1000, 10**4, 10**5, 10**6]
    by_pop = measure_population(
        problem, weights, pops, numpy_max_pop=10**4 if quick else 10**5, repeats=3 if quick else 5
    )
    sizes = [360, 3600] if quick else [90, 180, 360, 720, 3600, 36000]
    n_pop = 1000  # 36 000 angles x 1e3 designs = 3.6e7 design-angles per call already
    by_n = measure_samples(scene_obj, weights, sizes, n_pop, repeats=3, dtype=jnp.float64)
    by_n32 = measure_samples(
        scene_obj, weights, sizes if not quick else sizes[:1], n_pop, repeats=3, dtype=jnp.float32
    )

    prof = profile(problem, weights, 10**4 if quick else 10**5)
    paired = paired_numpy_ratio(problem, weights, 10**4, rounds=2 if quick else 7)
    big = [r for r in by_pop if 10**4 <= r["population"] <= 10**6]
    lib_rate = min(r["library_evals_per_s"] for r in big)
    fused_rate = min(r["fused_evals_per_s"] for r in big)
    at = next(r for r in by_pop if r["population"] == 10**4)
    return {
        "evaluations_per_s": lib_rate,
        "evaluations_per_s_note": "camjax GA fitness (vmap of ga.design_fitness), float64, N=360: the "
        f"lowest rate over populations 1e4..{max(r['population'] for r in big)}",
        "fused_evaluations_per_s": fused_rate,
        "fraction_of_fused": lib_rate / fused_rate,
        "numpy_evaluations_per_s": at["numpy_evals_per_s"],
        "numpy_ratio": paired["ratio"],
        "numpy_ratio_note": "camjax / vectorized NumPy rate at population 1e4, N=360: median of "
        "interleaved rounds (numpy_ratio_rounds)",
        "numpy_ratio_rounds": paired,
        "numpy_ratio_single": at["library_evals_per_s"] / at["numpy_evals_per_s"],
        "fused_numpy_ratio": at["fused_evals_per_s"] / at["numpy_evals_per_s"],
        "population_exponent_library": _exponent(by_pop, "population", "library_s", 1000),
        "population_exponent_fused": _exponent(by_pop, "population", "fused_s", 1000),
        "samples_exponent_library": _exponent(by_n, "samples", "library_s", 360),
        "samples_exponent_fused": _exponent(by_n, "samples", "fused_s", 360),
        "samples_exponent_library_360_to_3600": _exponent(
            [r for r in by_n if r["samples"] <= 3600], "samples", "library_s", 360
        ),
        "angle_cliff": angle_cliff(scene_obj, weights) if not quick else None,
        "library_blocked_evaluations_per_s": min(r["library_blocked_evals_per_s"] for r in big),
        "population_exponent_library_blocked": _exponent(by_pop, "population", "library_blocked_s", 1000),
        "profile": prof,
        "by_population": by_pop,
        "by_samples_float64": by_n,
        "by_samples_float32": by_n32,
    }
