"""Smoke test of the benchmark harness: tiny cases run and agree; nothing about speed."""

import json
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


def test_compile_ledger_summary_counts_by_file_program_and_shape(tmp_path):
    """Two workers' ledgers written by hand: the totals, the ranking and the programs lowered under
    two grid sizes (the shape that differs named, the shared one not)."""
    from benchmarks import compile_ledger

    (tmp_path / "ledger-gw0.jsonl").write_text("\n".join([
        '{"test": "tests/test_a.py::t1", "records": [["lower", "jit(solve_batch)", {"float64[90]": 4, "float64[]": 3}],'
        ' ["compile", "jit(solve_batch)", 4.0], ["trace", "jit(solve_batch)", 1.0]]}',
        '{"test": "tests/test_a.py::t2", "records": [["hit", "jit_f", 0.0], ["compile", "jit(add)", 0.5]]}']) + "\n")
    (tmp_path / "ledger-gw1.jsonl").write_text(
        '{"test": "tests/test_b.py::t", "records": [["lower", "jit(solve_batch)", {"float64[360]": 4, "float64[]": 3}],'
        ' ["compile", "jit(solve_batch)", 6.0], ["lower", "jit(add)", {"float64[]": 3}]]}\n')
    result = compile_ledger.summary(compile_ledger.read(tmp_path))
    assert result["compile_s"] == 10.5 and result["trace_s"] == 1.0
    assert list(result["files"]) == ["tests/test_b.py", "tests/test_a.py"]
    assert result["files"]["tests/test_a.py"] == {"compile_s": 4.5, "compiles": 2, "trace_s": 1.0}
    assert result["programs"]["jit(solve_batch)"] == {"compile_s": 10.0, "compiles": 2}
    assert result["shapes"] == {"jit(solve_batch)": {"signatures": 2, "varying": ["float64[360]", "float64[90]"]}}
    # the two solve programs differ in the grid's size alone: the cheaper (4 s) is what one size saves;
    # jit(add)'s lowering has no compile after it, so it is not counted
    assert result["sizes_only"] == {"compile_s": 4.0,
                                    "programs": {"jit(solve_batch)": {"compile_s": 4.0, "structures": 1}}}
    # no "solve" records: nothing to pair the design programs with
    assert result["solves"] == {"compile_s": 0, "sets": []}


def test_compile_ledger_pairs_each_design_program_with_its_solve(tmp_path):
    """Three design programs: one solve (type, mode, solver) at two grid sizes and another solver at
    the first size; only the first two are one program under a shared size, and the cheaper (2 s)
    is what it saves."""
    from benchmarks import compile_ledger

    def line(test, label, n, seconds):
        return json.dumps({"test": test, "records": [
            ["solve", label, {"n": n}], ["lower", "jit(search_batch)", {f"float64[{n}]": 5, "float64[]": 3}],
            ["compile", "jit(search_batch)", seconds]]})

    (tmp_path / "ledger-gw0.jsonl").write_text("\n".join([
        line("tests/test_a.py::t1", "Roller global newton s1", 90, 3.0),
        line("tests/test_b.py::t2", "Roller global newton s1", 360, 2.0),
        line("tests/test_c.py::t3", "Roller global ga s1", 90, 5.0)]) + "\n")
    result = compile_ledger.summary(compile_ledger.read(tmp_path))["solves"]
    assert result["compile_s"] == 2.0
    (only,) = result["sets"]
    assert only["solve"] == "Roller global newton s1" and only["compile_s"] == 2.0
    assert [(p["n"], p["compile_s"], p["tests"]) for p in only["programs"]] == [
        (90, 3.0, ["tests/test_a.py::t1"]), (360, 2.0, ["tests/test_b.py::t2"])]
