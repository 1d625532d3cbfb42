"""A helical compression spring sized for the co-design's spring: wire and coil diameter, active coils.

Where [synthesis.helical_spring] gives a material and ranges, the spring of the co-design (the
designed rate k and preload P of :mod:`camjax.codesign.spring`, or the [follower]'s when no spring
is designed) is realized as a round-wire helical compression spring of least mass. SI inside (m,
N, Pa, kg, Hz); the formulas are the standard ones (Shigley, *Mechanical Engineering Design*, ch. 10):

- rate k = G d^4 / (8 D^3 n_a) (N/m): d the wire diameter, D the mean coil diameter, n_a the
  active coils, G the shear modulus (the torsion of a wire of length pi D n_a, tests);
- spring index C = D / d;
- Wahl factor K_w = (4C - 1) / (4C - 4) + 0.615 / C (curvature and direct shear);
- shear stress tau = K_w 8 F D / (pi d^3) (Pa) at the largest spring force F_max = P + k s_max,
  s_max the follower's largest lift: the loads model's spring force is k (s + x0) with P = k x0
  (:func:`camjax.loads.force_parts`), largest where s is;
- surge, the fundamental natural frequency of the spring between fixed ends,
  f_n = d / (2 pi n_a D^2) sqrt(G / (2 rho)) = (1/2) sqrt(k / m_a) (Hz), m_a = pi^2 d^2 D n_a rho / 4
  the active coils' mass (the two forms are the same, tests);
- mass (the objective) m = pi^2 d^2 D (n_a + n_e) rho / 4, n_e the inactive end coils (2: squared
  and ground ends), which also give the solid height L_s = d (n_a + n_e).

**The surge constraint.** f_n >= surge_ratio x H x f_cam, f_cam = rpm / 60 x overspeed (the fastest
speed the scene names: the harmonics rise with the speed) and H the highest significant harmonic of
the follower's motion. H is scene data (``harmonics``) or, by default, taken from the lift's own
spectrum: the least H such that the harmonics above H hold at most ``spectrum_tail`` (default
1e-5) of the lift's spectral energy (its variance over a revolution, :func:`significant_harmonic`).
Any harmonic above H then has an amplitude of at most sqrt(2 tail var(s)) <= sqrt(tail / 2) h
(h the stroke), 0.22 % of the stroke at 1e-5. That is the "common practice" count made a property
of the cam: it gives H = 7 to 11 for 90-degree standard rises, 11 to 20 for 45-degree ones (the
rule of thumb for valve cams, 13, lies between), and it follows a designed law. ``surge_ratio``
(default 1.2) keeps f_n clear of the H-th harmonic itself (a steel spring's resonance is a few %
wide); with H = 13 it gives f_n >= 15.6 f_cam, the low end of Shigley's "15 to 20 times the
frequency of the motion". 0 turns the surge constraint off.

**The sizing.** With k fixed (matched exactly), n_a = G d^4 / (8 D^3 k) is eliminated and the
problem has two variables. In (C, d) every constraint is monotone in d at fixed C: the stress
(tau ∝ K_w C / d^2), n_a >= n_lo (n_a = G d / (8 C^3 k)), d >= d_lo, D = C d >= D_lo are lower
bounds on d; the surge (f_n ∝ C / d^2), n_a <= n_hi, d <= d_hi, D <= D_hi upper bounds; and the
mass (∝ (G d^4 / (8 C^3 k) + n_e) C d^2) grows with d. So at each index the optimum is the largest
lower bound d*(C), feasible iff it is at most the least upper bound, and the problem is one
variable: C in [C_lo, C_hi] (default 4 to 12, Shigley's range). :func:`size_spring` minimizes the
mass over ln C on a grid of :data:`GRID` points zoomed :data:`ZOOMS` times onto the best point's
neighbours (to ~1e-12 in ln C), ranking infeasible points by how far apart the bounds are,
ln(d*(C) / least upper bound): with no feasible C it ends at the least infeasible spring and says
which constraints it breaks and by how much. tests/test_helical_spring.py checks it against a
brute-force grid in (d, D) and SciPy SLSQP.

Pure JAX: :func:`size_spring` runs under ``jit`` and ``vmap`` (a batch of problems); its answer is
an argmin over a grid, so differentiate the formula functions, not the sizing.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

GRID = 257  # points of each zoom of the search over ln C
ZOOMS = 6  # zooms onto the best point's two neighbours: ln(3) / 256 x (2 / 256)^5 ~ 1e-13 in ln C
BIND_TOL = 1e-6  # a constraint with relative slack below this binds
BROKEN_TOL = 1e-12  # a relative slack above -this is the constraint at its limit to rounding: not broken
CLASH = 0.15  # fractional overrun to closure of the free length reported (Shigley: xi >= 0.15)
SPECTRUM_SAMPLES = 2048  # lift samples over a revolution for the spectrum (1024 harmonics)
_INFEASIBLE = 1e4  # rank of an infeasible index over any ln(mass / kg) of a real spring

LOWER = ("stress", "active_coils_low", "wire_low", "coil_low")  # lower bounds on d at fixed C
UPPER = ("surge", "active_coils_high", "wire_high", "coil_high")  # upper bounds on d at fixed C
CONSTRAINTS = (*LOWER, *UPPER, "index_low", "index_high")  # the order of Sizing.slack


class HelicalProblem(NamedTuple):
    """One sizing, SI; every field a float (a batch of problems under ``vmap``)."""

    rate_N_per_m: float  # k, to be matched exactly
    force_max_N: float  # F_max = P + k s_max
    shear_modulus_Pa: float  # G
    density_kg_m3: float  # rho
    allowable_shear_Pa: float  # tau_allow
    required_hz: float  # least surge frequency (0: no surge constraint)
    wire_lo_m: float
    wire_hi_m: float
    coil_lo_m: float
    coil_hi_m: float
    index_lo: float
    index_hi: float
    coils_lo: float  # active coils
    coils_hi: float
    end_coils: float  # inactive coils (mass and solid height)


class Sizing(NamedTuple):
    """The answer of :func:`size_spring` (scalars; SI)."""

    feasible: jax.Array  # bool: every constraint holds
    wire_m: jax.Array  # d
    coil_m: jax.Array  # D (mean)
    index: jax.Array  # C
    active_coils: jax.Array  # n_a
    wahl: jax.Array  # K_w
    shear_Pa: jax.Array  # tau at F_max
    surge_hz: jax.Array  # f_n
    mass_kg: jax.Array  # with the end coils (the objective)
    active_mass_kg: jax.Array
    gap: jax.Array  # ln(largest lower bound / least upper bound) on d at C: <= 0 feasible
    slack: jax.Array  # (10,) relative slack of each of CONSTRAINTS (< 0: broken)


def rate(d, D, n_a, G):
    """k = G d^4 / (8 D^3 n_a): N/m from m, m, coils, Pa."""
    return G * d**4 / (8.0 * D**3 * n_a)


def active_coils_for(d, D, k, G):
    """n_a = G d^4 / (8 D^3 k): the active coils giving rate k (N/m)."""
    return G * d**4 / (8.0 * D**3 * k)


def wahl_factor(C):
    """K_w = (4C - 1) / (4C - 4) + 0.615 / C (C > 1)."""
    return (4.0 * C - 1.0) / (4.0 * C - 4.0) + 0.615 / C


def shear_stress(F, d, D):
    """tau = K_w 8 F D / (pi d^3) (Pa): force N, diameters m."""
    return wahl_factor(D / d) * 8.0 * F * D / (math.pi * d**3)


def active_mass(d, D, n_a, rho):
    """m_a = pi^2 d^2 D n_a rho / 4 (kg): the active coils' wire (length pi D n_a)."""
    return math.pi**2 * d**2 * D * n_a * rho / 4.0


