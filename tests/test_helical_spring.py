"""The helical compression spring sized for the co-design's spring (camjax.codesign.helical,
[synthesis.helical_spring]): the formulas against independent derivations (the rate from the torsion
of a straight wire, the surge from a lumped fixed-fixed chain, the Wahl factor against Bergstrasser's);
the sizing against a brute-force grid in (d, D) and SciPy SLSQP, with the constraints holding at the
answer; the least infeasible spring; the significant harmonic against a spectrum built by hand; the
scene's block end to end; bad input refused naming the field."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from camjax import loads, program
from camjax.cli import main
from camjax.codesign import CodesignError, codesign_scene
from camjax.codesign import helical as hx
from camjax.errors import SceneError
from camjax.scene import builtin_scene_text, scene_from_dict

G, RHO = 79.3e9, 7850.0  # steel, Pa and kg/m^3


def problem(**kw) -> hx.HelicalProblem:
    """A spring of the built-in co-design scene's size (3004 N/m, 39 N preload + 10 mm lift)."""
    base = dict(rate_N_per_m=3004.0, force_max_N=69.1, shear_modulus_Pa=G, density_kg_m3=RHO,
                allowable_shear_Pa=500e6, required_hz=48.0, wire_lo_m=0.5e-3, wire_hi_m=5e-3,
                coil_lo_m=5e-3, coil_hi_m=50e-3, index_lo=4.0, index_hi=12.0, coils_lo=3.0,
                coils_hi=15.0, end_coils=2.0)
    base.update(kw)
    return hx.HelicalProblem(**{k: float(v) for k, v in base.items()})


# problems with different constraints binding at the optimum (found by the brute force below too)
CASES = {
    "stress": problem(),  # interior index: the stress alone
    "stress_surge": problem(required_hz=268.0),  # the surge cuts the index range: both bind
    "coils_high": problem(coils_hi=8.0),
    "coils_low": problem(rate_N_per_m=50000.0, force_max_N=500.0, coils_lo=8.0),
    "wire_low": problem(wire_lo_m=2.5e-3),  # the index at its top, the stress slack
    "coil_high": problem(coil_hi_m=12e-3, coils_hi=30.0),
}
SIZE = jax.jit(hx.size_spring)


def sized(p):
    return jax.tree.map(np.asarray, SIZE(jax.tree.map(jnp.asarray, p)))


def constraint_values(p, d, D):
    """Every constraint as g >= 0 (relative) from the formulas in NumPy, and the total mass (kg)."""
    d, D = np.float64(d), np.float64(D)
    n_a = G * d**4 / (8.0 * D**3 * p.rate_N_per_m)
    C = D / d
    with np.errstate(divide="ignore", invalid="ignore"):  # C = 1 (outside the index range) on the grid
        kw = (4 * C - 1) / (4 * C - 4) + 0.615 / C
    tau = kw * 8.0 * p.force_max_N * D / (math.pi * d**3)
    m_a = math.pi**2 * d**2 * D * n_a * RHO / 4.0
    f_n = 0.5 * np.sqrt(p.rate_N_per_m / m_a)  # the mass form, not the module's d, D form
    g = np.stack(np.broadcast_arrays(1 - tau / p.allowable_shear_Pa, f_n / p.required_hz - 1, n_a / p.coils_lo - 1,
                  1 - n_a / p.coils_hi, d / p.wire_lo_m - 1, 1 - d / p.wire_hi_m, D / p.coil_lo_m - 1,
                  1 - D / p.coil_hi_m, C / p.index_lo - 1, 1 - C / p.index_hi))
    return g, math.pi**2 * d**2 * D * (n_a + p.end_coils) * RHO / 4.0


def brute_force(p, n=2000):
    """The least mass over an n x n geometric grid of (d, D) in the boxes (inf: none feasible)."""
    d = np.geomspace(p.wire_lo_m, p.wire_hi_m, n)[:, None]
    D = np.geomspace(p.coil_lo_m, p.coil_hi_m, n)[None, :]
    g, m = constraint_values(p, d, D)
    ok = np.all(g >= 0.0, axis=0)
    return float(m[ok].min()) if ok.any() else math.inf


