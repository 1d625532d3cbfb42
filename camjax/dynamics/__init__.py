"""Follower-train dynamics, follower jump and feedforward compensation (SPEC section 6).

Models, each a pure JAX function of one design (batch with ``vmap``):

- :mod:`~camjax.dynamics.plant`: the elastic follower train :class:`Plant` (the cam imposes the
  follower motion theta2; the load theta3 follows through k23, damped to ground by c3:
  I3 theta3'' + c3 theta3' + k23 theta3 = k23 theta2) and its periodic steady state, harmonic by
  harmonic (:func:`steady_state`).
- :mod:`~camjax.dynamics.harmonics`: cam laws as limited Fourier series (:class:`CamHarmonics`),
  from the FFT of a motion program's samples.
- :mod:`~camjax.dynamics.integrate`: :func:`periodic_rk4`, the one "settle, then record the last
  cycle" RK4 loop, and the models it runs: :func:`integrate_train` and the flexible drive
  (:class:`Drive`, :func:`simulate_drive`: constant-speed motor -> coupling k01, c01 -> cam
  inertia I1 -> follower train; the cam-speed ripple).
- :mod:`~camjax.dynamics.compensation`: linear (harmonic-wise inverse of G, and its time form),
  nonlinear (drive flexibility, fitted back to a limited Fourier law), robustness grid.
- :mod:`~camjax.dynamics.jump`: contact force, jump speed, minimum preload and spring rate.
- :mod:`~camjax.dynamics.shaping`: gradient-based law shaping through the model.
- :mod:`~camjax.dynamics.report`: one function per [dynamics] ``compute`` entry and the typed
  :class:`DynamicsReport` that :func:`scene_dynamics` returns.
- :mod:`~camjax.dynamics.budget`: the work a scene asks for, estimated before it runs, the
  budget ``camjax dynamics`` refuses beyond (without ``--force``) and its progress bar.

Units: SI inside. The generalized coordinate is the follower displacement in m (translating
follower: I in kg, c in N s/m, k in N/m, forces in N) or the follower angle in rad (oscillating
follower: I in kg m^2, c in N m s/rad, k in N m/rad, "forces" are torques in N m). Cam angle phi
in rad, cam speed Omega in rad/s.
"""

from camjax.dynamics.compensation import (
    NonlinearCompensation,
    compensate_linear,
    compensate_nonlinear,
    compensate_time,
    robustness_grid,
)
from camjax.dynamics.context import (
    closure_of,
    drive_of,
    plant_of,
    program_cam,
    program_values,
    shaping_constraints,
)
from camjax.dynamics.harmonics import (
    TWO_PI,
    CamHarmonics,
    CamValues,
    cam_grid,
    evaluate_cam,
    fit_harmonics,
    harmonics_from_samples,
    max_abs,
    mean_square,
    pad_harmonics,
    trim_harmonics,
)
from camjax.dynamics.integrate import (
    Drive,
    DriveResponse,
    DriveState,
    Settling,
    TrainState,
    integrate_train,
    periodic_rk4,
    rk4_step,
    settling,
    settling_cycles,
    simulate_drive,
)
from camjax.dynamics.jump import (
    ForceClosure,
    JumpSpeed,
    contact_force,
    jump_speed,
    min_contact_force,
    min_preload,
    min_spring_rate,
)
from camjax.dynamics.plant import (
    Plant,
    damping_ratio,
    natural_frequency_rad_s,
    perturbed_plant,
    resonant_harmonic,
    steady_state,
    tracking_error_harmonics,
    transfer,
)
from camjax.dynamics.report import DynamicsReport, scene_dynamics
from camjax.dynamics.shaping import ShapingResult, band_tracking_ms, shape_law

__all__ = [
    "TWO_PI", "CamHarmonics", "CamValues", "Drive", "DriveResponse", "DriveState", "DynamicsReport",
    "ForceClosure", "JumpSpeed", "NonlinearCompensation", "Plant", "Settling", "ShapingResult",
    "TrainState", "band_tracking_ms", "cam_grid", "closure_of", "compensate_linear",
    "compensate_nonlinear", "compensate_time", "contact_force", "damping_ratio", "drive_of",
    "evaluate_cam", "fit_harmonics", "harmonics_from_samples", "integrate_train", "jump_speed",
    "max_abs", "mean_square", "min_contact_force", "min_preload", "min_spring_rate",
    "natural_frequency_rad_s", "pad_harmonics", "periodic_rk4", "perturbed_plant", "plant_of",
    "program_cam", "program_values", "resonant_harmonic", "rk4_step", "robustness_grid",
    "scene_dynamics", "settling", "settling_cycles", "shape_law", "shaping_constraints",
    "simulate_drive", "steady_state", "tracking_error_harmonics", "transfer", "trim_harmonics",
]