def surge_frequency(d, D, n_a, G, rho):
    """f_n = d / (2 pi n_a D^2) sqrt(G / (2 rho)) (Hz): the spring between fixed ends."""
    return d / (2.0 * math.pi * n_a * D**2) * jnp.sqrt(G / (2.0 * rho))


def surge_frequency_from_mass(k, m_a):
    """f_n = (1/2) sqrt(k / m_a) (Hz): the same surge from the rate (N/m) and active mass (kg)."""
    return 0.5 * jnp.sqrt(k / m_a)


def _bounds(p: HelicalProblem, C):
    """Lower and upper bounds on d (m) at index C: arrays (4, ...) in the order of LOWER, UPPER."""
    k, G = p.rate_N_per_m, p.shear_modulus_Pa
    stress = jnp.sqrt(8.0 * p.force_max_N * C * wahl_factor(C) / (math.pi * p.allowable_shear_Pa))
    coil_d = 8.0 * C**3 * k / G  # d per active coil at C
    wave = 4.0 * C * k * jnp.sqrt(G / (2.0 * p.density_kg_m3)) / (math.pi * G)  # f_n d^2
    surge = jnp.sqrt(wave / jnp.where(p.required_hz > 0.0, p.required_hz, 1.0))
    surge = jnp.where(p.required_hz > 0.0, surge, jnp.inf)
    lower = jnp.stack([stress, coil_d * p.coils_lo, p.wire_lo_m + 0.0 * C, p.coil_lo_m / C])
    upper = jnp.stack([surge, coil_d * p.coils_hi, p.wire_hi_m + 0.0 * C, p.coil_hi_m / C])
    return lower, upper


