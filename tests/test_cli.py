"""`camjax design`: outputs, strict JSON, and clean failures (exit 2, one message, no files)."""

import json
import os
import re
import subprocess
import sys
import time

import pytest

from camjax import cli
from camjax.scene import builtin_scene_text

ALL_FILES = {"result.json", "svaj.png", "profile.png", "loads.png", "stress.png", "profile.csv",
             "profile.dxf"}


def _strict_json(path):
    def refuse(token):
        raise AssertionError(f"{path} holds {token}")

    return json.loads(path.read_text(), parse_constant=refuse)


@pytest.fixture(scope="session")
def design_run(tmp_path_factory):
    """`camjax design --out DIR` on the default scene, in process, without the disk cache, its
    figures and DXF drawn in two processes of their own as the command draws them by default (the
    other CLI tests draw in the test's process: tests/conftest.py)."""
    out = tmp_path_factory.mktemp("design") / "out"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
        mp.setenv("CAMJAX_DRAWING_PROCESSES", "2")
        rc = cli.main(["design", "--out", str(out), "--dpi", "40"])
    return rc, out


@pytest.mark.slow
def test_design_writes_every_declared_output(design_run):
    rc, out = design_run
    assert rc == 0
    assert {p.name for p in out.iterdir()} == ALL_FILES
    data = _strict_json(out / "result.json")
    for block, keys in {
        "kinematics.velocity_m_s": ("max", "max_deg", "min", "min_deg"),
        "kinematics.accel_m_s2": ("max", "max_deg", "min", "min_deg"),
        "kinematics.jerk_m_s3": ("max", "max_deg", "min", "min_deg"),
        "loads.force_N": ("max", "max_deg", "min", "min_deg"),
        "loads.torque_Nm": ("max", "max_deg", "min", "min_deg"),
        "design": ("mode", "base_radius_mm", "face_width_mm", "objective", "feasible"),
        "stress_MPa": ("max", "max_deg"),
        "rho_mm": ("min", "min_deg"),
    }.items():
        node = data
        for part in block.split("."):
            node = node[part]
        assert set(keys) <= set(node), block
    for key in ("samples", "min_base_radius_mm", "min_base_radius_deg", "min_face_width_mm"):
        assert key in data
    assert {"joint_deg", "jump_s", "jump_v", "jump_a", "jump_j", "class"} <= set(data["flcd"][0])
    # the design block and the evaluated stress describe the same cam
    assert data["stress_MPa"]["max"] == data["design"]["peak_stress_MPa"]
    assert data["design"]["mode"] == "global"


@pytest.mark.slow
def test_builtin_name_gives_the_same_result(design_run, tmp_path, monkeypatch):
    monkeypatch.setenv("CAMJAX_COMPILATION_CACHE", "0")
    _, out = design_run
    assert cli.main(["design", "default", "--out", str(tmp_path), "--dpi", "40"]) == 0
    assert _strict_json(tmp_path / "result.json") == _strict_json(out / "result.json")


def _variant(old, new):
    text = builtin_scene_text("default")
    assert text.count(old) == 1, old
    return text.replace(old, new)


BAD_SCENES = {
    "angles_not_360": (_variant("angle_deg = 120 }", "angle_deg = 130 }"), "motion.segments.angle_deg"),
    "unknown_law": (_variant('law = "cycloidal", lift_mm = 5.0 },\n  { kind = "dwell"',
                             'law = "cycloid", lift_mm = 5.0 },\n  { kind = "dwell"'),
                    "motion.segments[1].law"),
    "negative_lift": (_variant('angle_deg = 80, law = "cycloidal", lift_mm = 5.0',
                               'angle_deg = 80, law = "cycloidal", lift_mm = -5.0'),
                      "motion.segments[1].lift_mm"),
    "non_numeric": (_variant("rpm = 240.0", 'rpm = "fast"'), "motion.rpm"),
    "unknown_key": (_variant("mass_kg = 1.0", "mass_kg = 1.0\nmas_kg = 2.0"), "follower.mas_kg"),
    "return_short": (_variant('angle_deg = 60, law = "cycloidal", lift_mm = 5.0',
                              'angle_deg = 60, law = "cycloidal", lift_mm = 4.0'), "motion.segments"),
    "not_toml": ("[motion\nrpm = 1", "toml"),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENES))
