"""Exact extrema end to end: the [motion] switch, the report's figures and every solver's answer."""

import math

import numpy as np
import pytest
from reference import reference_force, reference_motion, stress_coefficient
from scipy.optimize import brentq, minimize_scalar

import camjax
from camjax.evaluate import scene_arrays
from camjax.followers.flat import problem as P
from camjax.scene import builtin_scene_text, parse_scene
from camjax.solvers.base import solve

H = 5.0  # lift of the reference case, mm
RHO_MIN = 1e-3  # the flat face's default min_curvature_radius_mm (the default scene sets none), mm


def numpy_reference(theta_deg):
    """Independent NumPy s + s'' (mm) and stress coefficient C (MPa mm^0.5) of the reference case (SPEC 4, 5)."""
    s, _, d2s = reference_motion(theta_deg)
    return s + d2s, stress_coefficient(reference_force(theta_deg))


@pytest.mark.slow
def test_report_min_base_radius_is_the_closed_form():
    """max -(s + s'') on the 60-deg cycloidal return, at cos 2 pi u = -1/35 (test_extrema derives it)."""
    a = math.acos(1.0 / 35.0)
    u = (math.pi + a) / (2 * math.pi)
    need = RHO_MIN - H * (u + math.sin(a) / (2 * math.pi) - 2 * math.pi / (math.pi / 3) ** 2 * math.sin(a))
    report = camjax.design_report(camjax.load_scene())
    assert report["extrema"] == "exact"
    assert report["min_base_radius_mm"] == pytest.approx(need, rel=1e-12)
    assert report["min_base_radius_deg"] == pytest.approx(300 + 60 * (1 - u), abs=1e-7)
    # the face width is 2 max|s'| = 2 h 2 / beta on the return (x = 1/2 is a sample: exact either way)
    assert report["min_face_width_mm"] == pytest.approx(2 * H * 2 / (math.pi / 3), rel=1e-14)


def test_min_base_radius_honours_the_scene_curvature_limit():
    """A scene's min_curvature_radius_mm moves the smallest admissible R_b by exactly that limit
    (rho = R_b + s + s'' >= rho_min), and the drawing at that + 1 mm keeps it (no violation)."""
    text = builtin_scene_text("default")
    text = text[:text.index("[design]")].replace("gravity_m_s2 = 9.81",
                                                 "gravity_m_s2 = 9.81\nmin_curvature_radius_mm = 2.0")
    a = math.acos(1.0 / 35.0)
    u = (math.pi + a) / (2 * math.pi)
    need = 2.0 - H * (u + math.sin(a) / (2 * math.pi) - 2 * math.pi / (math.pi / 3) ** 2 * math.sin(a))
    report = camjax.design_report(parse_scene(text))
    assert report["min_base_radius_mm"] == pytest.approx(need, rel=1e-12)  # closed form, as above
    drawn = report["evaluated_at"]
    assert drawn["base_radius_mm"] == math.ceil(need + 1.0)
    assert drawn["feasible"] and not drawn["violations"]
    # rho at the drawing radius: R_b - need + rho_min, its smallest value >= the limit
    assert report["rho_mm"]["min"] == pytest.approx(drawn["base_radius_mm"] - need + 2.0, rel=1e-12)


def test_grid_switch_keeps_the_samples():
    text = builtin_scene_text("default").replace("samples = 360", 'samples = 360\nextrema = "grid"')
    scene = parse_scene(text[:text.index("[design]")])  # the sizing only: no design solved
    assert scene.motion.extrema == "grid"
    report = camjax.design_report(scene)
    q, _ = numpy_reference(np.arange(360.0))
    assert report["extrema"] == "grid"
    assert report["min_base_radius_mm"] == pytest.approx(RHO_MIN - q.min(), rel=1e-12)  # 24.1031, a sample
    assert report["min_base_radius_deg"] == 315.0


