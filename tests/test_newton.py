"""camjax.solvers.newton: the interior-point optimum equals SciPy SLSQP's on every follower type's example
scene (three weightings through one compiled program per type), its certificate's dF*/d limit matches
central finite differences of re-solved optima, and the certificate reaches result.json from one program
in global and pointwise mode and for the GA's and the hybrid's final points."""

import dataclasses
import functools
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import followers
from camjax.family import weights_of
from camjax.solvers import certificate, epigraph, limits, newton, scipy_family
from camjax.solvers.base import family_of, problem_from_scene, solve

pytest.importorskip("scipy")

SAMPLES = 90
WEIGHTINGS = ((1.0, 1.0), (0.9, 0.1), (0.1, 0.9))
# One compiled program per follower type for every batch of certificates in this file: rows of
# (problem, weights) pairs, len(WEIGHTINGS) at a time (the sensitivities' moved problems padded).
_certify_rows = jax.jit(jax.vmap(newton.certify))


@functools.cache
def _problem(scene_name, samples=SAMPLES):
    """The built-in scene's problem on ``samples`` grid angles, built once (a build compiles its
    program again)."""
    scene = camjax.load_scene(scene_name)
    scene = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, samples=samples, extrema="grid"))
    return problem_from_scene(scene)


def _stacked(trees):
    return jax.tree.map(lambda *x: jnp.stack(x), *trees)


def _row(tree, i):
    return jax.tree.map(lambda x: x[i], tree)


def _certify_all(problems, w):
    """newton.certify of each problem at weights ``w`` through ``_certify_rows``: the problems in
    batches of len(WEIGHTINGS) rows, the last one padded with the first problem."""
    rows = len(WEIGHTINGS)
    padded = list(problems) + [problems[0]] * (-len(problems) % rows)
    ws = _stacked([w] * rows)
    certs = [jax.device_get(_certify_rows(_stacked(padded[i:i + rows]), ws)) for i in range(0, len(padded), rows)]
    return [_row(c, i) for c in certs for i in range(rows)][: len(problems)]


@functools.cache
def _example_certificates(name):
    """The example scene of follower type ``name`` at SAMPLES grid angles and its certificates at
    the three weightings (one call of ``_certify_rows``)."""
    problem = _problem(followers.get(name).example_scene)
    w = weights_of([a for a, _ in WEIGHTINGS], [g for _, g in WEIGHTINGS])
    return problem, jax.device_get(_certify_rows(_stacked([problem] * len(WEIGHTINGS)), w))


@pytest.fixture(scope="module", params=followers.names())
def solved(request):
    """The three weightings of one follower type through one compiled program, and SLSQP on each."""
    name = request.param
    problem, certs = _example_certificates(name)
    return name, problem, certs, [scipy_family.slsqp(problem, a, g) for a, g in WEIGHTINGS]


@pytest.mark.slow
def test_matches_slsqp(solved):
    """Both stop at a KKT point of the same grid problem (SLSQP with ftol 1e-12, newton with the
    barrier at 1e-11: its objective above the optimum by about rows * mu ~ 1e-9 of F): 1e-7
    relative leaves margin. Iterations (the steps of the central paths followed, one at a time):
    the issue's aim, a median of 40 per weighting, on the three, and no case over 60 (the first
    path's steps here; the knife edge's whole grid takes 135,
    :func:`test_exchange_rounds_reach_the_whole_grids_optimum`)."""
    name, problem, certs, refs = solved
    fam = family_of(problem)
    iterations = np.asarray(certs.result.iterations)
    assert np.median(iterations) <= 40 and iterations.max() <= 60, (name, iterations)
    for i, ((a, g), ref) in enumerate(zip(WEIGHTINGS, refs, strict=True)):
        cert = jax.tree.map(lambda x, i=i: x[i], certs)
        w = weights_of(a, g)
        ev = fam.evaluate(problem, w, cert.result.design)
        assert bool(ev.feasible), (name, a, g)
        assert ref.max_violation < 1e-9
        assert bool(cert.result.converged), (name, a, g)
        assert abs(float(ev.objective) / ref.objective - 1.0) < 1e-7, (name, a, g)
        assert max(float(x) for x in cert.result.kkt) <= newton.DEFAULT_SETTINGS.tol
        # the multipliers reproduce the objective's unit weight: the epigraph rows' sum to 1
        n = problem.theta_deg.shape[-1]
        np.testing.assert_allclose(float(np.sum(np.asarray(cert.result.multipliers)[:n])), 1.0, rtol=1e-8)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["roller", "oscillating_roller"])
