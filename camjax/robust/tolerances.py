"""[tolerances]: which scene values are built with a spread, and the seeded samples drawn from them.

Each key of the section names a scene value and its spread, e.g.::

    [tolerances]
    roller_radius_mm = { sd = 0.01 }                      # normal, standard deviation (units of the value)
    rpm = { half_width = 30, dist = "uniform" }          # uniform in nominal +- half_width
    spring_N_per_m = { sd_percent = 5 }                  # sd as a percentage of the nominal value
    profile_error_mm = { amplitude = 0.005, harmonics = [2, 3, 5] }

A value is ``rpm`` ([motion]), a [follower] key of the scene's follower type that the scene gives
(its dimensions and its train: mass, spring, preload, ...; not the limits ``max_pressure_angle_deg``
and ``min_curvature_radius_mm``, which are requirements, not built values), ``cam_width_mm``
([contact]), a [dynamics] value of the follower train's model (``I3``, ``c3``, ``k23``: what its
residual vibration depends on besides the cam speed, which follows ``rpm`` unless [dynamics] gives
``cam_speed_hz``), or a design variable of the [design] (``base_radius_mm``, ...: the nominal is then
the solved design's value). ``profile_error_mm`` is a radial form error of the cam surface,
eps(theta) = sum_h a cos(h theta + phi_h) over the listed harmonics h, each of amplitude a (mm) and a
phase phi_h drawn uniform in [0, 2 pi) per sample; it adds to the follower's lift (translating
followers; the cam's surface moves along the follower axis to first order).

Samples are drawn with :mod:`jax.random`: sample i from ``fold_in(PRNGKey(seed), i)``, so the first
samples of a run are the same whatever the sample count (reproducible, prefix-stable).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax.errors import MISSING, SceneError
from camjax.scene.reader import TableReader

DISTRIBUTIONS = ("normal", "uniform")
SPREAD_KEYS = ("sd", "sd_percent", "half_width", "half_width_percent", "dist")
PROFILE_KEY = "profile_error_mm"
LIMIT_KEYS = ("max_pressure_angle_deg", "min_curvature_radius_mm")
CONTACT_KEYS = ("cam_width_mm",)
DYNAMICS_KEYS = ("I3", "c3", "k23")  # the follower train's plant (camjax.dynamics.context.plant_of)


class Tolerance(NamedTuple):
    """One toleranced scene value: where it lives and its spread."""

    name: str  # the scene key, e.g. "roller_radius_mm"
    section: str  # "motion", "follower", "train", "contact" or "design"
    dist: str  # "normal" or "uniform"
    spread: float  # sd (normal) or half width (uniform); percent of the nominal when ``relative``
    relative: bool  # spread given in percent of the nominal value

    def scale(self, nominal: float) -> float:
        """The spread in the value's units at ``nominal``: sd (normal) or half width (uniform)."""
        return abs(nominal) * self.spread / 100.0 if self.relative else self.spread

    def sd(self, nominal: float) -> float:
        """The standard deviation of the drawn value (uniform: half width / sqrt 3)."""
        s = self.scale(nominal)
        return s if self.dist == "normal" else s / math.sqrt(3.0)


class ProfileError(NamedTuple):
    """Radial form error of the cam surface: each harmonic of amplitude ``amplitude_mm``, random phase."""

    amplitude_mm: float
    harmonics: tuple[int, ...]


class Tolerances(NamedTuple):
    """A scene's [tolerances] (values in the section's order; ``profile`` None when not given)."""

    values: tuple[Tolerance, ...]
    profile: ProfileError | None = None


def value_names(scene) -> dict[str, str]:
    """The toleranceable values of a scene, name -> section (see the module docstring)."""
    from camjax import followers

    kind = followers.of(scene)
    out = {"rpm": "motion"}
    train = scene.follower.train
    for key in kind.keys:
        if key in LIMIT_KEYS:
            continue
        if train is not None and key in train._fields:
            out[key] = "train"
        elif train is None and key in _train_keys(kind):
            continue  # loads are off: nothing to spread
        else:
            out[key] = "follower"
    if scene.contact is not None:
        out.update(dict.fromkeys(CONTACT_KEYS, "contact"))
    if scene.dynamics is not None:
        out.update(dict.fromkeys(DYNAMICS_KEYS, "dynamics"))
    if scene.design is not None:
        out.update(dict.fromkeys(kind.variables, "design"))
    return out


def _train_keys(kind) -> tuple[str, ...]:
    from camjax.loads import FollowerTrain, RockerTrain

    return RockerTrain._fields if kind.rocking else FollowerTrain._fields


