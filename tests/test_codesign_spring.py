"""The spring as a co-design variable ([synthesis] spring_N_per_m, preload_N, min_contact_force_N,
overspeed; camjax.codesign.spring): contact kept at the overspeed on the design written, measured by
the project's loads model of the final scene; the closed-form preload is exact because the objective
grows with the preload; a free spring never loses to the same co-design with the spring fixed inside
the box; the rate search against a brute-force scan; the constraint binds; the envelope gradient in
the rate against central differences; bad input exits 2 naming the field and writes nothing."""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest
from codesign_fixtures import design_keeping_codesign
from scene_text import toml_of

from camjax import loads, program
from camjax.cli import main
from camjax.codesign import Codesign, CodesignError, codesign_scene
from camjax.codesign import spring as spring_mod
from camjax.codesign.builtin import builtin_kinematics
from camjax.errors import SceneError
from camjax.evaluate import scene_arrays
from camjax.program import Kinematics
from camjax.scene import builtin_scene_text, scene_from_dict

SAMPLES = 120  # search grid (3 deg)
ITERATIONS = 400  # BFGS steps at most (the command's; these searches stop by themselves after ~70)
RATE = [1000.0, 20000.0]  # N/m
PRELOAD = [1.0, 200.0]  # N
MARGIN = 5.0  # N
OVERSPEED = 1.2


def spring_data(**synthesis) -> dict:
    """The built-in codesign scene made small (8 control values per designed law, 120 samples) with
    a free spring (the scene's own: 3004 N/m, 13 mm = 39.05 N, inside the box)."""
    data = tomllib.loads(builtin_scene_text("codesign"))
    for seg in data["motion"]["segments"]:
        if seg.get("design"):
            seg["control_count"] = 8
    data["motion"]["samples"] = SAMPLES
    data["synthesis"].update(spring_N_per_m=RATE, preload_N=PRELOAD, min_contact_force_N=MARGIN,
                             overspeed=OVERSPEED)
    data["synthesis"].update(synthesis)
    return data


def force_of(scene, rpm: float, samples: int) -> np.ndarray:
    """The contact force (N) of a scene with fixed laws by the project's loads (scene_arrays)."""
    fast = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, rpm=rpm))
    return np.asarray(scene_arrays(fast, samples=samples, extrema="grid").force_N)


@pytest.fixture(scope="module")
def command_run(tmp_path_factory):
    """`camjax design` of the free spring's scene (its 120 samples, the command's 400 steps) and the
    co-design it computed on the way: one co-design serves the end-to-end test and the checks of
    the search's result."""
    folder = tmp_path_factory.mktemp("spring")
    path = folder / "spring.toml"
    path.write_text(toml_of(spring_data()))
    outcome, _ = design_keeping_codesign([str(path), "--out", str(folder / "out")])
    assert outcome.scene.motion.samples == SAMPLES
    return folder / "out", outcome


@pytest.fixture(scope="module")
def free(command_run):
    """The free spring's scene and its co-design (codesign_scene(scene, SAMPLES, ITERATIONS): the
    command's)."""
    return scene_from_dict(spring_data(), "spring"), command_run[1]


@pytest.fixture(scope="module")
def cd():
    return Codesign(scene_from_dict(spring_data(), "spring"), SAMPLES)


# ------------------------------------------------------------------------------ quick: bad input