def slsqp(p):
    """SciPy SLSQP on (ln d, ln D) from 15 starts (5 wires x 3 indices): the best feasible end's mass, (d, D)."""
    from scipy.optimize import minimize

    def mass(x):
        return constraint_values(p, math.exp(x[0]), math.exp(x[1]))[1] * 1e3  # g: scale ~1

    best = (math.inf, None)
    starts = [(d, c * d) for d in np.geomspace(p.wire_lo_m, p.wire_hi_m, 5) for c in (5.0, 8.0, 11.0)]
    for x0 in np.log(np.asarray(starts)):
        with np.errstate(all="ignore"):  # its line search may try a wire of 0 or inf
            r = minimize(mass, x0, method="SLSQP", options={"ftol": 1e-14, "maxiter": 500},
                         constraints=[{"type": "ineq",
                                       "fun": lambda x: constraint_values(p, math.exp(x[0]), math.exp(x[1]))[0]}])
        d, D = np.exp(r.x)
        if r.success and np.all(constraint_values(p, d, D)[0] >= -1e-10) and r.fun * 1e-3 < best[0]:
            best = (r.fun * 1e-3, (d, D))
    return best


# ------------------------------------------------------------------------------ the formulas


def test_rate_is_the_torsion_of_the_straight_wire():
    """A force F on a coil of mean diameter D twists the wire (length L = pi D n_a, polar moment
    J = pi d^4 / 32) by T = F D / 2: angle T L / (G J), deflection angle x D / 2. Same to rounding."""
    d, D, n, F = 1.8e-3, 14e-3, 9.5, 10.0
    twist = (F * D / 2) * (math.pi * D * n) / (G * math.pi * d**4 / 32)
    assert float(hx.rate(d, D, n, G)) == pytest.approx(F / (twist * D / 2), rel=1e-13)
    assert float(hx.active_coils_for(d, D, float(hx.rate(d, D, n, G)), G)) == pytest.approx(n, rel=1e-13)


def test_wahl_factor_against_bergstrasser():
    """Bergstrasser's K_B = (4C + 2) / (4C - 3) approximates Wahl's within 1.5 % over 4 <= C <= 12
    (1.4 % at C = 4, the largest), and both tend to 1 as C grows; K_w > K_s = 1 + 0.5 / C (direct
    shear alone)."""
    C = np.linspace(4.0, 12.0, 81)
    kw = np.asarray(hx.wahl_factor(C))
    kb = (4 * C + 2) / (4 * C - 3)
    assert np.max(np.abs(kw / kb - 1)) < 0.015
    assert np.all(kw > 1 + 0.5 / C) and np.all(np.diff(kw) < 0)
    assert float(hx.wahl_factor(1e6)) == pytest.approx(1.0, abs=2e-6)
    # the stress: 8 F D / (pi d^3) is the torsion 16 T / (pi d^3) of T = F D / 2, times K_w
    d, D, F = 2e-3, 16e-3, 50.0
    assert float(hx.shear_stress(F, d, D)) == pytest.approx(
        float(hx.wahl_factor(D / d)) * 16 * (F * D / 2) / (math.pi * d**3), rel=1e-14)


def test_surge_forms_agree_and_match_a_lumped_chain():
    """f_n = d / (2 pi n_a D^2) sqrt(G / 2 rho) equals (1/2) sqrt(k / m_a) (to rounding), and the
    lowest frequency of the spring as a fixed-fixed chain of 400 masses m_a / 400 and springs 400 k
    (a dense eigenproblem) is the same within 1e-5 (the chain's error is pi^2 / (24 N^2) = 2.6e-6)."""
    d, D, n = 1.8e-3, 14e-3, 9.5
    k = float(hx.rate(d, D, n, G))
    m = float(hx.active_mass(d, D, n, RHO))
    f1 = float(hx.surge_frequency(d, D, n, G, RHO))
    assert f1 == pytest.approx(float(hx.surge_frequency_from_mass(k, m)), rel=1e-14)
    N = 400
    K = N * k * (2 * np.eye(N - 1) - np.eye(N - 1, k=1) - np.eye(N - 1, k=-1))
    w2 = np.linalg.eigvalsh(K / (m / N))[0]
    assert f1 == pytest.approx(math.sqrt(w2) / (2 * math.pi), rel=1e-5)


