"""The oscillating roller's design problem on the solver interface: the solvers' smallest cam against the
independent sizing (arm-angle scan + bisection) and a dense scan over the pivot distance, gradients
against finite differences, refused bounds, sweeps."""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from test_rocker import ROLLER_SCENE

from camjax import followers
from camjax.evaluate import scene_arrays
from camjax.family import Weights
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.followers.oscillating_roller import problem as OP
from camjax.scene import SceneError, parse_scene
from camjax.solvers.base import problem_from_scene, solve


def edited(text, *replacements):
    """``text`` with each (old, new) replaced; each old must occur exactly once."""
    for old, new in replacements:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    return text


# test_rocker's rocker on a coarser grid, with an asymmetric pair of laws (so that the rotation
# matters), no damping, and a [design] section (DESIGN: more bounds)
SCENE = edited(
    ROLLER_SCENE, ("samples = 360", "samples = 180"), ("damping_N_m_s_per_rad = 0.01\n", ""),
    ('{ kind = "return", angle_deg = 120, law = "cycloidal", lift_deg = 20.0 },\n  { kind = "dwell",  angle_deg = 60 },',
     '{ kind = "return", angle_deg = 100, law = "poly_3_4_5", lift_deg = 20.0 },\n  { kind = "dwell",  angle_deg = 80 },'),
) + """
[design]
base_radius_mm = [5.0, 60.0]
DESIGN
sigma_max_MPa = 2000.0
alpha = 1.0
gamma = 0.0
"""


def text_of(rotation="ccw", design=""):
    return SCENE.replace("ROT", rotation).replace("DESIGN", design)


def scene_of(rotation="ccw", design=""):
    return parse_scene(text_of(rotation, design))


# A scene's arrays and problem built once per scene text: each build compiles its program again.
@functools.cache
def arrays_of(text, extrema=None):
    scene = parse_scene(text)
    return scene_arrays(scene) if extrema is None else scene_arrays(scene, extrema=extrema)


