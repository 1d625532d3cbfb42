"""Smoke test of the benchmark harness: tiny cases run and agree; nothing about speed."""

import sys
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

import camjax

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/ is not installed

from benchmarks import fitness as fz  # noqa: E402
from benchmarks import harness, run, scaling  # noqa: E402
from camjax.family import weights_of
from camjax.followers.flat import problem as P  # noqa: E402


@pytest.mark.slow
def test_fitness_implementations_agree():
    problem = P.problem_from_scene(camjax.load_scene(), samples=90, extrema="grid")
    weights = weights_of(1.0, 1.0)
    designs = fz.random_designs(problem, 37)
    lib = fz.library_fitness(problem, weights, designs)
    fused = scaling.blocked(fz.fused_fitness, block=16)(fz.fused_scene(problem), weights, designs)
    r, length = np.asarray(designs.base_radius_mm), np.asarray(designs.face_width_mm)
    numpy = fz.numpy_fitness(fz.numpy_scene(fz.fused_scene(problem)), 1.0, 1.0, r, length)
    tiled = fz.tiled_fitness(fz.fused_scene(problem), weights, designs, tile=30)
    for other in (fused, numpy, tiled):
        assert fz.max_disagreement(lib, other) < 1e-9


def test_time_jit_separates_compile_and_returns_output():
    timing, out = harness.time_jit(lambda x: jnp.sum(x**2), jnp.arange(4.0), repeats=2, min_time_s=0.0)
    assert timing.compile_s > 0 and timing.median_s > 0 and timing.repeats >= 2
    assert float(out) == 14.0


def test_targets_table_reads_json_keys():
    data = {"pointwise": {"speedup": 150.0}, "fitness": {"numpy_ratio": 2.0}}
    status = {t["key"]: t["status"] for t in run.evaluate_targets(data)}
    assert status["pointwise.speedup"] == "pass"
    assert status["fitness.numpy_ratio"] == "MISS"
    assert status["sweep.ga_speedup"] == "not run"
