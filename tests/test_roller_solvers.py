"""The roller design problem solved by every registered solver and mode, against independent optima:
a dense scan over (R_b, R_f, e), the closed-form/bisection prime radius, and SciPy."""

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax.followers.roller import geometry as roller_geo
from camjax.followers.roller import problem as R
from camjax.scene import with_design
from camjax.solvers import scipy_roller
from camjax.solvers.base import solve
from camjax.solvers.registry import MODES, SOLVERS


@pytest.fixture(scope="module")
def scene():
    return camjax.load_scene("roller")


@pytest.fixture(scope="module")
def size_only(scene):
    # the built-in roller scene has gamma = 0; on the grid: the references here scan the samples
    return R.problem_from_scene(scene, extrema="grid")


# The scene's arrays and problems built once: each build compiles its program again.
@pytest.fixture(scope="module")
def kin(scene):
    return camjax.scene_arrays(scene).kin


@pytest.fixture(scope="module")
def fixed_roller_and_offset(scene):
    """R_f = 5 mm and e = 1 mm fixed, size only: the pointwise design (largest R_b over the
    angles) is then the global one."""
    fixed = with_design(scene, roller_radius_mm=5.0, offset_mm=1.0, gamma=0.0).design
    return R.problem_from_scene(dataclasses.replace(scene, design=fixed), extrema="grid")


def dense_scan_prime_radius(scene, kin, zooms=3, grid=(41, 11, 41)):
    """Smallest feasible R_b + R_f over a grid of (R_b, R_f, e) in the [design] box, zoomed.

    Feasibility straight from the geometry (max |phi| <= limit, smallest convex cam radius >=
    min_curvature_radius_mm), not from the problem's constraint functions.
    """
    f, d = scene.follower, scene.design
    lim = math.radians(f.max_pressure_angle_deg)

    def cost(rb, rf, e):
        g = roller_geo.roller_geometry(rb, rf, e, kin, scene.motion.rotation, f.min_curvature_radius_mm)
        ok = (jnp.max(jnp.abs(g.pressure_angle)) <= lim) & (jnp.min(g.undercut_margin) >= 0)
        return jnp.where(ok, rb + rf, jnp.inf)

    cost = jax.jit(jax.vmap(cost))
    box = [d.bounds(name) for name in ("base_radius_mm", "roller_radius_mm", "offset_mm")]
    lo, hi = np.array([b[0] for b in box]), np.array([b[1] for b in box])
    box_lo, box_hi = lo.copy(), hi.copy()
    for _ in range(zooms + 1):
        axes = [np.linspace(lo[i], hi[i], grid[i]) for i in range(3)]
        pts = [x.ravel() for x in np.meshgrid(*axes, indexing="ij")]
        c = np.asarray(cost(*map(jnp.asarray, pts)))
        k = int(np.argmin(c))
        best = np.array([p[k] for p in pts])
        cell = 2 * (hi - lo) / (np.array(grid) - 1)
        lo, hi = np.maximum(best - cell, box_lo), np.minimum(best + cell, box_hi)
    return float(c[k]), best


@functools.partial(jax.jit, static_argnames="rotation")
def _prime_radii(kin, roller_radius_mm, offsets_mm, max_pressure_angle_rad, min_curvature_radius_mm, rotation):
    """The smallest admissible R_p (closed form + bisection) at each offset: one compiled program
    per number of offsets, whatever the scene's values (the scans of every test here)."""
    return jax.vmap(lambda e: roller_geo.roller_min_prime_radius(
        kin, roller_radius_mm, e, max_pressure_angle_rad, min_curvature_radius_mm, rotation).prime_radius_mm)(offsets_mm)


def prime_radii(scene, kin, roller_radius_mm, offsets_mm):
    """_prime_radii of the scene's follower on the grid ``kin``."""
    f = scene.follower
    return np.asarray(_prime_radii(kin, roller_radius_mm, jnp.asarray(offsets_mm),
                                   math.radians(f.max_pressure_angle_deg), f.min_curvature_radius_mm,
                                   scene.motion.rotation))


