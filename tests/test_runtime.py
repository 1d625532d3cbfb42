"""The program cache (camjax.runtime.program_cache): a saved program gives what tracing gives.

References are the same function run through plain ``jax.jit`` (the cache only skips tracing:
results must agree to the last bit) and finite differences for gradients through the wrapper.
"""

import dataclasses
from functools import partial
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import runtime


class Pair(NamedTuple):
    a: jax.Array
    b: jax.Array


def _model(pair: Pair, key, scale, power: int = 2):
    noise = jax.random.uniform(key, pair.a.shape, dtype=pair.a.dtype)
    return {"sum": jnp.sum(pair.a ** power) * scale + pair.b, "noisy": pair.a + noise}


model = runtime.program_cache(_model, static_argnames=("power",))


@pytest.fixture
def cache(tmp_path):
    """The program cache on in a fresh folder, this process's memory of loaded programs cleared."""
    before = runtime._PROGRAM_DIR[0]
    runtime.use_program_cache(tmp_path)
    yield tmp_path
    runtime._PROGRAM_DIR[0] = before
    runtime._LOADED.clear()


def _args():
    return Pair(jnp.linspace(0.0, 1.0, 7), jnp.asarray(0.5)), jax.random.key(3), 2.0


def _same(x, y):
    for u, v in zip(jax.tree.leaves(x), jax.tree.leaves(y), strict=True):
        np.testing.assert_array_equal(np.asarray(u), np.asarray(v))


def test_saved_program_gives_the_traced_result(cache):
    expected = jax.jit(_model, static_argnames="power")(*_args(), power=3)
    cold = model(*_args(), power=3)  # exported and saved
    files = list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}"))
    assert len(files) == 1
    runtime._LOADED.clear()  # as a fresh process: read back from the file
    warm = model(*_args(), power=3)
    _same(cold, expected)
    _same(warm, expected)
    assert isinstance(warm, dict) and set(warm) == {"sum", "noisy"}


def test_static_values_and_shapes_key_their_own_programs(cache):
    pair, key, scale = _args()
    model(pair, key, scale, power=2)
    model(pair, key, scale, power=3)
    model(Pair(jnp.ones(4), pair.b), key, scale, power=2)
    assert len(list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}"))) == 3
    _same(model(pair, key, scale, power=2), _model(pair, key, scale, 2))


def test_a_loaded_program_takes_new_values(cache):
    pair, key, scale = _args()
    run = model.load(pair, key, scale)
    other = Pair(pair.a * 3.0, jnp.asarray(-1.0))
    _same(run(other, jax.random.key(4), 5.0), _model(other, jax.random.key(4), 5.0))


def test_traced_calls_and_gradients_go_through_jit(cache):
    pair, key, scale = _args()

    def total(a):
        return model(Pair(a, pair.b), key, scale)["sum"]

    g = jax.grad(total)(pair.a)
    np.testing.assert_allclose(g, 2.0 * scale * pair.a, rtol=1e-12)  # d/da scale sum(a^2)
    batch = jax.vmap(lambda b: model(Pair(pair.a, b), key, scale)["sum"])(jnp.arange(3.0))
    np.testing.assert_allclose(batch, float(_model(pair, key, scale)["sum"]) - 0.5 + jnp.arange(3.0),
                               rtol=1e-12)
    assert list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}")) == []  # nothing exported for traced calls


def test_an_unreadable_program_is_exported_again(cache):
    model(*_args())
    (path,) = cache.glob(f"*{runtime.PROGRAM_SUFFIX}")
    path.write_bytes(b"not a program")
    runtime._LOADED.clear()
    _same(model(*_args()), _model(*_args()))
    assert path.read_bytes() != b"not a program"


def test_off_is_plain_jit():
    before = runtime._PROGRAM_DIR[0]
    runtime._PROGRAM_DIR[0] = None
    try:
        _same(model(*_args()), _model(*_args()))
        # the static arguments given to load hold for the call (the mode or solver of a design)
        _same(model.load(*_args(), power=3)(*_args()), _model(*_args(), 3))
    finally:
        runtime._PROGRAM_DIR[0] = before


