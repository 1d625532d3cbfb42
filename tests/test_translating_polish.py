"""Translating followers' designs keep every limit at every cam angle, not only at the samples.

For the roller, the knife edge and the curved face, a scene whose binding limit peaks between two
samples of a coarse grid (180 samples, 2 deg): the design solved on the samples (``extrema =
"grid"``) passes the limit between them, and the design solved with exact extrema (the polish of
:mod:`camjax.followers._polish`) keeps it. The reference is brute force: each constraint of the
family (its per-angle formulas, checked against finite differences of the drawn outline in the
followers' own tests) on a grid of 2 000 001 samples, whose own error at a smooth peak is
~(pi / 2e6)^2 relative, far below the 1e-7 mm the polish keeps. The polished design moves less
than the grid's error: by no more than twice the limit's deficit there (the binding radius moves
about one for one with the base radius near the crest; the pressure angle and the stress less).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import followers
from camjax.followers._polish import POLISH_MARGIN_MM, segment_peaks
from camjax.scene import builtin_scene_text, parse_scene, with_samples
from camjax.solvers.base import solve

pytestmark = pytest.mark.slow  # each case compiles a solve on the grid and one with exact extrema

SAMPLES = 180
DENSE = 2_000_001
FINE = 32 * SAMPLES


def _scene(name, *edits):
    text = builtin_scene_text(name)
    for old, new in edits:
        assert old in text, old
        text = text.replace(old, new)
    return with_samples(parse_scene(text), SAMPLES)


CASES = {
    # the knife edge's convex-radius limit binds (a sharp crest) instead of its pressure angle
    "knife_edge": (_scene("knife-edge", ("min_curvature_radius_mm = 10.0", "min_curvature_radius_mm = 25.0")),
                   "curvature"),
    # a large roller: the undercut binds
    "roller_undercut": (_scene("roller", ("roller_radius_mm = [3.0, 12.0]", "roller_radius_mm = [11.0, 12.0]"),
                               ("min_curvature_radius_mm = 1.0 #", "min_curvature_radius_mm = 6.0 #")),
                        "undercut"),
    # a small roller and a low allowable stress: the contact stress binds
    "roller_stress": (_scene("roller", ("roller_radius_mm = [3.0, 12.0]", "roller_radius_mm = 3.0"),
                             ("sigma_max_MPa = 1000.0", "sigma_max_MPa = 285.0")), "stress"),
    # the reference case: the face width (the contact's travel across it) binds
    "curved_face": (_scene("curved-face"), "face_travel"),
}


@pytest.fixture(scope="module")
def solved():
    out = {}

    def get(case):
        if case not in out:
            scene, _ = CASES[case]
            family = followers.get(scene.follower.type).problem_module()
            weights = (scene.design.alpha, scene.design.gamma)
            grid = solve(family.problem_from_scene(scene, extrema="grid"), weights, solver="gradient")
            problem = family.problem_from_scene(scene)  # with exact extrema; built once (a build compiles)
            exact = solve(problem, weights, solver="gradient")
            dense = family.problem_from_scene(scene, samples=DENSE, extrema="grid")
            # the grid's error: its design against the design solved on a grid 32 times finer
            # (whose own error is ~1000 times smaller: a limit passed between samples by the
            # constraint's curvature over half a sample, or its slope beside a joint)
            fine = solve(family.problem_from_scene(scene, samples=FINE, extrema="grid"), weights, solver="gradient")
            out[case] = (family, grid, exact, dense, problem, fine)
        return out[case]

    return get


@functools.partial(jax.jit, static_argnums=0)
def _segment_peaks(family, problem, design):
    """segment_peaks of the family's polished constraints: one compiled program per family and
    grid, for the samples' design and the polished one, and for the cases of one family."""
    return segment_peaks(problem, design, family.constraints, family.exact_constraints(problem),
                         program=problem.model.program, at=lambda j, t: family.problem_at(problem, j, t))


def _refined_maxima(family, problem, design) -> dict[str, float]:
    """Each polished constraint's exact max (mm): the largest of its refined segment peaks."""
    peaks = _segment_peaks(family, problem, jax.tree.map(jnp.asarray, design))
    return dict(zip(family.exact_constraints(problem), (float(v) for v in jnp.max(peaks, axis=1)), strict=True))


@functools.partial(jax.jit, static_argnums=0)
def _constraints(family, problem, design):
    """The family's constraints at every angle of ``problem``: one compiled program per family and
    grid (op by op, each operation compiles and runs unfused over the 2 000 001 samples)."""
    return family.constraints(problem, design)


def _dense_maxima(family, dense, design) -> dict[str, tuple[float, float]]:
    """Each constraint's max (mm) over the dense grid, and that max's resolution (mm): the change
    of the constraint over one sample beside the best one (the smaller of its two neighbours',
    as a peak at a joint, where s'' jumps, is a one-sided limit next to the jump)."""
    g = _constraints(family, dense, jax.tree.map(jnp.asarray, design))
    out = {}
    for name, v in g._asdict().items():
        v = np.asarray(v)
        i = int(np.argmax(v))
        step = min(abs(v[i] - v[i - 1]), abs(v[(i + 1) % v.size] - v[i]))
        out[name] = (float(v[i]), float(step))
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_the_samples_design_breaks_the_limit_between_the_samples_and_the_polished_one_keeps_it(case, solved):
    _, binding = CASES[case]
    family, grid, exact, dense, problem, fine = solved(case)
    before, after = _dense_maxima(family, dense, grid.design), _dense_maxima(family, dense, exact.design)
    deficit, resolution = before[binding]
    # the grid's design sits on the limit at its samples and passes it between them: by ~1e-3 mm
    # at 2 deg (the constraint's curvature over a half-sample, (pi / 180)^2 relative of ~10 mm)
    assert deficit > 1e-5, (case, before)
    # the exact extrema see it too (never below the dense grid's max, and within its resolution)
    exact_before = _refined_maxima(family, problem, grid.design)[binding]
    scale = float(family.size_norm(dense))
    assert deficit - 1e-12 <= exact_before <= deficit + 2 * resolution + 1e-12, (case, exact_before, deficit)
    # with exact extrema every refined max is the margin below its limit, or lower
    refined = _refined_maxima(family, problem, exact.design)
    for name, value in refined.items():
        assert value <= -POLISH_MARGIN_MM * (1 - 1e-6), (case, name, refined)
    # the polished design keeps every constraint at every angle (1e-9 relative: the dense grid's
    # own resolution of a peak it may straddle), its binding one within 1e-6 of the limit (active)
    for name, (value, _) in after.items():
        assert value <= 1e-9 * scale, (case, name, after)
    assert after[binding][0] > -1e-6 * scale, (case, after)
    assert bool(exact.feasible)
    # and moves by about the grid's error: its objective and its variables by less than twice the
    # grid's optimum is off the fine grid's (the minimum-norm step is not the optimum's own move:
    # it may take R_b where the optimum would trade the offset)
    error = max(abs(float(getattr(fine.design, n)) - float(getattr(grid.design, n))) for n in exact.design._fields)
    for name in type(exact.design)._fields:
        move = abs(float(getattr(exact.design, name)) - float(getattr(grid.design, name)))
        assert move <= 2.0 * error + 1e-12, (case, name, move, error)
    objective_error = abs(float(fine.objective - grid.objective))
    assert abs(float(exact.objective - grid.objective)) <= 2.0 * objective_error + 1e-12, (case, objective_error)
