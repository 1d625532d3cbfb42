"""[follower], [contact], [design], [guide] and [dynamics]: each section's keys checked and read."""

from __future__ import annotations

import math
from typing import Any

from camjax.contact import Material
from camjax.errors import MISSING, SceneError
from camjax.followers.oscillating_flat.geometry import OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM
from camjax.followers.roller.geometry import ROLLER_MIN_CURVATURE_RADIUS_MM
from camjax.loads import FollowerTrain, Guide, RockerTrain
from camjax.scene.reader import DEFAULT, TableReader, build, fixed_or_free, number_list
from camjax.scene.spec import (
    DYNAMICS_COMPUTE,
    FOLLOWER_TYPES,
    OSCILLATING_TYPES,
    ContactSpec,
    DesignSpec,
    DynamicsSpec,
    FollowerSpec,
    MotionSpec,
)
from camjax.solvers.registry import MODES, SOLVERS


def parse_follower(r: TableReader) -> FollowerSpec:
    ftype = r.choice("type", FOLLOWER_TYPES)
    if ftype in OSCILLATING_TYPES:
        return parse_oscillating_follower(r, ftype)
    r.check_keys(("type", "mass_kg", "spring_N_per_m", "preload_mm", "damping_Ns_per_m",
                  "gravity_m_s2", "roller_radius_mm", "offset_mm", "max_pressure_angle_deg",
                  "min_curvature_radius_mm"))
    train = None
    if r.has("mass_kg") or r.has("spring_N_per_m"):
        train = build(
            FollowerTrain,
            mass_kg=r.number("mass_kg", DEFAULT, low=0.0),
            spring_N_per_m=r.number("spring_N_per_m", DEFAULT, low=0.0),
            preload_mm=r.number("preload_mm", DEFAULT),
            damping_Ns_per_m=r.number("damping_Ns_per_m", DEFAULT, low=0.0),
            gravity_m_s2=r.number("gravity_m_s2", DEFAULT),
        )
    else:
        for key in ("preload_mm", "damping_Ns_per_m", "gravity_m_s2"):
            if r.has(key):
                raise r.error(key, r.table[key], "needs mass_kg or spring_N_per_m (loads are off)")
    if ftype == "roller":
        limit = r.number("max_pressure_angle_deg", DEFAULT, low=0.0, low_open=True)
        if limit is not DEFAULT and limit >= 90.0:
            raise r.error("max_pressure_angle_deg", limit, "out of range", "> 0 and < 90")
        return build(FollowerSpec, type=ftype, train=train,
                      roller_radius_mm=r.number("roller_radius_mm", low=0.0, low_open=True),
                      offset_mm=r.number("offset_mm", DEFAULT), max_pressure_angle_deg=limit,
                      # a roller's default differs from the flat face's: 0 = just no undercut
                      min_curvature_radius_mm=r.number("min_curvature_radius_mm",
                                                       ROLLER_MIN_CURVATURE_RADIUS_MM, low=0.0))
    for key in ("roller_radius_mm", "offset_mm", "max_pressure_angle_deg"):
        if r.has(key):
            raise r.error(key, r.table[key], "only for type = 'roller'")
    # > 0: a flat face on rho = 0 rides a corner, where the contact stress is unbounded
    return build(FollowerSpec, type=ftype, train=train,
                  min_curvature_radius_mm=r.number("min_curvature_radius_mm", DEFAULT, low=0.0,
                                                   low_open=True))


OSCILLATING_KEYS = {
    "oscillating_roller": ("pivot_distance_mm", "arm_length_mm", "roller_radius_mm", "max_pressure_angle_deg",
                           "min_curvature_radius_mm"),
    "oscillating_flat": ("pivot_distance_mm", "face_offset_mm", "min_curvature_radius_mm"),
}
ROCKER_LOAD_KEYS = ("inertia_kg_m2", "spring_N_m_per_rad", "preload_rad", "damping_N_m_s_per_rad")


