"""Scale-out: sharded vs unsharded (4 CPU host devices), process pool and Ray vs sequential,
killed workers, retries, resume. The sequential in-process sweep is the reference throughout."""

import json
import os
import subprocess
import sys
from functools import partial
from pathlib import Path

import jax
import pytest

# tests/ is on sys.path (pytest's default import mode); spawned workers inherit it, Ray workers
# get it through PYTHONPATH, so the fault-injecting block function unpickles by reference.
from scaleout_helpers import compile_in_worker, crash_once

from camjax.followers.flat.problem import problem_from_scene
from camjax.scaleout import (
    BlockStore,
    ManifestMismatch,
    ProcessMap,
    SequentialMap,
    SweepSpec,
    make_blocks,
    pareto_records,
    run_blocks,
    solve_block,
)
from camjax.scene import builtin_scene_text, load_scene
from camjax.solvers.sweep import sweep

TESTS = Path(__file__).parent
WEIGHTINGS = [(10.0 ** e, 1.0) for e in (-1.0, -0.5, 0.0, 0.25, 0.5, 1.0, 1.5, 2.0)]
BLOCK_SIZE = 2  # 4 blocks
SCENES = [("default", builtin_scene_text("default"))]


def _blocks(cache_dir=None, spec=None):
    return make_blocks(SCENES, WEIGHTINGS, BLOCK_SIZE, spec or SweepSpec(), cache_dir=cache_dir)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Records of the sequential sweep, block by block."""
    folder = tmp_path_factory.mktemp("sequential")
    run = run_blocks(_blocks(), folder, SequentialMap(), block_size=BLOCK_SIZE)
    assert run.complete and run.computed == [0, 1, 2, 3]
    store = BlockStore(folder)
    return {i: store.read_block(i)["records"] for i in range(4)}


def _records_by_block(folder) -> dict:
    store = BlockStore(folder)
    return {i: store.read_block(i)["records"] for i in sorted(store.finished())}


@pytest.mark.slow
def test_block_sweep_equals_the_in_process_sweep(reference):
    # the blocks, each rebuilt from the scene text, give the records of camjax.solvers.sweep.sweep
    recs = pareto_records([r for i in sorted(reference) for r in reference[i]])
    assert [r["weighting"] for r in recs] == list(range(len(WEIGHTINGS)))
    problem = problem_from_scene(load_scene("default"))
    # chunks of the blocks' size: the sweep runs the fixture's compiled program (that the records
    # do not depend on the chunk size is tests/test_sweep.py's test_chunking_does_not_change_results)
    whole = sweep(problem, [a for a, _ in WEIGHTINGS], [1.0], chunk_size=BLOCK_SIZE).records()
    for mine, ref in zip(recs, whole, strict=True):
        assert mine["pareto"] == ref["pareto"] and mine["feasible"] == ref["feasible"]
        for key in ("alpha", "gamma", "base_radius_mm", "face_width_mm", "size_mm", "stress_max_MPa",
                    "objective"):
            assert mine[key] == pytest.approx(ref[key], rel=1e-12, abs=1e-12), key
    # more weight on size -> smaller cam and higher stress (the trade the sweep exists to show)
    sizes = [r["size_mm"] for r in recs]
    stresses = [r["stress_max_MPa"] for r in recs]
    assert sizes == sorted(sizes, reverse=True) and sizes[0] > sizes[-1]
    assert stresses == sorted(stresses) and stresses[0] < stresses[-1]


@pytest.mark.slow
def test_sharded_equals_unsharded_on_4_host_devices(compilation_cache_env):
    # a fresh interpreter: the device count is fixed when JAX starts its backend; it compiles into
    # the tests' compilation cache (JAX reads its settings from the environment)
    proc = subprocess.run([sys.executable, str(TESTS / "scaleout_sharded_check.py")],
                          capture_output=True, text=True, timeout=300, env={**os.environ, **compilation_cache_env})
    assert proc.returncode == 0, proc.stderr[-3000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert res["devices"] == 4
    for pd in (1, 2):
        assert res[f"fitness_bitwise_{pd}"] is True
    assert res["fitness_shards_2"] == 4  # really spread over the 4 devices
    assert res["ga_population_sharded_max_diff_mm"] <= 1e-12
    # sharded_solve in pointwise mode: every leaf of the solution (the 90 per-angle designs
    # included) to rounding, its 2 weightings padded and spread over the 4 devices
    assert res["gradient_pointwise_per_angle_shape"] == [2, 90]
    assert res["gradient_pointwise_sharded_max_diff"] <= 1e-12
    assert res["gradient_pointwise_devices"] == 4
    for key in ("gradient_global", "ga_global"):
        assert res[f"records_{key}_count"] == 6
        assert res[f"records_{key}_rel_diff"] <= 1e-12, key


@pytest.mark.slow
def test_process_pool_survives_a_killed_worker(reference, tmp_path):
    marker = tmp_path / "crashed"
    backend = ProcessMap(workers=2)
    # the tests' compilation cache where there is one: the workers (the one started after the
    # crash too) load the block program the reference sweep compiled, where a fresh folder made
    # each of them compile it (~30 CPU s; that a worker writes the folder it is given is the test
    # below's)
    cache = jax.config.jax_compilation_cache_dir or tmp_path / "jax-cache"
    try:
        run = run_blocks(_blocks(cache_dir=str(cache)), tmp_path / "sweep", backend,
                         block_size=BLOCK_SIZE,
                         block_fn=partial(crash_once, victim=2, marker=str(marker)))
    finally:
        backend.close()
    assert marker.exists()  # the worker really died
    assert run.complete and run.computed == [0, 1, 2, 3]
    assert 2 in run.retried
    assert _records_by_block(tmp_path / "sweep") == reference


@pytest.mark.slow
def test_a_pool_worker_compiles_into_the_cache_it_is_given(tmp_path):
    """A spawned worker, configured as every block function configures it
    (camjax.scaleout.blocks.configure_worker), writes what it compiles into the task's folder: the
    folder the workers of a sweep share."""
    folder = tmp_path / "jax-cache"
    backend = ProcessMap(workers=1)
    try:
        [(_, outcome)] = list(backend.map_unordered(compile_in_worker, [str(folder)]))
    finally:
        backend.close()
    assert outcome.ok, outcome.error
    assert outcome.value == str(folder)
    assert any(folder.iterdir())  # the worker wrote its compiled program there


# Ray launches its processes with fork+exec; JAX's warning about os.fork does not apply to that
@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:os.fork:RuntimeWarning")
def test_ray_sweep_matches_sequential_and_survives_a_killed_worker(reference, tmp_path):
    pytest.importorskip("ray")
    from camjax.scaleout import RayMap

    marker = tmp_path / "crashed"
    path = os.pathsep.join([str(TESTS), os.environ.get("PYTHONPATH", "")])
    backend = RayMap(workers=2, runtime_env={"env_vars": {"PYTHONPATH": path}})
    try:
        import ray

        # the local instance stays on loopback (Ray would otherwise use the host's interface)
        assert {node["NodeManagerAddress"] for node in ray.nodes()} == {"127.0.0.1"}
        # the tests' compilation cache where there is one: the workers load the block program the
        # reference sweep compiled (that a worker writes one:
        # test_a_pool_worker_compiles_into_the_cache_it_is_given)
        cache = jax.config.jax_compilation_cache_dir or tmp_path / "jax-cache"
        run = run_blocks(_blocks(cache_dir=str(cache)), tmp_path / "sweep", backend,
                         block_size=BLOCK_SIZE,
                         block_fn=partial(crash_once, victim=1, marker=str(marker)))
    finally:
        backend.close()
    assert marker.exists()
    assert run.complete and run.computed == [0, 1, 2, 3]
    assert run.retried == [1]  # only the killed block ran twice: no finished block was lost
    store = BlockStore(tmp_path / "sweep")
    assert [store.read_block(i)["attempts"] for i in range(4)] == [1, 2, 1, 1]
    assert _records_by_block(tmp_path / "sweep") == reference


class _Interrupt(BaseException):
    """Stands for Ctrl-C / a killed driver: not an Exception, so nothing catches it."""


@pytest.mark.slow
def test_interrupted_sweep_resumes_without_recomputing(reference, tmp_path):
    calls = []

    def interrupted_after_two(task):
        if len(calls) == 2:
            raise _Interrupt
        calls.append(task.index)
        return solve_block(task)

    with pytest.raises(_Interrupt):
        run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE, block_fn=interrupted_after_two)
    store = BlockStore(tmp_path)
    assert store.finished() == {0, 1}
    before = {i: store.block_path(i).read_bytes() for i in (0, 1)}
    assert not list(store.blocks_dir.glob("*.tmp"))  # no half-written block

    resumed = []

    def counting(task):
        resumed.append(task.index)
        return solve_block(task)

    run = run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE, resume=True,
                     block_fn=counting)
    assert resumed == [2, 3] and run.skipped == [0, 1] and run.computed == [2, 3]
    assert {i: store.block_path(i).read_bytes() for i in (0, 1)} == before  # untouched
    assert _records_by_block(tmp_path) == reference

    again = run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE, resume=True,
                       block_fn=counting)
    assert again.computed == [] and again.skipped == [0, 1, 2, 3] and resumed == [2, 3]


@pytest.mark.slow
def test_resume_with_other_parameters_is_refused(reference, tmp_path):
    run_blocks(_blocks()[:1], tmp_path, SequentialMap(), block_size=BLOCK_SIZE)
    other = make_blocks(SCENES, WEIGHTINGS, 4, SweepSpec())
    with pytest.raises(ManifestMismatch, match="block_size"):
        run_blocks(other, tmp_path, SequentialMap(), block_size=4, resume=True)
    with pytest.raises(ManifestMismatch, match="spec"):
        run_blocks(_blocks(spec=SweepSpec(solver="ga")), tmp_path, SequentialMap(), block_size=BLOCK_SIZE,
                   resume=True)
    with pytest.raises(ManifestMismatch, match="--resume"):
        run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE)


@pytest.mark.slow
def test_failing_block_is_retried_then_recorded_and_finished_on_resume(reference, tmp_path):
    attempts = []

    def always_fails_on_3(task):
        if task.index == 3:
            attempts.append(task.index)
            raise RuntimeError("solver blew up")
        return solve_block(task)

    run = run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE, attempts=3,
                     block_fn=always_fails_on_3)
    assert attempts == [3, 3, 3]  # bounded retries
    assert not run.complete and list(run.failed) == [3] and "solver blew up" in run.failed[3]
    store = BlockStore(tmp_path)
    assert store.finished() == {0, 1, 2}
    error = json.loads(store.error_path(3).read_text())
    assert error["attempts"] == 3 and "RuntimeError: solver blew up" in error["error"]

    run = run_blocks(_blocks(), tmp_path, SequentialMap(), block_size=BLOCK_SIZE, resume=True)
    assert run.complete and run.computed == [3] and not store.error_path(3).exists()
    assert _records_by_block(tmp_path) == reference


@pytest.mark.slow
def test_cli_block_sweep_equals_in_process_sweep_and_resumes(tmp_path, capsys):
    from camjax.cli import main

    # chunks and blocks of BLOCK_SIZE weightings of the default scene: the command runs the
    # compiled program of the module's reference sweep (6 weightings: 3 blocks)
    args = ["sweep", "--alpha", "0.1,1,10", "--gamma", "1,2"]
    blocks = ["--backend", "sequential", "--block-size", str(BLOCK_SIZE)]
    assert main(args + ["--out", str(tmp_path / "plain"), "--chunk-size", str(BLOCK_SIZE)]) == 0
    out = tmp_path / "blocks"
    assert main(args + ["--out", str(out)] + blocks) == 0
    plain = json.loads((tmp_path / "plain" / "pareto.json").read_text())["records"]
    assert json.loads((out / "pareto.json").read_text())["records"] == plain

    store = BlockStore(out)
    kept = store.block_path(0).stat().st_mtime_ns, store.block_path(0).read_bytes()
    store.block_path(1).unlink()  # as if the sweep had been interrupted before block 1
    capsys.readouterr()
    assert main(args + ["--out", str(out)] + blocks + ["--resume"]) == 0
    err = capsys.readouterr().err
    assert "resumed: 2 blocks read" in err and "block 1:" in err
    assert "block 0:" not in err and "block 2:" not in err
    assert (store.block_path(0).stat().st_mtime_ns, store.block_path(0).read_bytes()) == kept
    assert json.loads((out / "pareto.json").read_text())["records"] == plain

    # other weightings into the same folder: refused, exit 2, nothing rewritten
    assert main(["sweep", "--alpha", "0.1,1", "--gamma", "1,2", "--out", str(out), "--resume"]) == 2
    assert "other parameters" in capsys.readouterr().err


def test_mode_and_solver_names_come_from_the_registry():
    # one list of names: the block spec, the sweep, the CLI and scene parsing all read the registry
    from camjax.cli import build_parser
    from camjax.scaleout import blocks
    from camjax.solvers import registry, sweep

    assert blocks.SOLVERS is registry.SOLVERS and blocks.MODES is registry.MODES
    assert sweep.SOLVERS is registry.SOLVERS and sweep.MODES is registry.MODES
    design = build_parser()._subparsers._group_actions[0].choices["design"]
    choices = {a.dest: a.choices for a in design._actions if a.dest in ("mode", "solver")}
    assert choices == {"mode": registry.MODES, "solver": registry.SOLVERS}
    with pytest.raises(ValueError, match="solver: 'bfgs' is not allowed; use gradient, ga, hybrid, newton"):
        SweepSpec(solver="bfgs")
