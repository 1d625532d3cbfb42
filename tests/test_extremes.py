"""Numerical stability at the extremes: property tests and the stability matrix."""

import json
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import reference_motion

import camjax
from camjax import contact, loads, program
from camjax.followers.flat import geometry as flat_geo
from camjax.laws import LAWS
from camjax.numerics import precision_warning
from camjax.program import MotionProgram, Segment
from validation import extremes
from validation.extremes import run_matrix

LAW_NAMES = sorted(LAWS)


@pytest.fixture(scope="module")
def matrix(default_scene):
    return run_matrix(default_scene)


@pytest.mark.slow
def test_matrix_has_no_failure_and_no_nonfinite(matrix):
    failed = [c for c in matrix if not c.passed]
    assert not failed, "\n".join(f"{c.group}: {c.name}: {c.value} vs {c.reference}" for c in failed)
    assert len(matrix) > 150
    assert all(math.isfinite(c.value) for c in matrix)


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(st.sampled_from(LAW_NAMES), st.floats(0.0, 1.0, allow_nan=False))
def test_every_law_finite_and_bounded_for_all_x(name, x):
    v = LAWS[name](jnp.asarray(x))
    assert all(np.isfinite(float(t)) for t in v)
    # every registered law is monotone non-decreasing between 0 and 1
    assert -1e-12 <= float(v.p) <= 1.0 + 1e-12
    assert float(v.dp) >= -1e-12


@pytest.mark.slow
@settings(max_examples=25, deadline=None)
@given(st.floats(0.5, 359.5), st.floats(1e-6, 1e3), st.integers(1, 5000))
def test_programs_match_numpy_for_any_angle_lift_grid(rise_deg, lift, n):
    cyc = LAWS["cycloidal"]
    prog = MotionProgram.from_segments(
        [Segment("rise", rise_deg, cyc, lift), Segment("return", 360.0 - rise_deg, cyc, lift)]
    )
    kin = program.evaluate(prog, n)
    s_ref, v_ref, _ = reference_motion(np.arange(n) * 360.0 / n, lift, (0.0, rise_deg), (rise_deg, 360.0 - rise_deg))
    np.testing.assert_allclose(kin.s, s_ref, atol=1e-12 * lift)
    # the derivative carries 1/beta: relative to its own peak
    np.testing.assert_allclose(kin.ds, v_ref, atol=1e-12 * max(np.max(np.abs(v_ref)), 1e-300))


@pytest.mark.slow
@settings(max_examples=40, deadline=None)
@given(st.floats(-3.0, 1.0), st.floats(0.0, 20_000.0))
def test_stress_force_and_gradients_finite_for_any_radius_and_speed(default_scene, default_arrays, log_factor, rpm):
    # the default scene's arrays once (a fresh scene_arrays compiles its program again per example)
    sc, arrays = default_scene, default_arrays
    rb_min = float(flat_geo.flat_min_base_radius(arrays.kin)[0])
    rb = rb_min * 10.0**log_factor  # 1e-3 x .. 10 x the minimum
    c, train = sc.contact, sc.follower.train

    def peak(params):
        rb, w = params
        motion = program.time_kinematics(arrays.kin, w)
        f = loads.kinetostatic_force(train, motion)
        rho = flat_geo.flat_radius_of_curvature(rb, arrays.kin)
        sigma = contact.hertz_line_stress(f, rho, c.cam_width_mm, c.cam, c.follower)
        return jnp.max(sigma) + jnp.max(loads.cam_torque(f, arrays.kin.ds)) - jnp.min(rho)

    val, grad = jax.value_and_grad(peak)(jnp.asarray([rb, rpm * 2 * math.pi / 60]))
    assert np.isfinite(float(val)) and np.all(np.isfinite(np.asarray(grad)))


@pytest.mark.slow
def test_float32_warns_near_the_curvature_limit_and_not_far_from_it(default_scene):
    a32 = camjax.scene_arrays(default_scene, dtype=jnp.float32)
    rb_min = float(flat_geo.flat_min_base_radius(a32.kin)[0])
    far = flat_geo.flat_radius_of_curvature(jnp.float32(rb_min * 1.2), a32.kin)
    near = flat_geo.flat_radius_of_curvature(jnp.float32(rb_min + 1e-3), a32.kin)
    assert precision_warning(rb_min * 1.2, a32.kin.s, a32.kin.d2s, far, jnp.float32) is None
    msg = precision_warning(rb_min + 1e-3, a32.kin.s, a32.kin.d2s, near, jnp.float32)
    assert msg is not None and "float64" in msg
    # float64 keeps its documented 1e-9 down to the same design
    a64 = camjax.scene_arrays(default_scene)
    near64 = flat_geo.flat_radius_of_curvature(rb_min + 1e-3, a64.kin)
    assert precision_warning(rb_min + 1e-3, a64.kin.s, a64.kin.d2s, near64, jnp.float64) is None


