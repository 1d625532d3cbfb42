"""Hostile input for every command: one line, the right exit status, no traceback, DIR untouched.

Every case runs ``camjax.cli.main(argv)`` in process (fast). Each asserts the exit status, exactly
one stderr line that names the offending field, option or path, no traceback, nothing on stdout,
and that the output folder (holding an earlier run's files) is byte-for-byte what it was and no
staging folder is left beside it. The signal tests need a real process and are marked slow.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from camjax import cli
from camjax.output import folder as output_folder
from camjax.scene import QUOTE_CHARS, builtin_scene_text

DEFAULT = builtin_scene_text("default")
# kinematics and geometry only: no loads, no solver, so a run takes about a second
KINEMATIC = """
[motion]
rpm = 100.0
samples = 180
segments = [
  { kind = "dwell", angle_deg = 90 },
  { kind = "rise", angle_deg = 90, law = "cycloidal", lift_mm = 4.0 },
  { kind = "dwell", angle_deg = 90 },
  { kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 4.0 },
]
[follower]
type = "flat"
"""


def _variant(old: str, new: str, text: str = DEFAULT) -> str:
    assert text.count(old) == 1, old
    return text.replace(old, new)


def snapshot(path: Path) -> dict[str, bytes] | None:
    """Every file under ``path`` (relative name -> bytes); None when nothing is there."""
    if not path.exists():
        return None
    if path.is_file():
        return {"": path.read_bytes()}
    return {str(p.relative_to(path)): p.read_bytes() for p in sorted(path.rglob("*")) if p.is_file()}


def leftovers(parent: Path) -> list[str]:
    """Staging or set-aside folders of a run (there must be none once it has returned)."""
    return sorted(p.name for p in parent.iterdir() if output_folder.STAGING in p.name
                  or output_folder.OLD in p.name)


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    try:
        rc = cli.main(argv)
    except SystemExit as exc:  # argparse's own exit
        rc = exc.code
    captured = capsys.readouterr()
    return rc, captured.out, captured.err


# ------------------------------------------------------------------------------ the corpus

# name -> (argv with {dir} = the old output folder, {scene} = the scene file, {file} = a plain
# file, {tmp} = the test folder; scene text or None; word the stderr line must contain; status)
SCENE_ARGS = ["design", "{scene}", "--out", "{dir}"]
NESTED = "a = " + "[" * 100_000 + "]" * 100_000 + "\n"
CASES: dict[str, tuple[list[str], str | bytes | None, str, int]] = {
    # scene files the user cannot have meant
    "binary_scene": (SCENE_ARGS, bytes(range(256)) * 4, "UTF-8", 2),
    "nul_in_scene": (SCENE_ARGS, DEFAULT.encode() + b"\x00\x01", "NUL", 2),
    "utf16_scene": (SCENE_ARGS, DEFAULT.encode("utf-16"), "UTF-16", 2),
    "utf16_be_scene": (SCENE_ARGS, b"\xfe\xff" + DEFAULT.encode("utf-16-be"), "UTF-16", 2),
    "latin1_scene": (SCENE_ARGS, ("# caf\xe9\n" + DEFAULT).encode("latin-1"), "UTF-8", 2),
    "empty_scene": (SCENE_ARGS, "", "motion", 2),
    "not_toml": (SCENE_ARGS, "[motion\nrpm = 1", "toml", 2),
    "nested_too_deep": (SCENE_ARGS, NESTED, "toml", 2),
    "huge_unknown_section": (SCENE_ARGS, DEFAULT + "\n[" + "x" * 1_000_000 + "]\n", "unknown key", 2),
    "huge_unknown_value": (SCENE_ARGS, _variant("mass_kg = 1.0", "mass_kg = 1.0\nmas_kg = '"
                                                 + "y" * 1_000_000 + "'"), "follower.mas_kg", 2),
    "newline_in_key": (SCENE_ARGS, DEFAULT + '\n["a\\nb"]\n', "unknown key", 2),
    "unknown_key": (SCENE_ARGS, _variant("mass_kg = 1.0", "mass_kg = 1.0\nmas_kg = 2.0"), "follower.mas_kg", 2),
    "rpm_1e160": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = 1e160"), "motion.rpm", 2),
    # magnitudes past any cam's, that would overflow float64 downstream: refused naming the field
    "lift_overflows": (SCENE_ARGS, DEFAULT.replace("lift_mm = 5.0", "lift_mm = 1e300"),
                       "motion.segments[1].lift_mm = 1e+300: outside the physical range (allowed: 1e-06 "
                       "to 1e+06 mm)", 2),
    "sigma_max_underflows": (SCENE_ARGS, _variant("sigma_max_MPa = 1230.0", "sigma_max_MPa = 1e-300"),
                             "design.sigma_max_MPa = 1e-300: outside the physical range", 2),
    "mass_1e308": (SCENE_ARGS, _variant("mass_kg = 1.0", "mass_kg = 1e308"),
                   "follower.mass_kg = 1e+308: outside the physical range (allowed: 0, or 1e-09 to 1e+06 kg)", 2),
    "spring_1e-300": (SCENE_ARGS, _variant("spring_N_per_m = 3004.0", "spring_N_per_m = 1e-300"),
                      "follower.spring_N_per_m = 1e-300", 2),
    "bounds_1e300": (SCENE_ARGS, _variant("[5.0, 40.0]", "[5.0, 1e300]"),
                     "design.base_radius_mm = [5.0, 1e+300]: 1e+300 is outside the physical range", 2),
    "bounds_1e-300": (SCENE_ARGS, _variant("[5.0, 25.0]", "[1e-300, 25.0]"), "design.face_width_mm", 2),
    "young_1e300": (SCENE_ARGS, _variant("E_MPa = 2.1e5", "E_MPa = 1e300"), "contact.cam.E_MPa = 1e+300", 2),
    "rocker_inertia_1e-300": (SCENE_ARGS, _variant("inertia_kg_m2 = 0.002", "inertia_kg_m2 = 1e-300",
                                                   builtin_scene_text("oscillating-roller")),
                              "follower.inertia_kg_m2 = 1e-300: outside the physical range", 2),
    "dynamics_inertia_1e-300": (["dynamics", "{scene}", "--out", "{dir}"],
                                _variant("I3 = 0.357", "I3 = 1e-300", builtin_scene_text("thesis-bench")),
                                "dynamics.I3 = 1e-300", 2),
    "dynamics_factor_1e300": (["dynamics", "{scene}", "--out", "{dir}"],
                              _variant("speed_factors = [0.8, 0.9, 1.0, 1.1, 1.2]", "speed_factors = [0.8, 1e300]",
                                       builtin_scene_text("thesis-bench")),
                              "dynamics.speed_factors = [0.8, 1e+300]: 1e+300 is outside the physical range", 2),
    "rpm_over_max": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = 1.0000001e6"), "motion.rpm", 2),
    "rpm_negative": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = -1.0"), "motion.rpm", 2),
    "rpm_nan": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = nan"), "motion.rpm", 2),
    "rpm_inf": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = inf"), "motion.rpm", 2),
    "rpm_text": (SCENE_ARGS, _variant("rpm = 240.0", 'rpm = "fast"'), "motion.rpm", 2),
    "rpm_bool": (SCENE_ARGS, _variant("rpm = 240.0", "rpm = true"), "motion.rpm", 2),
    "samples_1": (SCENE_ARGS, _variant("samples = 360", "samples = 1"), "motion.samples", 2),
    "samples_too_coarse": (SCENE_ARGS, _variant("samples = 360", "samples = 40"), "motion.samples", 2),
    "samples_1e7": (SCENE_ARGS, _variant("samples = 360", "samples = 10_000_000"), "motion.samples", 2),
    "samples_float": (SCENE_ARGS, _variant("samples = 360", "samples = 360.5"), "motion.samples", 2),
    "angles_not_360": (SCENE_ARGS, _variant("angle_deg = 120 }", "angle_deg = 130 }"), "angle_deg", 2),
    "unknown_law": (SCENE_ARGS, _variant('80, law = "cycloidal"', '80, law = "cycloid"'),
                    "motion.segments[1].law", 2),
    "negative_lift": (SCENE_ARGS, _variant("80, law = \"cycloidal\", lift_mm = 5.0",
                                           "80, law = \"cycloidal\", lift_mm = -5.0"),
                      "motion.segments[1].lift_mm", 2),
    "return_short": (SCENE_ARGS, _variant('60, law = "cycloidal", lift_mm = 5.0',
                                          '60, law = "cycloidal", lift_mm = 4.0'), "motion.segments", 2),
    "segments_not_list": (SCENE_ARGS, "[motion]\nrpm = 100.0\nsegments = 3\n[follower]\ntype = 'flat'\n",
                          "motion.segments", 2),
    "follower_type": (SCENE_ARGS, _variant('type = "flat"', 'type = "round"'), "follower.type", 2),
    "roller_without_radius": (SCENE_ARGS, KINEMATIC.replace('type = "flat"', 'type = "roller"'),
                              "follower.roller_radius_mm", 2),
    "contact_without_loads": (SCENE_ARGS, KINEMATIC + "[contact]\ncam_width_mm = 10.0\n"
                              "cam = { E_MPa = 2.1e5, poisson = 0.3 }\n"
                              "follower = { E_MPa = 2.1e5, poisson = 0.3 }\n", "contact", 2),
    "poisson_over_half": (SCENE_ARGS, _variant("poisson = 0.26", "poisson = 0.7"), "contact.follower.poisson", 2),
    "bounds_reversed": (SCENE_ARGS, _variant("[5.0, 40.0]", "[40.0, 5.0]"), "design.base_radius_mm", 2),
    "sigma_max_zero": (SCENE_ARGS, _variant("sigma_max_MPa = 1230.0", "sigma_max_MPa = 0.0"),
                       "design.sigma_max_MPa", 2),
    "weights_both_zero": (SCENE_ARGS, _variant("alpha = 1.0\ngamma = 1.0", "alpha = 0.0\ngamma = 0.0"),
                          "design.alpha", 2),
    "section_not_table": (SCENE_ARGS, "motion = 3\n[follower]\ntype = 'flat'\n", "motion = 3: must be a table", 2),
    "scene_is_a_folder": (["design", "{tmp}", "--out", "{dir}"], None, "scene", 2),
    "scene_name_too_long": (["design", "{tmp}/" + "s" * 10_000, "--out", "{dir}"], None, "scene", 2),
    "scene_name_nul": (["design", "a\x00b.toml", "--out", "{dir}"], None, "scene", 2),
    "scene_missing": (["design", "{tmp}/nothing.toml", "--out", "{dir}"], None, "scene", 2),
    # not "no such file": what the path names instead (and nothing is opened: a FIFO would block)
    "scene_fifo": (["design", "{tmp}/special/fifo", "--out", "{dir}"], None,
                   "is not a regular file: it is a FIFO", 2),
    "scene_dev_zero": (["design", "/dev/zero", "--out", "{dir}"], None,
                       "scene = '/dev/zero': is not a regular file: it is a character device", 2),
    "dynamics_scene_dev_null": (["dynamics", "/dev/null", "--out", "{dir}"], None, "not a regular file", 2),
    "scene_dangling_link": (["design", "{tmp}/dangling", "--out", "{dir}"], None,
                            "is a link whose target is missing", 2),
    # 8 samples (SAMPLES_PER_SEGMENT) of the finest grid (1e6) span 8 * 360 / 1e6 = 0.00288 deg
    "segment_1e-9_deg": (SCENE_ARGS, _variant("{ kind = \"dwell\",  angle_deg = 100 }",
                                              "{ kind = \"dwell\", angle_deg = 1e-9 },\n"
                                              "  { kind = \"dwell\", angle_deg = 99.999999999 }"),
                         "motion.segments[0].angle_deg = 1e-09: too short for any grid", 2),
    "swing_lift_on_translating": (SCENE_ARGS, DEFAULT.replace("lift_mm = 5.0", "lift_deg = 5.0", 1),
                                  "lift_deg", 2),
    # the output location, checked before any computation
    "out_empty": (["design", "--out", ""], None, "--out", 2),
    "out_blank": (["design", "--out", "   "], None, "--out", 2),
    "out_is_a_file": (["design", "--out", "{file}"], None, "--out", 2),
    "out_under_a_file": (["design", "--out", "{file}/sub/dir"], None, "--out", 2),
    "out_nul": (["design", "--out", "{tmp}/a\x00b"], None, "--out", 2),
    "out_foreign_folder": (["design", "--out", "{tmp}/foreign"], None, "--out", 2),
    "out_root": (["design", "--out", "/"], None, "--out", 2),
    "out_long_path_under_a_file": (["design", "--out", "{file}/" + "a" * 10_000], None, "characters)", 2),
    "sweep_address_long": (["sweep", "--alpha", "1", "--gamma", "1", "--backend", "process", "--address",
                            "h" * 10_000, "--out", "{dir}"], None, "--address", 2),
    "out_current_folder": (["design", "--out", "."], None, "--out", 2),
    # /proc and /sys: os.access says root may write there, but nothing can be made in them
    "out_under_proc": (["design", "--out", "/proc/camjax-out"], None, "--out = '/proc/camjax-out': cannot write", 2),
    "out_deep_under_proc": (["design", "--out", "/proc/camjax/a/b"], None, "--out", 2),
    "sweep_out_under_proc": (["sweep", "--alpha", "1", "--gamma", "1", "--out", "/proc/camjax-out"], None,
                             "--out", 2),
    "block_sweep_out_under_sys": (["sweep", "--alpha", "1", "--gamma", "1", "--backend", "sequential",
                                   "--out", "/sys/camjax-out"], None, "--out", 2),
    "dynamics_out_under_proc": (["dynamics", "thesis-bench", "--out", "/proc/camjax-out"], None, "--out", 2),
    "extremes_out_under_proc": (["check-extremes", "--out", "/proc/camjax-out"], None, "--out", 2),
    "laws_json_under_proc": (["laws", "--json", "/proc/camjax-laws.json"], None, "--json", 2),
    "laws_plot_under_sys": (["laws", "--plot", "/sys/camjax-laws.png"], None, "--plot", 2),
    "out_dangling_link": (["design", "--out", "{tmp}/dangling"], None, "is a link whose target is missing", 2),
    "out_parent_folder": (["design", "--out", ".."], None, "--out", 2),
    "sweep_out_is_a_file": (["sweep", "--alpha", "1", "--gamma", "1", "--out", "{file}"], None, "--out", 2),
    "extremes_out_is_a_file": (["check-extremes", "--out", "{file}"], None, "--out", 2),
    "dynamics_out_empty": (["dynamics", "thesis-bench", "--out", ""], None, "--out", 2),
    "laws_json_folder": (["laws", "--json", "{tmp}"], None, "--json", 2),
    "laws_json_under_file": (["laws", "--json", "{file}/laws.json"], None, "--json", 2),
    "laws_json_empty": (["laws", "--json", ""], None, "--json", 2),
    # options
    "base_radius_negative": (["design", "--base-radius", "-3", "--out", "{dir}"], None, "--base-radius", 2),
    "base_radius_nan": (["design", "--base-radius", "nan", "--out", "{dir}"], None, "--base-radius", 2),
    "base_radius_inf": (["design", "--base-radius", "inf", "--out", "{dir}"], None, "--base-radius", 2),
    "base_radius_huge": (["design", "--base-radius", "1e300", "--out", "{dir}"], None, "--base-radius", 2),
    "base_radius_text": (["design", "--base-radius", "ten", "--out", "{dir}"], None, "--base-radius", 2),
    "dpi_zero": (["design", "--dpi", "0", "--out", "{dir}"], None, "--dpi", 2),
    "dpi_huge": (["design", "--dpi", "100000", "--out", "{dir}"], None, "--dpi", 2),
    "samples_zero": (["design", "--samples", "0", "--out", "{dir}"], None, "--samples", 2),
    "samples_coarse": (["design", "--samples", "40", "--out", "{dir}"], None, "--samples", 2),
    "samples_over_max": (["design", "--samples", "1000001", "--out", "{dir}"], None, "--samples", 2),
    "samples_text": (["design", "--samples", "many", "--out", "{dir}"], None, "--samples", 2),
    "mode_unknown": (["design", "--mode", "best", "--out", "{dir}"], None, "--mode", 2),
    "alpha_negative": (["design", "--alpha", "-1", "--out", "{dir}"], None, "--alpha", 2),
    "seed_negative": (["design", "--seed", "-1", "--out", "{dir}"], None, "--seed", 2),
    # 2**64: past the 64-bit integer JAX makes a PRNG key from (it raised OverflowError, exit 1)
    "seed_2_64": (["design", "--seed", "18446744073709551616", "--out", "{dir}"], None,
                  "--seed = 18446744073709551616: out of range (allowed: >= 0 and <= 9223372036854775807)", 2),
    "sweep_seed_2_64": (["sweep", "--alpha", "1", "--gamma", "1", "--seed", str(2**63), "--out", "{dir}"],
                        None, "--seed", 2),
    "scene_seed_2_64": (SCENE_ARGS, _variant("gamma = 1.0", "gamma = 1.0\nseed = 18446744073709551616"),
                        "design.seed", 2),
    "design_option_without_design": (["design", "{scene}", "--mode", "pointwise", "--out", "{dir}"],
                                     KINEMATIC, "--mode", 2),
    "unknown_option": (["design", "--colour", "red", "--out", "{dir}"], None, "--colour", 2),
    "missing_out": (["design"], None, "--out", 2),
    "no_command": ([], None, "COMMAND", 2),
    "unknown_command": (["desing", "--out", "{dir}"], None, "desing", 2),
    "sweep_alpha_text": (["sweep", "--alpha", "1,x", "--gamma", "1", "--out", "{dir}"], None, "--alpha", 2),
    "sweep_alpha_empty": (["sweep", "--alpha", "", "--gamma", "1", "--out", "{dir}"], None, "--alpha", 2),
    "sweep_alpha_nan": (["sweep", "--alpha", "nan", "--gamma", "1", "--out", "{dir}"], None, "--alpha", 2),
    "sweep_alpha_negative": (["sweep", "--alpha", "-1", "--gamma", "1", "--out", "{dir}"], None, "--alpha", 2),
    "sweep_gamma_1e300": (["sweep", "--alpha", "1", "--gamma", "1,1e300", "--out", "{dir}"], None,
                          "--gamma = 1,1e+300: 1e+300 is outside the physical range (allowed: 0, or 1e-12 to 1e+12)", 2),
    "design_alpha_1e300": (["design", "--alpha", "1e300", "--out", "{dir}"], None,
                           "--alpha = 1e+300: outside the physical range", 2),
    "sweep_long_list": (["sweep", "--alpha", "1," + "z" * 10_000, "--gamma", "1", "--out", "{dir}"], None,
                        "--alpha", 2),
    "sweep_both_zero": (["sweep", "--alpha", "0", "--gamma", "0", "--out", "{dir}"], None, "--alpha", 2),
    "sweep_chunk_zero": (["sweep", "--alpha", "1", "--gamma", "1", "--chunk-size", "0", "--out", "{dir}"],
                         None, "--chunk-size", 2),
    "sweep_samples_coarse": (["sweep", "--alpha", "1", "--gamma", "1", "--samples", "9", "--out", "{dir}"],
                             None, "--samples", 2),
    "sweep_without_design": (["sweep", "{scene}", "--alpha", "1", "--gamma", "1", "--out", "{dir}"],
                             KINEMATIC, "[design]", 2),
    "sweep_binary_scene": (["sweep", "{scene}", "--alpha", "1", "--gamma", "1", "--out", "{dir}"],
                           b"\x89PNG\r\n\x1a\n\x00\x00", "UTF-8", 2),
    "extremes_binary_scene": (["check-extremes", "{scene}", "--out", "{dir}"], b"\xff\xd8\xff\x00", "UTF-8", 2),
    "extremes_samples_coarse": (["check-extremes", "--samples", "3", "--out", "{dir}"], None, "--samples", 2),
    "dynamics_without_section": (["dynamics", "default", "--out", "{dir}"], None, "[dynamics]", 2),
    "dynamics_dpi": (["dynamics", "thesis-bench", "--dpi", "1", "--out", "{dir}"], None, "--dpi", 2),
    "dynamics_utf16_scene": (["dynamics", "{scene}", "--out", "{dir}"], DEFAULT.encode("utf-16"), "UTF-16", 2),
    "dynamics_missing_scene": (["dynamics", "--out", "{dir}"], None, "scene", 2),
}


# the environment camjax reads: name -> (argv, variables set, word the stderr line must contain)
ENV_CASES: dict[str, tuple[list[str], dict[str, str], str]] = {
    # a Unicode digit passes str.isdigit but is no count (int('²') raised ValueError, exit 1)
    "drawing_processes_superscript": (["design", "--out", "{dir}"], {"CAMJAX_DRAWING_PROCESSES": "\u00b2"},
                                      "CAMJAX_DRAWING_PROCESSES = '\u00b2': not a count"),
    "drawing_processes_arabic_digit": (["design", "--out", "{dir}"], {"CAMJAX_DRAWING_PROCESSES": "\u0663"},
                                       "CAMJAX_DRAWING_PROCESSES"),
    "drawing_processes_17": (["design", "--out", "{dir}"], {"CAMJAX_DRAWING_PROCESSES": "17"},
                             "CAMJAX_DRAWING_PROCESSES = '17'"),
    "drawing_processes_huge": (["design", "--out", "{dir}"], {"CAMJAX_DRAWING_PROCESSES": "9" * 5000},
                               "CAMJAX_DRAWING_PROCESSES"),
    # checked by every command, not only the one that reads it
    "drawing_processes_sweep": (["sweep", "--alpha", "1", "--gamma", "1", "--out", "{dir}"],
                                {"CAMJAX_DRAWING_PROCESSES": "-1"}, "CAMJAX_DRAWING_PROCESSES"),
    "progress_word": (["dynamics", "thesis-bench", "--out", "{dir}"], {"CAMJAX_PROGRESS": "yes"},
                      "CAMJAX_PROGRESS = 'yes': not a switch"),
    "debug_word": (["laws", "--json", "{tmp}/laws.json"], {"CAMJAX_DEBUG": "true"}, "CAMJAX_DEBUG"),
    "verify_two": (["design", "--out", "{dir}"], {"CAMJAX_PROGRAM_CACHE_VERIFY": "2"},
                   "CAMJAX_PROGRAM_CACHE_VERIFY"),
    "compile_ahead_word": (["design", "--out", "{dir}"], {"CAMJAX_COMPILE_AHEAD": "on"},
                           "CAMJAX_COMPILE_AHEAD = 'on': not a switch"),
    "program_cache_is_a_file": (["design", "--out", "{dir}"], {"CAMJAX_PROGRAM_CACHE": "{file}"},
                                "CAMJAX_PROGRAM_CACHE"),
    "compilation_cache_is_a_file": (["check-extremes", "--out", "{dir}"], {"CAMJAX_COMPILATION_CACHE": "{file}"},
                                    "CAMJAX_COMPILATION_CACHE"),
}


@pytest.fixture
def place(tmp_path):
    """A test folder with an earlier run's output folder, a plain file, a foreign folder and a
    link to nothing."""
    (tmp_path / "dangling").symlink_to(tmp_path / "gone")
    (tmp_path / "special").mkdir()
    os.mkfifo(tmp_path / "special" / "fifo")
    old = tmp_path / "out"
    old.mkdir()
    (old / "result.json").write_text('{"scene": "earlier run"}\n')
    (old / "loads.png").write_bytes(b"earlier figure")
    (tmp_path / "plain.txt").write_text("not a folder")
    (tmp_path / "foreign").mkdir()
    (tmp_path / "foreign" / "notes.txt").write_text("the user's own file")
    return tmp_path


def _argv(template: list[str], place: Path) -> list[str]:
    keys = {"dir": str(place / "out"), "scene": str(place / "scene.toml"), "file": str(place / "plain.txt"),
            "tmp": str(place)}
    return [a.format(**keys) if "{" in a and "[" not in a else a for a in template]


def test_the_corpus_is_large_and_covers_every_command():
    commands = {argv[0] for argv, *_ in CASES.values() if argv}
    assert len(CASES) >= 60
    assert commands == {"design", "sweep", "check-extremes", "dynamics", "laws", "desing"}


@pytest.mark.parametrize("name", sorted(CASES))
def test_hostile_input_is_one_line_and_changes_nothing(name, place, capsys, monkeypatch):
    monkeypatch.setenv("CAMJAX_COMPILATION_CACHE", "0")
    template, scene, word, status = CASES[name]
    if scene is not None:
        path = place / "scene.toml"
        path.write_bytes(scene if isinstance(scene, bytes) else scene.encode())
    before = {p.name: snapshot(p) for p in place.iterdir()}
    rc, out, err = run(_argv(template, place), capsys)
    assert rc == status, err
    lines = err.splitlines()
    assert len(lines) == 1, err[:2000]
    assert "Traceback" not in err and out == ""
    assert word in lines[0]
    # a value is quoted with at most ~100 characters (plus the message around it)
    assert len(lines[0]) < 1000
    assert {p.name: snapshot(p) for p in place.iterdir()} == before
    assert leftovers(place) == []


@pytest.mark.parametrize("name", sorted(ENV_CASES))
def test_a_bad_environment_is_one_line_and_changes_nothing(name, place, capsys, monkeypatch):
    template, variables, word = ENV_CASES[name]
    monkeypatch.setenv("CAMJAX_COMPILATION_CACHE", "0")
    for key, value in variables.items():
        monkeypatch.setenv(key, _argv([value], place)[0])
    calls = []  # no work starts: neither a design nor a sweep is computed
    monkeypatch.setattr("camjax.pipeline.analyse", lambda *a, **k: calls.append(a))
    monkeypatch.setattr("camjax.pipeline.sweep_scene", lambda *a, **k: calls.append(a))
    before = {p.name: snapshot(p) for p in place.iterdir()}
    rc, out, err = run(_argv(template, place), capsys)
    assert rc == 2, err
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err and out == "", err[:2000]
    assert word in lines[0] and len(lines[0]) < 1000
    assert calls == []
    assert {p.name: snapshot(p) for p in place.iterdir()} == before and leftovers(place) == []


def test_a_platform_jax_cannot_start_is_one_line_naming_jax_platforms(place, capsys, monkeypatch):
    # in this process JAX has started already: its answer for a missing CUDA (a bare
    # AssertionError from jaxlib) is what the check is given
    import jax

    def no_cuda(*args, **kwargs):
        raise AssertionError()

    monkeypatch.setenv("JAX_PLATFORMS", "cuda")
    monkeypatch.setattr(jax, "devices", no_cuda)
    before = snapshot(place / "out")
    rc, out, err = run(["design", "--out", str(place / "out")], capsys)
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    assert err.startswith("camjax design: error: JAX_PLATFORMS = 'cuda': JAX cannot start this platform")
    assert snapshot(place / "out") == before


@pytest.mark.slow
def test_jax_platforms_cuda_without_a_gpu_exits_2(place):
    import jax

    if any(d.platform == "gpu" for d in jax.devices()) or jax.default_backend() == "gpu":
        pytest.skip("this machine has a GPU: JAX_PLATFORMS=cuda is a valid setting here")
    proc = _start(["laws"], place, JAX_PLATFORMS="cuda")
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 2, err
    assert len(err.strip().splitlines()) == 1 and "JAX_PLATFORMS = 'cuda'" in err and "Traceback" not in err


@pytest.mark.parametrize("key", sorted(__import__("camjax.scene.ranges", fromlist=["RANGES"]).RANGES))
def test_every_range_admits_its_ends_and_refuses_past_them(key):
    # the reader's check against the table: the ends pass, 1e-9 past either end is refused naming
    # the field, and 0 is left to the key's own rule
    from camjax.scene import SceneError
    from camjax.scene.ranges import physical_range
    from camjax.scene.reader import TableReader

    lo, hi, _ = physical_range(key)

    def read(v):
        return TableReader({key: v}, "section", None).number(key, low=None)

    assert read(hi) == hi and read(-hi) == -hi and read(0.0) == 0.0
    with pytest.raises(SceneError, match=rf"^section\.{key} = .*: outside the physical range \(allowed: "):
        read(hi * (1 + 1e-9))
    if lo > 0:
        assert read(lo) == lo
        with pytest.raises(SceneError, match=rf"^section\.{key} = "):
            read(lo * (1 - 1e-9))


def test_the_physical_ranges_are_documented():
    # docs/scenes.md's table shows every key's range as the code has it
    from camjax.scene.ranges import RANGES

    text = (Path(cli.__file__).resolve().parents[2] / "docs" / "scenes.md").read_text()
    section = text.split("## Physical ranges", 1)[1].split("\n## ", 1)[0]
    rows = {line.split("|")[1].strip(): line for line in section.splitlines() if line.startswith("| `")}
    for key, (lo, hi, unit) in RANGES.items():
        row = next((line for names, line in rows.items() if f"`{key}`" in names), None)
        assert row is not None, key
        assert f"{hi:g}" in row and (lo == 0 or f"{lo:g}" in row) and unit in row, (key, row)


def test_the_shortest_segment_any_grid_resolves():
    # SAMPLES_PER_SEGMENT samples of a SAMPLES_MAX grid: 8 * 360 / 1e6 = 0.00288 deg; a segment of
    # that angle parses (on the finest grid), one 1 % shorter is refused naming its angle_deg
    from camjax.scene import SAMPLES_MAX, SAMPLES_PER_SEGMENT, SceneError, parse_scene

    least = SAMPLES_PER_SEGMENT * 360.0 / SAMPLES_MAX
    assert least == pytest.approx(0.00288, rel=1e-12)

    def scene(angle: float) -> str:
        return KINEMATIC.replace("samples = 180", f"samples = {SAMPLES_MAX}").replace(
            "{ kind = \"dwell\", angle_deg = 90 },\n  { kind = \"return\"",
            f"{{ kind = \"dwell\", angle_deg = {angle!r} }},\n  {{ kind = \"dwell\", angle_deg = {90 - angle!r} }},"
            "\n  { kind = \"return\"")

    assert parse_scene(scene(least)).motion.samples == SAMPLES_MAX
    with pytest.raises(SceneError, match=r"motion\.segments\[2\]\.angle_deg = 0\.00285\d*: too short for "
                       r"any grid: 8 samples of the finest \(1000000\) span 0\.00288 deg \(allowed: >= 0\.00288"):
        parse_scene(scene(0.99 * least))


def test_a_huge_unknown_section_is_quoted_short(place, capsys):
    (place / "scene.toml").write_text(DEFAULT + "\n[" + "q" * 5_000_000 + "]\n")
    rc, _, err = run(["design", str(place / "scene.toml"), "--out", str(place / "out")], capsys)
    assert rc == 2
    assert err.count("q") <= QUOTE_CHARS + 10 and "5000000 characters" in err


def test_an_unwritable_output_folder_is_refused_before_any_work(place, capsys, monkeypatch):
    # root may write anywhere, so the permission answer is what the check is given
    target = place / "out"
    real = os.access
    monkeypatch.setattr(output_folder.os, "access",
                        lambda p, mode, **kw: False if Path(p) == target else real(p, mode, **kw))
    calls = []
    monkeypatch.setattr("camjax.pipeline.analyse", lambda *a, **k: calls.append(a))
    before = snapshot(target)
    rc, _, err = run(["design", "--out", str(target)], capsys)
    assert rc == 2 and "--out" in err and "permission denied" in err and err.count("\n") == 1
    assert calls == [] and snapshot(target) == before


WRITERS = {  # every command that writes, with the computation that must not start
    "design": (["design", "--out", "{dir}"], "camjax.pipeline.analyse"),
    "sweep": (["sweep", "--alpha", "1", "--gamma", "1", "--out", "{dir}"], "camjax.pipeline.sweep_scene"),
    "block_sweep": (["sweep", "--alpha", "1", "--gamma", "1", "--backend", "sequential", "--out", "{dir}"],
                    "camjax.scaleout.driver.sweep_blocks"),
    "dynamics": (["dynamics", "thesis-bench", "--out", "{dir}"], "camjax.dynamics.scene_dynamics"),
    "check-extremes": (["check-extremes", "--out", "{dir}"], "camjax.scene.load_scene"),
    "laws_json": (["laws", "--json", "{dir}/laws.json"], "camjax.laws.summarize"),
    "laws_plot": (["laws", "--plot", "{dir}/laws.png"], "camjax.laws.summarize"),
}


@pytest.mark.parametrize("command", sorted(WRITERS))
def test_a_place_where_nothing_can_be_made_is_refused_before_any_work(command, place, capsys, monkeypatch):
    # a read-only file system: the permission bits allow writing (root, or a rw mode on a ro
    # mount), making the staging folder fails with EROFS
    import errno
    import tempfile

    def read_only(*args, **kwargs):
        raise OSError(errno.EROFS, os.strerror(errno.EROFS))

    monkeypatch.setattr(tempfile, "mkdtemp", read_only)
    template, work = WRITERS[command]
    calls = []
    monkeypatch.setattr(work, lambda *a, **k: calls.append(a))
    before = snapshot(place / "out")
    rc, out, err = run(_argv(template, place), capsys)
    option = template[1] if template[0] == "laws" else "--out"
    assert rc == 2 and out == "" and err.count("\n") == 1, err
    assert f"{option} = " in err and "Read-only file system" in err
    assert calls == [] and snapshot(place / "out") == before and leftovers(place) == []


@pytest.mark.slow
def test_an_os_error_while_writing_is_one_line_and_changes_nothing(place, capsys, monkeypatch):
    def full(*args, **kwargs):
        raise OSError(28, "No space left on device", "profile.csv")

    monkeypatch.setattr("camjax.output.export.write_profile_csv", full)
    (place / "scene.toml").write_text(KINEMATIC)
    before = snapshot(place / "out")
    rc, _, err = run(["design", str(place / "scene.toml"), "--out", str(place / "out"), "--dpi", "20"], capsys)
    assert rc == 1 and err.count("\n") == 1 and "No space left on device" in err and "Traceback" not in err
    assert snapshot(place / "out") == before and leftovers(place) == []


def test_an_unexpected_error_is_one_line(place, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("x" * 10_000)

    monkeypatch.setattr("camjax.pipeline.analyse", broken)
    rc, _, err = run(["design", "--out", str(place / "out")], capsys)
    assert rc == 1 and err.count("\n") == 1 and "ZeroDivisionError" in err and len(err) < 600


# ------------------------------------------------------------------- folders replaced whole


@pytest.mark.slow
def test_a_run_replaces_the_folder_whole(place, capsys):
    (place / "scene.toml").write_text(KINEMATIC)
    rc, _, _ = run(["design", str(place / "scene.toml"), "--out", str(place / "out"), "--dpi", "20"], capsys)
    assert rc == 0
    # the earlier loads.png is gone: a kinematics-only scene draws no loads
    assert sorted(p.name for p in (place / "out").iterdir()) == [
        "profile.csv", "profile.dxf", "profile.png", "result.json", "svaj.png"]
    assert leftovers(place) == []


class _Blocks:
    """A block backend whose blocks return made-up records at once (or fail): the folder handling
    of a block sweep without solving anything."""

    def __init__(self, fail: bool = False):
        self.fail, self.solved = fail, []

    def map_unordered(self, fn, tasks):
        from camjax.scaleout.backends import Outcome

        for pos, task in enumerate(tasks):
            self.solved.append(task.index)
            if self.fail:
                yield pos, Outcome(False, None, "RuntimeError: injected", 0.0, "")
                continue
            records = [{"alpha": a, "gamma": g, "size_mm": 10.0 + a, "stress_max_MPa": 100.0 + g,
                        "feasible": True, "scene": task.scene_name, "weighting": task.first_weighting + i,
                        "solver": task.spec.solver, "mode": task.spec.mode}
                       for i, (a, g) in enumerate(task.weightings)]
            yield pos, Outcome(True, records, "", 0.0, "test")

    def close(self):
        pass


def _block_sweep(place: Path, capsys, monkeypatch, backend: _Blocks, *extra: str) -> int:
    from camjax.solvers import sweep

    class Figure:
        def savefig(self, path, **kwargs):
            Path(path).write_bytes(b"pareto figure")

    monkeypatch.setattr("camjax.scaleout.driver.make_backend", lambda *a, **k: backend)
    monkeypatch.setattr(sweep, "plot_pareto", lambda *a, **k: Figure())
    rc, _, _ = run(["sweep", "--alpha", "1,2", "--gamma", "1", "--backend", "sequential", "--block-size", "1",
                    "--out", str(place / "out"), *extra], capsys)
    return rc


SWEEP_SET = {"pareto.json", "pareto.png", "manifest.json", "blocks/000000.json", "blocks/000001.json"}


def test_a_block_sweep_replaces_an_earlier_designs_folder_whole(place, capsys, monkeypatch):
    # the folder holds an earlier design's result.json and loads.png: neither survives the sweep
    assert _block_sweep(place, capsys, monkeypatch, _Blocks()) == 0
    assert set(snapshot(place / "out")) == SWEEP_SET and leftovers(place) == []


def test_a_resumed_block_sweep_keeps_its_checkpoint_and_nothing_else(place, capsys, monkeypatch):
    # interrupted (every block failed): the checkpoint is written beside what the folder held
    before = snapshot(place / "out")
    assert _block_sweep(place, capsys, monkeypatch, _Blocks(fail=True)) == 1
    after = snapshot(place / "out")
    assert {k: v for k, v in after.items() if k in before} == before
    assert set(after) - set(before) == {"manifest.json", "blocks/000000.error.json", "blocks/000001.error.json"}
    # a finished block, then a resume: block 0 is read, not solved again; the earlier files go
    first = _Blocks()
    assert _block_sweep(place, capsys, monkeypatch, first, "--resume") == 0
    kept = snapshot(place / "out")["blocks/000000.json"]
    (place / "out" / "blocks" / "000001.json").unlink()
    (place / "out" / "result.json").write_text('{"scene": "a design written here meanwhile"}\n')
    again = _Blocks()
    assert _block_sweep(place, capsys, monkeypatch, again, "--resume") == 0
    assert first.solved == [0, 1] and again.solved == [1]
    final = snapshot(place / "out")
    assert set(final) == SWEEP_SET and final["blocks/000000.json"] == kept and leftovers(place) == []


def test_a_failed_swap_puts_the_checkpoint_back(tmp_path, monkeypatch):
    from camjax.output.folder import replaced_folder

    out = tmp_path / "out"
    (out / "blocks").mkdir(parents=True)
    (out / "blocks" / "000000.json").write_text("block")
    (out / "manifest.json").write_text("manifest")
    (out / "result.json").write_text("earlier")
    before = snapshot(out)
    real = os.replace

    def failing(src, dst):
        if Path(dst) == out and output_folder.STAGING in Path(src).name:  # the new folder into place
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(output_folder.os, "replace", failing)
    with pytest.raises(OSError), replaced_folder(out, ("manifest.json", "blocks")) as tmp:
        (tmp / "pareto.json").write_text("new")
    assert snapshot(out) == before and leftovers(tmp_path) == []


@pytest.mark.slow
def test_a_stale_staging_folder_of_a_dead_run_is_cleaned(place, capsys):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = place / f".out.{output_folder.STAGING}-{dead.pid}"
    stale.mkdir()
    (stale / "half.png").write_bytes(b"x" * 1000)
    aside = place / f".out.{output_folder.OLD}-{dead.pid}"  # killed after setting the old DIR aside
    aside.mkdir()
    alive = place / f".out.{output_folder.STAGING}-{os.getppid()}"  # a live process's: kept
    alive.mkdir()
    (place / "scene.toml").write_text(KINEMATIC)
    rc, _, _ = run(["design", str(place / "scene.toml"), "--out", str(place / "out"), "--dpi", "20"], capsys)
    assert rc == 0
    assert leftovers(place) == [alive.name]


def test_a_folder_set_aside_by_a_killed_run_comes_back(place):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = place / "out"
    before = snapshot(out)
    aside = place / f".out.{output_folder.OLD}-{dead.pid}"
    out.rename(aside)  # a run killed between its two renames
    output_folder.clean_stale(out)
    assert snapshot(out) == before and leftovers(place) == []


# ------------------------------------------------------------------------ unusable geometry


@pytest.fixture(scope="module")
def infeasible_run(tmp_path_factory):
    """design --base-radius 10 --strict on the default scene (smallest admissible R_b 24.10 mm)."""
    out = tmp_path_factory.mktemp("infeasible") / "out"
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
        import io
        from contextlib import redirect_stderr, redirect_stdout

        err, std = io.StringIO(), io.StringIO()
        with redirect_stderr(err), redirect_stdout(std):
            rc = cli.main(["design", "--base-radius", "10", "--strict", "--dpi", "20", "--out", str(out)])
    return rc, std.getvalue(), err.getvalue(), out


@pytest.mark.slow
def test_infeasible_geometry_is_loud(infeasible_run):
    import json

    rc, std, err, out = infeasible_run
    assert rc == cli.STRICT_EXIT
    data = json.loads((out / "result.json").read_text())
    at = data["evaluated_at"]
    assert at["base_radius_mm"] == 10.0 and at["feasible"] is False
    assert {v["constraint"] for v in at["violations"]} == {"curvature", "stress"}
    # flat face: rho = R_b + s + s'', so min rho = 10 - (smallest admissible R_b), independently
    # of the curves; the message prints it to 4 significant figures
    rho_min = 10.0 - data["min_base_radius_mm"]
    assert f"{rho_min:.4g} mm" in next(v["message"] for v in at["violations"] if v["constraint"] == "curvature")
    warnings = err.splitlines()
    assert len(warnings) == 2 and all(w.startswith("camjax design: warning: ") for w in warnings)
    assert "R_b = 10.0000 mm" in std and "INFEASIBLE" in std  # the radius the files were drawn at
    assert (out / "profile.dxf").exists()  # written anyway: --strict only changes the exit status


@pytest.mark.slow
def test_a_feasible_design_has_no_warning(tmp_path, capsys, monkeypatch):
    # the smallest admissible radius + 1 mm of a kinematics-only scene: rho > 0 everywhere
    (tmp_path / "scene.toml").write_text(KINEMATIC)
    rc, std, err = run(["design", str(tmp_path / "scene.toml"), "--strict", "--dpi", "20", "--out",
                        str(tmp_path / "out")], capsys)
    assert rc == 0 and err == "" and ": feasible" in std


@pytest.mark.slow
def test_rpm_1e6_runs_with_finite_results(tmp_path, capsys, monkeypatch):
    import json

    monkeypatch.setenv("CAMJAX_COMPILATION_CACHE", "0")
    text = KINEMATIC.replace("rpm = 100.0", "rpm = 1e6").replace('type = "flat"', 'type = "flat"\nmass_kg = 1.0'
                                                                  "\nspring_N_per_m = 3000.0")
    (tmp_path / "scene.toml").write_text(text)
    rc, _, err = run(["design", str(tmp_path / "scene.toml"), "--dpi", "20", "--out", str(tmp_path / "out")],
                     capsys)
    assert rc == 0 and "Traceback" not in err
    data = json.loads((tmp_path / "out" / "result.json").read_text(), parse_constant=float.__call__)
    # 4 mm cycloidal rise over 90 deg: peak s'' = 2 pi h / beta^2 = 2 pi 4 / (pi/2)^2 mm/rad^2,
    # times omega^2 (omega = 1e6 rpm = 104720 rad/s), times 1e-3 m/mm
    omega = 1e6 * 2 * 3.141592653589793 / 60
    peak = 2 * 3.141592653589793 * 4.0 / (3.141592653589793 / 2) ** 2 * omega**2 * 1e-3
    assert data["kinematics"]["accel_m_s2"]["max"] == pytest.approx(peak, rel=1e-3)  # grid: 1 deg steps
    assert {v["constraint"] for v in data["evaluated_at"]["violations"]} == {"contact"}


# ---------------------------------------------------------------------------------- signals


def _start(args: list[str], tmp_path: Path, **variables: str) -> subprocess.Popen:
    # this checkout's camjax, whatever the working folder
    root = str(Path(cli.__file__).resolve().parents[2])
    path = os.pathsep.join([root, *filter(None, [os.environ.get("PYTHONPATH")])])
    env = {**os.environ, "CAMJAX_COMPILATION_CACHE": "0", "PYTHONUNBUFFERED": "1", "PYTHONPATH": path,
           **variables}
    # started as from a shell: SIGINT at its default (a test runner's worker may ignore it, and an
    # ignored signal is inherited, and stays ignored by camjax's design)
    return subprocess.Popen([sys.executable, "-m", "camjax.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for_import(proc: subprocess.Popen, seconds: float) -> None:
    """Let the process get past its imports (an interrupt during them cannot be caught)."""
    time.sleep(seconds)
    assert proc.poll() is None, proc.communicate()


@pytest.mark.slow
@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_sweep_answers_an_interrupt_within_a_second(sig, status, place):
    before = snapshot(place / "out")
    # 4000 weightings in chunks of 1000: compiling and solving one takes well over 5 s on 2 cores
    alphas = ",".join(f"{0.01 * (k + 1):g}" for k in range(2000))
    proc = _start(["sweep", "--alpha", alphas, "--gamma", "1,2", "--chunk-size", "1000", "--out",
                   str(place / "out")], place)
    seen = ""
    while "sweep (" not in seen:  # the progress bar: the first chunk is being compiled
        char = proc.stderr.read(1)
        assert char, proc.communicate()
        seen += char
    time.sleep(1.0)
    sent = time.perf_counter()
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    waited = time.perf_counter() - sent
    assert proc.returncode == status, err
    assert "1/4" not in err  # interrupted in the first chunk
    assert waited < 1.5, waited  # the process ends within about a second (the worker is abandoned)
    said = [line for line in err.splitlines() if "camjax sweep:" in line]
    assert len(said) == 1 and ("interrupted" in said[0] or "terminated" in said[0])
    assert "Traceback" not in err and "Fatal" not in err
    assert snapshot(place / "out") == before and leftovers(place) == []


@pytest.mark.slow
def test_design_interrupted_while_writing_leaves_the_folder_as_it_was(place):
    # a 1e5-sample design spends seconds writing; interrupt it then, again and again
    before = snapshot(place / "out")
    for delay in (4.0, 6.0, 8.0):
        proc = _start(["design", "--samples", "100000", "--dpi", "30", "--out", str(place / "out")], place)
        time.sleep(delay)
        if proc.poll() is None:  # a fast machine may finish before the interrupt: checked below
            proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        after = snapshot(place / "out")
        if proc.returncode == 0:  # finished first: the whole new set
            assert "result.json" in after and "profile.dxf" in after and "loads.png" in after
            return
        assert proc.returncode == 130 and len(err.strip().splitlines()) == 1, err
        assert after == before and leftovers(place) == []


# ------------------------------------------------------------- interrupted writes (property)


class Injected(OSError):
    """The failure a test injects into the file writing."""


def _scene_text(rpm: float, angles: tuple[float, float, float, float], lift: float, law: str,
                samples: int) -> str:
    d1, rise, d2, ret = angles
    # the samples' own extrema: a program of its own per drawn scene (angles and law are compiled
    # in) either way, but the refined extrema's were 3/4 of its compile time; the files are what is tested
    return f"""