@pytest.mark.parametrize("key, value, field", [
    ("spring_N_per_m", [0.0, 100.0], "synthesis.spring_N_per_m"),
    ("spring_N_per_m", [-5.0, 100.0], "synthesis.spring_N_per_m"),
    ("spring_N_per_m", [500.0, 100.0], "synthesis.spring_N_per_m"),
    ("spring_N_per_m", 0.0, "synthesis.spring_N_per_m"),
    ("preload_N", [0.0, 10.0], "synthesis.preload_N"),
    ("preload_N", [20.0, 10.0], "synthesis.preload_N"),
    ("overspeed", 0.9, "synthesis.overspeed"),
    ("min_contact_force_N", -1.0, "synthesis.min_contact_force_N"),
])
def test_bad_spring_bounds_are_refused_naming_the_field(tmp_path, capsys, key, value, field):
    with pytest.raises(SceneError) as exc:
        scene_from_dict(spring_data(**{key: value}), "bad")
    assert exc.value.field == field
    # the command: one line naming the field, exit 2, nothing written
    text = builtin_scene_text("codesign").replace(
        "[synthesis]", f"[synthesis]\n{key} = {json.dumps(value)}")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and "Traceback" not in err[0]
    assert not out.exists()


def test_spring_keys_parse_to_the_spec():
    spec = scene_from_dict(spring_data(), "spring").synthesis.spring
    assert spec.rate_N_per_m == tuple(RATE) and spec.preload_N == tuple(PRELOAD)
    assert spec.min_contact_force_N == MARGIN and spec.overspeed == OVERSPEED
    fixed = scene_from_dict(spring_data(spring_N_per_m=3000.0), "spring").synthesis.spring
    assert fixed.rate_N_per_m == (3000.0, 3000.0)
    data = spring_data()
    for key in ("spring_N_per_m", "preload_N", "min_contact_force_N", "overspeed"):
        del data["synthesis"][key]
    assert scene_from_dict(data, "plain").synthesis.spring is None


# ------------------------------------------------------------------------------ slow


@pytest.mark.slow
def test_a_spring_without_the_followers_loads_exits_2(tmp_path, capsys):
    # the knife-edge scene (its design needs no stress) without its follower train, its rise and
    # return designed
    text = builtin_scene_text("knife-edge")
    for line in ("mass_kg = 0.3\n", "spring_N_per_m = 1500.0\n", "preload_mm = 8.0\n",
                 "damping_Ns_per_m = 0.4\n", "gravity_m_s2 = 9.81\n"):
        assert line in text
        text = text.replace(line, "")
    text = text.replace('law = "cycloidal"', 'law = "bspline", degree = 3, control_count = 8, design = true')
    text += "\n[synthesis]\nobjective = { l2_jerk = 1e-6 }\nspring_N_per_m = [1000.0, 2000.0]\n"
    path = tmp_path / "noloads.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "synthesis.spring_N_per_m" in err[0] and "loads" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_no_spring_in_the_box_keeps_contact_exits_2_saying_by_how_much(tmp_path, capsys):
    data = spring_data(min_contact_force_N=1000.0)
    with pytest.raises(CodesignError) as exc:
        codesign_scene(scene_from_dict(data, "infeasible"), SAMPLES, max_iterations=2)
    msg = str(exc.value)
    assert msg.startswith("synthesis.min_contact_force_N") and "binds" in msg and "short" in msg
    # by how much: the best spring of the box for contact leaves the least force over the angle
    # at most the first dwell's (s = v = a = 0), preload + m g = 200 + 9.81 N: 790.19 N short or more
    short = float(msg.split(" N short")[0].rsplit(", ", 1)[1])
    assert short >= 1000.0 - 200.0 - 9.81 - 1e-9
    # the command on the same scene: the co-design's pieces above serve it (the built-in scene's
    # 360 samples and 16 control values would compile each again just to reach the same refusal)
    path = tmp_path / "infeasible.toml"
    path.write_text(toml_of(data))
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "synthesis.min_contact_force_N" in err[0]
    assert not out.exists()


