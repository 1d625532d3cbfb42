"""Exact sizing and the exact smallest cam radius of curvature, against 10^6-sample grids.

With ``[motion] extrema = "exact"`` (the default) the smallest admissible base radius of every
follower whose sizing is a search (the rockers, the curved face) is the root of its limits' peak
refined between the samples (:func:`camjax.followers._sizing.exact_boundary`), and a roller
rocker's smallest cam-surface radius is 1/kappa - R at the refined max of its pitch curvature.
Each is checked against an independent brute force: the follower's own closed-form geometry on
10^6 samples (``jax.jit``), the smallest radius where its limits hold found by bisection on it.

Tolerances: a sampled extremum's error falls as N^-2 (docs/benchmarks.md, "Grid or exact
extrema"); the worst such figure at N = 360 is ~1e-3 relative, so on 10^6 samples it is
~1e-3 (360 / 10^6)^2 ~ 1e-10: the exact values must agree to DENSE_TOL = 1e-9 relative, and the
grid's must miss by more (so that the check can tell the two apart).
"""

import dataclasses
import math
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax.followers.curved_face import geometry as curved_geo
from camjax.followers.oscillating_curved_face import geometry as rocker_curved_geo
from camjax.followers.oscillating_flat import geometry as rocker_flat_geo
from camjax.followers.oscillating_roller import geometry as rocker_roller_geo
from camjax.pipeline import design_report
from camjax.program import evaluate as evaluate_program

DENSE = 1_000_000
DENSE_TOL = 1e-9  # relative; the 10^6-sample grid's own error is ~1e-10 (module docstring)
N = 360


# the oscillating roller's scene with the pivot its design ends at: the pressure angle then admits
# arm start angles in a narrow window only (rise and return bind from either side), which the
# exact sizing must not step over; a pivot 1e-5 mm off and the window is gone between the samples
NARROW = "oscillating-roller-narrow"
NARROW_PIVOT_MM = 69.51200860910005
CLOSED = "oscillating-roller-closed"
CLOSED_PIVOT_MM = 69.512


def _scene(name, samples=N, extrema="exact"):
    scene = camjax.load_scene(name.removesuffix("-narrow").removesuffix("-closed"))
    if name in (NARROW, CLOSED):
        pivot = NARROW_PIVOT_MM if name == NARROW else CLOSED_PIVOT_MM
        scene = dataclasses.replace(scene, follower=dataclasses.replace(scene.follower, pivot_distance_mm=pivot))
    return dataclasses.replace(scene, design=None,
                               motion=dataclasses.replace(scene.motion, samples=samples, extrema=extrema))


def _dense_kin(scene):
    """The scene's kinematics on its grid: the program alone, so that scenes of one motion (the
    oscillating roller's variants and its curved face) share one compiled program."""
    return evaluate_program(scene.motion.program, scene.motion.samples)


# The closed-form geometry's excess as programs of the design and the scene's numbers (arguments,
# not constants): the rocking roller's scenes and the rocking curved face share one program.
@partial(jax.jit, static_argnames="rotation")
def _rocker_flat_excess(rb, kin, pivot, face_offset, min_rho, rotation):
    g = rocker_flat_geo.oscillating_flat_geometry(pivot, face_offset, rb, kin, rotation)
    return min_rho - jnp.min(g.radius_of_curvature)


@partial(jax.jit, static_argnames="rotation")
def _curved_face_excess(rb, kin, face_radius, offset, min_rho, lim, rotation):
    g = curved_geo.geometry(rb, face_radius, offset, kin, rotation, min_rho)
    return jnp.maximum(jnp.max(jnp.abs(g.pressure_angle)) - lim, -jnp.min(g.undercut_margin))


@partial(jax.jit, static_argnames="rotation")
def _rocker_roller_excess(rb, kin, pivot, arm, radius, min_rho, lim, rotation):
    g = rocker_roller_geo.oscillating_roller_geometry(pivot, arm, radius, rb + radius, kin, rotation, min_rho)
    return jnp.maximum(jnp.max(jnp.abs(g.pressure_angle)) - lim, -jnp.min(g.undercut_margin))


def _excess(name, scene):
    """excess(R_b) on the scene's grid: the largest violation of the sizing's limits (<= 0:
    admissible), from the follower's closed-form geometry (jitted in R_b)."""
    f, rotation = scene.follower, scene.motion.rotation
    kin = _dense_kin(scene)
    if name == "oscillating-flat":
        return partial(_rocker_flat_excess, kin=kin, pivot=f.pivot_distance_mm, face_offset=f.face_offset_mm,
                       min_rho=f.min_curvature_radius_mm, rotation=rotation)
    if name == "curved-face":
        lim = min(math.radians(f.max_pressure_angle_deg),
                  float(curved_geo.face_travel_limit_rad(f.face_radius_mm, f.face_width_mm)))
        return partial(_curved_face_excess, kin=kin, face_radius=f.face_radius_mm, offset=f.offset_mm,
                       min_rho=f.min_curvature_radius_mm, lim=lim, rotation=rotation)
    radius = f.roller_radius_mm if name.startswith("oscillating-roller") else f.face_radius_mm
    lim = math.radians(f.max_pressure_angle_deg)
    if name == "oscillating-curved-face":
        lim = min(lim, float(rocker_curved_geo.face_travel_limit_rad(f.face_radius_mm, f.face_width_mm)))
    return partial(_rocker_roller_excess, kin=kin, pivot=f.pivot_distance_mm, arm=f.arm_length_mm, radius=radius,
                   min_rho=f.min_curvature_radius_mm, lim=lim, rotation=rotation)