def parse_oscillating_follower(r: TableReader, ftype: str) -> FollowerSpec:
    """[follower] of a rocker: pivot, arm or face, limits, and the train about the pivot.

    Whether the geometry closes for the prime (base) radius the cam gets is checked where that
    radius is known (the design or the sizing); here d > 0, l > 0 and R_f > 0.
    """
    own = OSCILLATING_KEYS[ftype]
    translating = ("mass_kg", "spring_N_per_m", "preload_mm", "damping_Ns_per_m", "gravity_m_s2", "offset_mm")
    for key in translating:
        if r.has(key):
            raise r.error(key, r.table[key], f"not a key of an {ftype} follower",
                          ", ".join((*own, *ROCKER_LOAD_KEYS)))
    r.check_keys(("type", *own, *ROCKER_LOAD_KEYS))
    train = None
    if r.has("inertia_kg_m2") or r.has("spring_N_m_per_rad"):
        train = build(RockerTrain, inertia_kg_m2=r.number("inertia_kg_m2", DEFAULT, low=0.0),
                       spring_N_m_per_rad=r.number("spring_N_m_per_rad", DEFAULT, low=0.0),
                       preload_rad=r.number("preload_rad", DEFAULT),
                       damping_N_m_s_per_rad=r.number("damping_N_m_s_per_rad", DEFAULT, low=0.0))
    else:
        for key in ("preload_rad", "damping_N_m_s_per_rad"):
            if r.has(key):
                raise r.error(key, r.table[key], "needs inertia_kg_m2 or spring_N_m_per_rad (loads are off)")
    pivot = r.number("pivot_distance_mm", low=0.0, low_open=True)
    if ftype == "oscillating_flat":
        # a flat face's own default (rho > 0: a face on rho = 0 rides a corner)
        return build(FollowerSpec, type=ftype, train=train, pivot_distance_mm=pivot,
                      face_offset_mm=r.number("face_offset_mm", DEFAULT),
                      min_curvature_radius_mm=r.number("min_curvature_radius_mm",
                                                       OSCILLATING_FLAT_MIN_CURVATURE_RADIUS_MM, low=0.0,
                                                       low_open=True))
    limit = r.number("max_pressure_angle_deg", DEFAULT, low=0.0, low_open=True)
    if limit is not DEFAULT and limit >= 90.0:
        raise r.error("max_pressure_angle_deg", limit, "out of range", "> 0 and < 90")
    return build(FollowerSpec, type=ftype, train=train, pivot_distance_mm=pivot,
                  arm_length_mm=r.number("arm_length_mm", low=0.0, low_open=True),
                  roller_radius_mm=r.number("roller_radius_mm", low=0.0, low_open=True),
                  max_pressure_angle_deg=limit,
                  # as for a translating roller: 0 = just no undercut
                  min_curvature_radius_mm=r.number("min_curvature_radius_mm", ROLLER_MIN_CURVATURE_RADIUS_MM,
                                                   low=0.0))

def parse_material(r: TableReader) -> Material:
    r.check_keys(("E_MPa", "poisson"))
    return Material(r.number("E_MPa", low=0.0, low_open=True),
                    r.number("poisson", low=-1.0, low_open=True, high=0.5))


def parse_contact(r: TableReader) -> ContactSpec:
    r.check_keys(("cam_width_mm", "cam", "follower"))
    return ContactSpec(cam_width_mm=r.number("cam_width_mm", low=0.0, low_open=True),
                       cam=parse_material(r.sub("cam")), follower=parse_material(r.sub("follower")))


DESIGN_VARIABLES = {"flat": ("base_radius_mm", "face_width_mm"),
                    "roller": ("base_radius_mm", "roller_radius_mm", "offset_mm"),
                    "oscillating_roller": ("base_radius_mm", "roller_radius_mm", "pivot_distance_mm",
                                           "arm_length_mm"),
                    "oscillating_flat": ("base_radius_mm", "pivot_distance_mm", "face_offset_mm")}


def rocker_sigma_max(r: TableReader, has_contact: bool, common: dict) -> float | None:
    """sigma_max_MPa of a roller or rocker [design]: required with [contact], refused without (no stress)."""
    if has_contact:
        return r.number("sigma_max_MPa", low=0.0, low_open=True)
    if r.has("sigma_max_MPa"):
        raise r.error("sigma_max_MPa", r.table["sigma_max_MPa"], "needs a [contact] section (no "
                      "stress is modelled without it)")
    if common["gamma"] != 0:
        raise r.error("gamma", common["gamma"], "the stress term needs a [contact] section",
                      "0 without [contact]")
    return None


def check_rocker_closes(r: TableReader, base, roller, pivot_distance_mm, arm_length_mm) -> None:
    """Refuse bounds in which no oscillating-roller design closes: |d - l| < R_p < d + l nowhere.

    Designs of the box that do not close are left to the solver's reach constraint; a box with
    none that does is a scene error naming pivot_distance_mm (the pivot cannot be placed).
    """
    (d0, d1), (l0, l1) = pivot_distance_mm, arm_length_mm
    rp0, rp1 = base[0] + roller[0], base[1] + roller[1]
    gap = max(d0 - l1, l0 - d1, 0.0)  # smallest |d - l| in the box
    if rp1 <= gap or rp0 >= d1 + l1:
        value = list(pivot_distance_mm) if d0 != d1 else d0
        raise r.error("pivot_distance_mm", value,
                      f"no design in the bounds closes: the prime radius R_b + R_f ({rp0:g}..{rp1:g} mm) "
                      f"must lie between |d - l| (>= {gap:g} mm) and d + l (<= {d1 + l1:g} mm)",
                      "a pivot distance closer to the arm length, or a larger base radius")


