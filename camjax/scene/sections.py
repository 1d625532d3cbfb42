"""[contact], [design], [guide] and [dynamics]: each section's keys checked and read.

The [follower] section is each follower type's own (:mod:`camjax.followers`), and so are its
[design] variables (:func:`parse_design` reads the keys every [design] has).
"""

from __future__ import annotations

import math
from typing import Any

from camjax.contact import Material
from camjax.errors import MISSING, SceneError
from camjax.loads import Guide
from camjax.scene.reader import DEFAULT, TableReader, build, number_list
from camjax.scene.spec import (
    DYNAMICS_COMPUTE,
    ContactSpec,
    DesignSpec,
    DynamicsSpec,
    FollowerSpec,
    MotionSpec,
    RobustSpec,
)
from camjax.solvers.registry import MODES, SOLVERS

SEED_MAX = 2**63 - 1  # design.seed / --seed: JAX takes the seed of a PRNG key as a 64-bit integer


def parse_material(r: TableReader) -> Material:
    r.check_keys(("E_MPa", "poisson"))
    return Material(r.number("E_MPa", low=0.0, low_open=True),
                    r.number("poisson", low=-1.0, low_open=True, high=0.5))


def parse_contact(r: TableReader) -> ContactSpec:
    r.check_keys(("cam_width_mm", "cam", "follower"))
    return ContactSpec(cam_width_mm=r.number("cam_width_mm", low=0.0, low_open=True),
                       cam=parse_material(r.sub("cam")), follower=parse_material(r.sub("follower")))


def sigma_max(r: TableReader, has_contact: bool, common: dict) -> float | None:
    """sigma_max_MPa of a [design]: required with [contact], refused without (no stress is
    modelled; a follower whose design needs the stress refuses a [design] without [contact] first)."""
    if has_contact:
        return r.number("sigma_max_MPa", low=0.0, low_open=True)
    if r.has("sigma_max_MPa"):
        raise r.error("sigma_max_MPa", r.table["sigma_max_MPa"], "needs a [contact] section (no "
                      "stress is modelled without it)")
    if common["gamma"] != 0:
        raise r.error("gamma", common["gamma"], "the stress term needs a [contact] section",
                      "0 without [contact]")
    return None


def parse_design(r: TableReader, follower, spec: FollowerSpec, has_contact: bool) -> DesignSpec:
    """[design] of any follower type: the keys every one has (mode, weights, solver, seed,
    sigma_max_MPa) here, its design variables from the follower (``follower.design_bounds``)."""
    from camjax import followers

    own, optional = follower.variables, follower.optional_variables
    others = {v for f in followers.all_followers() for v in (*f.variables, *f.optional_variables)}
    others -= {*own, *optional}
    for key in sorted(others):
        if r.has(key):
            raise r.error(key, r.table[key], f"is not a design variable of a {follower.name} follower",
                          ", ".join(own))
    r.check_keys(("mode", *own, *optional, "sigma_max_MPa", "alpha", "gamma", "solver", "seed", "robust"))
    common = dict(
        mode=r.choice("mode", MODES, DEFAULT),
        alpha=r.number("alpha", DEFAULT, low=0.0),
        # no stress term without [contact] (a roller may be sized without it)
        gamma=r.number("gamma", DEFAULT if has_contact else 0.0, low=0.0),
        solver=r.choice("solver", SOLVERS, DEFAULT),
        seed=r.number("seed", DEFAULT, low=0, high=SEED_MAX, integer=True),
    )
    bounds = follower.design_bounds(r, spec)
    free = max(1, sum(1 for lo, hi in bounds.values() if hi > lo))
    robust = parse_robust(r.sub("robust"), free) if r.has("robust") else None
    names = (name for name in (*own, *optional) if name in bounds)
    design = build(DesignSpec, variables=tuple((name, bounds[name]) for name in names),
                   sigma_max_MPa=sigma_max(r, has_contact, common), robust=robust, **common)
    if design.alpha == 0 and design.gamma == 0:
        raise r.error("alpha", 0.0, "alpha and gamma are both zero: nothing to minimize",
                      "alpha >= 0, gamma >= 0, not both 0")
    return design


ROBUST_SAMPLES_MAX = 20_000  # design.robust.samples: each holds its problem on the grid (memory)


def parse_robust(r: TableReader, free: int) -> RobustSpec:
    """[design] robust = { probability, samples, seed }: a robust design's sample set, for a design
    of ``free`` free variables (d): at least d / (1 - probability) - 1 samples (the order statistic
    of :mod:`camjax.robust.design` then discards none)."""
    r.check_keys(("probability", "samples", "seed"))
    p = r.number("probability", low=0.0, low_open=True, high=1.0)
    if p >= 1.0:
        raise r.error("probability", p, "must be below 1 (no finite sample set keeps a limit surely)",
                      "0 < probability < 1")
    n = r.number("samples", low=1, high=ROBUST_SAMPLES_MAX, integer=True)
    need = math.ceil(free / (1.0 - p) - 1 - 1e-9)
    if n < need:
        raise r.error("samples", n, f"too few for probability {p:g} with {free} free design variable"
                      f"{'s' if free > 1 else ''}: at least d / (1 - probability) - 1 = {need}",
                      f"{need}..{ROBUST_SAMPLES_MAX}")
    seed = r.number("seed", 0, low=0, high=2**32 - 1, integer=True)
    return RobustSpec(float(p), int(n), int(seed))


def parse_guide(r: TableReader) -> Guide:
    r.check_keys(("length_mm", "cam_friction", "guide_friction", "overhang_ratio"))
    return Guide(r.number("length_mm", low=0.0, low_open=True), r.number("cam_friction", low=0.0),
                 r.number("guide_friction", low=0.0), r.number("overhang_ratio", low=0.0))