def _apply(part, power: int = 2):
    return part.args[0] ** power


apply = runtime.program_cache(_apply, static_argnames=("power",))


def test_an_uncacheable_tree_is_traced_with_the_static_arguments_given(cache):
    """A tree structure that does not pickle (a local function in its auxiliary data, as a law
    built at run time) has no key: it is traced as usual, and the static arguments given to load
    still hold (a cached design once ran the default solver here instead of the one asked for)."""
    part = jax.tree_util.Partial(lambda v: v, jnp.arange(3.0))
    np.testing.assert_array_equal(apply.load(part, power=3)(part), np.arange(3.0) ** 3)
    np.testing.assert_array_equal(apply(part, power=3), np.arange(3.0) ** 3)
    np.testing.assert_array_equal(apply(part), np.arange(3.0) ** 2)
    assert list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}")) == []


@pytest.mark.slow
@pytest.mark.parametrize("scene_name", ["default", "oscillating-roller"])
def test_design_solve_through_a_saved_program_matches(cache, scene_name):
    """The design's solver through its saved program (as the command line runs it) against the
    same solve traced with plain ``jax.jit``, on a translating and a rocking follower's problem (each
    family's own tree of arrays), with the scene's solver: the same solution to the last bit
    (every array it holds). tests/cache_matrix.py compares the command line with saved programs
    against the same programs traced afresh, and relies on this for plain ``jax.jit``."""
    from camjax.pipeline import design_problem
    from camjax.solvers import base

    scene = camjax.load_scene(scene_name)
    problem = design_problem(scene)
    weights, solver = (scene.design.alpha, scene.design.gamma), scene.design.solver
    runtime._PROGRAM_DIR[0] = None
    base._COMPILED.clear()
    traced = base.solve(problem, weights, solver=solver)
    runtime.use_program_cache(cache)
    base._COMPILED.clear()
    saved = base.solve(problem, weights, solver=solver)
    base._COMPILED.clear()
    # both programs really saved (an entry point whose export fails runs as plain jax.jit, and the
    # comparison would then hold trivially: the search's once did, its chunk size not static)
    names = {path.name.split("-")[0] for path in cache.glob(f"*{runtime.PROGRAM_SUFFIX}")}
    assert {"camjax.solvers.base.search_batch", "camjax.solvers.base.judge_batch"} <= names, names
    _same(saved, traced)  # design, evaluation, certificate, ...