def parse_tolerances(r: TableReader, scene) -> Tolerances:
    """The [tolerances] table of ``scene`` read and checked (SceneError naming the key)."""
    from camjax import followers

    allowed = value_names(scene)
    values, profile = [], None
    for key, spec in r.table.items():
        if key == PROFILE_KEY:
            if followers.of(scene).rocking:
                raise r.error(key, spec, "a form error is modelled for translating followers only "
                              "(it adds to the lift in mm)", ", ".join(allowed))
            profile = _profile(r.sub(key))
            continue
        if key not in allowed:
            why = ("a limit, not a built value" if key in LIMIT_KEYS else
                   "not a value of this scene" if key in _known_anywhere() else "unknown value")
            if scene.dynamics is not None and _is_dynamics_key(key):
                why = ("a [dynamics] value the follower train's residual vibration does not use (its "
                       "plant: " + ", ".join(DYNAMICS_KEYS) + ")")
            elif key in DYNAMICS_KEYS:
                why = "a [dynamics] value: the scene has no [dynamics]"
            raise r.error(key, spec, why, ", ".join([*allowed, PROFILE_KEY]))
        values.append(_spread(r.sub(key), key, allowed[key]))
    return Tolerances(tuple(values), profile)


def _known_anywhere() -> set[str]:
    from camjax import followers

    return ({k for f in followers.all_followers() for k in (*f.keys, *f.variables)}
            | {"rpm", *CONTACT_KEYS, *DYNAMICS_KEYS})


def _is_dynamics_key(key: str) -> bool:
    from dataclasses import fields

    from camjax.scene.spec import DynamicsSpec

    return key in {f.name for f in fields(DynamicsSpec)}


def _spread(r: TableReader, name: str, section: str) -> Tolerance:
    r.check_keys(SPREAD_KEYS)
    dist = r.choice("dist", DISTRIBUTIONS, "normal") if r.has("dist") else "normal"
    wanted = ("sd", "sd_percent") if dist == "normal" else ("half_width", "half_width_percent")
    given = [k for k in SPREAD_KEYS[:4] if r.has(k)]
    wrong = [k for k in given if k not in wanted]
    if wrong:
        raise r.error(wrong[0], r.table[wrong[0]], f"not a spread of a {dist} distribution",
                      " or ".join(wanted))
    if len(given) != 1:
        raise SceneError(r.path, MISSING if not given else {k: r.table[k] for k in given},
                         f"give exactly one spread of a {dist} distribution", " or ".join(wanted),
                         r.source)
    key = given[0]
    spread = r.number(key, low=0.0)
    if not math.isfinite(spread):
        raise r.error(key, spread, "must be finite")
    return Tolerance(name, section, dist, float(spread), key.endswith("_percent"))


def _profile(r: TableReader) -> ProfileError:
    r.check_keys(("amplitude", "harmonics"))
    amplitude = r.number("amplitude", low=0.0)
    raw = r.table.get("harmonics", MISSING)
    if raw is MISSING:
        raise r.error("harmonics", MISSING, "is required (a list of positive integers, e.g. [2, 3, 5])")
    if (not isinstance(raw, list) or not raw or len(raw) > 64
            or any(isinstance(h, bool) or not isinstance(h, int) or not 1 <= h <= 1000 for h in raw)):
        raise r.error("harmonics", raw, "must be a list of 1 to 64 integers in 1..1000", "e.g. [2, 3, 5]")
    if not math.isfinite(amplitude):
        raise r.error("amplitude", amplitude, "must be finite")
    return ProfileError(float(amplitude), tuple(int(h) for h in raw))


# ------------------------------------------------------------------------------ drawing


class Draws(NamedTuple):
    """Samples (leading axis N): standard variates and the form error's phases."""

    unit: jax.Array  # (N, k): standard normal (normal) or uniform in [-1, 1] (uniform) per value
    phases: jax.Array  # (N, H): phases of the form error's harmonics, rad in [0, 2 pi)


DRAW_BLOCK = 4096  # samples drawn per call of one compiled program (any N shares it)


def draw(tolerances: Tolerances, samples: int, seed: int, dtype=None) -> Draws:
    """``samples`` seeded draws (sample i from ``fold_in(PRNGKey(seed), i)``: prefix-stable)."""
    dtype = dtype or jnp.result_type(float)
    k = len(tolerances.values)
    h = 0 if tolerances.profile is None else len(tolerances.profile.harmonics)
    uniform = tuple(t.dist == "uniform" for t in tolerances.values)
    program = _draw_program(uniform, h, jnp.dtype(dtype).name)
    base = jax.random.PRNGKey(int(seed))
    units, phases = [], []
    for start in range(0, int(samples), DRAW_BLOCK):
        u, p = program(base, jnp.arange(start, start + DRAW_BLOCK))
        units.append(u)
        phases.append(p)
    if not units:
        return Draws(jnp.zeros((0, k), dtype), jnp.zeros((0, h), dtype))
    return Draws(jnp.concatenate(units)[:samples], jnp.concatenate(phases)[:samples])


@functools.lru_cache(maxsize=16)
def _draw_program(uniform: tuple[bool, ...], h: int, dtype: str):
    """The jitted draw of a block of sample indices (one per distribution pattern and dtype)."""
    k = len(uniform)
    mask = jnp.asarray(uniform, bool)

    def one(base, i):
        kv, ku, kp = jax.random.split(jax.random.fold_in(base, i), 3)
        z = jnp.where(mask, jax.random.uniform(ku, (k,), dtype, -1.0, 1.0),
                      jax.random.normal(kv, (k,), dtype))
        return z, jax.random.uniform(kp, (h,), dtype, 0.0, 2.0 * jnp.pi)

    return jax.jit(jax.vmap(one, in_axes=(None, 0)))
