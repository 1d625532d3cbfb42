"""Polynomial segments solved from joint conditions: closed forms, refusals, units, joints.

References are the textbook closed forms the conditions must reproduce exactly (3-4-5, 4-5-6-7,
the cubic Hermite), compared as fractions (no tolerance: the solve is exact) and, evaluated, to
1e-12 of the lift (float64 evaluation of a degree <= 7 Bernstein sum: ~1e-15).
"""

import math
from fractions import Fraction as F

import jax.numpy as jnp
import numpy as np
import pytest

from camjax.laws import LAWS
from camjax.program import MotionProgram, Segment, evaluate, joints, motion_at
from camjax.program.conditions import (
    FREE,
    MATCH,
    ConditionError,
    EndConditions,
    Plan,
    SegmentConditions,
    ThroughPoint,
    lowest_degree_polynomial,
    solve_program,
    unmatched_joints,
)
from camjax.scene import SceneError, parse_scene

FLAT = """
[follower]
type = "flat"
"""


def _scene(segments: str, follower: str = FLAT, samples: int = 360):
    return parse_scene(f"[motion]\nrpm = 60.0\nsamples = {samples}\nsegments = [\n{segments}\n]\n{follower}", "t")


def _dwell_rise_dwell(start=None, end=None, lift=10.0):
    cond = SegmentConditions(start or EndConditions(), end or EndConditions())
    return [Plan("dwell", 90.0), Plan("rise", 90.0, lift, conditions=cond), Plan("dwell", 90.0),
            Plan("return", 90.0, lift, LAWS["poly_3_4_5"])]


def test_match_with_dwells_is_3_4_5_exactly():
    out = solve_program(_dwell_rise_dwell())
    sol = out[1]
    assert sol.degree == 5
    assert sol.q == (0, 0, 0, F(10), F(-15), F(6))
    x = np.linspace(0.0, 1.0, 101)
    v = sol.law(jnp.asarray(x))
    ref = (10 * x**3 - 15 * x**4 + 6 * x**5, 30 * x**2 - 60 * x**3 + 30 * x**4,
           60 * x - 180 * x**2 + 120 * x**3, 60 - 360 * x + 360 * x**2)
    for k in range(4):
        np.testing.assert_allclose(np.asarray(v[k]), ref[k], rtol=0, atol=1e-12 * max(1, np.max(np.abs(ref[k]))))


def test_jerk_matched_too_is_4_5_6_7_exactly():
    m = EndConditions(j=MATCH)
    sol = solve_program(_dwell_rise_dwell(m, m))[1]
    assert sol.degree == 7
    assert sol.q == (0, 0, 0, 0, F(35), F(-84), F(70), F(-20))


@pytest.mark.parametrize("v0, v1", [(0.05, 0.2), (0.3, -0.1), (0.0, 0.0)])
def test_given_end_velocities_are_the_cubic_hermite(v0, v1):
    lift, beta = 10.0, 90.0
    cond = (EndConditions(F(v0), FREE, FREE), EndConditions(F(v1), FREE, FREE))
    sol = solve_program(_dwell_rise_dwell(*cond, lift=lift))[1]
    # Hermite basis on [0, 1]: q = (-2x^3 + 3x^2) + m0 (x^3 - 2x^2 + x) + m1 (x^3 - x^2) with the
    # slopes in normalized units m = v beta / h (v in mm/deg)
    m0, m1 = F(v0) * F(beta) / F(lift), F(v1) * F(beta) / F(lift)
    ref = (F(0), m0, 3 - 2 * m0 - m1, -2 + m0 + m1)
    assert sol.q == ref[: sol.degree + 1] and all(c == 0 for c in ref[sol.degree + 1:])
    assert sol.degree == (3 if ref[3] != 0 else 2 if ref[2] != 0 else 1)


def test_lowest_degree_takes_a_gap_in_the_orders():
    """a = 0 at both ends with v free: the straight line q = x already meets them (degree 1)."""
    zero_a = EndConditions(FREE, F(0), FREE)
    sol = solve_program(_dwell_rise_dwell(zero_a, zero_a))[1]
    assert sol.degree == 1 and sol.q == (0, 1)