def test_formula_gradients_against_central_differences():
    """jax.grad of the stress, surge, mass and rate in (d, D) against central differences (step
    1e-6 relative: truncation ~1e-12, rounding ~1e-10; tolerance 1e-7)."""
    x = np.asarray([1.8e-3, 14e-3])
    fns = {"stress": lambda x: hx.shear_stress(69.1, x[0], x[1]),
           "surge": lambda x: hx.surge_frequency(x[0], x[1], 9.5, G, RHO),
           "mass": lambda x: hx.active_mass(x[0], x[1], 9.5, RHO),
           "rate": lambda x: hx.rate(x[0], x[1], 9.5, G)}
    for name, f in fns.items():
        g = np.asarray(jax.grad(f)(jnp.asarray(x)))
        fd = np.asarray([(float(f(x + e)) - float(f(x - e))) / (2 * e[i])
                         for i, e in enumerate(np.diag(x * 1e-6))])
        np.testing.assert_allclose(g, fd, rtol=1e-7, err_msg=name)


# ------------------------------------------------------------------------------ the sizing


@pytest.mark.slow  # > 2 s (a compile of its own)
@pytest.mark.parametrize("name", list(CASES))
def test_sizing_matches_brute_force_and_slsqp(name):
    """The answer: k matched (1e-12), every constraint held (to 1e-12 relative: the binding ones are
    met at rounding), no grid point of a 2000 x 2000 grid in (d, D) lighter (1e-12), the grid's best
    within 2 % (its spacing: 0.1 % in d, ~4 % in mass near a vertex), and SLSQP's best end from 15
    starts within 1e-6 (its tolerance)."""
    p = CASES[name]
    s = sized(p)
    assert bool(s.feasible)
    assert float(hx.rate(s.wire_m, s.coil_m, s.active_coils, G)) == pytest.approx(p.rate_N_per_m, rel=1e-12)
    g, m = constraint_values(p, float(s.wire_m), float(s.coil_m))
    assert np.all(g >= -1e-12), g
    assert m == pytest.approx(float(s.mass_kg), rel=1e-12)
    brute = brute_force(p)
    assert m <= brute * (1 + 1e-12) and brute <= m * 1.02, (m, brute)
    best, _ = slsqp(p)
    assert m == pytest.approx(best, rel=1e-6), (m, best)
    assert m <= best * (1 + 1e-9)


def test_the_binding_constraints_are_the_expected_ones():
    """Each case binds what it was built to (slack <= BIND_TOL) and nothing else."""
    expect = {"stress": {"stress"}, "stress_surge": {"stress", "surge"},
              "coils_high": {"stress", "active_coils_high"}, "coils_low": {"stress", "active_coils_low"},
              "wire_low": {"wire_low", "index_high"}, "coil_high": {"stress", "coil_high"}}
    for name, p in CASES.items():
        slack = dict(zip(hx.CONSTRAINTS, np.asarray(sized(p).slack).tolist(), strict=True))
        bound = {n for n, v in slack.items() if v <= hx.BIND_TOL}
        assert bound == expect[name], (name, bound)


def test_a_batch_under_vmap_equals_one_at_a_time():
    """The same masses to 1e-14; the wire to 1e-8: at an interior optimum the mass is flat in C to
    second order, so a rounding-level change of the merit (another fusion of the batch) moves the
    argmin by up to sqrt(1e-16)."""
    ps = list(CASES.values())
    batch = jax.tree.map(lambda *xs: jnp.asarray(xs), *ps)
    out = jax.jit(jax.vmap(hx.size_spring))(batch)
    for i, p in enumerate(ps):
        one = sized(p)
        np.testing.assert_allclose(np.asarray(out.mass_kg[i]), one.mass_kg, rtol=1e-14)
        np.testing.assert_allclose(np.asarray(out.wire_m[i]), one.wire_m, rtol=1e-8)


def test_no_feasible_spring_gives_the_least_infeasible_one():
    """A surge requirement above every spring of the ranges: not feasible (the brute force and SLSQP
    find none); the answer is the spring of highest surge frequency among those meeting the stress:
    asking for its f_n (less 1e-9) makes the problem feasible, 0.1 % more leaves it infeasible; the
    message names the surge and how far short it falls."""
    p = problem(required_hz=400.0)
    s = sized(p)
    assert not bool(s.feasible) and float(s.gap) > 0.0
    assert brute_force(p, 600) == math.inf and slsqp(p)[0] == math.inf
    f = float(s.surge_hz)
    assert bool(sized(p._replace(required_hz=f * (1 - 1e-9))).feasible)
    assert not bool(sized(p._replace(required_hz=f * 1.001)).feasible)
    slack = dict(zip(hx.CONSTRAINTS, np.asarray(s.slack).tolist(), strict=True))
    msg = hx.infeasible_message(p, jax.tree.map(float, s._replace(slack=0.0)), slack)
    assert "surge frequency" in msg and "% short" in msg and "stress" in msg
    assert f"{100 * (1 - f / 400.0):.3g} % short" in msg


