"""docs/extending.md's worked examples run as written: a follower type, a motion law, a solver.

Each example block of the page is marked by an HTML comment on the line before it:

- ``<!-- example: file PATH -->``: the block is the whole file PATH of the package;
- ``<!-- example: insert PATH after LINE -->``: the block goes into PATH after the line LINE;
- ``<!-- example: run NAME -->``: the block is code to run, NAME one of follower, law, solver.

A follower type is registered by its folder and a solver by a line of the registry, both global
to a process, so the follower and the solver run in a subprocess on a copy of the package with the
page's files written into it; the checks are appended to the page's code there. The law runs in
this process, and the law registry is restored afterwards.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import laws
from camjax.scene import builtin_scene_text, parse_scene, with_samples

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "extending.md"
EXAMPLE = re.compile(r"^<!-- example: (file|insert|run) (.+?) -->\n```(\w+)\n(.*?)^```", re.S | re.M)


def _examples() -> list[tuple[str, str, str, str]]:
    """(kind, argument, language, code) of every marked block, in the page's order."""
    return EXAMPLE.findall(PAGE.read_text())


def _run_block(name: str) -> str:
    (code,) = [c for kind, arg, _, c in _examples() if kind == "run" and arg == name]
    return code


def test_every_code_block_of_the_page_is_an_example_a_test_runs():
    text = PAGE.read_text()
    fences = re.findall(r"^```\w+\n", text, flags=re.M)  # opening fences (every block names its language)
    assert len(re.findall(r"^```", text, flags=re.M)) == 2 * len(fences)
    examples = _examples()
    # every opening fence is one of the marked examples: no code on the page goes unrun
    assert len(fences) == len(examples) > 0
    runs = sorted(arg for kind, arg, _, _ in examples if kind == "run")
    assert runs == ["follower", "law", "solver"]


@pytest.fixture(scope="module")
def package(tmp_path_factory) -> Path:
    """A copy of the package with the page's files and insertions applied (the working folder of
    the subprocesses, which import camjax from it)."""
    root = tmp_path_factory.mktemp("extended")
    shutil.copytree(ROOT / "camjax", root / "camjax", ignore=shutil.ignore_patterns("__pycache__"))
    for kind, arg, _, code in _examples():
        if kind == "file":
            path = root / arg
            assert not path.exists(), f"{arg} exists in camjax already: the example would replace it"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(code)
        elif kind == "insert":
            rel, anchor = arg.split(" after ", 1)
            path = root / rel
            lines = path.read_text().splitlines(keepends=True)
            (at,) = [i for i, line in enumerate(lines) if line.rstrip("\n") == anchor]
            path.write_text("".join(lines[: at + 1]) + code + "".join(lines[at + 1:]))
    return root


