"""One answer whatever the path: the command line with its saved-program cache on, cold or warm, in
any order of runs, writes what it writes with every program traced afresh.

One follower type (FULL_SEQUENCE) runs a sequence of commands through :func:`camjax.cli.main`, one
option changed at a time (mode, solver, seed, samples, weights, base radius, edits of the scene
file: extrema, rotation, each design variable fixed or free, the stress limit; :func:`full_runs`),
all sharing one cache folder; every other type runs the part of its sequence that traces its own code (:func:`own_runs`), one of them (QUICK_SEQUENCE) with the runs a stale
cache once got wrong added. Every run starts as a fresh process would (this process's memory of
loaded programs cleared), in the cache's verify mode (every program read from the folder traced
again and its StableHLO compared with the saved one's: a key that misses a trace-time input
raises). Each result.json (dynamics.json) must equal, number for number, the same run
with every program traced afresh (its reference); the quick sequence's stale-cache runs then run again in
reverse order, and the dynamics runs that saved a program again, every program now loaded from
the folder, with the same check (a run that saved none loaded every one already).

The reference (:func:`_references`) is the same command with each program traced and exported
when the sequence first needs it, and never read back from a folder: equality is exact because a
saved program is the traced program itself. Its programs are compiled once for the sequence, so
the runs with the shared folder find each compile in the compilation cache instead of compiling
the program a second time (a reference with the cache off, plain ``jax.jit``, compiled another
module of the same program: ~20 % of the matrix's time). That an exported program computes what
plain ``jax.jit`` computes, bit for bit, is tests/test_runtime.py's (a toy program, the design's
solve of a translating and of a rocking follower, ``camjax dynamics``). Figures and the DXF are not drawn here (they read no saved
program); everything the JSON holds is computed as the command computes it.

The sequences and checks shared by tests/test_cache_matrix*.py (several files, so that the matrix
spreads over the workers of ``pytest -n auto --dist loadfile``); validation/snapshot.py runs the
full sequences of :data:`SCENES` (:func:`_runs`, sweeps too).
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path

from camjax import cli, followers, runtime
from validation.compare_results import differences

# keys that time the run: they differ between any two runs
TIMING_KEYS = frozenset({"seconds", "compile_s", "run_s", "timings", "elapsed_s"})

FLAT = (Path(__file__).resolve().parents[1] / "camjax" / "scenes" / "default.toml").read_text()
ROLLER = (Path(__file__).resolve().parents[1] / "camjax" / "scenes" / "roller.toml").read_text()

ROCKER = """
[motion]
rpm = 300.0
samples = 90
rotation = "ccw"
segments = [
  { kind = "rise",   angle_deg = 120, law = "cycloidal", lift_deg = 20.0 },
  { kind = "dwell",  angle_deg = 60 },
  { kind = "return", angle_deg = 100, law = "poly_3_4_5", lift_deg = 20.0 },
  { kind = "dwell",  angle_deg = 80 },
]

[follower]
type = "oscillating_roller"
pivot_distance_mm = 80.0
arm_length_mm = 60.0
roller_radius_mm = 8.0
inertia_kg_m2 = 0.002
spring_N_m_per_rad = 20.0
preload_rad = 0.3

[contact]
cam_width_mm = 8.0
cam = { E_MPa = 2.1e5, poisson = 0.3 }
follower = { E_MPa = 2.1e5, poisson = 0.3 }