def test_jit_and_eager_paths_agree(default_scene):
    prog = default_scene.motion.program
    jitted = program.evaluate(prog, 720)
    with jax.disable_jit():
        eager = program.evaluate(prog, 720)
    for a, b in zip(jitted, eager, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-12)


def test_nan_or_inf_in_a_scene_is_rejected_with_the_field():
    text = camjax.scene.builtin_scene_text("default")
    for old, new, field in [
        ("rpm = 240.0", "rpm = nan", "motion.rpm"),
        ("mass_kg = 1.0", "mass_kg = inf", "follower.mass_kg"),
        ("sigma_max_MPa = 1230.0", "sigma_max_MPa = -inf", "design.sigma_max_MPa"),
        ("cam_width_mm = 10.0", "cam_width_mm = nan", "contact.cam_width_mm"),
    ]:
        with pytest.raises(camjax.SceneError) as info:
            camjax.parse_scene(text.replace(old, new))
        assert info.value.field == field


def test_check_extremes_command_writes_report(tmp_path, monkeypatch):
    from camjax import cli

    # the full matrix runs in test_matrix_has_no_failure...; here only the command's plumbing
    monkeypatch.setattr(
        extremes,
        "run_matrix",
        lambda scene, progress=None: [
            extremes._case("demo", "one", 1.0, 1.0, 0.0),
            extremes._case("demo", "two", 2.0, 1.0, 0.5),
        ],
    )
    rc = cli.main(["check-extremes", "--out", str(tmp_path / "x")])
    data = json.loads((tmp_path / "x" / "extremes.json").read_text())
    assert rc == 1 and data["summary"] == {"cases": 2, "passed": 1, "failed": 1}
    assert data["skipped"] == []  # the default scene declares every model the matrix uses
    assert (tmp_path / "x" / "extremes.txt").read_text().count("FAIL") == 1


def _without(text, section):
    head, _, rest = text.partition(f"[{section}]")
    _, nxt, tail = rest.partition("\n[")
    return head + (nxt + tail if nxt else "")


def test_groups_needing_an_undeclared_model_are_skipped_with_the_reason():
    text = camjax.scene.builtin_scene_text("default")
    no_contact = camjax.parse_scene(_without(_without(text, "design"), "contact"), "nocontact")
    skipped = {s["group"]: s["reason"] for s in extremes.skipped_groups(no_contact)}
    assert sorted(skipped) == ["geometry and stress", "optimization", "precision"]
    assert all("[contact]" in r and "'nocontact'" in r for r in skipped.values())
    assert "[design]" in skipped["optimization"]
    kinematic = _without(_without(text, "design"), "contact")
    for line in ("mass_kg = 1.0\n", "spring_N_per_m = 3004.0\n", "preload_mm = 13.0\n",
                 "damping_Ns_per_m = 0.345\n", "gravity_m_s2 = 9.81\n"):
        kinematic = kinematic.replace(line, "")
    skipped = extremes.skipped_groups(camjax.parse_scene(kinematic, "kinematic"))
    assert [s["group"] for s in skipped] == ["geometry and stress", "speed", "precision", "optimization"]
    assert "follower.mass_kg" in skipped[1]["reason"]
    assert extremes.skipped_groups(camjax.load_scene()) == []