@pytest.mark.slow
@pytest.mark.parametrize("argv, name, entry_points", [
    (["dynamics", "thesis-bench"], "dynamics.json", ()),
    # two weightings in one chunk of the CPU's size: the search and judgement programs of a batch
    (["sweep", "default", "--alpha", "0.5,2", "--gamma", "1"], "pareto.json",
     ("camjax.solvers.base.search_batch", "camjax.solvers.base.judge_batch")),
], ids=["dynamics", "sweep"])
def test_cli_with_saved_programs_writes_what_it_writes_without(argv, name, entry_points, tmp_path, monkeypatch):
    """The command line as users run it (program cache on, verify mode off: first run exports,
    second loads) against the same command with the cache off: the same JSON, value for value
    (a sweep's but for its seconds); the warm run exports nothing again, and the entry points named
    were saved (a program whose export fails runs as plain ``jax.jit``, and the comparison would
    then hold trivially).

    ``camjax design`` of every follower type, cold and loading saved programs, against the same
    programs traced afresh is tests/test_cache_matrix.py's (in verify mode, which runs the same path
    and only adds the comparison with a fresh trace); the design's solve against plain ``jax.jit``,
    :func:`test_design_solve_through_a_saved_program_matches`."""
    import json

    from camjax import cli
    from camjax.solvers import base

    def written(run):
        data = json.loads((tmp_path / run / name).read_text())
        data.pop("seconds", None)  # a sweep's wall time
        return data

    programs = tmp_path / "programs"

    def saved_programs():  # file name -> modification time of every saved program
        return {path.name: path.stat().st_mtime_ns for path in programs.glob(f"*{runtime.PROGRAM_SUFFIX}")}

    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE", "0")
    assert cli.main([*argv, "--out", str(tmp_path / "off")]) == 0
    before = runtime._PROGRAM_DIR[0]
    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE", str(programs))
    try:
        base._COMPILED.clear()  # the off run's programs are plain jax.jit ones
        assert cli.main([*argv, "--out", str(tmp_path / "cold")]) == 0
        saved = saved_programs()
        assert saved
        assert set(entry_points) <= {file.split("-")[0] for file in saved}, sorted(saved)
        runtime._LOADED.clear()  # as a fresh process: read the saved programs back
        base._COMPILED.clear()
        assert cli.main([*argv, "--out", str(tmp_path / "warm")]) == 0
        assert saved_programs() == saved  # nothing exported again
    finally:
        runtime._PROGRAM_DIR[0] = before
        runtime._LOADED.clear()
        base._COMPILED.clear()
    off = written("off")
    for run in ("cold", "warm"):
        assert written(run) == off, run


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["default", "oscillating-roller"])
def test_compiling_ahead_draws_the_same_design(tmp_path, monkeypatch, scene):
    """The command line runs the drawing for the scene's own follower in a second thread while the
    design solves (runtime.ahead: its programs compiled beside the solver's), then the drawing at
    the design: the same result.json, number for number, as without; and the second thread ran.
    A translating follower and a rocker (whose drawing takes the design's dimensions as data)."""
    import json
    import threading

    from camjax import cli, followers
    from camjax.followers._rocking import RockingFollower
    from camjax.followers._translating import TranslatingFollower
    from camjax.scene import load_scene
    from validation.compare_results import differences

    family = RockingFollower if followers.get(load_scene(scene).follower.type).rocking else TranslatingFollower
    threads = []
    drawn_run = family._drawn_run

    def spy(self, *args, **kwargs):
        threads.append(threading.current_thread().name)
        return drawn_run(self, *args, **kwargs)

    monkeypatch.setattr(family, "_drawn_run", spy)
    results = {}
    try:
        for setting in ("1", "0"):
            monkeypatch.setenv("CAMJAX_COMPILE_AHEAD", setting)
            threads.clear()
            assert cli.main(["design", scene, "--out", str(tmp_path / setting), "--dpi", "30"]) == 0
            results[setting] = (json.loads((tmp_path / setting / "result.json").read_text()), list(threads))
    finally:
        runtime._AHEAD[0] = False
    assert results["1"][1] == [runtime.AHEAD_THREAD, runtime.COMPUTE_THREAD]  # ahead, then at the design
    assert results["0"][1] == [runtime.COMPUTE_THREAD]
    diff = differences(results["1"][0], results["0"][0],
                       ignore=frozenset({"seconds", "compile_s", "run_s", "timings", "elapsed_s"}))
    assert not diff, diff[:10]


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["thesis-bench", "constant-velocity"])
def test_without_a_design_the_drawing_compiles_beside_the_sizing(tmp_path, monkeypatch, scene):
    """A scene without [design]: the drawing at a provisional base radius runs in a second thread
    while the smallest cam is sized (runtime.ahead), then at the radius drawn: the same result.json,
    number for number, as without. A rocker and a translating follower."""
    import json
    import threading

    from camjax import cli, followers
    from camjax.followers._rocking import RockingFollower
    from camjax.followers._translating import TranslatingFollower
    from camjax.scene import load_scene
    from validation.compare_results import differences

    assert load_scene(scene).design is None
    family = RockingFollower if followers.get(load_scene(scene).follower.type).rocking else TranslatingFollower
    threads = []
    at_radius = family._at_radius

    def spy(self, *args, **kwargs):
        threads.append(threading.current_thread().name)
        return at_radius(self, *args, **kwargs)

    monkeypatch.setattr(family, "_at_radius", spy)
    results = {}
    try:
        for setting in ("1", "0"):
            monkeypatch.setenv("CAMJAX_COMPILE_AHEAD", setting)
            threads.clear()
            assert cli.main(["design", scene, "--out", str(tmp_path / setting), "--dpi", "30"]) == 0
            results[setting] = (json.loads((tmp_path / setting / "result.json").read_text()), sorted(threads))
    finally:
        runtime._AHEAD[0] = False
    assert results["1"][1] == sorted([runtime.AHEAD_THREAD, runtime.COMPUTE_THREAD])  # provisional, drawn
    assert results["0"][1] == [runtime.COMPUTE_THREAD]
    diff = differences(results["1"][0], results["0"][0],
                       ignore=frozenset({"seconds", "compile_s", "run_s", "timings", "elapsed_s"}))
    assert not diff, diff[:10]