def test_the_surge_constraint_off():
    """surge_ratio 0 (required 0): the surge no longer binds, the answer no heavier than with it."""
    with_surge, without = sized(CASES["stress_surge"]), sized(CASES["stress_surge"]._replace(required_hz=0.0))
    assert bool(without.feasible) and float(without.mass_kg) <= float(with_surge.mass_kg)
    assert np.isinf(np.asarray(without.slack)[hx.CONSTRAINTS.index("surge")])


# ------------------------------------------------------------------------------ the harmonic


def test_significant_harmonic_against_a_spectrum_built_by_hand():
    """s = sum of a_n cos(n theta + phi_n), a_n = n^-3 up to 40: the harmonic energies are a_n^2 / 2,
    so H (the least harmonic above which at most ``tail`` of the energy lies) follows from the a_n
    alone; the FFT-based H is the same for several tails."""
    n = np.arange(1, 41)
    a = n**-3.0
    phi = np.random.default_rng(0).uniform(0, 2 * np.pi, n.size)
    theta = np.arange(2048) * 2 * np.pi / 2048
    s = 3.0 + (a[:, None] * np.cos(n[:, None] * theta + phi[:, None])).sum(0)
    e = a**2
    for tail in (1e-2, 1e-4, 1e-6, 1e-8):
        above = e.sum() - np.cumsum(e)  # energy above each harmonic
        expect = int(n[np.argmax(above <= tail * e.sum())])
        assert int(hx.significant_harmonic(jnp.asarray(s), tail)) == expect


def test_a_shorter_rise_has_higher_harmonics():
    """The cycloidal rise and return over 45 deg reach higher harmonics than over 90 deg (the same
    stroke), and at the default tail the 90-degree program's H lies in 5..15 (common practice: ~13)."""
    from camjax.laws import LAWS
    from camjax.program import MotionProgram, Segment

    def harmonic(beta):
        p = MotionProgram.from_segments([Segment("dwell", 100), Segment("rise", beta, LAWS["cycloidal"], 10.0),
                                         Segment("dwell", 260 - 2 * beta),
                                         Segment("return", beta, LAWS["cycloidal"], 10.0)])
        return int(hx.significant_harmonic(jnp.asarray(hx.lift_samples(p)), 1e-5))

    assert 5 <= harmonic(90) <= 15 and harmonic(45) > harmonic(90)


# ------------------------------------------------------------------------------ the scene

SAMPLES = 120
HELICAL = {"allowable_shear_MPa": 500.0, "wire_mm": [0.3, 5.0], "coil_mm": [3.0, 40.0]}


def scene_data(helical=None, spring=True) -> dict:
    """The built-in codesign scene made small (8 control values, 120 samples), a free spring (the
    spring tests' box) and a helical spring."""
    data = tomllib.loads(builtin_scene_text("codesign"))
    for seg in data["motion"]["segments"]:
        if seg.get("design"):
            seg["control_count"] = 8
    data["motion"]["samples"] = SAMPLES
    if spring:
        data["synthesis"].update(spring_N_per_m=[1000.0, 20000.0], preload_N=[1.0, 200.0],
                                 min_contact_force_N=5.0, overspeed=1.2)
    data["synthesis"]["helical_spring"] = dict(HELICAL if helical is None else helical)
    return data


def test_helical_keys_parse_with_defaults():
    spec = scene_from_dict(scene_data(), "h").synthesis.helical
    assert (spec.shear_modulus_GPa, spec.density_kg_m3, spec.surge_ratio) == (79.3, 7850.0, 1.2)
    assert spec.harmonics is None and spec.index == (4.0, 12.0) and spec.active_coils == (3.0, 15.0)
    assert spec.wire_mm == (0.3, 5.0) and spec.coil_mm == (3.0, 40.0)
    spec = scene_from_dict(scene_data({**HELICAL, "harmonics": 13, "surge_ratio": 0}), "h").synthesis.helical
    assert spec.harmonics == 13 and spec.surge_ratio == 0.0