def test_check_extremes_reports_skipped_groups(tmp_path, monkeypatch, capsys):
    from camjax import cli

    seen = []
    monkeypatch.setattr(extremes, "run_matrix",
                        lambda scene, progress=None: seen.append(scene.name) or [extremes._case("d", "a", 1, 1, 0)])
    scene = tmp_path / "nocontact.toml"
    scene.write_text(_without(_without(camjax.scene.builtin_scene_text("default"), "design"), "contact"))
    rc = cli.main(["check-extremes", str(scene), "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    data = json.loads((tmp_path / "x" / "extremes.json").read_text())
    assert rc == 0 and seen == ["nocontact"]
    assert [s["group"] for s in data["skipped"]] == ["geometry and stress", "precision", "optimization"]
    for s in data["skipped"]:
        assert f"skipping {s['group']}: {s['reason']}" in err


@pytest.mark.slow
def test_check_extremes_runs_on_a_scene_without_contact(tmp_path):
    # the real matrix (no stubs) on a scene without [contact]: the groups it can run, no crash
    from camjax import cli

    scene = tmp_path / "nocontact.toml"
    scene.write_text(_without(_without(camjax.scene.builtin_scene_text("default"), "design"), "contact"))
    assert cli.main(["check-extremes", str(scene), "--out", str(tmp_path / "x")]) == 0
    data = json.loads((tmp_path / "x" / "extremes.json").read_text())
    assert {c["group"] for c in data["cases"]} == {"laws", "polynomials", "programs", "speed"}
    assert data["summary"]["failed"] == 0


def test_check_extremes_without_the_validation_folder_is_one_line(tmp_path, monkeypatch, capsys):
    # an installed wheel has camjax/ but no validation/ beside it
    from camjax import cli
    from camjax.cli import check_extremes

    monkeypatch.setattr(check_extremes, "__file__",
                        str(tmp_path / "site-packages" / "camjax" / "cli" / "check_extremes.py"))
    rc = cli.main(["check-extremes", "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1
    assert "validation" in err and "source checkout" in err and "Traceback" not in err
    assert not (tmp_path / "x").exists()


@pytest.mark.slow
@pytest.mark.parametrize("follower", ["oscillating_roller", "oscillating_flat"])
def test_check_extremes_runs_the_matrix_for_an_oscillating_follower(tmp_path, capsys, follower):
    # the real matrix on a rocker scene with loads and [contact]: the rocker's own geometry, speed
    # and precision cases run (no flat-face formula on a rocker), every case passes, nothing crashes
    # (before: exit 1, a TypeError from the flat face's stress coefficient, None for a rocker)
    from test_rocker import FLAT_SCENE, ROLLER_SCENE

    from camjax import cli

    scene = tmp_path / "rocker.toml"
    scene.write_text((ROLLER_SCENE if follower == "oscillating_roller" else FLAT_SCENE).replace("ROT", "cw"))
    rc = cli.main(["check-extremes", str(scene), "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert rc == 0, err
    data = json.loads((tmp_path / "x" / "extremes.json").read_text())
    groups = {c["group"] for c in data["cases"]}
    assert {"laws", "polynomials", "programs", "rocker geometry", "stress", "rocker speed",
            "rocker precision"} <= groups
    assert "geometry" not in groups and "speed" not in groups  # the translating groups' cases
    assert data["summary"]["failed"] == 0 and data["summary"]["cases"] == len(data["cases"]) > 150
    assert [s["group"] for s in data["skipped"]] == ["optimization"]  # the scene has no [design]


@pytest.mark.slow
def test_rocker_optimization_cases_pass_on_a_rocker_design_scene():
    # the optimization group on an oscillating roller's [design]: the size-only optimum against the
    # independent sizing, extreme weights finite, sigma_max = 1 MPa named, collapsed bounds exact
    from test_oscillating_problem import SCENE

    cases = extremes.optimization_cases(camjax.parse_scene(SCENE.replace("ROT", "cw").replace("DESIGN", "")))
    assert {c.group for c in cases} == {"rocker optimization", "determinism"} and len(cases) == 10
    failed = [c for c in cases if not c.passed]
    assert not failed, "\n".join(f"{c.name}: {c.value} vs {c.reference}" for c in failed)


def test_a_translating_roller_skips_the_flat_face_groups_by_name(tmp_path, monkeypatch, capsys):
    # the flat face's geometry, precision and optimization cases mean nothing on a roller (and the
    # optimization group exited 1 with a ValueError): they are skipped with the follower type named
    from camjax import cli

    scene = camjax.load_scene("roller")
    skipped = {s["group"]: s["reason"] for s in extremes.skipped_groups(scene)}
    assert sorted(skipped) == ["geometry and stress", "optimization", "precision"]
    assert all("follower.type = 'roller'" in r for r in skipped.values())
    seen = []
    monkeypatch.setattr(extremes, "GROUPS", tuple(g._replace(run=lambda sc, name=g.name: seen.append(name) or [])
                                                  for g in extremes.GROUPS))
    assert cli.main(["check-extremes", "roller", "--out", str(tmp_path / "x")]) == 0
    assert seen == ["laws", "polynomials", "programs", "speed"]
    err = capsys.readouterr().err
    assert "skipping optimization: has no cases for follower.type = 'roller'" in err
