"""The program cache (camjax.runtime.program_cache): a saved program gives what tracing gives.

References are the same function run through plain ``jax.jit`` (the cache only skips tracing:
results must agree to the last bit) and finite differences for gradients through the wrapper.
"""

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

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
        assert model.load(*_args()) is model.jitted
        _same(model(*_args()), _model(*_args()))
    finally:
        runtime._PROGRAM_DIR[0] = before


@pytest.mark.slow
def test_design_solve_through_a_saved_program_matches(cache, default_scene, default_arrays):
    """The design's solver through its saved program (as the command line runs it) against the
    same solve traced: the same design to the last bit."""
    from camjax.pipeline import design_problem
    from camjax.solvers import base

    problem = design_problem(default_scene, default_arrays)
    runtime._PROGRAM_DIR[0] = None
    base._COMPILED.clear()
    traced = base.solve(problem, (1.0, 1.0))
    runtime.use_program_cache(cache)
    base._COMPILED.clear()
    saved = base.solve(problem, (1.0, 1.0))
    base._COMPILED.clear()
    _same(saved.design, traced.design)
    _same(saved.evaluation, traced.evaluation)


@pytest.mark.slow
@pytest.mark.parametrize("command, scene, name", [("design", "roller", "result.json"),
                                                  ("dynamics", "thesis-bench", "dynamics.json")])
def test_cli_with_saved_programs_writes_what_it_writes_without(command, scene, name, tmp_path, monkeypatch):
    """The command line as users run it (program cache on: first run exports, second loads)
    against the same command with the cache off: the same JSON, value for value."""
    import json

    from camjax import cli

    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE", "0")
    assert cli.main([command, scene, "--out", str(tmp_path / "off")]) == 0
    before = runtime._PROGRAM_DIR[0]
    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE", str(tmp_path / "programs"))
    try:
        assert cli.main([command, scene, "--out", str(tmp_path / "cold")]) == 0
        assert list((tmp_path / "programs").glob(f"*{runtime.PROGRAM_SUFFIX}"))
        runtime._LOADED.clear()  # as a fresh process: read the saved programs back
        from camjax.solvers import base

        base._COMPILED.clear()
        assert cli.main([command, scene, "--out", str(tmp_path / "warm")]) == 0
    finally:
        runtime._PROGRAM_DIR[0] = before
        runtime._LOADED.clear()
    off = json.loads((tmp_path / "off" / name).read_text())
    for run in ("cold", "warm"):
        assert json.loads((tmp_path / run / name).read_text()) == off, run
