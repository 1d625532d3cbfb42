"""The physical range of every number a scene gives, by key.

Each key's range is (smallest magnitude, largest magnitude, unit). A value of 0 passes when the key
allows 0 (its own rule, e.g. ``mass_kg >= 0``); any other value must lie within the range in
magnitude. The ranges reach far past every real cam (a lift of 1 nm to 1 km, a mass of 1 µg to
1000 t) and stop where the computation's products and quotients could leave float64: a scene value
of 1e308 kg or an inertia of 1e-300 is refused naming its field, not reported later as an overflow
with no field. A key not listed (a follower type's own) gets :data:`GENERIC`. The table is shown
in docs/scenes.md.

Integers (samples, steps, cycles, harmonics, seed) have their own exact limits in the parsers.
"""

from __future__ import annotations

LENGTH = (1e-6, 1e6, "mm")  # 1 nm .. 1 km
SIGNED_LENGTH = (0.0, 1e6, "mm")  # offsets and preloads: any sign, any small value
GENERIC = (1e-12, 1e12, "")  # a key this table does not name
INERTIA = (1e-12, 1e6, "kg or kg m^2")
STIFFNESS = (1e-9, 1e12, "N/m or N m/rad")
DAMPING = (1e-12, 1e9, "N s/m or N m s/rad")
FACTOR = (1e-6, 1e6, "")

RANGES: dict[str, tuple[float, float, str]] = {
    # [motion]
    "rpm": (1e-6, 1e6, "rpm"),
    "lift_mm": LENGTH,
    "lift_deg": (1e-6, 360.0, "deg"),  # the key's own rule (< 180) is the tighter one
    # [follower] geometry (every type), and the same names as [design] bounds
    "base_radius_mm": LENGTH,
    "face_width_mm": LENGTH,
    "roller_radius_mm": LENGTH,
    "pivot_distance_mm": LENGTH,
    "arm_length_mm": LENGTH,
    "offset_mm": SIGNED_LENGTH,
    "face_offset_mm": SIGNED_LENGTH,
    "min_curvature_radius_mm": LENGTH,
    "max_pressure_angle_deg": (1e-6, 360.0, "deg"),  # and here (< 90)
    # [follower] loads
    "mass_kg": (1e-9, 1e6, "kg"),
    "spring_N_per_m": (1e-6, 1e12, "N/m"),
    "preload_mm": SIGNED_LENGTH,
    "damping_Ns_per_m": (1e-9, 1e9, "N s/m"),
    "gravity_m_s2": (0.0, 1e4, "m/s^2"),
    "inertia_kg_m2": (1e-15, 1e6, "kg m^2"),
    "spring_N_m_per_rad": (1e-9, 1e12, "N m/rad"),
    "preload_rad": (0.0, 1e3, "rad"),
    "damping_N_m_s_per_rad": (1e-15, 1e9, "N m s/rad"),
    # [contact]
    "cam_width_mm": LENGTH,
    "E_MPa": (1e-3, 1e7, "MPa"),
    "poisson": (0.0, 1.0, ""),
    # [design]
    "sigma_max_MPa": (1e-3, 1e7, "MPa"),
    "alpha": (1e-12, 1e12, ""),
    "gamma": (1e-12, 1e12, ""),
    # [guide]
    "length_mm": LENGTH,
    "cam_friction": (0.0, 10.0, ""),
    "guide_friction": (0.0, 10.0, ""),
    "overhang_ratio": (0.0, 1e6, ""),
    # [dynamics]
    "I1": INERTIA,
    "I2": INERTIA,
    "I3": INERTIA,
    "k01": STIFFNESS,
    "k23": STIFFNESS,
    "spring_rate": STIFFNESS,
    "c01": DAMPING,
    "c3": DAMPING,
    "follower_damping": DAMPING,
    "spring_preload": (0.0, 1e3, "m or rad"),
    "weight": (0.0, 1e9, "N"),
    "cam_speed_hz": (1e-6, 1e6 / 60.0, "Hz"),
    "transient_tolerance": (1e-15, 0.5, ""),
    "damping_factors": FACTOR,
    "speed_factors": FACTOR,
    "wn_factors": FACTOR,
    "jump_speed_range_hz": (1e-6, 1e7, "Hz"),
    "shaping_band": FACTOR,
}


def physical_range(key: str) -> tuple[float, float, str]:
    """(smallest nonzero magnitude, largest magnitude, unit) of a scene key (its last name)."""
    return RANGES.get(key, GENERIC)


def outside(key: str, value: float) -> bool:
    """Whether a nonzero ``value`` of ``key`` lies outside its physical range (0 never does)."""
    lo, hi, _ = physical_range(key)
    return value != 0 and not lo <= abs(value) <= hi


def allowed_text(key: str, *, zero: bool, signed: bool) -> str:
    """The range of ``key`` in words, for a message: ``zero`` whether the key allows 0, ``signed``
    whether it allows negative values."""
    lo, hi, unit = physical_range(key)
    unit = f" {unit}" if unit else ""
    if signed:
        span = f"-{hi:g} to {hi:g}{unit}"
        return span if lo == 0 else f"0, or {lo:g} to {hi:g}{unit} in magnitude, either sign"
    span = f"{lo:g} to {hi:g}{unit}"
    return f"0, or {span}" if zero and lo > 0 else span