@pytest.mark.slow
def test_the_objective_grows_with_the_preload(cd):
    """Eliminating the preload by its least feasible value is exact: at a fixed rate and laws the
    inner optimum (the family's objective at its own optimal geometry) never decreases as the
    preload grows past the least one (the stress grows with the force at every angle)."""
    for names in (("poly_3_4_5", "modified_sine"), ("cycloidal", "cycloidal")):
        kin4 = builtin_kinematics(cd, names)
        for k in (1500.0, 6000.0):
            need = float(spring_mod.least_preload(cd.spring, kin4, k))
            ps = max(need, PRELOAD[0]) + np.asarray([0.0, 0.5, 2.0, 8.0, 30.0, 100.0])
            fs = [float(cd._inner(kin4, (k, p))[0]) for p in ps]
            assert np.all(np.diff(fs) >= -1e-12), (names, k, fs)  # nondecreasing, to rounding
            assert fs[-1] > fs[0] + 1e-4  # and it does grow: gamma > 0 weighs the stress


@pytest.mark.slow
def test_the_contact_holds_at_the_overspeed_on_the_design_written_and_binds(free):
    """(a) measured by the project's loads of the final scene (the designed laws and spring fixed in
    it), not by the co-design's internals; (d) the objective rewards a lighter spring, so the
    constraint binds: the least force equals the margin."""
    scene, out = free
    sp = out.spring
    rpm = scene.motion.rpm * OVERSPEED
    train = out.scene.follower.train
    assert train.spring_N_per_m == pytest.approx(sp["rate_N_per_m"], rel=1e-15)
    assert train.spring_N_per_m * train.preload_mm * 1e-3 == pytest.approx(sp["preload_N"], rel=1e-12)
    assert RATE[0] <= sp["rate_N_per_m"] <= RATE[1] and PRELOAD[0] <= sp["preload_N"] <= PRELOAD[1]
    # the search grid's samples are every 10th of a 10x finer grid's (k 360/N deg = 10k 360/(10N)
    # deg, to a rounding of the angle): one program of the scene's loads serves both grids
    fine = force_of(out.scene, rpm, 10 * SAMPLES)
    force = fine[::10]
    # on the search grid: >= the margin to rounding (1e-9 N on forces of ~1e2 N), and equal to it
    assert force.min() >= MARGIN - 1e-9
    assert sp["binding"] == "contact"
    assert force.min() == pytest.approx(MARGIN, abs=1e-9)
    assert sp["min_contact_force_at_overspeed_N"] == pytest.approx(force.min(), abs=1e-12)
    # between the samples: the finer grid; the force is Lipschitz (F' jumps where s''' does), so
    # its minimum lies at most h/2 max|F'| below the search grid's, h the search grid's step
    step = 2.0 * math.pi / SAMPLES
    slope = np.max(np.abs(np.diff(fine))) / (step / 10)
    assert fine.min() >= MARGIN - 0.5 * step * slope
    # at the design speed the contact force is larger still (less inertia pulls it off)
    assert force_of(out.scene, scene.motion.rpm, SAMPLES).min() >= MARGIN - 1e-9


# Two searches that stall on the piecewise-smooth F (each ends where no step along its direction
# or the gradient decreases F by 1e-12 relative) end apart by where they stall: a free rate whose
# search ends on the low rate bound against the same co-design with the rate fixed there, measured
# 4.5e-8 relative on one 2-core EPYC and 1.07e-5 on another (a CPU with AVX-512, where XLA's code
# differs in its last bits, and so do the searches' paths). At 40 steps, before either search
# stopped, the gap was 2.5e-5.
STALL_SCATTER = 5e-5