BAD = [
    ({"shear_modulus_GPa": -79.3}, "shear_modulus_GPa"),
    ({"density_kg_m3": 0.0}, "density_kg_m3"),
    ({"allowable_shear_MPa": -1.0}, "allowable_shear_MPa"),
    ({"wire_mm": [3.0, 1.0]}, "wire_mm"),
    ({"coil_mm": [0.0, 10.0]}, "coil_mm"),
    ({"coil_mm": 10.0}, "coil_mm"),
    ({"index": [1.0, 12.0]}, "index"),
    ({"active_coils": [-1.0, 10.0]}, "active_coils"),
    ({"surge_ratio": -1.0}, "surge_ratio"),
    ({"harmonics": 0}, "harmonics"),
    ({"harmonics": 2.5}, "harmonics"),
    ({"harmonics": 13, "spectrum_tail": 1e-4}, "spectrum_tail"),
    ({"spectrum_tail": 1.0}, "spectrum_tail"),
    ({"end_coils": -2.0}, "end_coils"),
    ({"wire": [1.0, 2.0]}, "wire"),
]


@pytest.mark.parametrize("change, key", BAD)
def test_bad_helical_input_is_refused_naming_the_field(change, key):
    with pytest.raises(SceneError) as exc:
        scene_from_dict(scene_data({**HELICAL, **change}), "bad")
    assert exc.value.field == f"synthesis.helical_spring.{key}"
    data = scene_data()
    del data["synthesis"]["helical_spring"]["allowable_shear_MPa"]
    with pytest.raises(SceneError) as exc:
        scene_from_dict(data, "bad")
    assert exc.value.field == "synthesis.helical_spring.allowable_shear_MPa"


def scene_text(helical, spring=True) -> str:
    """:func:`scene_data` as a scene file ([synthesis] is the built-in scene's last section)."""
    text = builtin_scene_text("codesign").replace("samples = 360", f"samples = {SAMPLES}").replace(
        "control_count = 16", "control_count = 8")
    if spring:
        text = text.replace("[synthesis]", "[synthesis]\nspring_N_per_m = [1000.0, 20000.0]\n"
                            "preload_N = [1.0, 200.0]\nmin_contact_force_N = 5.0\noverspeed = 1.2")
    return text + "\n[synthesis.helical_spring]\n" + "".join(
        f"{k} = {json.dumps(v)}\n" for k, v in helical.items())


@pytest.mark.parametrize("change, key", BAD[:2] + BAD[3:4])
def test_bad_helical_input_exits_2_writing_nothing(tmp_path, capsys, change, key):
    path = tmp_path / "bad.toml"
    path.write_text(scene_text({**HELICAL, **change}))
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"synthesis.helical_spring.{key}" in err[0] and "Traceback" not in err[0]
    assert not out.exists()


def test_a_rocker_is_refused_naming_the_field():
    data = tomllib.loads(builtin_scene_text("oscillating-roller"))
    for i in (0, 2):
        seg = data["motion"]["segments"][i]
        data["motion"]["segments"][i] = {k: seg[k] for k in ("kind", "angle_deg", "lift_deg")} | {
            "law": "bspline", "degree": 3, "control_count": 8, "design": True}
    data["synthesis"] = {"objective": {"l2_jerk": 1e-6}, "helical_spring": HELICAL}
    with pytest.raises(CodesignError) as exc:
        codesign_scene(scene_from_dict(data, "rocker"), SAMPLES, max_iterations=1)
    assert exc.value.field == "synthesis.helical_spring" and "translating" in str(exc.value)


@pytest.fixture(scope="module")
def codesigned():
    scene = scene_from_dict(scene_data(), "helical")
    return scene, codesign_scene(scene, SAMPLES, max_iterations=5)