@functools.cache
def problem_of(text, extrema=None):
    """The scene's problem; extrema "grid": on its samples."""
    scene = parse_scene(text)
    return problem_from_scene(scene) if extrema is None else problem_from_scene(scene, arrays_of(text, extrema))


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_smallest_cam_with_fixed_pivot_and_arm_is_the_sizing(rotation):
    text = text_of(rotation)
    scene, grid = parse_scene(text), arrays_of(text, "grid")
    sol = solve(problem_of(text, "grid"), (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    sizing = rocker_roller_geo.oscillating_roller_min_prime_radius(grid.kin, 80.0, 60.0, 8.0, math.radians(30.0),
                                                                   0.0, rotation)
    # both reach the boundary of the same admissible set (on the samples): the sizing by bisection
    # in the arm angle (to float64 resolution), the solver to its feasibility tolerance (1e-7 rad in
    # phi ~ 1e-5 mm)
    assert float(sol.design.base_radius_mm) == pytest.approx(float(sizing.base_radius_mm), abs=1e-5)
    # with exact extrema the polish moves the design onto the continuous limit: |phi| <= 30 deg
    # between the samples too (to the polish's margin), within the 2-deg grid's error of the above
    exact = solve(problem_of(text), (1.0, 0.0), mode="global", solver="gradient")
    radius = float(exact.design.base_radius_mm)
    phi = followers.get("oscillating_roller").curve_extremes(scene, arrays_of(text), ("pressure_angle",), radius)
    assert max(phi["pressure_angle"].max, -phi["pressure_angle"].min) <= math.radians(30.0) + 1e-12
    assert bool(exact.evaluation.feasible) and abs(radius - float(sizing.base_radius_mm)) < 1e-2


@pytest.mark.slow
def test_pointwise_mode_condenses_to_the_same_smallest_cam():
    problem = problem_of(text_of(), "grid")  # both on the samples
    glob = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    point = solve(problem, (1.0, 0.0), mode="pointwise", solver="gradient")
    # size only, one free variable: the largest per-angle need is the whole-cam need
    assert float(point.design.base_radius_mm) == pytest.approx(float(glob.design.base_radius_mm), abs=1e-5)


@pytest.mark.slow
def test_free_pivot_distance_beats_every_point_of_a_dense_scan():
    # on the samples, as the scan's sizing is: the solver and the scan judge the same admissible set
    # (the polish onto the continuous limits: test_smallest_cam_with_fixed_pivot_and_arm_is_the_sizing)
    text = text_of(design="pivot_distance_mm = [65.0, 110.0]")
    sol = solve(problem_of(text, "grid"), (1.0, 0.0), mode="global", solver="hybrid", seed=0)
    assert bool(sol.evaluation.feasible)
    kin = arrays_of(text, "grid").kin
    # brute force: the independent sizing at every pivot distance on a 0.25 mm grid
    # (every pivot distance through one compiled program: a loop of eager calls compiles the
    # search's while loop once per distance)
    scan = jax.jit(jax.vmap(lambda d: rocker_roller_geo.oscillating_roller_min_prime_radius(
        kin, d, 60.0, 8.0, math.radians(30.0)).base_radius_mm))
    best = float(jnp.min(scan(jnp.arange(65.0, 110.0 + 1e-9, 0.25))))
    # the optimum lies between grid points: it may only beat the scan's best, by little
    assert float(sol.design.base_radius_mm) <= best + 1e-4
    assert float(sol.design.base_radius_mm) >= best - 0.5


def assert_gradients(family, scene, x0, far_points, sums):
    """jacfwd of the objective, of the constraints named in ``sums`` (summed over the angles) and of
    the reach (the same at every angle) at ``x0`` against central differences; finite values and
    gradients at each of ``far_points`` (designs where the geometry breaks down)."""
    problem = problem_from_scene(scene)
    w = Weights(jnp.asarray(1.0), jnp.asarray(1.0))

    def f(x):
        design = family.Design(*x)
        c = family.constraints(problem, design)
        return jnp.stack([family.objective(problem, w, design), *(jnp.sum(getattr(c, name)) for name in sums),
                          c.reach[0]])

    # the values, the jacobian (forward mode) and the summed gradient (reverse mode) in one compiled
    # program; the steps and the differences in NumPy (float64, as in JAX): op by op, each JAX
    # operation would compile a program of its own
    program = jax.jit(lambda x: (f(x), jax.jacfwd(f)(x), jax.grad(lambda y: jnp.sum(f(y)))(x)))
    x0 = np.asarray(x0, dtype=np.float64)
    jac = np.asarray(program(x0)[1])
    for j in range(x0.size):
        step = np.zeros(x0.size)
        step[j] = 1e-6
        fd = (np.asarray(program(x0 + step)[0]) - np.asarray(program(x0 - step)[0])) / 2e-6
        # central differences, h = 1e-6 mm: truncation ~h^2 |f'''|, round-off ~eps |f| / h <= 1e-6 for
        # the sums over 180 angles (|f| <= 1e3); the objective's max keeps its argmax near x0
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-6)
    for x in far_points:
        value, _, gradient = program(np.asarray(x, dtype=np.float64))
        assert np.all(np.isfinite(np.asarray(gradient))) and np.all(np.isfinite(np.asarray(value)))


@pytest.mark.slow
def test_objective_and_constraints_gradients_match_finite_differences():
    scene = parse_scene(SCENE.replace("ROT", "cw").replace("gamma = 0.0", "gamma = 1.0").replace(
        "DESIGN", "roller_radius_mm = [4.0, 12.0]\npivot_distance_mm = [60.0, 100.0]\narm_length_mm = [40.0, 80.0]"))
    # finite everywhere, also where the geometry cannot close or the roller undercuts
    far = ([1.0, 30.0, 60.0, 80.0], [5.0, 4.0, 100.0, 40.0], [60.0, 12.0, 60.0, 40.0])
    assert_gradients(OP, scene, [35.0, 8.0, 80.0, 60.0], far, ("pressure_angle", "undercut", "stress"))


def test_bounds_in_which_no_design_closes_are_refused():
    with pytest.raises(SceneError) as err:
        scene_of(design="pivot_distance_mm = [200.0, 300.0]")  # |d - l| >= 140 > R_p <= 68
    assert err.value.field == "design.pivot_distance_mm" and "closes" in str(err.value)
    flat = FLAT.replace("ROT", "ccw").replace("DESIGN", "").replace("[5.0, 130.0]", "[200.0, 300.0]")
    with pytest.raises(SceneError) as err:
        parse_scene(flat)  # R_b + f >= 210 > d = 150: no face touches the base circle
    assert err.value.field == "design.pivot_distance_mm" and "closes" in str(err.value)


@pytest.mark.slow
def test_sweep_of_an_oscillating_roller_scene():
    from camjax.pipeline import sweep_scene

    scene = parse_scene(SCENE.replace("ROT", "ccw").replace("gamma = 0.0", "gamma = 1.0").replace(
        "DESIGN", "roller_radius_mm = [4.0, 12.0]"))
    # one weighting per compiled call: the program of test_smallest_cam_with_fixed_pivot_and_arm_is_
    # the_sizing's solve on this grid with exact extrema (the sweep's results do not depend on the
    # chunk size; four chunks, each its own call)
    result = sweep_scene(scene, [1.0, 0.1], [0.0, 1.0], mode="global", solver="gradient", chunk_size=1)
    records = result.records()
    assert len(records) == 4 and all({"size_mm", "stress_max_MPa", "pivot_distance_mm"} <= set(r) for r in records)
    assert all(r["feasible"] for r in records)
    # more weight on stress never gives a smaller cam (alpha = 1: gamma 0 -> 1)
    size = {(r["alpha"], r["gamma"]): r["size_mm"] for r in records}
    assert size[(1.0, 1.0)] >= size[(1.0, 0.0)] - 1e-6


FLAT = (SCENE.replace('type = "oscillating_roller"', 'type = "oscillating_flat"')
        .replace("arm_length_mm = 60.0\nroller_radius_mm = 8.0", "face_offset_mm = 10.0")
        .replace("pivot_distance_mm = 80.0", "pivot_distance_mm = 150.0")
        .replace("base_radius_mm = [5.0, 60.0]", "base_radius_mm = [5.0, 130.0]"))


def flat_text(rotation, sigma_max):
    """The flat-face rocker of FLAT with no more bounds and the allowed stress sigma_max (MPa)."""
    return FLAT.replace("ROT", rotation).replace("DESIGN", "").replace("sigma_max_MPa = 2000.0",
                                                                       f"sigma_max_MPa = {sigma_max!r}")


@pytest.mark.slow
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_face_smallest_cam_is_the_sizing_and_the_stress_limit_binds_as_the_curves_say(rotation):
    from camjax import followers

    loose = flat_text(rotation, 1e6)
    # on the samples, as the sizing is (the exact polish: test_the_polish_keeps_the_flat_face_...)
    problem = problem_of(loose, "grid")
    sol = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    arrays = arrays_of(loose)
    sizing = rocker_flat_geo.oscillating_flat_min_base_radius(arrays.kin, 150.0, 10.0, 1e-3, rotation)
    # the same boundary rho = rho_min, by bisection in the arm angle and by the solver (1e-6 mm)
    assert float(sol.design.base_radius_mm) == pytest.approx(float(sizing.base_radius_mm), abs=1e-5)
    # a tight allowed stress binds instead: the peak of the report's stress curve (P = M / xi and
    # camjax.contact.hertz_line_stress, not the family's formula) sits on sigma_max
    tight = parse_scene(flat_text(rotation, 1000.0))
    sol = solve(problem_of(flat_text(rotation, 1000.0), "grid"), (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    assert float(sol.design.base_radius_mm) > float(sizing.base_radius_mm) + 0.01
    curves = followers.of(tight).evaluate(tight, arrays.kin, arrays.cam_speed_rad_s, float(sol.design.base_radius_mm))
    assert float(np.max(curves.stress_MPa)) == pytest.approx(1000.0, rel=1e-6)


@pytest.mark.slow
def test_flat_face_gradients_match_finite_differences_and_stay_finite():
    from camjax.followers.oscillating_flat import problem as FP

    scene = parse_scene(FLAT.replace("ROT", "ccw").replace("gamma = 0.0", "gamma = 1.0").replace(
        "DESIGN", "pivot_distance_mm = [120.0, 200.0]\nface_offset_mm = [-10.0, 20.0]"))
    # past the pivot (R_b + f > d), a face that never touches, a face swung past 90 deg
    far = ([200.0, 120.0, 20.0], [1.0, 150.0, -10.0], [140.0, 150.0, 5.0])
    assert_gradients(FP, scene, [95.0, 150.0, 10.0], far, ("curvature", "stress", "swing"))
    # pointwise mode condenses to the whole-cam smallest radius (size only, R_b free)
    problem = problem_of(flat_text("ccw", 1e6), "grid")  # both on the samples
    glob = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    point = solve(problem, (1.0, 0.0), mode="pointwise", solver="gradient")
    assert float(point.design.base_radius_mm) == pytest.approx(float(glob.design.base_radius_mm), abs=1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("sigma_max", [1e6, 1000.0])
def test_the_polish_keeps_the_flat_face_limits_between_the_samples(sigma_max):
    """With exact extrema the solver's design keeps rho >= rho_min and sigma <= sigma_max at every
    angle (the report's own curves, refined off the grid), where the samples' design breaks one of
    them between two samples; it moves no more than the 2-deg grid's error."""
    text = flat_text("ccw", sigma_max)
    scene = parse_scene(text)
    follower = followers.of(scene)
    grid = solve(problem_of(text, "grid"), (1.0, 0.0))
    exact = solve(problem_of(text), (1.0, 0.0))
    arrays = arrays_of(text)

    def worst(design):  # how far the continuous curves pass the limits (mm of rho, MPa of stress)
        e = follower.curve_extremes(scene, arrays, ("rho", "stress"), float(design.base_radius_mm))
        return max(1e-3 - e["rho"].min, e["stress"].max - sigma_max)

    assert worst(grid.design) > 0  # the samples' design breaks a limit between the samples
    assert worst(exact.design) <= 1e-9 * sigma_max and bool(exact.evaluation.feasible)
    assert 0 < float(exact.design.base_radius_mm - grid.design.base_radius_mm) < 0.5