def exact_offset_scan(scene, kin):
    """min over e of the smallest admissible R_p(e) (closed form + bisection), golden-refined in e
    (``kin``: the scene's kinematics on its grid)."""
    d = scene.design
    rf = d.bounds("roller_radius_mm")[0]  # with gamma = 0 the smallest roller is best: undercut only gets easier
    es = np.linspace(*d.bounds("offset_mm"), 801)
    k = int(np.argmin(prime_radii(scene, kin, rf, es)))
    a, b = es[max(k - 1, 0)], es[min(k + 1, len(es) - 1)]
    g = (math.sqrt(5) - 1) / 2
    for _ in range(80):
        x1, x2 = b - g * (b - a), a + g * (b - a)
        r1, r2 = prime_radii(scene, kin, rf, [x1, x2])
        a, b = (a, x2) if r1 < r2 else (x1, b)
    e = 0.5 * (a + b)
    return float(prime_radii(scene, kin, rf, [e, e])[0]), e  # a pair: the golden section's program


@pytest.mark.slow
def test_gradient_finds_the_optimal_offset(scene, size_only, kin):
    sol = solve(size_only, (1.0, 0.0), solver="gradient")
    assert bool(sol.feasible) and sol.status_name == "converged"
    rp = float(sol.base_radius_mm + sol.roller_radius_mm)
    exact_rp, exact_e = exact_offset_scan(scene, kin)
    scan_rp, scan_x = dense_scan_prime_radius(scene, kin)
    # the scan's best feasible point is feasible, so the optimum can only be smaller; the scan's
    # final cells (8e-4 mm in R_b, 1e-3 mm in e) bound how much smaller: a few um
    assert exact_rp <= scan_rp <= exact_rp + 5e-3
    assert abs(scan_x[2] - exact_e) < 5e-2
    # the solver reaches the exact optimum to its feasibility tolerance (1e-6 mm)
    assert rp == pytest.approx(exact_rp, abs=1e-6)
    assert float(sol.offset_mm) == pytest.approx(exact_e, abs=1e-5)
    # and the offset pays: against e = 0 the prime circle shrinks by 29 % (the example)
    centred = R.problem_from_scene(with_design(scene, offset_mm=0.0), extrema="grid")
    rp0 = float(solve(centred, (1.0, 0.0), solver="gradient").size_mm)
    assert 1 - rp / rp0 == pytest.approx(0.29, abs=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("mode", MODES)
def test_every_solver_and_mode_solves_the_roller_problem(scene, kin, fixed_roller_and_offset, solver, mode):
    problem = fixed_roller_and_offset
    sol = solve(problem, (1.0, 0.0), mode=mode, solver=solver)
    # R_f = 5 mm, e = 1 mm as a pair: the program of exact_offset_scan's golden section
    ref_rp = prime_radii(scene, kin, 5.0, [1.0, 1.0])[0]
    # gradient and hybrid to the feasibility tolerance; the GA (200 generations, decaying
    # mutation) to 1e-3 mm (measured ~1e-5)
    tol = 1e-3 if solver == "ga" else 1e-6
    assert float(sol.base_radius_mm) == pytest.approx(float(ref_rp) - 5.0, abs=tol)
    assert bool(sol.feasible) or solver == "ga"
    assert float(sol.roller_radius_mm) == 5.0 and float(sol.offset_mm) == 1.0
    out = sol.to_json(problem)
    assert out["prime_radius_mm"] == pytest.approx(out["base_radius_mm"] + 5.0, rel=1e-15)
    assert sol.record(problem)["offset_mm"] == 1.0


@pytest.fixture(scope="module")
def with_stress(scene):
    return R.problem_from_scene(dataclasses.replace(scene, design=dataclasses.replace(scene.design, gamma=1.0)),
                                extrema="grid")


@pytest.mark.slow
@pytest.mark.parametrize("weights", [(1.0, 1.0), (0.5, 1.0), (1.0, 0.1)])
def test_gradient_matches_scipy_slsqp_with_stress(with_stress, weights):
    problem = with_stress
    ours = solve(problem, weights, solver="gradient")
    ref = scipy_roller.slsqp(problem, *weights)
    assert ref.success and ref.max_violation < 1e-9
    # both converge to the same KKT point; SLSQP's finite-difference Jacobians limit it to ~1e-8
    assert float(ours.objective) == pytest.approx(ref.objective, rel=1e-7)
    assert bool(ours.feasible)


def _dense_max_pressure_angle_deg(scene, design, samples: int = 720_001) -> float:
    """max |phi| (deg) of a roller design over a dense grid, from the harmonic law in NumPy:
    s = L (1 - cos(pi x)) / 2 on a rise (mirrored on a return), x = (theta - start) / beta, and
    tan phi = (s' - e) / (d + s) with d = sqrt(R_p^2 - e^2) (ccw)."""
    theta = np.linspace(0.0, 360.0, samples)
    s, ds = np.zeros_like(theta), np.zeros_like(theta)
    start, level = 0.0, 0.0
    prog = scene.motion.program
    for kind, width, law, lift in zip(prog.kinds, prog.angles_deg, prog.laws, np.asarray(prog.lifts),
                                      strict=True):
        inside = (theta >= start) & (theta <= start + width)
        if kind != "dwell":
            assert law.name == "harmonic"
            x = (theta[inside] - start) / width
            sign = 1.0 if kind == "rise" else -1.0
            s[inside] = level + sign * lift * (1 - np.cos(np.pi * x)) / 2
            ds[inside] = sign * lift * np.pi / math.radians(width) * np.sin(np.pi * x) / 2
            level += sign * lift
        else:
            s[inside] = level
        start += width
    rp = float(design.base_radius_mm + design.roller_radius_mm)
    e = float(design.offset_mm)
    phi = np.arctan2(ds - e, math.sqrt(rp * rp - e * e) + s)
    return float(np.degrees(np.max(np.abs(phi))))


@pytest.mark.slow
def test_exact_extrema_keep_the_pressure_angle_between_the_samples(scene, size_only):
    """Solved on the 1 deg grid, the prime circle sits on the limit at the samples and passes it
    between them (the dense NumPy scan finds |phi| above 30 deg); with exact extrema (the scene's
    default) the polish moves the design until the dense max is the limit itself, to 1e-6 deg (the
    dense grid's own error at a smooth max is ~1e-9 deg; the polish keeps 1e-7 mm of margin, ~1e-7
    deg), never above it, moving no variable by more than 1e-4 mm."""
    limit = scene.follower.max_pressure_angle_deg
    grid = solve(size_only, (1.0, 0.0), solver="gradient")
    exact = solve(R.problem_from_scene(scene), (1.0, 0.0), solver="gradient")
    assert _dense_max_pressure_angle_deg(scene, grid.design) > limit + 1e-5
    assert _dense_max_pressure_angle_deg(scene, exact.design) == pytest.approx(limit, abs=1e-6)
    assert _dense_max_pressure_angle_deg(scene, exact.design) <= limit * (1 + 1e-9)
    assert bool(exact.feasible)
    for name in ("base_radius_mm", "roller_radius_mm", "offset_mm"):
        assert abs(float(getattr(exact, name) - getattr(grid, name))) < 1e-4, name


def test_an_offset_box_that_never_cuts_the_prime_circle_is_refused(scene):
    # R_p <= 2 + 3 = 5 mm everywhere in the box, |e| >= 6 mm: no design can work
    from camjax.scene import SceneError

    with pytest.raises(SceneError, match=r"design\.offset_mm.*every design in the bounds"):
        with_design(scene, base_radius_mm=[1.0, 2.0], roller_radius_mm=3.0, offset_mm=[6.0, 8.0])


@pytest.mark.slow
@pytest.mark.parametrize("solver", ["gradient", "hybrid"])
def test_a_box_with_offsets_past_some_prime_circles_is_solved_to_its_optimum(scene, kin, solver):
    """The issue's box, R_b in [1, 40] mm with e in [-5, 5] mm, holds designs with |e| >= R_p
    (R_b + R_f down to 4 mm): |e| < R_p is then a constraint (the pressure angle's, on the base
    circle's dwell), not a reason to refuse the box. The optimum lies inside the smaller box of
    test_gradient_finds_the_optimal_offset, so both must equal the exact offset scan's optimum
    (to the solvers' feasibility tolerance, 1e-6 mm)."""
    wide = with_design(scene, base_radius_mm=[1.0, 40.0], offset_mm=[-5.0, 5.0], gamma=0.0)
    sol = solve(R.problem_from_scene(wide, extrema="grid"), (1.0, 0.0), solver=solver)
    rp = float(sol.base_radius_mm + sol.roller_radius_mm)
    assert bool(sol.feasible) and abs(float(sol.offset_mm)) < rp
    exact_rp, _ = exact_offset_scan(wide, kin)  # the same motion: the scene's kinematics
    assert rp == pytest.approx(exact_rp, abs=1e-6)