def test_size_only_matches_slsqp(name):
    """alpha = 1, gamma = 0 (the built-in roller scenes' weighting; the size alone, every angle's
    objective row equal): converged within 60 iterations (as above), feasible, the objective
    within 1e-7 of SLSQP's (both stop at a KKT point of the same problem, as above), and the one
    row that holds t carries the objective's unit multiplier. The example scene's problem of
    test_matches_slsqp through its compiled program (SAMPLES grid angles: the degenerate objective,
    equal on every row, is the same on any grid)."""
    problem, _ = _example_certificates(name)
    cert = _certify_all([problem], weights_of(1.0, 0.0))[0]
    ref = scipy_family.slsqp(problem, 1.0, 0.0)
    ev = family_of(problem).evaluate(problem, weights_of(1.0, 0.0), cert.result.design)
    assert bool(cert.result.converged) and bool(ev.feasible)
    assert int(cert.result.iterations) <= 60
    assert ref.max_violation < 1e-9
    assert abs(float(ev.objective) / ref.objective - 1.0) < 1e-7
    np.testing.assert_allclose(float(np.asarray(cert.result.multipliers)[0]), 1.0, rtol=1e-8)


def _moved(problem, key, value):
    """The problem with one limit (a scene key of the certificate, or 'lower.<field>' / 'upper.<field>',
    a bound) set to value."""
    if key.startswith(("lower.", "upper.")):
        side, field = key.split(".", 1)
        box = getattr(problem, side)
        return problem._replace(**{side: box._replace(**{field: jnp.asarray(value, problem.theta_deg.dtype)})})
    return limits.limit_setters(problem)[key](problem, jnp.asarray(value, problem.theta_deg.dtype))