@pytest.mark.slow
def test_a_return_moves_down_by_its_conditions():
    cond = SegmentConditions(EndConditions(j=MATCH), EndConditions(j=MATCH))
    plans = [Plan("rise", 90.0, 8.0, LAWS["poly_4_5_6_7"]), Plan("dwell", 90.0),
             Plan("return", 120.0, 8.0, conditions=cond), Plan("dwell", 60.0)]
    sol = solve_program(plans)[2]
    prog = MotionProgram.from_segments([Segment("rise", 90.0, LAWS["poly_4_5_6_7"], 8.0), Segment("dwell", 90.0),
                                        Segment("return", 120.0, sol.law, 8.0), Segment("dwell", 60.0)])
    t = np.linspace(180.0, 300.0, 61)[:-1]
    kin = motion_at(prog, jnp.asarray(t))
    x = (t - 180.0) / 120.0
    q = 35 * x**4 - 84 * x**5 + 70 * x**6 - 20 * x**7
    np.testing.assert_allclose(np.asarray(kin.s), 8.0 * (1 - q), rtol=0, atol=1e-12 * 8.0)
    assert all(j.flcd_class == "ok" for j in joints(prog))


def test_through_point_is_met():
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 10.0, '
            'through = [{ at_deg = 30.0, s_mm = 6.0, v = 0.1 }] },\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 10.0 },')
    scene = _scene(text)
    seg = scene.motion.segments[1]
    assert seg["solved_degree"] == 7  # 4 end conditions + s, v at one point + s(0), s(1): 8 conditions
    kin = motion_at(scene.motion.program, jnp.asarray([120.0]))
    assert float(kin.s[0]) == pytest.approx(6.0, abs=1e-12 * 10)
    assert float(kin.ds[0]) * math.pi / 180 == pytest.approx(0.1, abs=1e-12)  # mm/rad -> mm/deg


def test_uniform_neighbour_fixes_velocity():
    plans = [Plan("dwell", 60.0), Plan("rise", 60.0, 10.0, conditions=SegmentConditions()),
             Plan("rise", 120.0, 20.0, LAWS["uniform"]), Plan("rise", 60.0, 10.0, conditions=SegmentConditions()),
             Plan("return", 60.0, 40.0, LAWS["cycloidal"])]
    out = solve_program(plans)
    # uniform 20 mm over 120 deg: v = 1/6 mm/deg, i.e. q'(1) = (1/6) 60 / 10 = 1 in normalized units
    q = out[1].q
    assert sum(c * p for p, c in enumerate(q)) == 1  # q'(1)
    assert sum(c * p * (p - 1) for p, c in enumerate(q)) == 0  # q''(1)
    assert q[:3] == (0, 0, 0)  # q(0) = q'(0) = q''(0) = 0 against the dwell


def test_both_sides_match_is_refused_naming_the_condition():
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 10.0 },')
    with pytest.raises(SceneError, match=r"^motion\.segments\[1\]\.end\.v: .*segments\[2\]\.start\.v is "
                                         r"'match' too and neither fixes it"):
        _scene(text)
    # one side giving the number resolves it: both take it, and the joint is smooth
    ok = _scene(text.replace('lift_mm = 5.0 },\n{ kind = "rise"',
                             'lift_mm = 5.0, end = { v = 0.1, a = 0.0 } },\n{ kind = "rise"', 1))
    jt = [j for j in joints(ok.motion.program) if j.after == 2][0]
    assert jt.flcd_class in ("ok", "perturbation")
    assert abs(jt.jump_v) <= 1e-12 and abs(jt.jump_a) <= 1e-9


def test_a_free_neighbour_is_solved_first_or_refused_in_a_circle():
    plans = [Plan("dwell", 90.0), Plan("rise", 90.0, 5.0, conditions=SegmentConditions()),
             Plan("rise", 90.0, 5.0, conditions=SegmentConditions(EndConditions(v=FREE, a=FREE),
                                                                  EndConditions())),
             Plan("return", 90.0, 10.0, LAWS["cycloidal"])]
    out = solve_program(plans)  # segment 2 first (its start free), then 1 takes its start values
    # segment 1's end velocity per degree = segment 2's start velocity per degree
    assert sum(c * p for p, c in enumerate(out[1].q)) * F(5) / F(90) == out[2].q[1] * F(5) / F(90)
    # a circle: each one's match waits on the other's free
    waits = SegmentConditions(EndConditions(v=FREE, a=F(0)), EndConditions())
    circle = [Plan("rise", 180.0, 5.0, conditions=waits), Plan("return", 180.0, 5.0, conditions=waits)]
    with pytest.raises(ConditionError, match=r"^segments\[0\]\.end\.v: .*nothing fixes it"):
        solve_program(circle)