def _rank(p: HelicalProblem, u):
    """The search's merit at ln C = u: ln(mass / kg) where feasible, else _INFEASIBLE + the gap."""
    C = jnp.exp(u)
    lower, upper = _bounds(p, C)
    d = jnp.max(lower, axis=0)
    gap = jnp.log(d) - jnp.log(jnp.min(upper, axis=0))
    n_a = d / (8.0 * C**3 * p.rate_N_per_m / p.shear_modulus_Pa)
    mass = active_mass(d, C * d, n_a + p.end_coils, p.density_kg_m3)
    return jnp.where(gap <= 0.0, jnp.log(mass), _INFEASIBLE + gap)


def size_spring(p: HelicalProblem, grid: int = GRID, zooms: int = ZOOMS) -> Sizing:
    """The least-mass spring of rate k within the constraints (see the module docstring), or, with
    none feasible, the least infeasible one (``feasible`` False, ``gap`` > 0). ``jit``/``vmap``."""
    a, b = jnp.log(p.index_lo), jnp.log(p.index_hi)
    lo, hi = a, b
    best_u, best_r = a, _rank(p, a)
    for _ in range(zooms):
        us = jnp.linspace(lo, hi, grid)
        r = _rank(p, us)
        i = jnp.argmin(r)
        better = r[i] < best_r
        best_u, best_r = jnp.where(better, us[i], best_u), jnp.where(better, r[i], best_r)
        h = (hi - lo) / (grid - 1)
        lo, hi = jnp.maximum(best_u - h, a), jnp.minimum(best_u + h, b)
    return sizing_at(p, jnp.exp(best_u))


def sizing_at(p: HelicalProblem, C) -> Sizing:
    """The spring of index C with the wire at its largest lower bound (the least mass at C)."""
    lower, upper = _bounds(p, C)
    d = jnp.max(lower)
    gap = jnp.log(d) - jnp.log(jnp.min(upper))
    D = C * d
    k, G, rho = p.rate_N_per_m, p.shear_modulus_Pa, p.density_kg_m3
    n_a = active_coils_for(d, D, k, G)
    tau = shear_stress(p.force_max_N, d, D)
    f_n = surge_frequency(d, D, n_a, G, rho)
    m_a = active_mass(d, D, n_a, rho)
    required = jnp.where(p.required_hz > 0.0, p.required_hz, 1.0)
    slack = jnp.stack([
        1.0 - tau / p.allowable_shear_Pa,
        n_a / p.coils_lo - 1.0, d / p.wire_lo_m - 1.0, D / p.coil_lo_m - 1.0,
        jnp.where(p.required_hz > 0.0, f_n / required - 1.0, jnp.inf),
        1.0 - n_a / p.coils_hi, 1.0 - d / p.wire_hi_m, 1.0 - D / p.coil_hi_m,
        C / p.index_lo - 1.0, 1.0 - C / p.index_hi,
    ])
    return Sizing(gap <= 0.0, d, D, C, n_a, wahl_factor(C), tau, f_n,
                  active_mass(d, D, n_a + p.end_coils, rho), m_a, gap, slack)


def significant_harmonic(s, tail: float) -> jax.Array:
    """H: the least harmonic such that the harmonics above it hold at most ``tail`` of the spectral
    energy of ``s`` (samples over one revolution, equally spaced, shape (N,)); an int array
    (``jit``/``vmap``; an integer has no gradient)."""
    c = jnp.fft.rfft(s - jnp.mean(s))[1:]
    energy = jnp.abs(c) ** 2
    total = jnp.sum(energy)
    cum = jnp.cumsum(energy) / jnp.where(total > 0.0, total, 1.0)
    return 1 + jnp.argmax(cum >= 1.0 - tail)


