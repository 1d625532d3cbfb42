"""Every registered follower type through the same checks: the follower contract's test list.

A follower gets all of these by being registered (a folder of ``camjax/followers``): each runs
its example scene (``Follower.example_scene``, a built-in scene with a [design]) and is held to
references independent of its own code:

- the scene's [follower] table, written back from the parsed spec, parses to the same spec;
- gradients of the design problem's objective and constraints through every design variable
  against central finite differences, and finite gradients for designs far outside the box;
- the follower riding on the exported outline (profile.csv) reproduces its motion s(theta) at the
  samples: found from the outline's points alone (a face's or a circle's contact, a slider's height
  or an arm's angle), to 1e-9 (mm or rad);
- the base circle read off the exported outline (dwells at s = 0) is the reported base radius;
- the exact extrema of the report are the extrema of a 100 000-sample grid of the same curves
  (never beaten by it, and within its resolution of them);
- result.json is strict JSON with the keys every report has; the figures are drawn;
- the command line writes the same JSON with the saved-program cache on (verify mode) and off.
"""

from __future__ import annotations

import functools
import json
import math
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import cli, followers
from camjax.scene import builtin_scene_text, parse_scene, with_samples

NAMES = followers.names()
# The quick loop (-m "not slow") runs the costly checks on the flat face; the full suite (CI) runs
# every follower through every check.
EACH_RUN = [name if name == "flat" else pytest.param(name, marks=pytest.mark.slow) for name in NAMES]  # `camjax design`
SHARED_KEYS = ("camjax_version", "scene", "dtype", "models", "samples", "cam_speed_rpm", "rotation",
               "follower_type", "segments", "kinematics", "flcd", "min_base_radius_mm", "evaluated_at", "design")


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """name -> (result.json dict, the folder `camjax design <example scene>` wrote), run once each."""
    out = {}

    def get(name):
        if name not in out:
            folder = tmp_path_factory.mktemp(name)
            scene = followers.get(name).example_scene
            assert cli.main(["design", scene, "--out", str(folder / "out"), "--dpi", "40"]) in (0, 3)
            out[name] = (json.loads((folder / "out" / "result.json").read_text()), folder / "out")
        return out[name]

    return get


@pytest.fixture(scope="module")
def runs():
    """name -> (scene, run, curves) of the example scene, computed once each."""
    out = {}

    def get(name):
        if name not in out:
            scene = camjax.load_scene(followers.get(name).example_scene)
            run = camjax.run_design(scene)
            out[name] = (scene, run, run.curves)
        return out[name]

    return get


@pytest.mark.parametrize("name", NAMES)
def test_the_example_scene_is_the_followers_and_has_a_design(name):
    f = followers.get(name)
    scene = camjax.load_scene(f.example_scene)
    assert scene.follower.type == name and scene.design is not None
    assert [v for v, _ in scene.design.variables] == list(f.variables)
    assert f.problem_module().problem_from_scene(scene) is not None


@pytest.mark.parametrize("name", NAMES)
def test_the_follower_table_written_back_parses_to_the_same_spec(name):
    """Scene round trip: the [follower] table written from the parsed spec (its keys read off the
    spec and its train) parses to an equal spec."""
    f = followers.get(name)
    text = builtin_scene_text(f.example_scene)
    scene = parse_scene(text)
    spec = scene.follower
    table = {"type": name}
    for key in f.keys:
        for holder in (spec, spec.train):
            if holder is not None and hasattr(holder, key):
                table[key] = getattr(holder, key)
    data = tomllib.loads(text)
    data["follower"] = table
    again = camjax.scene.scene_from_dict(data)
    assert again.follower == spec
    assert again.design == scene.design


def _problem_at_a_design(name):
    """The example's design problem at a design a tenth of the way from the box's centre to its
    upper corner: inside the box, at a generic point (every constraint's max over the angle has a
    single, interior argmax, and nothing is saturated). No solve: the gradients checked are the
    problem's own, at any design."""
    f = followers.get(name)
    scene = camjax.load_scene(f.example_scene)
    problem = camjax.problem_from_scene(scene)
    family = f.problem_module()
    lo, hi = family.bounds(problem)
    design = jax.tree.map(lambda a, b: a + 0.55 * (b - a), lo, hi)  # the centre + a tenth of the way up
    return family, problem, design, lo, hi


