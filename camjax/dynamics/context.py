"""Scene -> models: the plant, drive, force closure and cam of a scene's [dynamics], and the
context every analysis of :mod:`camjax.dynamics.report` reads."""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from camjax import program as prog
from camjax.dynamics.compensation import (
    compensate_linear,
)
from camjax.dynamics.harmonics import (
    TWO_PI,
    CamHarmonics,
    CamValues,
    cam_grid,
    harmonics_from_samples,
)
from camjax.dynamics.integrate import Drive
from camjax.dynamics.jump import (
    ForceClosure,
)
from camjax.dynamics.plant import (
    Plant,
)

# ------------------------------------------------------------------------ scene -> models


def plant_of(spec) -> Plant:
    """The follower train of a :class:`~camjax.scene.DynamicsSpec`."""
    return Plant(jnp.asarray(spec.I3), jnp.asarray(spec.c3), jnp.asarray(spec.k23))


def drive_of(spec) -> Drive:
    """The drive of a DynamicsSpec with drive flexibility (I1, k01, c01 given)."""
    return Drive(jnp.asarray(spec.I1), jnp.asarray(spec.I2), jnp.asarray(spec.k01), jnp.asarray(spec.c01))


def closure_of(spec) -> ForceClosure:
    """The force closure of a DynamicsSpec with a spring."""
    return ForceClosure(jnp.asarray(spec.I2), jnp.asarray(spec.spring_rate),
                        jnp.asarray(spec.spring_preload), jnp.asarray(spec.follower_damping),
                        jnp.asarray(spec.weight))


def synthesis_train(scene):
    """The follower train of a scene's [dynamics] as :class:`camjax.synthesis.vibration.Train` (the
    numbers the synthesis' train terms need, from :func:`plant_of` and :func:`closure_of`), with each
    designed segment's level at its start and signed lift in SI (the program's, as
    :func:`program_cam` scales it) and the speeds of [synthesis]'s band. None without [dynamics]."""
    from camjax.dynamics.plant import damping_ratio, natural_frequency_rad_s
    from camjax.synthesis.vibration import Train

    spec = scene.dynamics
    if spec is None:
        return None
    plant = plant_of(spec)
    syn = scene.synthesis
    band, count = (syn.speed_band, syn.speed_count) if syn is not None else (0.0, 1)
    factors = tuple(float(f) for f in (1.0 + band * np.linspace(-1.0, 1.0, count))) if count > 1 else (1.0,)
    program = scene.motion.program
    segments = {}
    for ds in scene.motion.designed:
        lo = program.start_deg[ds.index]
        ends = prog.motion_at_compiled(program, jnp.asarray([lo, lo + ds.angle_deg])).s
        s0, s1 = (float(v) * spec.motion_scale for v in np.asarray(ends))
        segments[ds.index] = (s0, s1 - s0)
    return Train(as_float(natural_frequency_rad_s(plant)), as_float(damping_ratio(plant)),
                 TWO_PI * float(spec.cam_speed_hz), factors, float(spec.k23), float(spec.I2),
                 float(spec.follower_damping), None if spec.spring_rate is None else float(spec.spring_rate),
                 float(spec.spring_preload), float(spec.weight), segments)


def program_cam(scene, samples: int | None = None, n_harmonics: int | None = None) -> CamHarmonics:
    """The scene's motion program as CamHarmonics in SI (m or rad), from the FFT of its samples."""
    spec = scene.dynamics
    n = spec.samples if samples is None else samples
    kin = prog.evaluate(scene.motion.program, n)
    return harmonics_from_samples(kin.s * spec.motion_scale, spec.harmonics if n_harmonics is None
                                  else n_harmonics)


def program_values(scene, angles_rad: jax.Array) -> CamValues:
    """Exact program law (not its harmonics) at arbitrary cam angles, SI."""
    kin = prog.motion_at(scene.motion.program, jnp.rad2deg(angles_rad))
    k = scene.dynamics.motion_scale
    return CamValues(kin.s * k, kin.ds * k, kin.d2s * k)


def shaping_constraints(scene) -> tuple[np.ndarray, np.ndarray]:
    """Cam angles (rad) and levels (SI) pinned by law shaping: every joint and dwell samples."""
    p = scene.motion.program
    angles = []
    for kind, start, width in zip(p.kinds, p.start_deg, p.angles_deg, strict=True):
        angles.extend(np.linspace(start, start + width, max(2, int(width // 5) + 1)) if kind == "dwell"
                      else [start])
    angles_deg = np.mod(np.asarray(angles), 360.0)
    levels = np.asarray(prog.motion_at_compiled(p, angles_deg).s) * scene.dynamics.motion_scale
    return np.deg2rad(angles_deg), levels


def as_float(x) -> float:
    return float(np.asarray(x))


def finite_or_none(x) -> float | None:
    v = as_float(x)
    return v if math.isfinite(v) else None


def coefficients_json(cam: CamHarmonics) -> dict:
    return {"cos": np.asarray(cam.cos).tolist(), "sin": np.asarray(cam.sin).tolist()}


@dataclass(frozen=True)
class Context:
    """What every analysis of one scene shares: models, the cam and its linear compensation."""

    scene: object  # camjax.scene.Scene with a [dynamics] section
    plant: Plant
    omega: float  # cam speed Omega, rad/s
    phi: jax.Array  # (N,) cam-angle grid, rad
    cam: CamHarmonics  # the program's harmonics, SI
    linear: CamHarmonics  # its linear compensation at Omega

    @property
    def spec(self):
        return self.scene.dynamics


def context(scene) -> Context:
    """The shared models of a scene with a [dynamics] section."""
    spec = scene.dynamics
    plant = plant_of(spec)
    omega = TWO_PI * spec.cam_speed_hz
    cam = program_cam(scene)
    return Context(scene, plant, omega, cam_grid(spec.samples), cam, compensate_linear(cam, plant, omega))