# ------------------------------------------------------------------------------ the scene's sizing


def check_scene(scene, error) -> None:
    """Refuse what the sizing cannot take (``error(field, msg)`` makes the exception): a rocker (its
    spring acts about the pivot), a follower without a spring."""
    from camjax import followers

    spec = scene.synthesis.helical if scene.synthesis is not None else None
    if spec is None:
        return
    if followers.of(scene).rocking:
        raise error("synthesis.helical_spring", "a helical spring is sized for translating followers "
                    "only (a rocker's spring acts about its pivot, N m/rad: not yet)")
    train = scene.follower.train
    if train is None or float(train.spring_N_per_m) <= 0.0:
        raise error("follower.spring_N_per_m", "synthesis.helical_spring needs the follower's spring "
                    "(allowed: follower.spring_N_per_m > 0, or synthesis.spring_N_per_m = [low, high])")


def lift_samples(program) -> np.ndarray:
    """The follower's lift s (scene units) at :data:`SPECTRUM_SAMPLES` angles over a revolution."""
    from camjax.program import evaluate

    return np.asarray(evaluate(program, SPECTRUM_SAMPLES).s)


def scene_problem(scene, fixed) -> tuple[HelicalProblem, dict]:
    """The sizing of the spring of ``fixed`` (the scene the design is written from: its follower
    train's rate and preload) with the material and ranges of ``scene``'s
    [synthesis.helical_spring]; and what the report says of its data."""
    spec = scene.synthesis.helical
    spring = scene.synthesis.spring
    overspeed = spring.overspeed if spring is not None else 1.0
    train = fixed.follower.train
    k = float(train.spring_N_per_m)
    preload = k * float(train.preload_mm) * 1e-3
    s = lift_samples(fixed.motion.program)
    levels = np.cumsum([0.0, *(float(h) if kind == "rise" else -float(h) if kind == "return" else 0.0
                               for kind, h in zip(fixed.motion.program.kinds,
                                                  np.asarray(fixed.motion.program.lifts), strict=True))])
    s_max = max(float(s.max()), float(levels.max()))  # mm
    cam_hz = fixed.motion.rpm / 60.0 * overspeed
    given = spec.harmonics is not None
    harmonic = spec.harmonics if given else int(significant_harmonic(jnp.asarray(s), spec.spectrum_tail))
    required = spec.surge_ratio * harmonic * cam_hz
    p = HelicalProblem(k, preload + k * s_max * 1e-3, spec.shear_modulus_GPa * 1e9, spec.density_kg_m3,
                       spec.allowable_shear_MPa * 1e6, required, spec.wire_mm[0] * 1e-3,
                       spec.wire_mm[1] * 1e-3, spec.coil_mm[0] * 1e-3, spec.coil_mm[1] * 1e-3, *spec.index,
                       *spec.active_coils, spec.end_coils)
    data = {"rate_N_per_m": k, "preload_N": preload, "lift_max_mm": s_max, "force_max_N": p.force_max_N,
            "cam_hz": cam_hz, "harmonic": harmonic,
            "harmonic_source": "given" if given else f"spectrum (tail {spec.spectrum_tail:g})",
            "harmonic_hz": harmonic * cam_hz, "surge_ratio": spec.surge_ratio, "required_surge_hz": required}
    return p, data


