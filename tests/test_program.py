"""Motion programs: sampling, scaling, FLCD joints, gradients, no retracing."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from reference import reference_motion

from camjax.laws import get_law, polynomial_law
from camjax.program import MotionProgram, Segment, evaluate, joints, motion_at, time_kinematics

CYC = get_law("cycloidal")


def ref_program(law="cycloidal", lift=5.0):
    L = get_law(law)
    return MotionProgram.from_segments(
        [Segment("dwell", 100), Segment("rise", 80, L, lift), Segment("dwell", 120),
         Segment("return", 60, L, lift)]
    )


@pytest.mark.parametrize("n", [360, 1000, 36000])
def test_reference_program_matches_numpy(n):
    kin = evaluate(ref_program(), n)
    s, v, a = reference_motion(np.arange(n) * 360.0 / n)
    np.testing.assert_allclose(kin.s, s, atol=1e-12)
    np.testing.assert_allclose(kin.ds, v, atol=1e-12)
    np.testing.assert_allclose(kin.d2s, a, atol=1e-11)


def test_reference_time_kinematics_spec_figures():
    kin = evaluate(ref_program(), 360)
    t = time_kinematics(kin, 240 * 2 * math.pi / 60)
    v, a = np.asarray(t.velocity), np.asarray(t.accel)
    # SPEC 5: 0.18 m/s at 140 deg, -0.239 (exactly -0.24) at 330 deg, +/-18.098 at 315/345
    assert v.max() == pytest.approx(0.18, abs=1e-12) and np.argmax(v) == 140
    assert v.min() == pytest.approx(-0.24, abs=1e-12) and np.argmin(v) == 330
    # exact: h (2 pi / beta^2) w^2 = 5e-3 * 2 pi / (pi/3)^2 * (8 pi)^2 = 18.0956 m/s^2
    peak = 5e-3 * 2 * math.pi / (math.pi / 3) ** 2 * (8 * math.pi) ** 2
    assert a.min() == pytest.approx(-peak, rel=1e-12) and np.argmin(a) == 315
    assert a.max() == pytest.approx(peak, rel=1e-12) and np.argmax(a) == 345
    assert peak == pytest.approx(18.098, abs=5e-3)  # source prints 18.098 (rounded g, pi)


def test_joints_cycloidal_has_perturbations_only():
    js = joints(ref_program())
    assert [j.joint_deg for j in js] == [0.0, 100.0, 180.0, 300.0]
    assert all(j.flcd_class == "perturbation" for j in js)
    # jerk jump at the start of the rise = h * 4 pi^2 / beta^3 exactly (one-sided limits)
    j100 = js[1]
    assert j100.jump_j == pytest.approx(5.0 * 4 * math.pi**2 / math.radians(80) ** 3, rel=1e-12)


@pytest.mark.parametrize(
    "law, expected",
    [("harmonic", "jerk"), ("double_cycloidal", "ok"), ("poly_4_5_6_7", "ok"), ("poly_3_4_5", "perturbation")],
)
def test_joint_classes_against_dwells(law, expected):
    classes = {j.flcd_class for j in joints(ref_program(law))}
    assert classes == {expected}


def test_double_harmonic_with_its_own_return_is_flcd():
    dh = get_law("double_harmonic")
    # D-R-D: the rise ends with an acceleration jump against the dwell
    bad = MotionProgram.from_segments([Segment("rise", 90, dh, 1), Segment("dwell", 90),
                                       Segment("return", 90, dh, 1), Segment("dwell", 90)])
    assert "jerk" in {j.flcd_class for j in joints(bad)}
    # rise straight into its own return of equal angle: -pi^2 meets -pi^2, and the third
    # derivative vanishes on both sides (sin pi, sin 2 pi): smooth to the third derivative
    good = MotionProgram.from_segments([Segment("rise", 90, dh, 1), Segment("return", 90, dh, 1),
                                        Segment("dwell", 180)])
    classes = {j.joint_deg: j.flcd_class for j in joints(good)}
    assert classes[90.0] == "ok"


def test_asymmetric_law_returns_are_time_reversed():
    p34 = get_law("poly_3_4")
    prog = MotionProgram.from_segments([Segment("rise", 180, p34, 1.0), Segment("return", 180, p34, 1.0)])
    kin = motion_at(prog, jnp.asarray([180.0 + 45.0]))
    # the return at x = 1/4 equals the rise at 1 - x = 3/4 (course text eq. 3.1), not 1 - p(1/4)
    x = 0.75
    assert float(kin.s[0]) == pytest.approx(4 * x**3 - 3 * x**4, abs=1e-15)
    # so the rise (ending with p''(1) = -12) meets its return without an acceleration jump, and
    # both meet the cycle start with p'' = 0: only the third derivative jumps
    assert {j.flcd_class for j in joints(prog)} == {"perturbation"}


def test_velocity_jump_is_a_shock():
    ramp = polynomial_law((1,))  # p = x: constant velocity, p'(0) = p'(1) = 1
    prog = MotionProgram.from_segments([Segment("rise", 90, ramp, 1.0), Segment("dwell", 90),
                                        Segment("return", 90, ramp, 1.0), Segment("dwell", 90)])
    assert {j.flcd_class for j in joints(prog)} == {"shock"}


def test_samples_between_and_on_boundaries():
    prog = ref_program()
    # 7 samples: none on a joint except 0 deg
    kin = evaluate(prog, 7)
    ref = reference_motion(np.arange(7) * 360 / 7)
    np.testing.assert_allclose(kin.s, ref[0], atol=1e-12)
    # exactly on a joint: the sample belongs to the segment that starts there
    at = motion_at(prog, jnp.asarray([100.0, 180.0, 300.0]))
    np.testing.assert_allclose(at.s, [0.0, 5.0, 5.0], atol=1e-15)
    np.testing.assert_allclose(at.ds, [0.0, 0.0, 0.0], atol=1e-15)


def test_validation_messages():
    with pytest.raises(ValueError, match="sum to 350"):
        MotionProgram.from_segments([Segment("dwell", 350)])
    with pytest.raises(ValueError, match="bring the follower back"):
        MotionProgram.from_segments([Segment("rise", 180, CYC, 2.0), Segment("return", 180, CYC, 1.0)])
    with pytest.raises(ValueError, match="below the start level"):
        MotionProgram.from_segments([Segment("return", 180, CYC, 1.0), Segment("rise", 180, CYC, 1.0)])
    with pytest.raises(ValueError, match="lift_mm"):
        MotionProgram.from_segments([Segment("rise", 180, CYC, -1.0), Segment("return", 180, CYC, 1.0)])


def test_gradient_wrt_lift_matches_finite_difference_and_no_retrace():
    prog = ref_program()

    def peak_accel(lifts):
        p = MotionProgram(prog.kinds, prog.angles_deg, prog.laws, lifts)
        return jnp.max(jnp.abs(evaluate(p, 360).d2s))

    lifts = prog.lifts
    g = jax.grad(peak_accel)(lifts)
    e = jnp.zeros(4).at[3].set(1e-6)
    fd = (peak_accel(lifts + e) - peak_accel(lifts - e)) / 2e-6
    assert float(g[3]) == pytest.approx(float(fd), rel=1e-7)
    assert np.all(np.isfinite(g))
    # peak |s''| is linear in the return lift: d/dh = 2 pi / beta^2
    assert float(g[3]) == pytest.approx(2 * math.pi / math.radians(60) ** 2, rel=1e-12)
    # a second program with other lifts reuses the compiled evaluation
    before = evaluate._cache_size()
    evaluate(MotionProgram(prog.kinds, prog.angles_deg, prog.laws, lifts * 2.0), 360)
    assert evaluate._cache_size() == before