@functools.cache
def _rows_and_jacobian(name):
    """The example problem's objective and constraint maxima as one row vector, and its Jacobian:
    one compiled program each (not one per operation), shared by the two gradient tests. Reverse
    mode, as ``jax.grad`` differentiates: an unselected branch's infinite derivative turns into NaN
    there (0 * inf), which the double-``where`` guards against, not in forward mode."""
    family, problem, design, lo, hi = _problem_at_a_design(name)
    weights = camjax.family.weights_of(1.0, 1.0)

    def f(d):
        cm = family.constraint_maxima(problem, d)
        return jnp.stack([family.objective(problem, weights, d), *jax.tree.leaves(cm)])

    return jax.jit(f), jax.jit(jax.jacrev(f)), design, lo, hi


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_gradients_through_every_design_variable_match_finite_differences(name):
    f, jacobian, design, lo, hi = _rows_and_jacobian(name)
    grads = jacobian(design)
    for var in design._fields:
        span = float(getattr(hi, var) - getattr(lo, var))
        if span == 0.0:  # a fixed variable: nothing to differentiate
            continue
        h = 1e-6 * max(span, 1.0)
        up = design._replace(**{var: getattr(design, var) + h})
        down = design._replace(**{var: getattr(design, var) - h})
        fd = (f(up) - f(down)) / (2 * h)
        g = getattr(grads, var)
        # central differences: truncation ~h^2 |f'''| and round-off ~eps |f| / h (1e-10 relative);
        # every row is a smooth function of the variable at this generic design
        np.testing.assert_allclose(np.asarray(g), np.asarray(fd), rtol=1e-5, atol=1e-7 * (1 + np.abs(fd).max()),
                                   err_msg=f"{name}: d/d{var}")


@pytest.mark.slow
@pytest.mark.parametrize("name", EACH_RUN)
def test_gradients_stay_finite_far_outside_the_box(name):
    """Every row (the objective, each constraint's maximum) and its gradient through every variable
    stay finite at designs scaled far inside and outside the box: the finite-difference test's
    programs (a finite Jacobian of every row is a finite gradient of any sum of the rows)."""
    f, jacobian, design, _, _ = _rows_and_jacobian(name)
    for factor in (1e-3, 0.5, 3.0):
        far = jax.tree.map(lambda x, k=factor: x * k, design)
        rows, grads = np.asarray(f(far)), jacobian(far)
        assert all(np.all(np.isfinite(np.asarray(v))) for v in jax.tree.leaves(grads)), (name, factor)
        assert not np.any(np.isnan(rows)) and not np.isnan(np.sum(rows)), (name, factor)


def _outline(folder):
    """(names, columns) of profile.csv."""
    with open(folder / "profile.csv") as fh:
        names = fh.readline().strip().split(",")
    return names, np.loadtxt(folder / "profile.csv", delimiter=",", skiprows=1)


def _ride(m, shape, x, y, theta_deg):
    """The follower's motion at each cam angle, found from the outline's points alone: a slider's
    height (mm) or an arm's angle (rad) at which the face or circle touches the outline."""
    sigma = 1.0 if m.rotation == "ccw" else -1.0
    out = []
    for th in np.deg2rad(theta_deg):
        a = sigma * th
        xf, yf = np.cos(a) * x - np.sin(a) * y, np.sin(a) * x + np.cos(a) * y  # the fixed frame
        if not m.oscillating:
            if shape == "face":  # a face normal to the axis (+Y) rests on the highest point
                out.append(np.max(yf))
            else:  # a circle of radius r on the axis x = e rests where it first touches
                r, e = m.roller_radius_mm, m.offset_mm
                gap = r**2 - (xf - e) ** 2
                near = gap >= -1e-9 * max(r, 1.0) ** 2  # a knife edge (r = 0) touches where x = e
                out.append(np.max(np.where(near, yf + np.sqrt(np.maximum(gap, 0.0)), -np.inf)))
            continue
        d = m.pivot_distance_mm
        rad, beta = np.hypot(xf - d, yf), np.arctan2(yf, xf - d)
        if shape == "face":  # the face at f from the pivot passes through P at psi = pi + asin(f/R) - beta
            psi = np.pi + np.arcsin(m.face_offset_mm / rad) - beta
        else:  # the circle at the arm's end (l) touches P where |C - P| = r
            rf, arm = m.roller_radius_mm, m.arm_length_mm
            c = (arm**2 + rad**2 - rf**2) / (2 * arm * rad)
            psi = np.where(np.abs(c) <= 1, np.pi - beta + np.arccos(np.clip(c, -1, 1)), -np.inf)
        finite = np.isfinite(psi)
        psi = np.where(finite, np.mod(np.where(finite, psi, 0.0) + np.pi, 2 * np.pi) - np.pi, -np.inf)
        out.append(np.max(psi))
    return np.asarray(out)