@pytest.mark.slow
@pytest.mark.parametrize("name,alpha,gamma", [("roller", 0.1, 0.9), ("oscillating_flat", 1.0, 1.0)])
def test_sensitivities_match_finite_differences(name, alpha, gamma):
    """Each reported dF*/d limit (envelope theorem) against a central difference of the optimum
    re-solved with that limit moved by +-h (all re-solves in one compiled program): sigma_max_MPa
    (h = 1 MPa), max_pressure_angle_deg (h = 0.05 deg, where the follower has one) and the bound
    with the largest reported sensitivity (h = 0.01 mm; it must be active: the roller's radius at
    its upper bound, the rocker's pivot distance at its lower one at these weightings). F* is
    smooth in a limit while the active set stays the same; the truncation error is ~h^2 F''' and
    each optimum is within ~1e-9 of F*, so ~1e-9 / (2 h) in the derivative: rtol 1e-4 plus an atol
    of 1e-7 per unit of the limit leaves margin."""
    # the unmoved problem: the example scene's certificate at this weighting (test_matches_slsqp's);
    # the re-solves through the same compiled program
    problem, certs = _example_certificates(name)
    first = _row(certs, WEIGHTINGS.index((alpha, gamma)))
    w = weights_of(alpha, gamma)
    fields = list(problem.lower._fields)
    bound_sens = np.asarray(first.bound_sensitivity)
    index = int(np.argmax(np.abs(bound_sens)))
    assert abs(bound_sens[index]) > 1e-4, "no active bound to check"
    side, field = ("lower", "upper")[index // len(fields)], fields[index % len(fields)]
    bound_key = f"{side}.{field}"
    steps = {"sigma_max_MPa": 1.0, "max_pressure_angle_deg": 0.05, bound_key: 0.01}
    values = {**{k: float(v) for k, v in limits.limit_values(problem).items()},
              bound_key: float(getattr(getattr(problem, side), field))}
    keys = [k for k in steps if k in values]
    batch = [_moved(problem, k, values[k] + sign * steps[k]) for k in keys for sign in (1, -1)]
    certs = [first, *_certify_all(batch, w)]
    assert all(bool(c.result.converged) for c in certs)
    objective = [float(family_of(p).objective(p, w, c.result.design))
                 for p, c in zip([problem, *batch], certs, strict=True)]
    base = first
    block = certificate.certificate_json(problem, base)
    for j, key in enumerate(keys):
        fd = (objective[1 + 2 * j] - objective[2 + 2 * j]) / (2 * steps[key])
        if key == bound_key:
            reported = float(np.asarray(base.bound_sensitivity)[index])
        else:
            reported = block["dF_dlimit"][key]
        np.testing.assert_allclose(reported, fd, rtol=1e-4, atol=1e-7, err_msg=key)
    assert block["dF_dlimit"]["sigma_max_MPa"] < 0  # a larger allowable stress never makes it worse


def test_certify_point_recovers_the_multipliers_at_the_optimum():
    """At newton's optimum the least-squares multipliers on the active rows (the GA's and the
    hybrid's certificate) satisfy KKT to the solver's accuracy and give the same dF*/d sigma_max
    (the active set is the rows within 1e-6 of their limit; the solver's inactive rows carry
    multipliers ~mu / slack ~1e-6 that the fit leaves out: a relative 1e-4 between the two)."""
    # the grid the sweep tests solve on (tests/test_sweep.py): its design program is compiled once
    problem = _problem("default", samples=360)
    w = weights_of(1.0, 1.0)
    # newton.certify in the solve's program (test_solution_json_carries_the_certificate's)
    cert = solve(problem, (1.0, 1.0), mode="global", solver="newton").certificate
    point = jax.jit(certificate.certify_point)(problem, w, cert.result.design)
    assert float(point.result.kkt.error) < 1e-6
    a = certificate.certificate_json(problem, cert)["dF_dlimit"]["sigma_max_MPa"]
    b = certificate.certificate_json(problem, point, solver="ga")["dF_dlimit"]["sigma_max_MPa"]
    np.testing.assert_allclose(b, a, rtol=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("mode,solver", [("global", "newton"), ("pointwise", "newton"), ("global", "ga")])
def test_solution_json_carries_the_certificate(mode, solver):
    """solve(...).to_json: the certificate computed in the solve's own program, for newton in both
    modes (pointwise: the critical angle's one-angle problem) and for the GA's final point."""
    problem = _problem("default")
    out = solve(problem, (1.0, 1.0), mode=mode, solver=solver).to_json(problem)
    cert = out["certificate"]
    for key in ("stationarity", "primal_feasibility", "complementarity", "iterations", "active", "limited_by"):
        assert key in cert, key
    assert cert["active"], "a bounded problem's optimum has an active constraint"
    if solver == "newton":
        assert cert["converged"]
        assert max(cert["stationarity"], cert["primal_feasibility"], cert["complementarity"]) <= 1e-9
    if mode == "pointwise":
        assert 0.0 <= cert["critical_angle_deg"] < 360.0
    for row in cert["active"]:
        assert row["limit"] and row["multiplier"] > 0.0, row
        assert (row["theta_deg"] is None) == (row["kind"] == "bound"), row


@pytest.mark.slow
@pytest.mark.parametrize("mode", ["global", "pointwise"])
def test_a_gradient_design_carries_its_final_points_certificate(mode):
    """The gradient solver certifies nothing itself: a design's JSON
    (:func:`camjax.solvers.certificate.solution_json`, what ``camjax design`` writes) carries its final
    point's certificate (multipliers fitted on the active rows). It names the rows newton's binds
    (kind and angle) and prices the stress limit as newton's certificate does, within ten times the
    stationarity residual it reports, plus 1e-8 (the fitted multipliers are as good as the point is
    stationary; measured on this grid: stationarity 4.2e-12 and a relative 1.8e-9 in global mode,
    5.8e-14 and 1.9e-10 in pointwise mode; the default scene's 360 samples through ``camjax design``:
    8.5e-4 and 1.1e-3), on the grid of test_solution_json_carries_the_certificate (newton's program
    compiled there)."""
    problem = _problem("default")
    got = certificate.solution_json(problem, solve(problem, (1.0, 1.0), mode=mode, solver="gradient"))["certificate"]
    ref = solve(problem, (1.0, 1.0), mode=mode, solver="newton").to_json(problem)["certificate"]
    assert got["method"] == certificate.METHODS["gradient"]
    assert {(r["kind"], r["theta_deg"]) for r in got["active"]} == {(r["kind"], r["theta_deg"]) for r in ref["active"]}
    assert got["limited_by"] == ref["limited_by"]
    tol = 10 * got["stationarity"] + 1e-8
    a, b = got["dF_dlimit"]["sigma_max_MPa"], ref["dF_dlimit"]["sigma_max_MPa"]
    assert abs(a / b - 1.0) <= tol, (a, b, tol)
    assert got["primal_feasibility"] == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("scene_name", ["default", "oscillating-flat"])
def test_design_with_newton_writes_the_certificate_and_names_what_limits(scene_name, tmp_path, capsys):
    """`camjax design --solver newton` (a translating and a rocking follower, the grid's 90
    samples as above: the translating flat face's solve is then the compiled program of
    test_solution_json_carries_the_certificate): result.json's design block holds the certificate
    of a converged solve, its residuals within the stopping rule, every active row named with its
    scene key and angle, and the summary says what limits the design."""
    import json
    import re

    from camjax.cli import main
    from camjax.scene import builtin_scene_text

    text = re.sub(r"(?m)^samples = \d+", f'samples = {SAMPLES}\nextrema = "grid"', builtin_scene_text(scene_name))
    path = tmp_path / "scene.toml"
    path.write_text(text)
    assert main(["design", str(path), "--solver", "newton", "--out", str(tmp_path / "out"), "--dpi", "20"]) == 0
    cert = json.loads((tmp_path / "out" / "result.json").read_text())["design"]["certificate"]
    assert cert["converged"] and cert["active"]
    assert max(cert["stationarity"], cert["primal_feasibility"], cert["complementarity"]) <= 1e-9
    for row in cert["active"]:
        # a bound has no angle; every other row binds at one cam angle
        assert row["limit"] and row["multiplier"] > 0.0, row
        assert (row["theta_deg"] is None) == ("bound" in row["kind"]), row
        assert row["theta_deg"] is None or 0.0 <= row["theta_deg"] < 360.0, row
    assert cert["limited_by"] in capsys.readouterr().out


ROBUST_SCENE = """
[motion]
rpm = 300.0
samples = 64
segments = [
  { kind = "rise",   angle_deg = 90,  law = "harmonic", lift_mm = 8.0 },
  { kind = "dwell",  angle_deg = 45 },
  { kind = "return", angle_deg = 180, law = "harmonic", lift_mm = 8.0 },
  { kind = "dwell",  angle_deg = 45 },
]

[follower]
type = "roller"
roller_radius_mm = 5.0
offset_mm = 0.0
max_pressure_angle_deg = 30.0
min_curvature_radius_mm = 1.0
mass_kg = 0.4
spring_N_per_m = 2000.0
preload_mm = 1.0
damping_Ns_per_m = 0.5
gravity_m_s2 = 9.81

[contact]
cam_width_mm = 8.0
cam = { E_MPa = 2.1e5, poisson = 0.3 }
follower = { E_MPa = 2.1e5, poisson = 0.3 }

[design]
base_radius_mm = [2.0, 40.0]
roller_radius_mm = [3.0, 12.0]
offset_mm = [-4.0, 4.0]
sigma_max_MPa = 1000.0
alpha = 1.0
gamma = 0.0
robust = { probability = 0.99, samples = 400 }

[tolerances]
roller_radius_mm = { sd = 0.01 }
offset_mm = { sd = 0.01 }
rpm = { half_width = 30, dist = "uniform" }
spring_N_per_m = { sd_percent = 5 }
preload_mm = { sd = 0.2 }
mass_kg = { sd_percent = 2 }
cam_width_mm = { sd = 0.05 }
profile_error_mm = { amplitude = 0.005, harmonics = [2, 3, 5] }
"""


@pytest.mark.slow
def test_robust_rounds_converge_and_the_certificate_names_binding_rows():
    """A robust roller (size only, each limit kept over all but the worst of 400 samples of eight
    tolerances, p = 0.99, 64 angles; a round solves newton's 16 samples nearest to breaking a
    limit, rows split by angle and sample, many of them near-parallel): newton converges within its
    200-iteration safeguard, feasible, every robust row kept. Its robust optimum is checked against
    the gradient solver's in tests/test_robust_design.py (the oscillating roller; measured 1.2e-9
    apart), and with every spread 0 against the nominal optimum for every follower type."""
    from camjax.robust import design as rd
    from camjax.scene import scene_from_dict

    scene = scene_from_dict(tomllib.loads(ROBUST_SCENE), "robust-newton")
    base = problem_from_scene(scene)
    weights = (scene.design.alpha, scene.design.gamma)
    nominal = solve(base, weights, solver="newton")
    problem = rd.robust_problem(scene, base, origin=nominal.design)
    subset = rd.SOLVER_SUBSET["newton"]
    robust, _, solved = rd.solve_rounds(problem, weights, mode="global", solver="newton", seed=0, subset=subset)
    assert robust.status_name == "converged"
    assert bool(robust.feasible)
    assert all(float(v) <= 1e-6 for v in robust.evaluation.rows)
    # the robust feasible set is inside the nominal one: no smaller than the nominal optimum
    assert float(robust.objective) >= float(nominal.objective) - 1e-9
    # the certificate names rows that bind: each row carrying 1 % of the largest multiplier or
    # more, its constraint at its cam angle over the round's kept samples, is at its limit (within
    # 1e-6 mm: the KKT tolerance of ~1e-8 scaled by the size norm), and every active row's
    # multiplier times its slack is the barrier's complementarity (<= 1e-5 mm; measured 1e-6: the
    # interior point's rows 7e-3 mm inside carry multipliers of 1.5e-4 against 0.96 and 0.72).
    # Its labels come from the round's subset, whose rows the multipliers are: labelled against
    # the full 400 samples they named the contact and the stress where the pressure angle binds
    block = robust.certificate_json(solved)
    named = [e for e in block["active"] if e["kind"] != "bound"]
    assert named, block
    family = family_of(solved)
    per = family.per_angle(solved)
    theta = np.asarray(solved.theta_deg).reshape(-1)
    for e in named:
        i = int(np.argmin(np.abs(theta - e["theta_deg"])))
        at = float(jnp.max(getattr(family.constraints(jax.tree.map(lambda x, i=i: x[i], per), robust.design),
                                   e["kind"])))
        assert e["multiplier"] * abs(at) <= 1e-5, e
        if e["multiplier"] >= 0.01 * named[0]["multiplier"]:
            assert at == pytest.approx(0.0, abs=1e-6), e


@pytest.mark.slow
@pytest.mark.parametrize("name", followers.names())
def test_forward_derivatives_match_reverse_mode(name):
    """The step's one forward-over-forward pass (rows, Jacobian, objective gradient, Lagrangian
    Hessian) against independent ones: the rows themselves, the Jacobian by reverse mode
    (jacrev) and the Hessian of phi + y . c by forward-over-reverse (jax.hessian), at the start
    of the solve with positive multipliers of O(1). Both are exact derivatives of the same
    function: they differ by rounding only (rtol 1e-9 of the largest entry, O(1) after the
    solver's normalization). The same pass along the free variables only (``free_variables``, as
    solve_batch counts them: 2 of 4 on the oscillating roller's and oscillating flat face's scenes)
    gives the same numbers in the free rows and columns and 0 in a fixed variable's."""
    problem = _problem(followers.get(name).example_scene)  # the example problem of the tests above
    w = weights_of(1.0, 1.0)
    free_count = newton.for_problem(problem, newton.DEFAULT_SETTINGS).free_variables

    @jax.jit
    def both(y_raw):
        fns = epigraph.epigraph_form(problem, w)
        z, _, _, _ = newton._start(problem, fns, None, newton.DEFAULT_SETTINGS, 0.1)
        y = 0.5 + y_raw[: fns.rows(z).shape[0]]
        ours = newton._derivatives(fns, z, y)
        reduced = newton._derivatives(fns, z, y, free_count)
        ref = (fns.rows(z), jax.jacrev(fns.rows)(z), jax.grad(fns.phi)(z),
               jax.hessian(lambda v: fns.phi(v) + y @ fns.rows(v))(z))
        f = fns.free
        masked = (ref[0], ref[1] * f, ref[2] * f, ref[3] * jnp.outer(f, f))
        return ours, reduced, ref, masked, f

    ours, reduced, ref, masked, free = both(jax.random.uniform(jax.random.key(0), (4096,)))
    assert int(np.sum(np.asarray(free))) == free_count + 1  # and t
    for got, want, what in [*zip(ours, ref, ("rows", "jacobian", "gradient", "hessian"), strict=True),
                            *zip(reduced, masked, ("free rows", "free jacobian", "free gradient",
                                                   "free hessian"), strict=True)]:
        scale = max(float(jnp.max(jnp.abs(want))), 1.0)
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=0, atol=1e-9 * scale, err_msg=what)


@pytest.mark.parametrize("name", ["roller", "oscillating_roller", "oscillating_curved_face", "groove"])
def test_the_smooth_rows_are_the_rows_but_for_the_kink(name):
    """A family's ``smooth_constraints`` (the interior point's rows, camjax.solvers.epigraph) against its
    ``constraints`` at 64 designs spread over the box (a Halton-like lattice, several infeasible):
    the pressure angle's row has the same sign at every angle (the same feasible set), is 0 where
    it is, and every other row is the same number (exactly: the same code). The groove's rows (a
    positive drive, its pressure angle already two rows) are its constraints unchanged."""
    problem = _problem(followers.get(name).example_scene if name in followers.names() else name)
    fam = family_of(problem)
    lower, upper = fam.bounds(problem)
    u = (np.arange(1, 65)[:, None] * np.asarray([0.618034, 0.754878, 0.569840, 0.535687, 0.523287])) % 1.0

    @jax.jit
    def both(u):
        design = jax.tree.map(lambda lo, hi, v: lo + (hi - lo) * v, lower, upper,
                              type(lower)(*u[: len(lower)]))
        return fam.constraints(problem, design), fam.smooth_constraints(problem, design)

    plain, smooth = jax.vmap(both)(jnp.asarray(u))
    for field in plain._fields:
        a, b = np.asarray(getattr(plain, field)), np.asarray(getattr(smooth, field))
        if field == "pressure_angle":
            assert np.all(np.sign(a) == np.sign(b)) and np.any(a > 0) and np.any(a < 0), field
            assert not np.array_equal(a, b)
        else:
            np.testing.assert_array_equal(a, b, err_msg=field)


@pytest.mark.parametrize("name", [*followers.names(), "groove", "conjugate"])
def test_take_angles_keeps_every_row_of_its_angles(name):
    """The exchange rounds solve on a subset of the grid (newton.take_angles): at a design away from
    the optimum every objective and constraint row of the subset's epigraph form equals the whole
    grid's row at the same angle (the same functions of the same grid values: rtol 1e-12), and the
    bound rows are the same. The angles are uneven and out of the grid's order on purpose. Every
    follower type's example scene and the positive drives (whose second contact's coefficient is a
    grid array inside the closure).

    The same forms are affine in t along their ``t_column`` (the interior point takes t's Jacobian
    column from it and no second derivative along t, newton._derivatives): the rows' forward
    derivative along t is that column exactly, phi's is 1, on the whole grid and on the subset,
    with the stress weighted and without (gamma = 0: the first objective row alone holds t)."""
    problem = _problem(followers.get(name).example_scene if name in followers.names() else name)
    w = weights_of(0.3, 0.7)
    n = problem.theta_deg.shape[-1]
    index = jnp.asarray([n - 1, 0, 7, 8, 31, n // 2, n // 2 + 1, 60])

    @jax.jit
    def both(problem, index):
        fns = epigraph.epigraph_form(problem, w)
        sub = epigraph.epigraph_form(newton.take_angles(problem, index), w)
        z = jnp.concatenate([0.37 * fns.u_max, jnp.asarray([0.25])])
        along_t = jnp.zeros_like(z).at[-1].set(1.0)
        slopes = [(jax.jvp(f.rows, (z,), (along_t,))[1], f.t_column, jax.jvp(f.phi, (z,), (along_t,))[1])
                  for f in (fns, sub, epigraph.epigraph_form(problem, weights_of(1.0, 0.0)))]
        return fns.rows(z), sub.rows(z), slopes

    full, sub, slopes = both(problem, index)
    for (tangent, column, slope), holding in zip(slopes, (n, index.shape[0], 1), strict=True):
        np.testing.assert_array_equal(np.asarray(tangent), np.asarray(column))
        assert float(slope) == 1.0 and float(-np.sum(np.asarray(column))) == holding
    blocks = len(epigraph.epigraph_form(problem, w).kinds) - 2  # the objective's and each constraint's
    k = index.shape[0]
    full, sub = np.asarray(full), np.asarray(sub)
    for b in range(blocks):
        np.testing.assert_allclose(sub[b * k:(b + 1) * k], full[b * n + np.asarray(index)], rtol=1e-12,
                                   atol=1e-300, err_msg=f"block {b}")
    np.testing.assert_array_equal(sub[blocks * k:], full[blocks * n:])


@pytest.mark.slow
def test_exchange_rounds_reach_the_whole_grids_optimum():
    """The knife edge's example scene at 360 angles and the three weightings: the exchange rounds
    (16 angles a round, the default's :data:`camjax.solvers.exchange.EXCHANGE_ANGLES`) and the
    interior point on the whole grid (``exchange_angles`` = 0) both converge, and to the same
    objective within 1e-7 relative (two KKT points of the same problem, each within the
    barrier's ~rows x mu ~ 1e-9 of F). The exchange's certificate is taken
    on the whole grid: its multipliers' epigraph sum is the objective's unit weight."""
    problem = _problem(followers.get("knife_edge").example_scene, 360)
    w = weights_of([a for a, _ in WEIGHTINGS], [g for _, g in WEIGHTINGS])
    whole_grid = dataclasses.replace(newton.DEFAULT_SETTINGS, exchange_angles=0)
    solve_all = jax.jit(jax.vmap(newton.minimize, in_axes=(None, 0, None, None)), static_argnums=3)
    rounds = solve_all(problem, w, None, newton.DEFAULT_SETTINGS)
    whole = solve_all(problem, w, None, whole_grid)
    assert np.all(np.asarray(rounds.converged)) and np.all(np.asarray(whole.converged))
    ev = jax.vmap(family_of(problem).evaluate, in_axes=(None, 0, 0))
    a, b = ev(problem, w, rounds.design), ev(problem, w, whole.design)
    assert np.all(np.asarray(a.feasible))
    np.testing.assert_allclose(np.asarray(a.objective), np.asarray(b.objective), rtol=1e-7)
    np.testing.assert_allclose(np.asarray(rounds.multipliers)[:, :360].sum(axis=1), 1.0, rtol=1e-8)
    # the residuals the rounds report (from the subset's) are the whole grid's, recomputed here from
    # every row and its Jacobian: the same numbers but for rounding (1e-15 absolute; each <= 1e-9)
    def residuals(w, z, y):
        return certificate.kkt_residuals(epigraph.epigraph_form(problem, w), z, y)

    recomputed = jax.vmap(residuals)(w, rounds.z, rounds.multipliers)
    for got, want in zip(rounds.kkt, recomputed, strict=True):
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-6, atol=1e-15)


# A start the knife edge's 16-angle exchange rounds fail from: benchmarks/follower_sweep.py's
# weighting 90 of 100 (alpha, gamma) and the hybrid's GA answer there (mm). From it the first round
# converged on its angles at a worse point (R_b 25.3 mm) and the later rounds ended unconverged
# (41 steps; before the rounds started again from the default start, the hybrid kept its GA answer,
# 3.9e-6 above the optimum, and this test failed on ``converged``).
KNIFE_ROUNDS_FAIL = {"weighting": (0.022579677172291576, 0.9774203228277084),
                     "start": (12.7155322, 1.58025218)}


@pytest.mark.slow
def test_rounds_that_fail_from_a_given_start_start_again_and_reach_the_optimum():
    """The knife edge's example scene at 360 angles from a start where the exchange rounds end
    unconverged: the rounds start again from the default start and converge, feasible, to SLSQP's
    objective within 1e-7 relative (SLSQP's ftol 1e-12; the interior point's barrier leaves
    ~rows x mu ~ 1e-9 of F)."""
    problem = _problem(followers.get("knife_edge").example_scene, 360)
    alpha, gamma = KNIFE_ROUNDS_FAIL["weighting"]
    w = weights_of(alpha, gamma)
    lower = family_of(problem).bounds(problem)[0]
    solved = jax.jit(newton.minimize)(problem, w, lower._make(jnp.asarray(KNIFE_ROUNDS_FAIL["start"])))
    assert bool(solved.converged)
    got = family_of(problem).evaluate(problem, w, solved.design)
    reference = scipy_family.slsqp(problem, alpha, gamma)
    want = family_of(problem).evaluate(problem, w, lower._make(jnp.asarray(reference.design)))
    assert bool(got.feasible) and bool(want.feasible)
    np.testing.assert_allclose(float(got.objective), float(want.objective), rtol=1e-7)


@pytest.mark.slow
def test_the_line_search_takes_the_same_steps_one_trial_or_all_at_once():
    """The line search's trial lengths tried one at a time (the default ``line_search_chunk``) or
    all 30 at once pick the same first accepted length, so the solve takes the same steps: on the
    oscillating flat face's example scene (the filter path, exchange rounds at 90 angles) the three
    weightings end after the same iterations at the same design (1e-12 relative: the rows of one
    trial and of a vmap of 30 are XLA's code for the same arithmetic)."""
    problem = _problem(followers.get("oscillating_flat").example_scene)
    w = weights_of([a for a, _ in WEIGHTINGS], [g for _, g in WEIGHTINGS])
    assert newton.DEFAULT_SETTINGS.line_search_chunk == 1
    at_once = dataclasses.replace(newton.DEFAULT_SETTINGS,
                                  line_search_chunk=newton.DEFAULT_SETTINGS.line_search_trials)
    solve_all = jax.jit(jax.vmap(newton.minimize, in_axes=(None, 0, None, None)), static_argnums=3)
    one, whole = solve_all(problem, w, None, newton.DEFAULT_SETTINGS), solve_all(problem, w, None, at_once)
    assert np.all(np.asarray(one.converged))
    np.testing.assert_array_equal(np.asarray(one.iterations), np.asarray(whole.iterations))
    np.testing.assert_allclose(np.asarray(one.z), np.asarray(whole.z), rtol=1e-12, atol=1e-15)