def parse_dynamics(r: TableReader, motion: MotionSpec, follower: FollowerSpec, rocking: bool) -> DynamicsSpec:
    """Only the keys the scene gives (and what other sections imply) override the defaults of
    :class:`DynamicsSpec`, which are written there once. ``rocking``: the follower swings (its
    dynamics is oscillating)."""
    r.check_keys(("follower", "I3", "c3", "k23", "I2", "I1", "k01", "c01", "cam_speed_hz", "compute",
                  "spring_rate", "spring_preload", "follower_damping", "weight", "samples",
                  "harmonics", "steps_per_cycle", "transient_tolerance", "max_cycles",
                  "damping_factors", "speed_factors", "wn_factors", "jump_speed_range_hz",
                  "shaping_band", "shaping_harmonics", "shaping_steps"))
    kind = r.choice("follower", ("translating", "oscillating"),
                    "oscillating" if rocking else MISSING)
    if rocking and kind != "oscillating":
        raise r.error("follower", kind, f"follower.type = {follower.type!r} swings: its dynamics is "
                      "oscillating", "oscillating")
    if kind == "oscillating" and not rocking:  # the older form: rad written as lift_mm
        for i, seg in enumerate(motion.segments):
            lift = seg.get("lift_mm", 0.0)
            if lift > math.pi:
                raise SceneError(f"motion.segments[{i}].lift_mm", lift, "with an oscillating follower "
                                 "the lift is read as rad; more than half a turn is not a cam",
                                 "lifts <= pi rad", r.source)
    default_speed = motion.rpm / 60.0
    kw: dict[str, Any] = {
        "follower": kind,
        "I3": r.number("I3", low=0.0, low_open=True),
        "c3": r.number("c3", low=0.0),
        "k23": r.number("k23", low=0.0, low_open=True),
        "cam_speed_hz": r.number("cam_speed_hz", default_speed if default_speed > 0 else MISSING,
                                 low=0.0, low_open=True),
    }
    compute = r.table.get("compute", list(DynamicsSpec.compute))
    if not (isinstance(compute, list) and all(c in DYNAMICS_COMPUTE for c in compute)):
        raise r.error("compute", compute, "must be a list of analyses", ", ".join(DYNAMICS_COMPUTE))
    kw["compute"] = tuple(dict.fromkeys(compute))
    drive_keys = [k for k in ("I1", "k01", "c01") if r.has(k)]
    if drive_keys and len(drive_keys) != 3:
        raise r.error(drive_keys[0], r.table[drive_keys[0]], "drive flexibility needs all of I1, k01, c01")
    if not drive_keys and ("drive" in compute or "nonlinear" in compute):
        raise r.error("compute", compute, "'drive' and 'nonlinear' need the drive: give I1, k01, c01")
    for k in drive_keys:
        kw[k] = r.number(k, low=0.0, low_open=(k != "c01"))
    # a translating follower's [follower] train supplies the closure and the follower inertia
    train = follower.train if kind == "translating" else None
    if train is not None:
        kw.update(I2=train.mass_kg, spring_preload=train.preload_mm * 1e-3,
                  follower_damping=train.damping_Ns_per_m, weight=train.mass_kg * train.gravity_m_s2)
        if train.spring_N_per_m > 0:
            kw["spring_rate"] = train.spring_N_per_m
    for key, low in (("I2", 0.0), ("spring_preload", None), ("follower_damping", 0.0), ("weight", None)):
        if r.has(key):
            kw[key] = r.number(key, low=low)
    if r.has("spring_rate"):
        kw["spring_rate"] = r.number("spring_rate", low=0.0, low_open=True)
    if "jump" in compute and follower.closure.positive:
        raise r.error("compute", compute, f"'jump' is not defined for a positive drive (follower.closure = "
                      f"{follower.closure.kind!r} holds the follower on its cam both ways)",
                      ", ".join(c for c in DYNAMICS_COMPUTE if c != "jump"))
    if "jump" in compute and kw.get("spring_rate") is None:
        raise r.error("compute", compute, "'jump' needs a force-closure spring: give spring_rate "
                      "(or follower.spring_N_per_m for a translating follower)")
    for key, low, high in (("samples", 8, 1_000_000), ("steps_per_cycle", 8, 100_000),
                           ("max_cycles", 2, 100_000), ("shaping_steps", 1, 100_000)):
        if r.has(key):
            kw[key] = r.number(key, low=low, high=high, integer=True)
    samples = kw.get("samples", DynamicsSpec.samples)
    # a coarse grid lowers the default harmonics (and with them the shaping harmonics)
    harmonics = (r.number("harmonics", low=1, integer=True) if r.has("harmonics")
                 else min(DynamicsSpec.harmonics, samples // 2 - 1))
    if harmonics >= samples / 2:
        raise r.error("harmonics", harmonics, "must be below samples / 2", f"< {samples / 2:g}")
    shaping_harmonics = (r.number("shaping_harmonics", low=1, integer=True) if r.has("shaping_harmonics")
                         else min(DynamicsSpec.shaping_harmonics, harmonics))
    if shaping_harmonics > harmonics:
        raise r.error("shaping_harmonics", shaping_harmonics, "must not exceed harmonics", f"<= {harmonics}")
    kw.update(harmonics=harmonics, shaping_harmonics=shaping_harmonics)
    if r.has("transient_tolerance"):
        kw["transient_tolerance"] = r.number("transient_tolerance", low=0.0, low_open=True, high=0.5)
    for key in ("damping_factors", "speed_factors", "wn_factors"):
        if r.has(key):
            kw[key] = number_list(r, key)
    for key in ("jump_speed_range_hz", "shaping_band"):
        if r.has(key):
            kw[key] = r.interval(key)
    return DynamicsSpec(**kw)


