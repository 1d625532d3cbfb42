"""The oscillating roller's design problem on the solver interface: the solvers' smallest cam against the
independent sizing (arm-angle scan + bisection) and a dense scan over the pivot distance, gradients
against finite differences, refused bounds, sweeps."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import geometry
from camjax import oscillating_problem as OP
from camjax.evaluate import scene_arrays
from camjax.problem import Weights
from camjax.scene import SceneError, parse_scene
from camjax.solvers.base import problem_from_scene, solve

SCENE = """
[motion]
rpm = 300.0
samples = 180
rotation = "ROT"
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
DESIGN
sigma_max_MPa = 2000.0
alpha = 1.0
gamma = 0.0
"""


def scene_of(rotation="ccw", design=""):
    return parse_scene(SCENE.replace("ROT", rotation).replace("DESIGN", design))


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_smallest_cam_with_fixed_pivot_and_arm_is_the_sizing(rotation):
    scene = scene_of(rotation)
    problem = problem_from_scene(scene)
    sol = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    kin = scene_arrays(scene).kin
    sizing = geometry.oscillating_roller_min_prime_radius(kin, 80.0, 60.0, 8.0, math.radians(30.0), 0.0, rotation)
    # both reach the boundary of the same admissible set: the sizing by bisection in the arm angle
    # (to float64 resolution), the solver to its feasibility tolerance (1e-7 rad in phi ~ 1e-5 mm)
    assert float(sol.design.base_radius_mm) == pytest.approx(float(sizing.base_radius_mm), abs=1e-5)


def test_pointwise_mode_condenses_to_the_same_smallest_cam():
    scene = scene_of()
    problem = problem_from_scene(scene)
    glob = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    point = solve(problem, (1.0, 0.0), mode="pointwise", solver="gradient")
    # size only, one free variable: the largest per-angle need is the whole-cam need
    assert float(point.design.base_radius_mm) == pytest.approx(float(glob.design.base_radius_mm), abs=1e-5)


@pytest.mark.slow
def test_free_pivot_distance_beats_every_point_of_a_dense_scan():
    scene = scene_of(design="pivot_distance_mm = [65.0, 110.0]")
    problem = problem_from_scene(scene)
    sol = solve(problem, (1.0, 0.0), mode="global", solver="hybrid", seed=0)
    assert bool(sol.evaluation.feasible)
    kin = scene_arrays(scene).kin
    # brute force: the independent sizing at every pivot distance on a 0.25 mm grid
    best = min(float(geometry.oscillating_roller_min_prime_radius(kin, d, 60.0, 8.0, math.radians(30.0)).base_radius_mm)
               for d in np.arange(65.0, 110.0 + 1e-9, 0.25))
    # the optimum lies between grid points: it may only beat the scan's best, by little
    assert float(sol.design.base_radius_mm) <= best + 1e-4
    assert float(sol.design.base_radius_mm) >= best - 0.5


def test_objective_and_constraints_gradients_match_finite_differences():
    scene = parse_scene(SCENE.replace("ROT", "cw").replace("gamma = 0.0", "gamma = 1.0").replace(
        "DESIGN", "roller_radius_mm = [4.0, 12.0]\npivot_distance_mm = [60.0, 100.0]\narm_length_mm = [40.0, 80.0]"))
    problem = problem_from_scene(scene)
    w = Weights(jnp.asarray(1.0), jnp.asarray(1.0))

    def f(x):
        design = OP.Design(*x)
        c = OP.constraints(problem, design)
        return jnp.stack([OP.objective(problem, w, design), jnp.sum(c.pressure_angle), jnp.sum(c.undercut),
                          jnp.sum(c.stress), c.reach[0]])

    x0 = jnp.asarray([35.0, 8.0, 80.0, 60.0])
    jac = jax.jit(jax.jacfwd(f))(x0)
    for j in range(4):
        step = jnp.zeros(4).at[j].set(1e-6)
        fd = (f(x0 + step) - f(x0 - step)) / 2e-6
        # central differences, h = 1e-6 mm: truncation ~h^2 |f'''|, round-off ~eps |f| / h <= 1e-7 for the
        # sums over 180 angles (|f| <= 1e3); the objective's max keeps its argmax near x0
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-6)
    # finite everywhere, also where the geometry cannot close or the roller undercuts
    for x in ([1.0, 30.0, 60.0, 80.0], [5.0, 4.0, 100.0, 40.0], [60.0, 12.0, 60.0, 40.0]):
        g = jax.grad(lambda x: jnp.sum(f(x)))(jnp.asarray(x))
        assert np.all(np.isfinite(np.asarray(g))) and np.all(np.isfinite(np.asarray(f(jnp.asarray(x)))))


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
    result = sweep_scene(scene, [1.0, 0.1], [0.0, 1.0], mode="global", solver="gradient")
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


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_flat_face_smallest_cam_is_the_sizing_and_the_stress_limit_binds_as_the_curves_say(rotation):
    from camjax.rocker import evaluate_rocker

    loose = parse_scene(FLAT.replace("ROT", rotation).replace("DESIGN", "").replace(
        "sigma_max_MPa = 2000.0", "sigma_max_MPa = 1e6"))
    problem = problem_from_scene(loose)
    sol = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    arrays = scene_arrays(loose)
    sizing = geometry.oscillating_flat_min_base_radius(arrays.kin, 150.0, 10.0, 1e-3, rotation)
    # the same boundary rho = rho_min, by bisection in the arm angle and by the solver (1e-6 mm)
    assert float(sol.design.base_radius_mm) == pytest.approx(float(sizing.base_radius_mm), abs=1e-5)
    # a tight allowed stress binds instead: the peak of the report's stress curve (P = M / xi and
    # camjax.contact.hertz_line_stress, not the family's formula) sits on sigma_max
    tight = parse_scene(FLAT.replace("ROT", rotation).replace("DESIGN", "").replace(
        "sigma_max_MPa = 2000.0", "sigma_max_MPa = 1000.0"))
    sol = solve(problem_from_scene(tight), (1.0, 0.0), mode="global", solver="gradient")
    assert bool(sol.evaluation.feasible)
    assert float(sol.design.base_radius_mm) > float(sizing.base_radius_mm) + 0.01
    curves = evaluate_rocker(tight, arrays.kin, arrays.cam_speed_rad_s, float(sol.design.base_radius_mm))
    assert float(np.max(curves.stress_MPa)) == pytest.approx(1000.0, rel=1e-6)


def test_flat_face_gradients_match_finite_differences_and_stay_finite():
    from camjax import oscillating_flat_problem as FP

    scene = parse_scene(FLAT.replace("ROT", "ccw").replace("gamma = 0.0", "gamma = 1.0").replace(
        "DESIGN", "pivot_distance_mm = [120.0, 200.0]\nface_offset_mm = [-10.0, 20.0]"))
    problem = problem_from_scene(scene)
    w = Weights(jnp.asarray(1.0), jnp.asarray(1.0))

    def f(x):
        design = FP.Design(*x)
        c = FP.constraints(problem, design)
        return jnp.stack([FP.objective(problem, w, design), jnp.sum(c.curvature), jnp.sum(c.stress),
                          jnp.sum(c.swing), c.reach[0]])

    x0 = jnp.asarray([95.0, 150.0, 10.0])
    jac = jax.jit(jax.jacfwd(f))(x0)
    for j in range(3):
        step = jnp.zeros(3).at[j].set(1e-6)
        fd = (f(x0 + step) - f(x0 - step)) / 2e-6
        # central differences, h = 1e-6 mm: round-off ~eps |f| / h <= 1e-6 for sums over 180 angles
        np.testing.assert_allclose(jac[:, j], fd, rtol=1e-6, atol=1e-6)
    # past the pivot (R_b + f > d), a face that never touches, a face swung past 90 deg
    for x in ([200.0, 120.0, 20.0], [1.0, 150.0, -10.0], [140.0, 150.0, 5.0]):
        g = jax.grad(lambda x: jnp.sum(f(x)))(jnp.asarray(x))
        assert np.all(np.isfinite(np.asarray(g))) and np.all(np.isfinite(np.asarray(f(jnp.asarray(x)))))
    # pointwise mode condenses to the whole-cam smallest radius (size only, R_b free)
    scene = parse_scene(FLAT.replace("ROT", "ccw").replace("DESIGN", "").replace(
        "sigma_max_MPa = 2000.0", "sigma_max_MPa = 1e6"))
    problem = problem_from_scene(scene)
    glob = solve(problem, (1.0, 0.0), mode="global", solver="gradient")
    point = solve(problem, (1.0, 0.0), mode="pointwise", solver="gradient")
    assert float(point.design.base_radius_mm) == pytest.approx(float(glob.design.base_radius_mm), abs=1e-5)