def _subprocess(package: Path, code: str) -> dict:
    """Run ``code`` with camjax imported from ``package``; the JSON it prints last."""
    cache = jax.config.jax_compilation_cache_dir  # the tests' compile cache, shared
    prelude = textwrap.dedent(f"""
        import json, math, os
        import camjax
        assert os.path.dirname(os.path.dirname(camjax.__file__)) == {str(package)!r}, camjax.__file__
        if {cache!r}:
            camjax.runtime.use_compilation_cache({cache!r})
    """)
    env = {**os.environ, "PYTHONPATH": str(package), "CAMJAX_PROGRAM_CACHE": "0"}
    done = subprocess.run([sys.executable, "-c", prelude + code], cwd=package, env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------------------------ follower


FOLLOWER_CHECKS = """
from dataclasses import replace
from camjax.scene import SceneError, builtin_scene_text, parse_scene, with_design

result = run.design.result
roller = camjax.load_scene("roller")  # the roller with the offset fixed at 0 in [design]
roller_run = camjax.run_design(with_design(roller, offset_mm=0.0))
refused = {}
text = builtin_scene_text("inline-roller")
for where, bad in (("follower", text.replace("roller_radius_mm = 5.0", "roller_radius_mm = 5.0\\noffset_mm = 1.0")),
                   ("design", text.replace("roller_radius_mm = [3.0, 12.0]",
                                           "roller_radius_mm = [3.0, 12.0]\\noffset_mm = [-1.0, 1.0]"))):
    try:
        parse_scene(bad)
    except SceneError as exc:
        refused[where] = str(exc)
report = followers.of(scene).report(scene, run)
print(json.dumps({
    "names": list(followers.names()), "type": scene.follower.type,
    "variables": [v for v, _ in scene.design.variables],
    "feasible": bool(result["feasible"]), "violations": [v.constraint for v in run.violations],
    "base_radius_mm": result["base_radius_mm"], "roller_radius_mm": result["roller_radius_mm"],
    "offset_mm": result["offset_mm"], "pressure_angle_max_deg": result["pressure_angle_max_deg"],
    "roller_prime_mm": roller_run.design.result["base_radius_mm"] + roller_run.design.result["roller_radius_mm"],
    "refused": refused, "report_offset_mm": report["roller"]["offset_mm"],
    "report_json": json.dumps(report, allow_nan=False) is not None,
}))
"""


def _harmonic_prime_radius(lift_mm: float, beta: float, tan_limit: float) -> float:
    """max over a harmonic rise of s' / tan(limit) - s, mm: the smallest prime radius of a roller
    on the cam's centre line (tan phi = s' / (R_p + s)), on a grid of 2e6 + 1 points (the maximum
    is smooth, so the grid's error is O(h^2) ~ 1e-12 of the lift)."""
    x = np.linspace(0.0, 1.0, 2_000_001)
    s = 0.5 * lift_mm * (1.0 - np.cos(np.pi * x))
    ds = 0.5 * lift_mm * np.pi / beta * np.sin(np.pi * x)
    return float(np.max(ds / tan_limit - s))


@pytest.mark.slow
def test_the_inline_roller_is_registered_and_designs_the_closed_form_smallest_cam(package):
    out = _subprocess(package, _run_block("follower") + FOLLOWER_CHECKS)
    assert "inline_roller" in out["names"] and out["type"] == "inline_roller"
    assert out["variables"] == ["base_radius_mm", "roller_radius_mm"]
    assert out["feasible"] and out["violations"] == []
    assert out["offset_mm"] == 0.0 and out["report_offset_mm"] == 0.0 and out["report_json"]
    prime = out["base_radius_mm"] + out["roller_radius_mm"]
    assert math.isfinite(prime) and prime > 0
    # the scene's rise (8 mm over 90 deg, harmonic) sets the pressure angle; the return (8 mm over
    # 180 deg) needs less. Size alone is the objective, so the prime circle is the smallest the 30 deg
    # limit admits: the solvers' feasibility tolerance (1e-9 rad on phi, i.e. ~1e-8 mm on R_p) and the
    # exact extrema's polish bound the difference
    need = _harmonic_prime_radius(8.0, math.pi / 2, math.tan(math.radians(30.0)))
    assert abs(prime - need) <= 1e-6 * need, (prime, need)
    # ... and the largest pressure angle on the samples is the limit's, to the O(h^2) of a smooth
    # maximum between 1 deg samples (phi'' ~ 1 rad per rad^2: ~1e-4 rad at most)
    assert 30.0 - 1e-2 <= out["pressure_angle_max_deg"] <= 30.0 + 1e-6
    # the roller with offset 0 fixed is the same problem: the same prime circle (both solves
    # converge to the same binding limit, to the solvers' tolerance)
    assert abs(prime - out["roller_prime_mm"]) <= 1e-6 * need
    # an offset is refused, naming the key and the types it belongs to
    assert "follower.offset_mm" in out["refused"]["follower"] and "roller" in out["refused"]["follower"]
    assert "design.offset_mm" in out["refused"]["design"]


# ----------------------------------------------------------------------------------- law


@pytest.fixture
def gutman():
    """The page's law block run here; LAWS as it was afterwards (it is the process' registry)."""
    saved = dict(laws.LAWS)
    namespace: dict = {}
    exec(compile(_run_block("law"), str(PAGE), "exec"), namespace)
    try:
        yield namespace["GUTMAN_F3"]
    finally:
        laws.LAWS.clear()
        laws.LAWS.update(saved)


def test_the_example_law_is_a_rest_to_rest_law_with_its_derivatives(gutman):
    assert laws.get_law("gutman_f3") is gutman
    ends = gutman(jnp.asarray([0.0, 1.0]))
    # p(0) = 0, p(1) = 1; p' and p'' vanish at both ends (sin, 1 - cos of whole turns: to rounding)
    np.testing.assert_allclose(ends.p, [0.0, 1.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(ends.dp, [0.0, 0.0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(ends.d2p, [0.0, 0.0], rtol=0, atol=1e-13)
    # each derivative against a central difference of the one before: error h^2/6 max|next| with
    # max|p''''| = (2 pi)^3 (15 + 27) / 16 ~ 650 -> ~1e-8 at h = 1e-5, plus rounding ~1e-16/h = 1e-11
    x = jnp.linspace(0.0, 1.0, 201)
    h = 1e-5
    hi, lo, mid = gutman(x + h), gutman(x - h), gutman(x)
    for f, df in (("p", "dp"), ("dp", "d2p"), ("d2p", "d3p")):
        fd = (getattr(hi, f) - getattr(lo, f)) / (2 * h)
        np.testing.assert_allclose(fd, getattr(mid, df), rtol=0, atol=2e-7 * (1 + float(jnp.max(jnp.abs(
            getattr(mid, df))))), err_msg=df)
    # it works under jit and grad, as every law must
    assert float(jax.jit(jax.grad(lambda t: gutman(t).p))(0.3)) == pytest.approx(float(gutman(0.3).dp), abs=1e-12)


def test_a_scene_takes_the_example_law(gutman):
    from camjax.evaluate import scene_arrays

    text = builtin_scene_text("roller").replace('law = "harmonic"', 'law = "gutman_f3"')
    scene = parse_scene(text)
    kin = scene_arrays(with_samples(scene, 90)).kin
    # the rise: 8 mm over 90 deg, s = h p(theta / beta) at the 90-sample grid's points (every 4 deg)
    theta = np.radians(np.arange(0, 92, 4))
    x = theta / (np.pi / 2)
    p = x - (15 * np.sin(2 * np.pi * x) + np.sin(6 * np.pi * x) / 3) / (32 * np.pi)  # the page's formula
    np.testing.assert_allclose(np.asarray(kin.s)[: len(x)], 8.0 * p, rtol=0, atol=1e-12)


def test_the_law_registry_is_as_it_was():
    # runs after the law tests (file order, -p no:randomly or not: the fixture restores either way)
    assert "gutman_f3" not in laws.LAWS


# -------------------------------------------------------------------------------- solver


SOLVER_CHECKS = """
from camjax.scene import with_design
from camjax.solvers import registry
from camjax.solvers.base import Settings

assert "random_search" in registry.SOLVERS
with_design(camjax.load_scene("roller"), solver="random_search")  # a scene may name it
fewer = solve(problem, (1.0, 0.0), solver="random_search", settings=Settings.of_solvers(
    random_search=camjax.solvers.base.solver_module("random_search").RandomSearchSettings(rounds=5)))
print(json.dumps({"status": found.status_name, "feasible": bool(found.feasible),
                  "objective": float(found.objective), "gradient": float(best.objective),
                  "gradient_feasible": bool(best.feasible), "few_rounds": float(fewer.objective)}))
"""


@pytest.mark.slow
def test_the_random_search_is_registered_and_finds_the_gradient_solvers_optimum(package):
    out = _subprocess(package, _run_block("solver") + SOLVER_CHECKS)
    assert out["gradient_feasible"] and out["feasible"] and out["status"] == "max_steps"
    # 60 rounds shrink the box to 0.7^59 ~ 7e-10 of its width around the best draw, so the search
    # ends next to the optimum the gradient solver converges to (measured 1e-12 apart; 40 rounds:
    # 1e-8); 1e-6 leaves room for the draws' luck, both ways (a design within the feasibility
    # tolerance may undercut the optimum by that much)
    assert out["objective"] == pytest.approx(out["gradient"], rel=1e-6)
    # the settings reach the solver: 5 rounds stop short (measured 0.4 % above the optimum)
    assert out["few_rounds"] > out["gradient"] * (1 + 1e-4)