@pytest.mark.slow
def test_a_free_spring_never_loses_to_a_fixed_one(free):
    """(b) the same co-design with the spring fixed at values inside the box that keep contact: the
    box's rate ends (preload still the least feasible) and the scene's own spring (3004 N/m, 39.05 N).

    The free spring ends at the fixed rate with the least F (F is flat in the rate there), and its
    F is no more than that case's to the scatter of two stalled searches (STALL_SCATTER), and no
    more than every other case's to 1e-6 relative."""
    _, out = free
    fixed_cases = [dict(spring_N_per_m=RATE[0]), dict(spring_N_per_m=RATE[1]),
                   dict(spring_N_per_m=3004.0, preload_N=3004.0 * 0.013)]
    others = [codesign_scene(scene_from_dict(spring_data(**case), "fixed"), SAMPLES,
                             max_iterations=ITERATIONS) for case in fixed_cases]
    best = min(range(len(others)), key=lambda k: others[k].objective)
    # the free rate on the best fixed rate: 3e-6 relative is where u's transform clips a start on a
    # bound (camjax.codesign.spring.u_of: 1e-6 of log(k_hi / k_lo))
    assert out.spring["rate_N_per_m"] == pytest.approx(fixed_cases[best]["spring_N_per_m"], rel=1e-5)
    for k, (case, other) in enumerate(zip(fixed_cases, others, strict=True)):
        tolerance = STALL_SCATTER if k == best else 1e-6
        assert out.objective <= other.objective * (1 + tolerance), (case, out.objective, other.objective)


@pytest.mark.slow
def test_the_rate_search_matches_a_brute_force_scan(cd):
    """(c) the law fixed (the 3-4-5 rise, modified sine return): the rate with the least objective by
    :meth:`Codesign.best_rate` against 41 rates geometric over the box, each with the least preload
    keeping contact computed here from the loads model and the family's inner optimum at it."""
    kin4 = builtin_kinematics(cd, ("poly_3_4_5", "modified_sine"))
    kin = Kinematics(np.zeros(SAMPLES), *np.asarray(kin4))
    motion = program.time_kinematics(kin, program.rpm_to_rad_s(240.0) * OVERSPEED)
    scan = []
    for k in np.geomspace(*RATE, 41):
        train = loads.FollowerTrain(1.0, k, 0.0, 0.345, 9.81)
        need = MARGIN - float(np.min(np.asarray(loads.kinetostatic_force(train, motion))))
        assert need <= PRELOAD[1]
        scan.append(float(cd._inner(kin4, (k, max(need, PRELOAD[0])))[0]))
    u, inner = cd.best_rate(kin4)
    # never worse than the grid (its ends are in both; the transform puts them 3e-6 relative inside:
    # objective changes below 1e-9), and not better than the grid by more than its resolution
    # allows: F(k) is flat then grows with a slope of at most 0.06 per unit log k (measured here),
    # so between grid points (0.075 in log k) it is within 0.005 of the grid's least
    assert inner.objective <= min(scan) + 1e-9
    assert inner.objective >= min(scan) - 0.005
    slopes = np.abs(np.diff(scan)) / (math.log(RATE[1] / RATE[0]) / 40)
    assert slopes.max() <= 0.1


@pytest.mark.slow
def test_the_envelope_gradient_in_the_rate_matches_central_differences(cd):
    """dF/dx (the laws' z and the rate's u) by the envelope theorem against central differences of
    F, where the least preload binds (2000 N/m) and where the preload's lower bound does (8000 N/m)."""
    for k in (2000.0, 8000.0):
        x = cd.x0.copy()
        x[-1] = spring_mod.u_of(cd.spring, k)
        f, inner = cd.value(x)
        g = cd.gradient(x, inner)
        fd = cd.gradient_fd(x, 1e-5)
        # the inner solve repeats to ~1e-12: differences at h = 1e-5 to ~1e-7 of the gradient
        assert np.linalg.norm(g - fd) <= 1e-6 * max(1.0, np.linalg.norm(fd)), (k, g, fd)
    assert abs(g[-1]) > 1e-3  # at 8000 N/m the rate matters (a stiffer spring: more stress)
    # a fixed rate: x = z, the preload (the least keeping contact) still follows the laws
    fixed = Codesign(scene_from_dict(spring_data(spring_N_per_m=2000.0), "fixed-rate"), SAMPLES)
    assert fixed.free == fixed.nz
    x = fixed.x0
    g = fixed.gradient(x, fixed.value(x)[1])
    fd = fixed.gradient_fd(x, 1e-5)
    assert np.linalg.norm(g - fd) <= 1e-6 * max(1.0, np.linalg.norm(fd)), (g, fd)