def _dense_boundary(excess, lo, hi, steps=36):
    """The smallest R_b in [lo, hi] with excess <= 0 (bisection; excess(lo) > 0 >= excess(hi) to
    round-off; 36 halvings of a bracket ~1e-2 wide: ~2e-13 relative)."""
    assert float(excess(lo)) > 0 >= float(excess(hi)) - 1e-12
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if float(excess(mid)) > 0 else (lo, mid)
    return hi


SIZED = ["oscillating-roller", NARROW, "oscillating-flat", "oscillating-curved-face", "curved-face"]


@pytest.mark.slow
@pytest.mark.parametrize("name", SIZED)
def test_exact_sizing_against_a_dense_grid(name):
    exact = design_report(_scene(name))["min_base_radius_mm"]
    grid = design_report(_scene(name, extrema="grid"))["min_base_radius_mm"]
    excess = _excess(name, _scene(name, DENSE, "grid"))
    # bracketed by the exact radius itself (admissible, asserted below): in the narrow window 1% more
    # is past the window's far side
    dense = _dense_boundary(excess, grid * (1 - 1e-2), exact)
    # never below the grid's (the grid misses peaks between its samples: its radius is too small)
    assert exact >= grid
    # the dense grid's boundary, to its own error; the grid's misses it by far more
    assert exact == pytest.approx(dense, rel=DENSE_TOL)
    assert abs(grid - dense) > 100 * DENSE_TOL * dense
    # admissible on the dense grid (its samples cannot exceed the refined peak, <= 0 at the root)
    assert float(excess(exact)) <= 1e-12


@pytest.mark.slow
def test_a_window_only_the_samples_see_is_refused():
    """Where the samples admit an arm start angle but no angle keeps the pressure angle between
    them, the exact sizing refuses the scene (as the grid's does where no sample admits one), and
    the grid's radius is indeed inadmissible on 10^6 samples."""
    grid = design_report(_scene(CLOSED, extrema="grid"))["min_base_radius_mm"]
    assert float(_excess(CLOSED, _scene(CLOSED, DENSE, "grid"))(grid)) > 0
    with pytest.raises(camjax.SceneError, match="at every cam angle"):
        design_report(_scene(CLOSED))


@pytest.mark.slow
@pytest.mark.parametrize("name", ["oscillating-roller", "oscillating-curved-face"])
def test_roller_rocker_smallest_cam_radius_against_a_dense_grid(name):
    report = design_report(_scene(name))
    rb = report["evaluated_at"]["base_radius_mm"]
    exact = report["evaluated"]["rho_mm"]["min"]
    grid = design_report(_scene(name, extrema="grid"), base_radius_mm=rb)["evaluated"]["rho_mm"]["min"]
    scene = _scene(name, DENSE, "grid")
    f = scene.follower
    radius = f.roller_radius_mm if name == "oscillating-roller" else f.face_radius_mm
    g = rocker_roller_geo.oscillating_roller_geometry(f.pivot_distance_mm, f.arm_length_mm, radius, rb + radius,
                                                      _dense_kin(scene), scene.motion.rotation)
    rho = np.asarray(g.cam_radius_of_curvature)
    assert np.all(np.asarray(g.pitch_curvature) > 0)  # convex everywhere: no pole of rho
    dense = float(np.min(rho))
    # a min over every angle is never above the samples' (nor the dense grid's, to round-off)
    assert exact <= grid
    assert exact <= dense + 1e-12 * abs(dense)
    assert exact == pytest.approx(dense, rel=DENSE_TOL)
    assert abs(grid - dense) > 100 * DENSE_TOL * abs(dense)


@pytest.mark.slow
def test_exact_boundary_of_a_known_limit():
    """One limit whose boundary is the max of a motion curve: g(theta; x) = s'(theta) - x, so the
    smallest admissible x is max s' (brute force: the 10^6-sample grid's max, to its ~1e-10
    relative error); the grid's, at 30 samples, is its largest sample and misses it."""
    from camjax.followers import _sizing

    scene = _scene("default", samples=30)
    arrays = camjax.scene_arrays(scene)
    kin = arrays.kin
    grid_x = float(np.max(np.asarray(kin.ds)))
    dense = _scene("default", DENSE, "grid")
    top = float(np.max(np.asarray(_dense_kin(dense).ds)))
    b = _sizing.exact_boundary(arrays.model.program, kin, jnp.asarray(grid_x), jnp.asarray(1e3), (),
                               limits=_velocity_limit)
    assert grid_x < top * (1 - 1e-6)  # the grid misses the peak
    assert float(b.x) >= grid_x and bool(b.refined)
    assert float(b.x) == pytest.approx(top, rel=DENSE_TOL)
    assert float(b.peak) <= 0.0


def _velocity_limit(kin, x, params):
    return (kin.ds - x)[None]