@pytest.mark.slow
def test_every_solver_reaches_the_continuous_optimum():
    """alpha = gamma = 1: R* is the root of g'(R) = 1/N - C*/(2 sigma_max rho*^(3/2)) (envelope
    theorem at the peak angle), found here from NumPy closed forms by SciPy (a 1e6-sample grid
    brackets the peak, Brent's bounded search polishes its angle, brentq solves for R)."""
    theta = np.arange(1_000_000) * 360.0 / 1_000_000
    q, c = numpy_reference(theta)

    def peak_angle(r):
        i = int(np.argmax(c / np.sqrt(r + q)))
        f = lambda x: -(lambda qq, cc: cc / np.sqrt(r + qq))(*numpy_reference(np.array([x])))[0]  # noqa: E731
        return minimize_scalar(f, bounds=(theta[i - 1], theta[i + 1]), method="bounded",
                               options={"xatol": 1e-13}).x

    def slope(r):
        qq, cc = numpy_reference(np.array([peak_angle(r)]))
        return 1 / 65 - cc[0] / (2 * 1230 * (r + qq[0]) ** 1.5)

    reference = brentq(slope, 26.0, 30.0, xtol=1e-14, rtol=1e-15)
    scene = camjax.load_scene()
    problem = P.problem_from_scene(scene, scene_arrays(scene))
    for solver in ("gradient", "ga"):
        r = solve(problem, (1.0, 1.0), solver=solver)
        # brentq's root is good to ~1e-14 relative; the polish converges to the last bits
        assert float(r.base_radius_mm) == pytest.approx(reference, rel=1e-11), solver
        assert float(r.face_width_mm) == pytest.approx(2 * H * 2 / (math.pi / 3), rel=1e-14)
        # the grid's answer is 3e-4 relative off: the test has teeth
    grid = P.problem_from_scene(scene, scene_arrays(scene, extrema="grid"))
    assert abs(float(solve(grid, (1.0, 1.0)).base_radius_mm) / reference - 1) > 1e-4


@pytest.mark.slow
def test_pointwise_condensed_design_is_the_continuous_max():
    """Pointwise, alpha = gamma = 1: R*(theta) = -q + (gamma N C / (2 alpha sigma_max))^(2/3) where
    that is feasible (SPEC 5's stationary point); its max over theta from NumPy closed forms on a
    1e6-sample grid, polished by SciPy's bounded Brent."""
    def radius(t):
        q, c = numpy_reference(t)
        return -q + np.maximum((65.0 * c / (2 * 1230.0)) ** (2 / 3), (c / 1230.0) ** 2)

    theta = np.arange(1_000_000) * 360.0 / 1_000_000
    i = int(np.argmax(radius(theta)))
    best = minimize_scalar(lambda x: -radius(np.array([x]))[0], bounds=(theta[i - 1], theta[i + 1]),
                           method="bounded", options={"xatol": 1e-12})
    scene = camjax.load_scene()
    r = solve(P.problem_from_scene(scene, scene_arrays(scene)), (1.0, 1.0), mode="pointwise")
    # Brent's max of a smooth function is good to ~eps relative in value
    assert float(r.base_radius_mm) == pytest.approx(-best.fun, rel=1e-12)
    assert float(r.base_radius_deg) == pytest.approx(best.x, abs=1e-5)
    assert float(r.face_width_mm) == pytest.approx(2 * H * 2 / (math.pi / 3), rel=1e-14)


@pytest.mark.slow
def test_the_polish_reaches_one_optimum_from_any_start_and_is_a_stationary_point():
    """The polish (model steps safeguarded by bisection) from the bracket's ends and the grid's
    answer ends at one R for each weighting, where the envelope-theorem slope of the objective,
    alpha/N + gamma d sigma*/dR / sigma_max, checked here by a central difference of the refined
    peak stress (step 1e-5 mm: truncation ~1e-10 of the slope), is zero or the bracket's end."""
    import jax
    import jax.numpy as jnp

    from camjax.family import Weights
    from camjax.followers.flat import optimum

    scene = camjax.load_scene()
    problem = P.problem_from_scene(scene, scene_arrays(scene))
    lo = float(P.required_base_radius(problem))
    hi = float(problem.upper.base_radius_mm)
    polish = jax.jit(jax.vmap(optimum.polish, in_axes=(None, 0, 0)))
    alphas = np.array([0.05, 0.3, 1.0, 1.0, 1.0])
    gammas = np.array([1.0, 1.0, 1.0, 0.3, 0.05])
    weights = Weights(jnp.asarray(alphas), jnp.asarray(gammas))
    results = []
    for start in (lo, hi, 0.5 * (lo + hi)):
        design = P.Design(jnp.full(5, start), jnp.full(5, 10.0))
        results.append(np.asarray(polish(problem, weights, design).base_radius_mm))
    # the same optimum from every start: the search does not depend on where it begins
    np.testing.assert_allclose(results[1], results[0], rtol=1e-11)
    np.testing.assert_allclose(results[2], results[0], rtol=1e-11)
    width = float(P.required_face_width(problem))

    def peak(r):
        return float(P.exact_peak_stress(problem, P.Design(jnp.asarray(r), jnp.asarray(width))).value)

    n, sigma_max, h = float(problem.size_norm_mm), float(problem.sigma_max_MPa), 1e-5
    for r, a, g in zip(results[0], alphas, gammas, strict=True):
        slope = a / n + g * (peak(r + h) - peak(r - h)) / (2 * h) / sigma_max
        inside = lo + 1e-9 < r < hi - 1e-9
        assert (abs(slope) < 1e-8 * a / n) if inside else True, (r, a, g, slope)
        assert inside or (r <= lo + 1e-9 and slope >= 0) or (r >= hi - 1e-9 and slope <= 0)