def test_ahead_of_nothing_or_inside_ahead_runs_nothing():
    """An ``ahead`` inside a thread that runs ahead (or of None) starts no thread of its own."""
    ran = []

    def inner():
        ran.append("inner")

    def outer():
        with runtime.ahead(inner):
            ran.append("outer body")

    before = runtime._AHEAD[0]
    runtime._AHEAD[0] = True
    try:
        with runtime.ahead(outer):
            pass
        with runtime.ahead(None):
            ran.append("body")
    finally:
        runtime._AHEAD[0] = before
    assert ran == ["outer body", "body"]


def test_two_threads_asking_for_one_program_make_it_once(cache, monkeypatch):
    """The drawing compiled ahead and the sizing may ask for one saved program at once (a roller's
    refined extrema): it is exported (and compiled) once, and both get its result."""
    import threading
    import time

    exports = []
    export = runtime._export

    def slow_export(*args, **kwargs):
        exports.append(threading.current_thread().name)
        time.sleep(0.3)  # the other thread asks meanwhile
        return export(*args, **kwargs)

    monkeypatch.setattr(runtime, "_export", slow_export)
    results = {}

    def ask(i):
        results[i] = model(*_args(), power=4)

    threads = [threading.Thread(target=ask, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(exports) == 1, exports
    _same(results[0], results[1])
    _same(results[0], jax.jit(_model, static_argnames="power")(*_args(), power=4))


# ------------------------------------------------------------------ what the key must hold

LEAK = {"power": 2}  # a module global read while tracing: what an entry point must never do


def _leaky(pair: Pair):
    return jnp.sum(pair.a ** LEAK["power"])


leaky = runtime.program_cache(_leaky)


def test_verify_mode_catches_a_trace_that_reads_state_outside_its_key(tmp_path, monkeypatch):
    """The verify mode is what proves the key complete: it must fail on a program whose trace reads
    something the key does not hold (here a module global changed between two calls)."""
    runtime.use_program_cache(tmp_path, verify=True)
    try:
        pair = _args()[0]
        assert float(leaky(pair)) == pytest.approx(float(jnp.sum(pair.a ** 2)), rel=1e-15)
        monkeypatch.setitem(LEAK, "power", 3)
        runtime._LOADED.clear()  # as a fresh process: the saved program is read back
        with pytest.raises(runtime.StaleProgramError, match="_leaky"):
            leaky(pair)
        runtime.use_program_cache(tmp_path, verify=False)  # without verify: the stale answer
        assert float(leaky(pair)) == pytest.approx(float(jnp.sum(pair.a ** 2)), rel=1e-15)
    finally:
        runtime.use_program_cache(None)


def test_verify_mode_checks_a_program_the_command_line_saved_without_its_digest(tmp_path, monkeypatch):
    """A program saved outside verify mode (as the command line saves it) carries no module digest;
    verify mode digests the saved program itself when it reads it: the same trace passes, a trace
    that reads a changed global fails."""
    import pickle

    runtime.use_program_cache(tmp_path, verify=False)
    try:
        pair = _args()[0]
        assert float(leaky(pair)) == pytest.approx(float(jnp.sum(pair.a ** 2)), rel=1e-15)
        (saved,) = tmp_path.glob(f"*{runtime.PROGRAM_SUFFIX}")
        assert pickle.loads(saved.read_bytes())["module_sha256"] is None
        runtime.use_program_cache(tmp_path, verify=True)  # clears this process's programs
        assert float(leaky(pair)) == pytest.approx(float(jnp.sum(pair.a ** 2)), rel=1e-15)
        monkeypatch.setitem(LEAK, "power", 3)
        runtime._LOADED.clear()
        with pytest.raises(runtime.StaleProgramError, match="_leaky"):
            leaky(pair)
    finally:
        runtime.use_program_cache(None)


TRACES: list = []  # one entry per trace of _counted


def _counted(pair: Pair):
    TRACES.append(1)  # runs while tracing only
    return pair.a * pair.b


counted = runtime.program_cache(_counted)


def test_module_text_is_the_same_from_two_call_sites_and_holds_no_location():
    """What verify mode compares: two traces of one program from different call sites differ in
    their source locations only; the text without them is the same, with no ``loc(`` left."""
    pair = _args()[0]

    def from_here():
        return runtime._export("m", _counted, {}, {"pair": pair})[0]

    def from_there():
        return runtime._export("m", _counted, {}, {"pair": pair})[0]

    here, there = from_here(), from_there()
    assert here.mlir_module() != there.mlir_module()  # the locations name the two callers
    text = runtime.module_text(here)
    assert text == runtime.module_text(there) and "loc(" not in text and "stablehlo.multiply" in text


def test_verify_mode_traces_each_program_read_from_the_folder_once(tmp_path):
    """Verify mode traces a program again when it is read from the folder (to compare it), not at
    every call: a program this process exported or compared already runs as it is."""
    runtime.use_program_cache(tmp_path, verify=True)
    try:
        pair = _args()[0]
        TRACES.clear()
        for _ in range(3):
            _same(counted(pair), pair.a * pair.b)
        assert len(TRACES) == 1  # exported on the first call, run as it is by the next two
        runtime._LOADED.clear()  # as a fresh process
        for _ in range(3):
            _same(counted(Pair(pair.a, 2 * pair.b)), 2 * pair.a * pair.b)
        assert len(TRACES) == 2  # read from the folder and traced once to compare
    finally:
        runtime.use_program_cache(None)


def test_the_key_holds_static_values_structure_shapes_dtypes_and_jax_options():
    half = jnp.asarray(0.5, jnp.float64)  # not weak-typed (a Python float is)
    static, dynamic = {"power": 2}, {"pair": Pair(jnp.zeros(7), half)}
    key = runtime.program_key("m", static, dynamic)
    assert runtime.program_key("m", dict(static), {"pair": Pair(jnp.ones(7), 2 * half)}) == key  # values: no
    other = [
        runtime.program_key("n", static, dynamic),
        runtime.program_key("m", {"power": 3}, dynamic),
        runtime.program_key("m", static, {"pair": Pair(jnp.ones(8), half)}),
        runtime.program_key("m", static, {"pair": Pair(jnp.ones(7, jnp.float32), half)}),
        runtime.program_key("m", static, {"pair": (jnp.ones(7), half)}),  # another tree
        runtime.program_key("m", static, {"pair": Pair(jnp.ones(7), 0.5)}),  # weak type
    ]
    assert len({key, *other}) == 1 + len(other)
    before = jax.config.jax_numpy_rank_promotion
    try:
        jax.config.update("jax_numpy_rank_promotion", "warn")  # an option a trace can read
        assert runtime.program_key("m", static, dynamic) != key
    finally:
        jax.config.update("jax_numpy_rank_promotion", before)
    assert runtime.program_key("m", static, dynamic) == key


@partial(jax.tree_util.register_dataclass, data_fields=["x"], meta_fields=["mode"])
@dataclasses.dataclass(frozen=True)
class Tagged:
    """A pytree with auxiliary data (as a problem family's static fields would be)."""

    x: jax.Array
    mode: str


def test_pytree_auxiliary_data_is_in_the_key():
    keys = {runtime.program_key("m", {}, {"t": Tagged(jnp.ones(3), mode)}) for mode in ("global", "pointwise")}
    assert len(keys) == 2


@pytest.mark.parametrize("damage", ["corrupted", "truncated", "another key", "empty"])
def test_a_damaged_saved_program_is_exported_again(cache, damage):
    model(*_args())
    (path,) = cache.glob(f"*{runtime.PROGRAM_SUFFIX}")
    blob = path.read_bytes()
    if damage == "corrupted":  # one byte flipped in the middle of the program
        i = len(blob) // 2
        path.write_bytes(blob[:i] + bytes([blob[i] ^ 0xFF]) + blob[i + 1:])
    elif damage == "truncated":
        path.write_bytes(blob[: len(blob) // 3])
    elif damage == "another key":  # a whole, valid program saved under this file's name
        model(*_args(), power=3)
        (other,) = set(cache.glob(f"*{runtime.PROGRAM_SUFFIX}")) - {path}
        path.write_bytes(other.read_bytes())
    else:
        path.write_bytes(b"")
    runtime._LOADED.clear()
    _same(model(*_args()), _model(*_args()))
    runtime._LOADED.clear()  # and the file now holds the right program again
    _same(model(*_args()), _model(*_args()))


def test_a_read_only_cache_folder_runs_and_writes_nothing(tmp_path):
    import os
    import stat

    folder = tmp_path / "programs"
    folder.mkdir()
    folder.chmod(stat.S_IRUSR | stat.S_IXUSR)
    if os.access(folder, os.W_OK):  # root writes to any mode: take a folder of a read-only file system
        folder.chmod(stat.S_IRWXU)
        folder = Path("/proc/self")
    before = sorted(os.listdir(folder))
    try:
        runtime.use_program_cache(folder)
        _same(model(*_args()), _model(*_args()))
        assert runtime._LOADED  # it ran a program of its own, in memory
        assert not [name for name in os.listdir(folder) if name not in before]
    finally:
        runtime.use_program_cache(None)
        if folder != Path("/proc/self"):
            folder.chmod(stat.S_IRWXU)


@pytest.mark.slow
def test_two_processes_writing_one_cache_at_once_agree(tmp_path):
    """Two fresh processes export the same programs into one folder at the same moment: both
    finish, both write the traced results, and a third reads what they left."""
    import subprocess
    import sys

    code = ("import sys, json, numpy as np, jax.numpy as jnp; from camjax import runtime; "
            "import tests.test_runtime as t; runtime.use_program_cache(sys.argv[1], verify=True); "
            "out = t.model(*t._args(), power=int(sys.argv[2])); "
            "print(json.dumps(float(out['sum'])))")
    root = str(__import__("pathlib").Path(__file__).resolve().parents[1])
    env = {**__import__("os").environ, "PYTHONPATH": root, "CAMJAX_COMPILATION_CACHE": "0"}
    procs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path), str(p)], cwd=root, env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for p in (2, 2, 3, 3)]
    outs = [p.communicate(timeout=300) for p in procs]
    for p, (_, err) in zip(procs, outs, strict=True):
        assert p.returncode == 0, err
    expected = {2: float(_model(*_args(), 2)["sum"]), 3: float(_model(*_args(), 3)["sum"])}
    got = [float(out) for out, _ in outs]
    assert got == [expected[2], expected[2], expected[3], expected[3]]
    assert len(list(tmp_path.glob(f"*{runtime.PROGRAM_SUFFIX}"))) == 2
    assert not list(tmp_path.glob("*.tmp"))  # no half-written file left behind
    third = subprocess.run([sys.executable, "-c", code, str(tmp_path), "3"], cwd=root, env=env,
                           capture_output=True, text=True, timeout=300)
    assert third.returncode == 0 and float(third.stdout) == expected[3], third.stderr