@pytest.mark.parametrize("extra, field", [
    ('through = [{ at_deg = 30.0, s_mm = 1.0 }, { at_deg = 30.0, s_mm = 2.0 }]', r"through\[1\]\.at_deg"),
    ('through = [{ at_deg = 90.0, s_mm = 1.0 }]', r"through\[0\]\.at_deg"),
    ('through = [{ at_deg = 30.0, s_deg = 1.0 }]', r"through\[0\]\.s_deg"),
    ('start = { v = "fast" }', r"start\.v"),
    ('start = { w = 1.0 }', r"start\.w"),
    ('end = { a = nan }', r"end\.a"),
    ('exponents = [3, 4, 5], start = { v = 0.0 }', r"start"),
])
def test_bad_conditions_are_refused_naming_the_field(extra, field):
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            f'{{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0, {extra} }},\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 5.0 },')
    with pytest.raises(SceneError, match=rf"^motion\.segments\[1\]\.{field}"):
        _scene(text)


def test_conditions_on_another_law_or_a_dwell_are_refused():
    text = ('{ kind = "dwell", angle_deg = 90, start = { v = 0.0 } },\n'
            '{ kind = "rise", angle_deg = 90, law = "cycloidal", lift_mm = 5.0, end = { v = 0.0 } },\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 5.0 },')
    with pytest.raises(SceneError, match=r"^motion\.segments\[0\]\.start"):
        _scene(text)
    with pytest.raises(SceneError, match=r"^motion\.segments\[1\]\.end = .*only for law 'polynomial'"):
        _scene(text.replace(", start = { v = 0.0 }", ""))


def test_a_motion_too_wild_to_evaluate_is_refused_naming_the_segment():
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0, start = { v = 1e12 } },\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 5.0 },')
    with pytest.raises(SceneError, match=r"^motion\.segments\[1\]: .*cannot be evaluated to 1e-09"):
        _scene(text)


def test_contradicting_conditions_at_one_point_are_refused():
    with pytest.raises(ConditionError, match=r"^b: contradicts a"):
        lowest_degree_polynomial([(F(0), 0, F(0), "a"), (F(1), 0, F(1), "c"), (F(0), 0, F(1), "b")], "seg")


def test_rocking_units_are_per_degree_of_the_swing():
    """deg/deg is rad/rad: a start velocity of 0.25 deg/deg is s' = 0.25 in the program (rad/rad)."""
    follower = """
[follower]
type = "oscillating_roller"
pivot_distance_mm = 80.0
arm_length_mm = 60.0
roller_radius_mm = 8.0
"""
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_deg = 20.0, start = { v = 0.25 }, '
            'through = [{ at_deg = 45.0, s_deg = 12.0 }] },\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_deg = 20.0 },')
    scene = _scene(text, follower)
    seg = scene.motion.program
    kin = motion_at(seg, jnp.asarray([90.0, 135.0]))
    assert float(kin.ds[0]) == pytest.approx(0.25, abs=1e-12)
    assert float(kin.s[1]) == pytest.approx(math.radians(12.0), abs=1e-12)


def test_a_joint_that_jumps_where_matching_was_asked_is_found():
    prog = MotionProgram.from_segments([Segment("dwell", 120.0), Segment("rise", 120.0, LAWS["uniform"], 5.0),
                                        Segment("return", 120.0, LAWS["cycloidal"], 5.0)])
    found = unmatched_joints(prog, [(), ("v", "a"), ()])
    assert [(i, name) for i, name, _ in found] == [(1, "v")]  # uniform after a dwell: v jumps, a does not
    assert found[0][2] == pytest.approx(5.0 / math.radians(120.0), rel=1e-12)


def test_through_values_follow_the_exact_solve():
    """s, v, a at the middle and rest at both ends: 9 conditions, so degree <= 8; they are
    symmetric under (x, q) -> (1 - x, 1 - q) (s = 1/2, a = 0 in the middle), which makes the x^8
    coefficient vanish: the lowest degree is 7. Every condition holds exactly (fractions)."""
    cond = SegmentConditions(through=(ThroughPoint(F(45), F(5), F(1, 10), F(0)),))
    plans = _dwell_rise_dwell()
    plans[1] = Plan("rise", 90.0, 10.0, conditions=cond)
    sol = solve_program(plans)[1]
    assert sol.degree == 7

    def d(x, k):
        return sum(c * math.perm(p, k) * x ** (p - k) for p, c in enumerate(sol.q) if p >= k)

    assert [d(F(0), k) for k in range(3)] == [0, 0, 0] and [d(F(1), k) for k in range(3)] == [1, 0, 0]
    assert [d(F(1, 2), k) for k in range(3)] == [F(1, 2), F(1, 10) * 90 / 10, 0]