[design]
base_radius_mm = [5.0, 60.0]
pivot_distance_mm = [65.0, 110.0]
sigma_max_MPa = 2000.0
alpha = 1.0
gamma = 0.5
solver = "gradient"   # the matrix's runs of the gradient solver (every built-in scene names newton)
"""

ROCKER_FLAT = (ROCKER.replace('type = "oscillating_roller"', 'type = "oscillating_flat"')
               .replace("arm_length_mm = 60.0\nroller_radius_mm = 8.0", "face_offset_mm = 10.0")
               .replace("pivot_distance_mm = 80.0", "pivot_distance_mm = 150.0")
               .replace("base_radius_mm = [5.0, 60.0]\npivot_distance_mm = [65.0, 110.0]",
                        "base_radius_mm = [5.0, 130.0]\npivot_distance_mm = [120.0, 200.0]"))


def _edit(text: str, *replacements: tuple[str, str]) -> str:
    for old, new in replacements:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


# follower -> (scene text, option sets, scene edits); each entry runs `design` once
SCENES = {
    "flat": (
        _edit(FLAT, ("samples = 360", "samples = 90"), ("gamma = 1.0", "gamma = 2.0")),
        [[], ["--mode", "pointwise"], ["--solver", "ga"], ["--solver", "ga", "--seed", "7"],
         ["--solver", "hybrid"], ["--samples", "120"], ["--alpha", "3", "--gamma", "1"],
         ["--base-radius", "33"], ["--mode", "pointwise", "--solver", "ga", "--seed", "7"]],
        [("samples = 90", 'samples = 90\nextrema = "grid"'),
         ("samples = 90", 'samples = 90\nrotation = "cw"'),
         ("face_width_mm = [5.0, 25.0]", "face_width_mm = [20.0, 20.0]"),
         ('mode = "global"', 'mode = "pointwise"'),
         ("sigma_max_MPa = 1230.0", "sigma_max_MPa = 200.0")],
    ),
    "roller": (
        _edit(ROLLER, ("samples = 360", "samples = 90"), ("gamma = 0.0", "gamma = 0.5")),
        [[], ["--mode", "pointwise"], ["--solver", "ga"], ["--solver", "ga", "--seed", "7"],
         ["--solver", "hybrid"], ["--samples", "120"], ["--alpha", "3", "--gamma", "1"],
         ["--base-radius", "30"]],
        [("samples = 90", 'samples = 90\nextrema = "grid"'),
         ('rotation = "ccw"', 'rotation = "cw"'),
         ("offset_mm = [-4.0, 4.0]", "offset_mm = 1.5"),
         ("roller_radius_mm = [3.0, 12.0]", "roller_radius_mm = 6.0"),
         ('mode = "global"', 'mode = "pointwise"'),
         ("sigma_max_MPa = 1000.0", "sigma_max_MPa = 700.0")],
    ),
    "oscillating_roller": (
        ROCKER,
        [[], ["--mode", "pointwise"], ["--solver", "ga"], ["--solver", "hybrid", "--seed", "7"],
         ["--samples", "120"], ["--alpha", "3", "--gamma", "1"]],
        [('rotation = "ccw"', 'rotation = "cw"'),
         ("pivot_distance_mm = [65.0, 110.0]", "pivot_distance_mm = [65.0, 110.0]\narm_length_mm = [50.0, 70.0]"),
         ("pivot_distance_mm = [65.0, 110.0]", "pivot_distance_mm = 90.0"),
         ("sigma_max_MPa = 2000.0", "sigma_max_MPa = 1500.0")],
    ),
    "oscillating_flat": (
        ROCKER_FLAT,
        [[], ["--mode", "pointwise"], ["--solver", "ga"], ["--solver", "hybrid", "--seed", "7"],
         ["--samples", "120"], ["--alpha", "3", "--gamma", "1"]],
        [('rotation = "ccw"', 'rotation = "cw"'),
         ("pivot_distance_mm = [120.0, 200.0]", "pivot_distance_mm = [120.0, 200.0]\nface_offset_mm = [-10.0, 20.0]"),
         ("pivot_distance_mm = [120.0, 200.0]", "pivot_distance_mm = 160.0"),
         ("sigma_max_MPa = 2000.0", "sigma_max_MPa = 1500.0")],
    ),
}

SWEEPS = [["--alpha", "0.5,2", "--gamma", "1"], ["--alpha", "0.5,2", "--gamma", "1", "--mode", "pointwise"],
          ["--alpha", "1", "--gamma", "0.5,2", "--solver", "ga", "--seed", "3"]]


def _run(argv: list[str], out: Path, cache: Path, monkeypatch, verify: bool = True) -> dict:
    """One command as a fresh process runs it, the program cache on in ``cache`` (in verify mode
    unless ``verify`` is False)."""
    from camjax.solvers import base

    runtime.use_program_cache(None)  # a fresh process starts with the cache off ...
    base._COMPILED.clear()  # ... and nothing compiled
    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE", str(cache))
    monkeypatch.setenv("CAMJAX_PROGRAM_CACHE_VERIFY", "1" if verify else "0")
    try:
        assert cli.main([*argv, "--out", str(out)]) == 0, argv
    finally:
        runtime.use_program_cache(None)
        monkeypatch.delenv("CAMJAX_PROGRAM_CACHE_VERIFY", raising=False)
    name = {"design": "result.json", "sweep": "pareto.json", "dynamics": "dynamics.json"}[argv[0]]
    return json.loads((out / name).read_text())


def _runs(follower: str, tmp: Path) -> list[list[str]]:
    """The follower's sequence of commands: each option set on the scene, each scene edit, sweeps
    (validation/snapshot.py runs them all; the matrix, :func:`full_runs` and :func:`own_runs`)."""
    text, options, _ = SCENES[follower]
    base = tmp / f"{follower}.toml"
    base.write_text(text)
    runs = [["design", str(base), *opts] for opts in options]
    runs += _edited_runs(follower, tmp)
    return runs + [["sweep", str(base), *opts] for opts in SWEEPS]


# A scene edit whose design runs the same programs on the same argument values as its sequence's
# base design (measured: each run's program keys and the digests of the arguments each program ran
# on): the flat face's rotation turns its profile in the command's own code, outside every program.
SAME_AS_BASE = {"flat": ['rotation = "cw"']}


def _edited_runs(follower: str, tmp: Path, *, every_edit: bool = True) -> list[list[str]]:
    """A design of each scene edit of the follower's sequence; ``every_edit`` False: without the
    edits that run no program on values another run does not (the [design] block's own mode, see
    :func:`full_runs`; :data:`SAME_AS_BASE`)."""
    text, _, edits = SCENES[follower]
    runs = []
    for k, (old, new) in enumerate(edits):
        same = new.startswith("mode =") or any(edit in new for edit in SAME_AS_BASE.get(follower, ()))
        if same and not every_edit:
            continue
        edited = tmp / f"{follower}-edit{k}.toml"
        edited.write_text(_edit(text, (old, new)))
        runs.append(["design", str(edited)])
    return runs


def _references(runs: list[list[str]], tmp: Path, monkeypatch) -> list[dict]:
    """Each run's JSON with every program it runs traced and exported afresh: the first time the
    sequence needs a program (by its key), then kept in this process for the later runs, as
    ``jax.jit`` keeps its traces; never read from a folder (the references' folder only receives
    what they export, and a key is exported once). A key that conflates two traces would make a
    wrong reference too, but the same load from the shared folder raises in verify mode; a fault
    in reading a saved program back shows as a difference."""
    programs: dict = {}
    program = runtime._program

    def traced_once(folder, name, fn, static, dynamic):
        key = runtime.program_key(name, static, dynamic)
        if key not in programs:
            programs[key] = program(folder, name, fn, static, dynamic)
        return programs[key]

    with monkeypatch.context() as patch:
        patch.setattr(runtime, "_program", traced_once)
        return [_run(argv, tmp / f"reference{k}", tmp / "reference-programs", patch, verify=False)
                for k, argv in enumerate(runs)]


def _check_sequence(runs: list[list[str]], tmp: Path, monkeypatch, warm: Sequence[int] = ()) -> list[int]:
    """Each run's reference (:func:`_references`), then each run with the cache on in one folder, in
    order (a run whose key an earlier run saved loads that program: the case a key that misses an
    input gets wrong, which verify mode then catches), then the runs numbered in ``warm`` again in
    reverse order, every program they run loaded from the folder (each compared with its
    reference as well). Returns the number of programs in the folder after each run in order."""
    cache = tmp / "programs"
    runtime._UNEXPORTABLE.clear()
    reference = _references(runs, tmp, monkeypatch)
    saved = []
    for k in [*range(len(runs)), *sorted(warm, reverse=True)]:
        on = _run(runs[k], tmp / f"on{k}", cache, monkeypatch)
        diff = differences(reference[k], on, ignore=TIMING_KEYS)
        assert not diff, f"{' '.join(runs[k])}: with the shared folder != traced afresh:\n" + "\n".join(diff[:20])
        saved.append(len(list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}"))))
    assert list(cache.glob(f"*{runtime.PROGRAM_SUFFIX}")), "the sequence saved no program"
    # a program whose export fails is traced by every command instead of loaded (silently: from
    # 2399a61 to d3c036d the search did so): every program of these commands exports
    assert not runtime._UNEXPORTABLE, f"programs the cache could not save: {runtime._UNEXPORTABLE}"
    return saved[:len(runs)]


# The full sequence above runs on one follower type (FULL_SEQUENCE); every other type runs OWN_RUNS,
# the part of it that traces the type's own code. What the rest checks does not depend on the
# follower: the program key is computed from an entry point's arguments by the same code for every
# type (camjax.runtime.program_key), and the solver, seed, sample count and weights only change
# generic entry-point arguments (static mode/solver, the PRNG keys, grid shapes, the weights' values)
# whose handling the full sequence checks once. A follower's code enters through what it
# traces: its problem in the solve program (the base design), its pointwise condensing (pointwise
# mode), its sizing programs keyed by rotation (the rotation edit), its exact or grid extrema, its
# own design variables free or fixed (the problem's tree structure: its scene edits) and its scene
# values as data (the stress-limit edit, or other weights: a run that loads every program the base
# run saved, which verify mode traces again).
FULL_SEQUENCE = "roller"
OWN_OPTIONS = [[], ["--mode", "pointwise"]]


def full_runs(tmp: Path) -> list[list[str]]:
    """FULL_SEQUENCE's sequence as the matrix runs it: every option set and scene edit but two kinds
    of run that check nothing another run does not (measured, recording each run's program keys
    and the digests of the arguments each program ran on):
    - the [design] block's own mode: the same programs on the same argument values as
      ``--mode pointwise`` (the scene's common code reads the mode);
    - the sweeps: ``camjax sweep`` runs the design's two entry points (the search and its
      judgement, camjax.solvers.base.compiled_batch) at a batch of one chunk, on the same key; a
      sweep with saved programs against the same command without is tests/test_runtime.py's."""
    text, options, _ = SCENES[FULL_SEQUENCE]
    base = tmp / f"{FULL_SEQUENCE}.toml"
    base.write_text(text)
    return [["design", str(base), *opts] for opts in options] + _edited_runs(FULL_SEQUENCE, tmp, every_edit=False)