def helical_report(scene, fixed) -> dict:
    """result.json's ``helical`` block: the least-mass spring (``status`` "optimal") with the
    constraints that bind, or (``status`` "infeasible") the least infeasible spring's broken
    constraints and by how much, in ``message``, and no dimensions."""
    p, data = scene_problem(scene, fixed)
    sz = jax.jit(size_spring)(jax.tree.map(jnp.asarray, p))
    slack = {n: (v if math.isfinite(v) else None)  # None: the surge constraint is off
             for n, v in zip(CONSTRAINTS, np.asarray(sz.slack).tolist(), strict=True)}
    sz = sz._replace(slack=None)
    sz = Sizing(*(None if v is None else float(v) for v in sz))
    spec = scene.synthesis.helical
    limits = {"allowable_shear_MPa": spec.allowable_shear_MPa, "wire_bounds_mm": list(spec.wire_mm),
              "coil_bounds_mm": list(spec.coil_mm), "index_bounds": list(spec.index),
              "active_coils_bounds": list(spec.active_coils), "end_coils": spec.end_coils,
              "shear_modulus_GPa": spec.shear_modulus_GPa, "density_kg_m3": spec.density_kg_m3}
    if not sz.feasible:
        broken = {n: v for n, v in slack.items() if v is not None and v < -BROKEN_TOL}
        lower, _ = _bounds(p, jnp.asarray(sz.index))
        least = {"index": sz.index, "wire_mm": 1e3 * sz.wire_m, "coil_mm": 1e3 * sz.coil_m,
                 "active_coils": sz.active_coils, "shear_MPa": 1e-6 * sz.shear_Pa, "surge_hz": sz.surge_hz,
                 "wire_set_by": LOWER[int(np.argmax(np.asarray(lower)))]}
        return {"status": "infeasible", **data, **limits, "broken": broken, "least_infeasible": least,
                "message": infeasible_message(p, sz, slack)}
    solid = sz.wire_m * (sz.active_coils + p.end_coils)
    travel = p.force_max_N / p.rate_N_per_m  # compression at the largest lift, m
    return {
        "status": "optimal", **data,
        "wire_mm": 1e3 * sz.wire_m, "coil_mm": 1e3 * sz.coil_m,
        "outer_diameter_mm": 1e3 * (sz.coil_m + sz.wire_m),
        "active_coils": sz.active_coils, "total_coils": sz.active_coils + p.end_coils, "index": sz.index,
        "wahl_factor": sz.wahl, "shear_MPa": 1e-6 * sz.shear_Pa, "surge_hz": sz.surge_hz,
        "mass_kg": sz.mass_kg, "active_mass_kg": sz.active_mass_kg,
        "solid_height_mm": 1e3 * solid, "free_length_mm": 1e3 * (solid + (1.0 + CLASH) * travel),
        "rate_check_N_per_m": float(rate(sz.wire_m, sz.coil_m, sz.active_coils, p.shear_modulus_Pa)),
        **limits, "binding": [n for n, v in slack.items() if v is not None and v <= BIND_TOL],
        "slack": slack,
    }


def infeasible_message(p: HelicalProblem, sz: Sizing, slack: dict) -> str:
    """One line: the least infeasible spring (where the bounds on d are least far apart) and each
    constraint it breaks, with its value against its limit."""
    C, d, D = float(sz.index), 1e3 * float(sz.wire_m), 1e3 * float(sz.coil_m)
    lower, _ = _bounds(p, jnp.asarray(C))
    sets = LOWER[int(np.argmax(np.asarray(lower)))]
    parts = []
    for name, v in slack.items():
        if v is None or v >= 0.0:
            continue
        if name == "stress":
            parts.append(f"shear stress {1e-6 * float(sz.shear_Pa):.4g} MPa > allowable "
                         f"{1e-6 * p.allowable_shear_Pa:.4g} MPa ({-100 * v:.3g} % over)")
        elif name == "surge":
            parts.append(f"surge frequency {float(sz.surge_hz):.4g} Hz < required {p.required_hz:.4g} Hz "
                         f"({-100 * v:.3g} % short)")
        elif name.startswith("active_coils"):
            parts.append(f"{float(sz.active_coils):.4g} active coils outside "
                         f"[{p.coils_lo:g}, {p.coils_hi:g}]")
        elif name.startswith("wire"):
            parts.append(f"wire {d:.4g} mm outside [{1e3 * p.wire_lo_m:g}, {1e3 * p.wire_hi_m:g}] mm")
        else:
            parts.append(f"coil {D:.4g} mm outside [{1e3 * p.coil_lo_m:g}, {1e3 * p.coil_hi_m:g}] mm")
    return (f"no helical spring in the ranges: the least infeasible (C = {C:.4g}, d = {d:.4g} mm set by "
            f"{sets}, D = {D:.4g} mm) breaks {'; '.join(parts)}")


def with_helical(scene, fixed, spring: dict | None) -> dict | None:
    """result.json's ``synthesis.codesign.spring`` with the ``helical`` block where the scene asks
    for one: the designed spring's report (:func:`camjax.codesign.search.spring_report`), or, when
    no spring is designed, the follower's rate and preload (``designed`` False)."""
    if scene.synthesis is None or scene.synthesis.helical is None:
        return spring
    if spring is None:
        train = fixed.follower.train
        k, x0 = float(train.spring_N_per_m), float(train.preload_mm)
        spring = {"designed": False, "rate_N_per_m": k, "preload_N": k * x0 * 1e-3, "preload_mm": x0}
    return {**spring, "helical": helical_report(scene, fixed)}