@pytest.mark.slow
@pytest.mark.parametrize("name", NAMES)
def test_the_follower_riding_on_the_exported_outline_reproduces_its_motion(name, runs, written):
    scene, run, curves = runs(name)
    data, folder = written(name)
    names, table = _outline(folder)
    col = {n: table[:, k] for k, n in enumerate(names)}
    drawing = followers.drawing(name)
    m = drawing.mechanism(curves)
    if run.violations:
        pytest.skip(f"the example's geometry breaks {[v.constraint for v in run.violations]}: no single contact")
    theta = col["theta_deg"]
    ride = _ride(m, drawing.CONTACT_SHAPE, col["x_mm"], col["y_mm"], theta)
    if m.oscillating:
        s = np.deg2rad(col["swing_deg"])
        got = ride - np.deg2rad(m.arm_start_angle_deg)
        tol = 1e-9  # rad: the outline's 12 decimals of mm over lengths of ~100 mm, and round-off
    else:
        s = col["s_mm"]
        got = ride - drawing.follower_points(m, np.zeros(1))[1][0]
        tol = 1e-9  # mm: the outline's 12 decimals, and round-off of the rotation
    np.testing.assert_allclose(got, s, rtol=0, atol=tol, err_msg=name)


@pytest.mark.parametrize("name", EACH_RUN)
def test_the_base_circle_of_the_exported_outline_is_the_reported_base_radius(name, written):
    data, folder = written(name)
    names, table = _outline(folder)
    col = {n: table[:, k] for k, n in enumerate(names)}
    s = col["s_mm"] if "s_mm" in col else col["swing_deg"]
    ds = col["ds_mm_per_rad"] if "ds_mm_per_rad" in col else col["ds_rad_per_rad"]
    rest = (np.abs(s) < 1e-12) & (np.abs(ds) < 1e-12)  # samples on the base circle (a dwell at s = 0)
    assert rest.sum() >= 3, name
    radius = np.hypot(col["x_mm"], col["y_mm"])[rest]
    # the outline's 12 decimals; every report names the radius the cam is drawn at
    np.testing.assert_allclose(radius, data["evaluated_at"]["base_radius_mm"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", EACH_RUN)
def test_exact_extrema_are_those_of_a_dense_grid(name, runs):
    """Every curve's refined max and min against a 100 000-sample grid of the same curve: never
    beaten by it (beyond round-off), and within the grid's resolution of it."""
    scene, run, curves = runs(name)
    extremes = run.extremes
    assert extremes, name
    from camjax.evaluate import curve_extremes, scene_arrays

    # the solver's JSON: a translating run's design carries it as .result, a rocking run's is it
    result = getattr(run.design, "result", run.design) or {}
    drawn = followers.get(name).drawn_follower(scene, result)

    def grid(samples):
        dense_scene = with_samples(scene, samples)
        arrays = scene_arrays(dense_scene, extrema="grid")
        return curve_extremes(dense_scene, arrays, tuple(extremes), run.base_radius_mm, follower=drawn)

    dense, denser = grid(100_000), None
    for key, e in extremes.items():
        g = dense[key]
        scale = max(abs(e.max), abs(e.min), 1e-300)
        # never beaten by the grid (beyond round-off)
        assert e.max >= g.max - 1e-12 * scale and e.min <= g.min + 1e-12 * scale, (name, key, e, g)
        # and within its resolution: a grid of h = 3.6e-3 deg misses a smooth peak by about
        # |f''| h^2 / 8, ~1e-9 of the curve's scale for these laws; where it misses by more (a
        # pole of |rho| at an inflection, a kink), a grid four times as fine comes closer
        for exact, coarse, sense in ((e.max, g.max, "max"), (e.min, g.min, "min")):
            if abs(exact - coarse) > 1e-6 * scale:
                denser = denser or grid(400_003)  # not a multiple: its samples fall between
                fine = getattr(denser[key], sense)
                assert abs(exact - fine) < abs(exact - coarse), (name, key, sense, exact, coarse, fine)


@pytest.mark.parametrize("name", EACH_RUN)
def test_result_json_is_strict_and_has_the_shared_keys(name, written):
    data, folder = written(name)
    text = (folder / "result.json").read_text()
    json.loads(text, parse_constant=lambda c: pytest.fail(f"{name}: {c} in result.json"))
    missing = [k for k in SHARED_KEYS if k not in data]
    assert not missing, (name, missing)
    assert data["follower_type"] == name
    f = followers.get(name)
    for var in f.variables:
        assert math.isfinite(data["design"][var]), (name, var)


@pytest.mark.parametrize("name", EACH_RUN)
def test_the_figures_profile_and_dxf_are_written(name, runs, written):
    from PIL import Image

    scene, run, curves = runs(name)
    data, folder = written(name)
    builders = followers.drawing(name).figure_builders(curves)
    for png in builders:
        with Image.open(folder / png) as img:
            assert img.size[0] > 100 and img.size[1] > 100, (name, png)
    assert (folder / "profile.dxf").stat().st_size > 1000
    names, table = _outline(folder)
    assert table.shape == (data["samples"], len(names)) and np.all(np.isfinite(table))


# The saved-program cache against the same programs traced afresh, for every follower type:
# tests/test_cache_matrix.py (each type's sequence of runs, cold and warm, in verify mode).


@pytest.mark.slow
@pytest.mark.parametrize("name", [n for n in followers.names() if not followers.get(n).rocking])
def test_the_drawing_geometry_is_one_program_for_every_design(name):
    """A translating follower's drawing geometry takes the dimensions a design varies and the base
    radius as data: two designs of the example scene's follower (each such dimension 5 % + 0.5 mm
    larger, the base radius 2 mm larger) run one compiled program, and the other design's curves
    equal those of the geometry traced with that design's dimensions as constants (1e-12 of each
    curve's scale: constants folded into the program round differently, nothing else)."""
    from dataclasses import replace

    from camjax.evaluate import scene_arrays
    from camjax.followers._translating import _geometry_program

    kind, scene = followers.get(name), camjax.load_scene(followers.get(name).example_scene)
    # the example's own arrays (samples, exact extrema): the program the design's drawing ran
    arrays = scene_arrays(scene)
    other = replace(scene.follower, **{k: 1.05 * v + 0.5 for k, v in kind.design_numbers(scene.follower).items()})
    kind.curves(scene, arrays, 30.0)
    # counted from here: an earlier test of this process may have compiled it for other grids
    program = _geometry_program(kind.name, kind.without_design_numbers(scene.follower)[0], scene.motion.rotation)
    entries, compiled = _geometry_program.cache_info().currsize, program._cache_size()
    drawn = kind.curves(scene, arrays, 32.0, follower=other)
    # the other design: the same program (no new entry, no new compile of the one there is)
    assert _geometry_program.cache_info().currsize == entries and program._cache_size() == compiled
    constants = jax.jit(lambda a: kind.geometry(other, scene.motion.rotation, a, 32.0))(arrays)
    for field in ("profile_x_mm", "profile_y_mm", "stress_MPa", "pressure_angle_deg", "pitch_rho_mm"):
        want = getattr(constants, field)
        if want is None:
            continue
        want, got = np.asarray(want), np.asarray(getattr(drawn, field))
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.max(np.abs(want)), err_msg=field)