@pytest.mark.slow
def test_the_codesigned_spring_is_sized(codesigned):
    """synthesis.codesign.spring.helical: the designed rate and preload; F_max the largest spring
    force of the loads model on the design written (max of k (y + x0)); the dimensions give the
    rate (1e-12); the stress and surge, recomputed by the formulas, within their limits; H the
    spectrum's, f_cam the overspeed's."""
    scene, out = codesigned
    sp = out.spring
    h = sp["helical"]
    assert h["status"] == "optimal"
    assert h["rate_N_per_m"] == sp["rate_N_per_m"] and h["preload_N"] == pytest.approx(sp["preload_N"], rel=1e-12)
    train = out.scene.follower.train
    kin = program.evaluate(out.scene.motion.program, hx.SPECTRUM_SAMPLES)
    force = loads.force_parts(train, program.time_kinematics(kin, 1.0)).spring
    assert h["force_max_N"] == pytest.approx(float(np.max(np.asarray(force))), rel=1e-12)
    d, D, n = h["wire_mm"] * 1e-3, h["coil_mm"] * 1e-3, h["active_coils"]
    assert float(hx.rate(d, D, n, G)) == pytest.approx(sp["rate_N_per_m"], rel=1e-12)
    assert float(hx.shear_stress(h["force_max_N"], d, D)) <= 500e6 * (1 + 1e-12)
    m_a = float(hx.active_mass(d, D, n, RHO))
    assert float(hx.surge_frequency_from_mass(sp["rate_N_per_m"], m_a)) >= h["required_surge_hz"]
    assert h["cam_hz"] == pytest.approx(240.0 / 60.0 * 1.2, rel=1e-15)
    assert h["required_surge_hz"] == pytest.approx(1.2 * h["harmonic"] * h["cam_hz"], rel=1e-15)
    assert h["harmonic"] == int(hx.significant_harmonic(jnp.asarray(kin.s), 1e-5))
    assert h["binding"] and set(h["binding"]) <= set(hx.CONSTRAINTS)
    assert h["mass_kg"] == pytest.approx(math.pi**2 * d**2 * D * (n + 2) * RHO / 4, rel=1e-12)


@pytest.mark.slow
def test_an_impossible_spring_is_reported_not_sized(codesigned):
    """Ranges no spring fits (a wire of at most 0.4 mm for a 20 N spring): status infeasible, a
    message naming what sets the least infeasible spring's wire (the stress: its least wire is
    sqrt(8 F C K_w / (pi tau)), recomputed here) and the broken constraint with its value, and
    no dimensions."""
    scene, out = codesigned
    spec = dataclasses.replace(scene.synthesis.helical, wire_mm=(0.3, 0.4))
    bad = dataclasses.replace(scene, synthesis=dataclasses.replace(scene.synthesis, helical=spec))
    h = hx.helical_report(bad, out.scene)
    assert h["status"] == "infeasible" and "wire_mm" not in h and "binding" not in h
    assert "wire_high" in h["broken"] and "stress" not in h["broken"]
    least = h["least_infeasible"]
    C = least["index"]
    d = math.sqrt(8 * h["force_max_N"] * C * float(hx.wahl_factor(C)) / (math.pi * 500e6))
    assert least["wire_set_by"] == "stress" and least["wire_mm"] == pytest.approx(1e3 * d, rel=1e-12)
    assert f"d = {1e3 * d:.4g} mm set by stress" in h["message"]
    assert f"wire {1e3 * d:.4g} mm outside [0.3, 0.4] mm" in h["message"]


@pytest.mark.slow
def test_a_fixed_spring_is_sized_and_the_command_reports_it(tmp_path, capsys, monkeypatch):
    """No spring keys: the [follower]'s spring is sized (``designed`` False); `camjax design` writes
    it in result.json and prints a line (the search cut to 5 steps for time)."""
    import camjax.codesign

    monkeypatch.setattr(camjax.codesign, "codesign_scene",
                        functools.partial(camjax.codesign.codesign_scene, max_iterations=5))
    path = tmp_path / "fixed.toml"
    # the design on the samples' extrema: its program then holds no law (the co-designed laws are
    # constants of an exact design's program, compiled for this test alone); the spring's sizing
    # and report, what is checked here, read the grid either way
    path.write_text(scene_text(HELICAL, spring=False).replace(f"samples = {SAMPLES}",
                                                              f'samples = {SAMPLES}\nextrema = "grid"'))
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out)]) == 0
    sp = json.loads((out / "result.json").read_text())["synthesis"]["codesign"]["spring"]
    assert sp["designed"] is False and sp["rate_N_per_m"] == 3004.0
    assert sp["preload_N"] == pytest.approx(3004.0 * 13e-3, rel=1e-12)
    h = sp["helical"]
    assert h["status"] == "optimal" and h["cam_hz"] == pytest.approx(4.0, rel=1e-15)
    assert h["force_max_N"] == pytest.approx(3004.0 * (13e-3 + 10e-3), rel=1e-12)
    assert "helical spring: wire" in capsys.readouterr().out