def test_scene_with_conditions_samples_like_its_closed_form():
    text = ('{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 10.0 },\n'
            '{ kind = "dwell", angle_deg = 90 },\n'
            '{ kind = "return", angle_deg = 90, law = "polynomial", lift_mm = 10.0, end = { j = "match" } },')
    scene = _scene(text)
    assert [s.get("solved_degree") for s in scene.motion.segments] == [None, 5, None, 6]
    kin = evaluate(scene.motion.program, 360)
    t = np.arange(360.0)
    x = np.clip((t - 90) / 90, 0, 1)
    ref = np.where(t < 180, 10 * (10 * x**3 - 15 * x**4 + 6 * x**5), 10.0)
    np.testing.assert_allclose(np.asarray(kin.s)[:270], ref[:270], rtol=0, atol=1e-12 * 10)
    assert scene.motion.asked_to_match[1] == ("v", "a") and scene.motion.asked_to_match[0] == ("v", "a", "j")


def test_every_builtin_scene_loads():
    """Built-in scenes are the files of camjax/scenes (discovered, not listed): each one parses,
    the constant-velocity one included, whose joint conditions are solved at load."""
    from camjax.scene import BUILTIN_SCENES, load_scene

    assert "constant-velocity" in BUILTIN_SCENES
    for name in BUILTIN_SCENES:
        load_scene(name)


@pytest.mark.slow
def test_the_constant_velocity_scene_is_c3():
    """The built-in constant-velocity scene: every joint reported "ok" with v, a, j asked to match
    (the report's flcd block as `camjax design` writes it; tests/test_cli.py runs the command that
    writes the block), and its displacement samples continuous through the jerk (finite
    differences).

    Central differences of s on the 0.5 deg grid (h = 8.7e-3 rad) estimate s', s'', s'''. Where a
    derivative is continuous, one step changes it by at most h times the next derivative's peak
    (mean value theorem; the peak taken 3 samples or more away from the joints, where the
    differences straddle no joint); across a jump it changes by the jump. The bounds: 1.5 h peak
    for s' and s'' (C1, C2; measured 1.0), and 0.2 of the s''' peak per step for s''' (C3;
    measured 0.087, and 0.48 with the jerk left free, 20 with the acceleration left free). The
    samples are the scene's program in float64 (profile.csv prints them to 12 decimals, a rounding
    of 1e-12 / h^3 = 2e-6 mm/rad^3 on s''': negligible either way).
    """
    from camjax.evaluate import scene_arrays
    from camjax.output.report import flcd_block
    from camjax.scene import load_scene

    scene = load_scene("constant-velocity")
    segments = [dict(seg) for seg in scene.motion.segments]
    assert [seg.get("solved_degree") for seg in segments] == [None, 6, None, 6, None, 7]
    assert all(j["class"] == "ok" and j["asked_to_match"] == ["v", "a", "j"] for j in flcd_block(scene))
    s = np.asarray(scene_arrays(scene, extrema="grid").kin.s)
    n = len(s)
    h = math.radians(360.0 / n)
    d1 = (np.roll(s, -1) - np.roll(s, 1)) / (2 * h)
    d2 = (np.roll(s, -1) - 2 * s + np.roll(s, 1)) / h**2
    d3 = (np.roll(s, -2) - 2 * np.roll(s, -1) + 2 * np.roll(s, 1) - np.roll(s, 2)) / (2 * h**3)
    joints_deg = np.cumsum([0.0] + [seg["angle_deg"] for seg in segments][:-1])
    k = np.arange(n)
    near = np.zeros(n, bool)
    for j in joints_deg * n / 360.0:
        near |= np.abs((k - j + n / 2) % n - n / 2) <= 3
    # constant velocity in the middle: 25 mm over 100 deg (away from its ends)
    mid = ~near & (k >= 100 * n / 360) & (k < 200 * n / 360)
    np.testing.assert_allclose(d1[mid], 25.0 / math.radians(100.0), rtol=1e-9)
    assert np.max(np.abs(np.diff(d1))) <= 1.5 * h * np.max(np.abs(d2[~near]))  # C1
    assert np.max(np.abs(np.diff(d2))) <= 1.5 * h * np.max(np.abs(d3[~near]))  # C2
    assert np.max(np.abs(np.diff(d3))) <= 0.2 * np.max(np.abs(d3[~near]))  # C3


def test_cli_refuses_an_unsolvable_set_with_exit_2(tmp_path, capsys):
    from camjax import cli

    path = tmp_path / "bad.toml"
    path.write_text(
        '[motion]\nrpm = 60.0\nsegments = [\n'
        '{ kind = "dwell", angle_deg = 90 },\n'
        '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0 },\n'
        '{ kind = "rise", angle_deg = 90, law = "polynomial", lift_mm = 5.0 },\n'
        '{ kind = "return", angle_deg = 90, law = "cycloidal", lift_mm = 10.0 },\n]\n' + FLAT)
    assert cli.main(["design", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "motion.segments[1].end.v" in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "out").exists()