def test_a_translating_spring_key_on_a_rocker_is_refused_naming_the_field():
    """A rocker's spring is a torsion spring (tests/test_codesign_spring_rocker.py): its keys are
    spring_N_m_per_rad, preload_N_m and min_contact_torque_N_m, not a translating follower's."""
    data = tomllib.loads(builtin_scene_text("oscillating-roller"))
    for i in (0, 2):
        seg = data["motion"]["segments"][i]
        data["motion"]["segments"][i] = {k: seg[k] for k in ("kind", "angle_deg", "lift_deg")} | {
            "law": "bspline", "degree": 3, "control_count": 8, "design": True}
    data["synthesis"] = {"objective": {"l2_jerk": 1e-6}, "spring_N_per_m": [10.0, 40.0]}
    with pytest.raises(SceneError) as exc:
        scene_from_dict(data, "rocker")
    assert exc.value.field == "synthesis.spring_N_per_m" and "spring_N_m_per_rad" in str(exc.value)


@pytest.mark.slow
def test_design_with_a_free_spring_end_to_end_and_fed_back(command_run):
    """`camjax design` writes the designed spring; the designed laws and spring fed back as a plain
    scene (no [synthesis]) keep contact at the overspeed and give the same design."""
    from camjax.pipeline import design_report

    out = command_run[0]
    res = json.loads((out / "result.json").read_text())
    sp = res["synthesis"]["codesign"]["spring"]
    assert set(sp) >= {"rate_N_per_m", "preload_N", "preload_mm", "min_contact_force_N", "overspeed",
                       "min_contact_force_at_overspeed_N", "binding"}
    assert sp["preload_mm"] == pytest.approx(1e3 * sp["preload_N"] / sp["rate_N_per_m"], rel=1e-12)
    data = spring_data()
    del data["synthesis"]
    for seg in res["synthesis"]["segments"]:
        data["motion"]["segments"][seg["segment"]] = seg["scene_segment"]
    data["follower"].update(spring_N_per_m=sp["rate_N_per_m"], preload_mm=sp["preload_mm"])
    scene = scene_from_dict(data, "fed-back")
    force = force_of(scene, 240.0 * OVERSPEED, SAMPLES)
    assert force.min() >= MARGIN - 1e-9  # on the search grid; 5 N within rounding where it binds
    if sp["binding"] == "contact":
        assert force.min() == pytest.approx(MARGIN, abs=1e-9)
    again = design_report(scene)
    assert again["design"]["objective"] == pytest.approx(res["design"]["objective"], rel=1e-9)
    # the loads written are the designed spring's (exact extrema at the design speed)
    assert again["loads"]["force_N"]["min"] == pytest.approx(res["loads"]["force_N"]["min"], rel=1e-9)


@pytest.mark.slow
def test_spring_keys_without_a_law_objective(tmp_path, capsys):
    """[synthesis] with spring keys and no objective: the co-design of size and stress alone (the
    law terms 0); `camjax synthesize`, which needs an objective, refuses the scene (exit 2)."""
    data = spring_data()
    del data["synthesis"]["objective"]
    scene = scene_from_dict(data, "no-objective")
    assert scene.synthesis.objective == ()
    out = codesign_scene(scene, SAMPLES, max_iterations=5)
    assert out.law_objective == 0.0 and np.isfinite(out.objective)
    assert out.spring["min_contact_force_at_overspeed_N"] >= MARGIN - 1e-9
    path = tmp_path / "s.toml"
    path.write_text(builtin_scene_text("codesign").replace("objective = { l2_jerk = 1e-6 }",
                                                           "min_contact_force_N = 5.0"))
    assert main(["synthesize", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "synthesis" in capsys.readouterr().err and not (tmp_path / "out").exists()