def own_runs(follower: str, tmp: Path) -> list[list[str]]:
    """The runs of ``follower`` that trace its own code (see the comment above FULL_SEQUENCE): the
    base design, pointwise mode and each scene edit of its sequence (those that run no program on
    values another run does not left out: :func:`_edited_runs`); a type without a sequence, its
    built-in example scene's (:func:`example_runs`)."""
    if follower not in SCENES:
        return example_runs(follower, tmp)
    base = tmp / f"{follower}.toml"
    base.write_text(SCENES[follower][0])
    runs = [["design", str(base), *opts] for opts in OWN_OPTIONS]
    return runs + _edited_runs(follower, tmp, every_edit=False)


def example_runs(follower: str, tmp: Path) -> list[list[str]]:
    """A follower type without a sequence of its own: its built-in example scene at 90 samples with
    the scene's own solver, each mode, another weighting (every program of the base run loaded), the
    other rotation and the grid's extrema. The built-in scenes name newton, so these runs and the
    full sequence's own (the roller's scene; with the GA and the hybrid) are that solver's, its
    certificate saved and loaded with the program; the gradient solver runs in the rockers'
    sequences (:data:`SCENES`: their scene texts name it)."""
    from camjax.scene import builtin_scene_text

    text = builtin_scene_text(followers.get(follower).example_scene)
    text = re.sub(r"(?m)^samples = \d+", "samples = 90", text)
    base = tmp / f"{follower}.toml"
    base.write_text(text)
    runs = [["design", str(base), *opts] for opts in ([*OWN_OPTIONS, ["--alpha", "3"]])]
    rotation = re.search(r'(?m)^rotation = "(\w+)"', text)
    other = 'rotation = "cw"' if rotation is None or rotation.group(1) == "ccw" else 'rotation = "ccw"'
    for k, edited_text in enumerate((re.sub(r'(?m)^rotation = "\w+"', "", text).replace(
            "samples = 90", f"samples = 90\n{other}"), text.replace("samples = 90", 'samples = 90\nextrema = "grid"'))):
        edited = tmp / f"{follower}-edit{k}.toml"
        edited.write_text(edited_text)
        runs.append(["design", str(edited)])
    return runs


# The quick sequence: QUICK_SEQUENCE's own runs and the runs a stale cache once got wrong (a GA run
# after another seed's; a pointwise run after a global one is among the own runs), those four then
# again in reverse order, every program loaded (tests/test_cache_matrix.py). It holds that type's
# own runs: the type is not in tests/test_cache_matrix_types_*.py.
QUICK_SEQUENCE = "flat"
QUICK_OPTIONS = [["--solver", "ga", "--seed", "7"], ["--solver", "ga"]]


def quick_runs(tmp: Path) -> tuple[list[list[str]], list[int]]:
    """(runs, the numbers of those run again warm) of the quick sequence (see above)."""
    runs = own_runs(QUICK_SEQUENCE, tmp)
    base = runs[0]
    return runs + [[*base, *opts] for opts in QUICK_OPTIONS], [0, 1, len(runs), len(runs) + 1]


def followers_share(part: int, parts: int) -> list[str]:
    """Every registered follower type but FULL_SEQUENCE's and QUICK_SEQUENCE's, dealt into ``parts``
    files (a new type's folder is covered without editing a test)."""
    own = [name for name in followers.names() if name not in (FULL_SEQUENCE, QUICK_SEQUENCE)]
    return own[part::parts]
