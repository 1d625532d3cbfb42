"""Scene -> the design-independent arrays every later stage uses, computed once per scene.

Only what the scene declares is computed: a scene without loads gets no force, one without
[contact] no stress coefficient. Everything downstream (geometry at a trial base radius, the
objective, the report) reads from :class:`SceneArrays`.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from camjax import contact, loads, program
from camjax.program import Kinematics, TimeKinematics
from camjax.scene import Scene


class SceneArrays(NamedTuple):
    """Per-sample arrays of a scene (shape (N,) each; None where the scene does not ask)."""

    theta_deg: jax.Array  # cam angle, degrees
    kin: Kinematics  # s, s', s'', s''' (mm, per rad)
    motion: TimeKinematics  # y, y', y'', y''' (SI) at the scene's speed
    cam_speed_rad_s: jax.Array
    force_N: jax.Array | None  # kinetostatic contact force
    torque_Nm: jax.Array | None  # cam torque
    stress_coefficient: jax.Array | None  # C with sigma = C / sqrt(rho), MPa mm^0.5


def scene_arrays(scene: Scene, samples: int | None = None, dtype=None) -> SceneArrays:
    """Evaluate a scene's motion and, when declared, its loads and contact coefficient.

    Args:
      scene: a validated scene.
      samples: override the scene's grid size N.
      dtype: floating dtype (default: float64 when x64 is on). float32 halves memory and is
        about 3x faster with sin/cos, at ~1e-7 relative accuracy; see the README's limits.
    """
    dtype = dtype or jnp.result_type(float)
    n = scene.motion.samples if samples is None else int(samples)
    prog = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), scene.motion.program)
    kin = program.evaluate(prog, n)
    omega = jnp.asarray(program.rpm_to_rad_s(scene.motion.rpm), dtype)
    motion = program.time_kinematics(kin, omega)
    force = torque = coeff = None
    train = scene.follower.train
    if train is not None:
        force = loads.kinetostatic_force(train, motion)
        torque = loads.cam_torque(force, kin.ds)
        if scene.contact is not None:
            c = scene.contact
            coeff = contact.stress_coefficient(force, c.cam_width_mm, c.cam, c.follower)
    theta_deg = program.sample_angles_deg(n, dtype)
    return SceneArrays(theta_deg, kin, motion, omega, force, torque, coeff)