def test_bad_scene_exits_2_with_one_message_and_no_files(case, tmp_path, capsys):
    text, field = BAD_SCENES[case]
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["design", str(scene), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == ""
    assert lines[0].startswith("camjax design: error: ")
    assert f" {field}" in lines[0] and "Traceback" not in captured.err
    assert not out.exists() or not any(out.iterdir())
    assert [p.name for p in tmp_path.iterdir()] == ["bad.toml"]  # no staging folder left behind


def test_failure_leaves_an_existing_output_folder_untouched(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("previous run")
    scene = tmp_path / "bad.toml"
    scene.write_text(BAD_SCENES["unknown_law"][0])
    assert cli.main(["design", str(scene), "--out", str(out)]) == 2
    assert [p.name for p in out.iterdir()] == ["keep.txt"]


@pytest.mark.parametrize("args, word", [(["--base-radius", "-3"], "--base-radius"),
                                         (["--base-radius", "nan"], "--base-radius"),
                                         (["--dpi", "5"], "--dpi"),
                                         (["no-such-scene"], "scene")])
def test_bad_arguments_exit_2(args, word, tmp_path, capsys):
    out = tmp_path / "out"
    assert cli.main(["design", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert word in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.slow
def test_console_entry_point_reports_without_traceback(tmp_path):
    # the real process: exit status 2 reaches the shell, stderr is one line
    scene = tmp_path / "bad.toml"
    scene.write_text(BAD_SCENES["negative_lift"][0])
    proc = subprocess.run([sys.executable, "-m", "camjax.cli", "design", str(scene), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True,
                          env={**os.environ, "CAMJAX_COMPILATION_CACHE": "0"}, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "lift_mm" in proc.stderr
    assert not (tmp_path / "out").exists()


_PHASES = re.compile(r"^camjax design: timings \(wall s\): (?P<phases>.*); total (?P<total>[0-9.]+)$", re.M)
_JAX = re.compile(r"^camjax design: JAX \(s, summed over threads\): tracing (?P<trace>[0-9.]+), lowering "
                  r"(?P<lower>[0-9.]+), XLA (?P<xla>[0-9.]+) for (?P<programs>\d+) programs \((?P<compiled>\d+) "
                  r"compiled, (?P<loaded>\d+) loaded from the compilation cache\)$", re.M)


def _timed_design(folder, caches):
    """`camjax design --timings` in a fresh process with the caches in ``caches``: (process wall
    s measured here, the phases [(name, s)], their printed total, JAX's figures, result.json)."""
    env = {**os.environ, "CAMJAX_COMPILATION_CACHE": str(caches / "xla"),
           "CAMJAX_PROGRAM_CACHE": str(caches / "programs")}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "camjax.cli", "design", "--out", str(folder), "--dpi", "40",
                           "--timings"], capture_output=True, text=True, env=env, timeout=300)
    wall = time.perf_counter() - start
    assert proc.returncode == 0, proc.stderr
    phases, jax_line = _PHASES.search(proc.stderr), _JAX.search(proc.stderr)
    assert phases and jax_line, proc.stderr
    named = [(p.rsplit(" ", 1)[0], float(p.rsplit(" ", 1)[1])) for p in phases["phases"].split(", ")]
    figures = {k: float(v) if "." in v else int(v) for k, v in jax_line.groupdict().items()}
    return wall, named, float(phases["total"]), figures, _strict_json(folder / "result.json")


@pytest.mark.slow
def test_timings_add_up_to_the_run_and_tell_a_first_run_from_a_later_one(design_run, tmp_path):
    """`--timings`' phases come in the order the command runs them, each >= 0, and add up to the
    run's total printed (its clock from start to stop, to 2 decimals a phase: no gap between the
    phases, none left out), which is the process's wall time measured here
    but for Python's start and exit (bounded at 0.5 s: they take ~0.1 s on 2 cores); JAX's line counts programs
    compiled in the first run of a scene (empty caches) and loaded in the second (the same
    caches), which compiles fewer; the result.json is the one a run without --timings writes."""
    cold = _timed_design(tmp_path / "cold", tmp_path / "caches")
    warm = _timed_design(tmp_path / "warm", tmp_path / "caches")
    for wall, named, total, _, _ in (cold, warm):
        # the figures before the files where they are drawn in this process (the tests' default),
        # after them where drawing processes draw them while the files are written
        names = [n for n, _ in named]
        assert names[:3] == ["start-up", "scene", "computing"] and sorted(names[3:]) == ["figures", "files"]
        assert all(s >= 0 for _, s in named)
        assert abs(sum(s for _, s in named) - total) <= 0.005 * len(named) + 1e-9
        assert wall - 0.5 <= total <= wall  # a clock started after the imports would miss ~1 s
    assert cold[3]["compiled"] >= 3 and cold[3]["xla"] > 0 and cold[3]["trace"] > 0
    assert warm[3]["loaded"] >= 3 and warm[3]["compiled"] < cold[3]["compiled"]
    _, out = design_run
    assert cold[4] == warm[4] == _strict_json(out / "result.json")


def test_design_refuses_rad_lifts_on_a_translating_follower(tmp_path, capsys):
    # the older way to write an oscillating follower: lift_mm read as rad by [dynamics], with a
    # translating follower's geometry that cannot describe it
    from camjax import cli

    text = builtin_scene_text("default").replace("lift_mm = 5.0", "lift_mm = 0.5")
    text += "\n[dynamics]\nfollower = \"oscillating\"\nI3 = 0.3\nc3 = 0.1\nk23 = 1000.0\n"
    path = tmp_path / "rad.toml"
    path.write_text(text)
    out = tmp_path / "tb"
    assert cli.main(["design", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "dynamics.follower = 'oscillating'" in err and "oscillating_roller" in err
    assert not out.exists()


def _class_from_end_values(dp, d2p, d3p, tol=1e-9):
    """FLCD class of a law's joint with a dwell, from its end derivatives alone (a dwell has 0)."""
    for name, value in (("shock", dp), ("jerk", d2p), ("perturbation", d3p)):
        if abs(value) > tol:
            return name
    return "ok"


@pytest.mark.slow
def test_laws_table_json_and_chart(tmp_path, capsys):
    import numpy as np

    from camjax.laws import LAWS

    table, chart = tmp_path / "laws.json", tmp_path / "charts" / "laws.png"
    assert cli.main(["laws", "--json", str(table), "--plot", str(chart)]) == 0
    rows = {r["law"]: r for r in _strict_json(table)["laws"]}
    assert list(rows) == list(LAWS)
    for name, law in LAWS.items():
        # the law's own end derivatives (NumPy, no program involved) decide the class
        v = [np.asarray(t) for t in law(np.array([0.0, 1.0]))]
        start = _class_from_end_values(v[1][0], v[2][0], v[3][0])
        end = _class_from_end_values(v[1][1], v[2][1], v[3][1])
        assert (rows[name]["joint_after_dwell"], rows[name]["joint_before_dwell"]) == (start, end), name
        assert rows[name]["flcd_against_dwells"] == ({start, end} <= {"ok", "perturbation"}), name
    # the classes of real joints: each law as rise and return between dwells (program.joints)
    from camjax.program import MotionProgram, Segment, joints

    for name in ("uniform", "double_harmonic", "poly_3_4"):
        law = LAWS[name]
        prog = MotionProgram.from_segments([Segment("dwell", 90.0), Segment("rise", 90.0, law, 1.0),
                                            Segment("dwell", 90.0), Segment("return", 90.0, law, 1.0)])
        by_deg = {round(j.joint_deg): j.flcd_class for j in joints(prog)}
        assert (rows[name]["joint_after_dwell"], rows[name]["joint_before_dwell"]) == (by_deg[90], by_deg[180])
    # SPEC section 1 statements and the constant-velocity law
    assert rows["uniform"]["joint_after_dwell"] == rows["uniform"]["joint_before_dwell"] == "shock"
    assert (rows["double_harmonic"]["joint_after_dwell"], rows["double_harmonic"]["joint_before_dwell"]) \
        == ("ok", "jerk")
    assert chart.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_laws_table_names_its_columns(capsys):
    assert cli.main(["laws"]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0].split()[:2] == ["law", "max|v|"]
    assert "uniform" in out and "shock" in out
    assert "FLCD" in out and "yes = velocity and acceleration continuous" in out


def test_laws_refuses_an_unknown_image_type(tmp_path, capsys):
    target = tmp_path / "laws.xyz"
    assert cli.main(["laws", "--plot", str(target)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--plot" in err[0] and ".png" in err[0]
    assert not target.exists()


@pytest.mark.slow
def test_design_animate_writes_the_gif_even_when_infeasible(tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "out"
    # R_b = 10 mm is far below the flat face's smallest admissible radius (about 24 mm)
    assert cli.main(["design", "--out", str(out), "--dpi", "30", "--base-radius", "10", "--animate"]) == 0
    printed = capsys.readouterr().out
    assert "files drawn at R_b = 10.0000 mm" in printed and "INFEASIBLE (curvature" in printed
    with Image.open(out / "motion.gif") as im:
        assert im.n_frames == 72
    assert "motion.gif" in printed


def break_outline(monkeypatch, module, function: str, field: str, index: int, value: float) -> None:
    """Make ``module.function`` (an evaluation returning curves) put ``value`` at ``field[index]``:
    an outline with a NaN or infinite point cannot be drawn."""
    real = getattr(module, function)

    def broken(*args, **kwargs):
        curves = real(*args, **kwargs)
        values = getattr(curves, field).copy()
        values[index] = value
        return curves._replace(**{field: values})

    monkeypatch.setattr(module, function, broken)


@pytest.mark.slow
def test_design_refuses_an_undrawable_outline_in_one_line(tmp_path, capsys, monkeypatch):
    from camjax.followers._translating import TranslatingFollower

    break_outline(monkeypatch, TranslatingFollower, "curves", "profile_x_mm", 7, float("nan"))
    out = tmp_path / "out"
    assert cli.main(["design", "--out", str(out), "--dpi", "30", "--animate"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    # one error line naming what cannot be drawn (no traceback)
    assert len(err) == 1
    assert err[0].startswith("camjax design: error: ") and "profile_x_mm is not finite at 1 of 360" in err[0]
    assert not out.exists()