[motion]
rpm = {rpm!r}
samples = {samples}
extrema = "grid"
segments = [
  {{ kind = "dwell", angle_deg = {d1!r} }},
  {{ kind = "rise", angle_deg = {rise!r}, law = "{law}", lift_mm = {lift!r} }},
  {{ kind = "dwell", angle_deg = {d2!r} }},
  {{ kind = "return", angle_deg = {ret!r}, law = "{law}", lift_mm = {lift!r} }},
]
[follower]
type = "flat"
"""


def _counting_writes(monkeypatch, root: Path, fail_at: int, error: type[BaseException]) -> list[str]:
    """Make the ``fail_at``-th write under ``root`` (file opened for writing, or a rename) raise."""
    import builtins
    import io

    seen: list[str] = []
    real_open, real_replace = builtins.open, os.replace

    def event(what: str) -> None:
        seen.append(what)
        if len(seen) == fail_at:
            raise error(28, "injected failure", what) if error is Injected else error()

    def guarded_open(file, mode="r", *args, **kwargs):
        if isinstance(file, str | os.PathLike) and str(root) in os.fspath(file) and set(mode) & set("wax+"):
            event(f"open {Path(os.fspath(file)).name}")
        return real_open(file, mode, *args, **kwargs)

    def guarded_replace(src, dst, *args, **kwargs):
        if str(root) in os.fspath(dst):  # the swap: DIR set aside, staging renamed into place
            event(f"rename {Path(os.fspath(dst)).name}")
        return real_replace(src, dst, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", guarded_open)
    monkeypatch.setattr(io, "open", guarded_open)
    monkeypatch.setattr(os, "replace", guarded_replace)
    return seen


NEW_SET = {"result.json", "svaj.png", "profile.png", "profile.csv", "profile.dxf"}


@pytest.mark.slow
def test_an_interrupted_write_leaves_the_old_or_the_new_complete_folder(tmp_path_factory):
    import json

    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    base = tmp_path_factory.mktemp("property")
    old = base / "template"
    # an earlier run's complete folder, with loads.png and stress.png, which the runs below do not
    # write: the default scene drawn at its smallest admissible radius (its [design] solve writes no
    # other file and was 2/3 of this run's CPU time: 20 s against 6.4 s without it)
    (base / "template.toml").write_text(DEFAULT[:DEFAULT.index("[design]")])
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
        assert cli.main(["design", str(base / "template.toml"), "--dpi", "10", "--out", str(old)]) == 0
    old_files = snapshot(old)
    assert {"loads.png", "stress.png"} <= set(old_files) and NEW_SET < set(old_files)

    angles = st.lists(st.integers(30, 150), min_size=3, max_size=3).filter(lambda a: sum(a) <= 330).map(
        lambda a: (float(a[0]), float(a[1]), float(a[2]), float(360 - sum(a))))

    @settings(max_examples=8, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
    @given(rpm=st.floats(1.0, 1e4), angles=angles, lift=st.floats(0.5, 20.0),
           law=st.sampled_from(["cycloidal", "harmonic", "poly_3_4_5"]), extra=st.integers(0, 300),
           fail_at=st.integers(1, 12), error=st.sampled_from([Injected, KeyboardInterrupt]))
    def check(rpm, angles, lift, law, extra, fail_at, error):
        import shutil
        import uuid

        place = base / uuid.uuid4().hex
        place.mkdir()
        shutil.copytree(old, place / "out")
        samples = 96 + extra  # >= 8 samples in a 30 deg segment
        (place / "scene.toml").write_text(_scene_text(rpm, angles, lift, law, samples))
        with pytest.MonkeyPatch.context() as mp:
            mp.setenv("CAMJAX_COMPILATION_CACHE", "0")
            mp.setenv("CAMJAX_DRAWING_PROCESSES", "0")  # every write in this process, where it is counted
            seen = _counting_writes(mp, place, fail_at, error)
            rc = cli.main(["design", str(place / "scene.toml"), "--dpi", "10", "--out", str(place / "out")])
        after = snapshot(place / "out")
        outcomes.add(len(seen) >= fail_at)
        assert leftovers(place) == []
        if len(seen) < fail_at:  # the run wrote everything before the failure was due
            assert rc == 0 and set(after) == NEW_SET
            data = json.loads(after["result.json"])
            assert data["cam_speed_rpm"] == rpm and data["samples"] == samples
            assert len(after["profile.csv"].decode().splitlines()) == samples + 1  # header + rows
        else:
            assert rc == (1 if error is Injected else 130), seen
            assert after == old_files

    outcomes: set[bool] = set()
    check()
    assert outcomes == {True, False}  # both interrupted and finished runs were drawn


@pytest.mark.slow
def test_a_failed_drawing_process_leaves_the_folder_as_it_was(place, monkeypatch, capsys):
    """A drawing process that fails (here: its figure function raises) ends the run with one
    line and status 1, and the output folder keeps its old files."""
    from camjax.output import drawing

    before = snapshot(place / "out")
    boot = drawing._BOOT.replace("serve(", "import camjax.followers._translating_drawing as p; "
                                 "p.svaj_figure = p.profile_figure = lambda *a: 1 / 0; serve(")
    monkeypatch.setattr(drawing, "_BOOT", boot)  # both workers fail: ZeroDivisionError
    monkeypatch.setenv("CAMJAX_DRAWING_PROCESSES", "2")  # the command's default (tests draw in process)
    rc = cli.main(["design", "--dpi", "10", "--out", str(place / "out")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 1 and len(err) == 1, err
    assert err[0].startswith("camjax design: error: DrawingError: drawing the figures and the DXF failed")
    assert snapshot(place / "out") == before and leftovers(place) == []


def test_drawing_processes_count_is_checked(place, monkeypatch, capsys):
    monkeypatch.setenv("CAMJAX_DRAWING_PROCESSES", "many")
    assert cli.main(["design", "--out", str(place / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "CAMJAX_DRAWING_PROCESSES = 'many': not a count (allowed: 0 to 16" in err


@pytest.mark.slow
def test_roller_violations_agree_with_the_minimum_base_radius():
    # the bisection of pipeline.min_base_radius (jitted, normalized violations) and the NumPy
    # checks on the drawn curves are separate computations of the same constraints: 1 % below
    # the minimum something must break, 1 % above nothing may
    from camjax.pipeline import run_design
    from camjax.scene import parse_scene

    scene = parse_scene(KINEMATIC.replace('type = "flat"', 'type = "roller"\nroller_radius_mm = 8.0\n'
                                          'offset_mm = 3.0'))
    minimum = run_design(scene).min_base_radius.radius_mm
    below = run_design(scene, base_radius_mm=0.99 * minimum).violations
    above = run_design(scene, base_radius_mm=1.01 * minimum).violations
    assert {v.constraint for v in below} & {"pressure_angle", "undercut"} and above == ()


def test_write_json_names_the_non_finite_key(tmp_path):
    from camjax.numerics import NonFiniteError
    from camjax.output.files import non_finite_key, write_json

    data = {"a": [1.0, {"b": 2.0, "c": float("nan")}], "d": float("inf")}
    assert non_finite_key(data) == "a[1].c" and non_finite_key({"x": [1.0]}) is None
    with pytest.raises(NonFiniteError, match=r"a\[1\]\.c"):
        write_json(tmp_path / "r.json", data)
    assert not (tmp_path / "r.json").exists()


@pytest.mark.slow
@pytest.mark.parametrize("sig, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupt_while_starting_is_one_line(sig, status, place):
    # half a second in, the process is still importing JAX: no traceback from inside the imports
    before = snapshot(place / "out")
    proc = _start(["design", "--out", str(place / "out")], place)
    time.sleep(0.5)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == status, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert snapshot(place / "out") == before and leftovers(place) == []