def parse_design(r: TableReader, follower: FollowerSpec, has_contact: bool) -> DesignSpec:
    """[design] of a flat-face or roller follower (DESIGN_VARIABLES says which variables)."""
    own = DESIGN_VARIABLES[follower.type]
    others = {v for vs in DESIGN_VARIABLES.values() for v in vs} - set(own)
    for key in sorted(others):
        if r.has(key):
            raise r.error(key, r.table[key], f"is not a design variable of a {follower.type} follower",
                          ", ".join(own))
    r.check_keys(("mode", *own, "sigma_max_MPa", "alpha", "gamma", "solver", "seed"))
    common = dict(
        mode=r.choice("mode", MODES, DEFAULT),
        alpha=r.number("alpha", DEFAULT, low=0.0),
        # no stress term without [contact] (a roller may be sized without it)
        gamma=r.number("gamma", DEFAULT if has_contact else 0.0, low=0.0),
        solver=r.choice("solver", SOLVERS, DEFAULT),
        seed=r.number("seed", DEFAULT, low=0, integer=True),
    )
    if follower.type == "flat":
        spec = build(DesignSpec, base_radius_mm=r.interval("base_radius_mm"),
                      face_width_mm=r.interval("face_width_mm"),
                      sigma_max_MPa=r.number("sigma_max_MPa", low=0.0, low_open=True), **common)
    elif follower.type == "oscillating_flat":
        base = fixed_or_free(r, "base_radius_mm")
        pivot = fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2)
        offset = fixed_or_free(r, "face_offset_mm", (follower.face_offset_mm,) * 2, positive=False)
        if base[0] + offset[0] >= pivot[1] or base[1] + offset[1] <= 0:
            raise r.error("pivot_distance_mm", list(pivot) if pivot[0] != pivot[1] else pivot[0],
                          f"no design in the bounds closes: R_b + face_offset ({base[0] + offset[0]:g}.."
                          f"{base[1] + offset[1]:g} mm) must lie between 0 and the pivot distance",
                          "a larger pivot distance")
        spec = build(DesignSpec, base_radius_mm=base, face_width_mm=None,
                      sigma_max_MPa=rocker_sigma_max(r, has_contact, common), pivot_distance_mm=pivot,
                      face_offset_mm=offset, **common)
    else:
        base = fixed_or_free(r, "base_radius_mm")
        roller = fixed_or_free(r, "roller_radius_mm", (follower.roller_radius_mm,) * 2)
        if follower.type == "oscillating_roller":
            variables = dict(
                pivot_distance_mm=fixed_or_free(r, "pivot_distance_mm", (follower.pivot_distance_mm,) * 2),
                arm_length_mm=fixed_or_free(r, "arm_length_mm", (follower.arm_length_mm,) * 2))
            check_rocker_closes(r, base, roller, **variables)
        else:
            offset = fixed_or_free(r, "offset_mm", (follower.offset_mm,) * 2, positive=False)
            reach = base[0] + roller[0]  # the smallest prime radius in the box
            if max(abs(offset[0]), abs(offset[1])) >= reach:
                raise r.error("offset_mm", list(offset) if offset[0] != offset[1] else offset[0],
                              f"allows |e| >= R_p = R_b + R_f (smallest in the bounds: {reach:g} mm): the "
                              "follower axis must cut the prime circle", f"|e| < {reach:g}")
            variables = dict(offset_mm=offset)
        sigma_max = rocker_sigma_max(r, has_contact, common)
        spec = build(DesignSpec, base_radius_mm=base, face_width_mm=None, sigma_max_MPa=sigma_max,
                      roller_radius_mm=roller, **variables, **common)
    if spec.alpha == 0 and spec.gamma == 0:
        raise r.error("alpha", 0.0, "alpha and gamma are both zero: nothing to minimize",
                      "alpha >= 0, gamma >= 0, not both 0")
    return spec


def parse_guide(r: TableReader) -> Guide:
    r.check_keys(("length_mm", "cam_friction", "guide_friction", "overhang_ratio"))
    return Guide(r.number("length_mm", low=0.0, low_open=True), r.number("cam_friction", low=0.0),
                 r.number("guide_friction", low=0.0), r.number("overhang_ratio", low=0.0))


def parse_dynamics(r: TableReader, motion: MotionSpec, follower: FollowerSpec) -> DynamicsSpec:
    """Only the keys the scene gives (and what other sections imply) override the defaults of
    :class:`DynamicsSpec`, which are written there once."""
    r.check_keys(("follower", "I3", "c3", "k23", "I2", "I1", "k01", "c01", "cam_speed_hz", "compute",
                  "spring_rate", "spring_preload", "follower_damping", "weight", "samples",
                  "harmonics", "steps_per_cycle", "transient_tolerance", "max_cycles",
                  "damping_factors", "speed_factors", "wn_factors", "jump_speed_range_hz",
                  "shaping_band", "shaping_harmonics", "shaping_steps"))
    kind = r.choice("follower", ("translating", "oscillating"),
                    "oscillating" if follower.oscillating else MISSING)
    if follower.oscillating and kind != "oscillating":
        raise r.error("follower", kind, f"follower.type = {follower.type!r} swings: its dynamics is "
                      "oscillating", "oscillating")
    if kind == "oscillating" and not follower.oscillating:  # the older form: rad written as lift_mm
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


