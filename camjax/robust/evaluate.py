"""The nominal design of a scene evaluated for a batch of toleranced values, in one vmapped program.

Every sample goes through the models ``camjax design`` runs: the scene with the drawn values (a
traced copy of the :class:`camjax.scene.Scene`, its numbers replaced by array data), its arrays
(:func:`camjax.evaluate.arrays_from_kinematics`: kinematics, loads, contact coefficient), its
follower's design problem (``problem_from_scene`` of the follower folder's ``problem.py``) and that
family's ``evaluate`` at the nominal design (the figures of result.json's ``design`` block: peak
stress, peak pressure angle, least curvature radius, and the constraint violations). So one
compiled program serves every sample and every follower type, through the follower contract.

Outputs per sample (Python names, units in the name): ``peak_stress_MPa`` (with [contact]),
``least_contact_force_N`` (translating with loads) or ``least_contact_moment_Nm`` (rocking with
loads), ``peak_pressure_angle_deg`` (types with a pressure angle), ``least_curvature_radius_mm``,
``dwell_position_error_mm`` (with a form error: max |eps| over the dwells' samples),
``peak_acceleration_m_s2`` (translating) or ``peak_acceleration_rad_s2`` (rocking). All are the
grid's (the family evaluation's) extrema on the scene's ``[motion] samples`` grid. With [dynamics],
``residual_vibration`` (m, or rad for an oscillating train): the follower train's steady-state
vibration about the cam's motion, max over the cycle of |theta3 - theta2|, the figure ``camjax
dynamics`` reports as dynamics.json's ``nominal.max_tracking_error`` (:func:`residual_vibration`).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax import followers, program
from camjax.evaluate import arrays_from_kinematics
from camjax.family import FEASIBILITY_RTOL_STRESS, FEASIBILITY_TOL_MM, FEASIBILITY_TOL_RAD, weights_of
from camjax.program import Kinematics
from camjax.robust.tolerances import Tolerances

CURVATURE_FIELDS = ("cam_rho_min_mm", "rho_min_mm", "profile_rho_min_mm")
# limit name -> the families' Violation fields that say it is broken
LIMIT_FIELDS = {"pressure_angle": ("pressure_angle",), "undercut": ("undercut", "curvature"),
                "stress": ("stress",)}


class Nominal(NamedTuple):
    """What every sample shares: the scene, its tolerances, the nominal design and values."""

    scene: Any
    tolerances: Tolerances
    design: dict[str, float]  # the nominal design's variables (mm), as result.json reports them
    values: tuple[float, ...]  # nominal of each toleranced value (tolerances.values' order)
    scales: tuple[float, ...]  # spread of each (sd or half width, the value's units)
    sds: tuple[float, ...]  # standard deviation of each drawn value


def nominal(scene, tolerances: Tolerances, design: dict[str, float]) -> Nominal:
    """The nominal values of the toleranced scene values at the nominal ``design``."""
    vals = tuple(float(_scene_value(scene, t.name, t.section, design)) for t in tolerances.values)
    scales = tuple(t.scale(v) for t, v in zip(tolerances.values, vals, strict=True))
    sds = tuple(t.sd(v) for t, v in zip(tolerances.values, vals, strict=True))
    return Nominal(scene, tolerances, dict(design), vals, scales, sds)


def _scene_value(scene, name: str, section: str, design: dict[str, float]):
    if section == "motion":
        return scene.motion.rpm
    if section == "dynamics":
        return getattr(scene.dynamics, name)
    if section == "train":
        return getattr(scene.follower.train, name)
    if section == "follower":
        return getattr(scene.follower, name)
    if section == "contact":
        return getattr(scene.contact, name)
    return design[name]


def perturbed_scene(nom: Nominal, values) -> tuple[Any, dict[str, Any]]:
    """The scene with the toleranced values replaced by ``values`` (arrays, traceable) and the
    design (dict) with its toleranced variables replaced. A design variable that is also a
    [follower] key (e.g. a roller's radius) is replaced in both. A [dynamics] cam speed that is the
    rpm's (not given apart) follows a drawn rpm."""
    scene, design = nom.scene, dict(nom.design)
    motion, spec, contact, dyn = scene.motion, scene.follower, scene.contact, scene.dynamics
    speed_of_rpm = dyn is not None and dyn.cam_speed_hz == motion.rpm / 60.0
    train = spec.train
    for t, v in zip(nom.tolerances.values, values, strict=True):
        if t.section == "motion":
            motion = dataclasses.replace(motion, rpm=v)
            if speed_of_rpm:
                dyn = dataclasses.replace(dyn, cam_speed_hz=v / 60.0)
        elif t.section == "dynamics":
            dyn = dataclasses.replace(dyn, **{t.name: v})
        elif t.section == "train":
            train = train._replace(**{t.name: v})
        elif t.section == "follower":
            spec = dataclasses.replace(spec, **{t.name: v})
        elif t.section == "contact":
            contact = dataclasses.replace(contact, **{t.name: v})
        else:
            design[t.name] = v
            if t.name in {f.name for f in dataclasses.fields(spec)}:
                spec = dataclasses.replace(spec, **{t.name: v})
    if train is not spec.train:
        spec = dataclasses.replace(spec, train=train)
    return dataclasses.replace(scene, motion=motion, follower=spec, contact=contact, dynamics=dyn), design


class Grid(NamedTuple):
    """What every sample shares on the angle grid: the nominal kinematics and the form error's
    harmonics cos(h theta), sin(h theta) ((H, N); (0, N) without one). Passed to the batch as
    arguments, so XLA computes them once instead of inside every sample's fusion."""

    kin: Kinematics
    cos_h: jax.Array
    sin_h: jax.Array


def grid(nom: Nominal, dtype=None) -> Grid:
    """The :class:`Grid` of a nominal (traceable; a jitted call computes it once)."""
    dtype = dtype or jnp.result_type(float)
    scene = nom.scene
    prog = jax.tree_util.tree_map(lambda x: jnp.asarray(x, dtype), scene.motion.program)
    kin0 = program.evaluate(prog, scene.motion.samples)
    profile = nom.tolerances.profile
    harmonics = () if profile is None else profile.harmonics
    h = jnp.asarray(harmonics, dtype).reshape(-1, 1)
    theta = jnp.deg2rad(program.sample_angles_deg(scene.motion.samples, dtype))[None, :]
    return Grid(kin0, jnp.cos(h * theta), jnp.sin(h * theta))


def form_error(profile, phases, g: Grid, dtype):
    """eps and its first three derivatives in theta (mm, mm/rad^k) of the form error on the grid:
    sum over the harmonics h of a cos(h theta + phi_h), written as
    a (cos phi_h cos h theta - sin phi_h sin h theta) with the angle's harmonics from ``g``."""
    if profile is None:
        z = jnp.zeros_like(g.kin.s)
        return z, z, z, z
    h = jnp.asarray(profile.harmonics, dtype)[:, None]
    a = jnp.asarray(profile.amplitude_mm, dtype)
    cp, sp = a * jnp.cos(phases)[:, None], a * jnp.sin(phases)[:, None]
    c = cp * g.cos_h - sp * g.sin_h  # a cos(h theta + phi)
    s = sp * g.cos_h + cp * g.sin_h  # a sin(h theta + phi)
    return c.sum(0), -(h * s).sum(0), -(h**2 * c).sum(0), (h**3 * s).sum(0)


def output_names(scene, tolerances: Tolerances) -> tuple[str, ...]:
    """The outputs of a scene's samples, in the order :func:`sample` returns them."""
    kind = followers.of(scene)
    ev = kind.problem_module().Evaluation._fields
    names = []
    if scene.contact is not None:
        names.append("peak_stress_MPa")
    if scene.follower.train is not None:
        names.append("least_contact_moment_Nm" if kind.rocking else "least_contact_force_N")
    if "pressure_angle_max_deg" in ev:
        names.append("peak_pressure_angle_deg")
    names.append("least_curvature_radius_mm")
    if tolerances.profile is not None:
        names.append("dwell_position_error_mm")
    names.append("peak_acceleration_rad_s2" if kind.rocking else "peak_acceleration_m_s2")
    if scene.dynamics is not None:
        names.append("residual_vibration")
    return tuple(names)


def limit_names(scene) -> tuple[str, ...]:
    """The limits whose breaking is counted: contact lost (with loads) and the family's."""
    viol = followers.of(scene).problem_module().Violation._fields
    out = ["contact_lost"] if scene.follower.train is not None else []
    for name, fields in LIMIT_FIELDS.items():
        if name == "stress" and scene.contact is None:
            continue
        if any(f in viol for f in fields):
            out.append(name)
    return tuple(out)


class Sample(NamedTuple):
    """One sample's outputs (shape () each, :func:`output_names`' order), broken limits (bool,
    :func:`limit_names`' order) and curves over the cam angle (lift, acceleration, contact load)."""

    outputs: jax.Array  # (n_out,)
    broken: jax.Array  # (n_lim,) bool
    lift: jax.Array  # (N,) mm (rocking: rad)
    accel: jax.Array  # (N,) m/s^2 (rocking: rad/s^2)
    load: jax.Array  # (N,) contact force N (rocking: moment N m); zeros without loads


class Drawn(NamedTuple):
    """One sample's scene and arrays: what the models see of it."""

    scene: Any  # the scene with the drawn values (traced copy)
    design: dict[str, Any]  # the design with its toleranced variables drawn
    arrays: Any  # camjax.evaluate.SceneArrays of the drawn scene, form error included
    eps: tuple  # the form error and its first three derivatives on the grid (mm, mm/rad^k)


def drawn(nom: Nominal, values, phases, g: Grid | None = None) -> Drawn:
    """The scene, design and arrays of one sample: toleranced ``values`` ((k,) array) and form-error
    ``phases`` ((H,), rad); ``g``: the nominal's :func:`grid` (computed here when None). Traceable."""
    dtype = jnp.result_type(float)
    scene, design = perturbed_scene(nom, [values[i] for i in range(len(nom.values))])
    g = grid(nom, dtype) if g is None else g
    eps = form_error(nom.tolerances.profile, phases, g, dtype)
    kin0 = g.kin
    kin = Kinematics(kin0.theta, *(a + e for a, e in zip(kin0[1:], eps, strict=True)))
    return Drawn(scene, design, arrays_from_kinematics(scene, kin), eps)


def residual_vibration(scene, profile=None, phases=None) -> jax.Array:
    """The follower train's residual vibration of a scene with [dynamics] (m, or rad for an
    oscillating train): max over the cam cycle of |theta3 - theta2|, the load's steady-state
    deviation from the cam's motion, from the transfer function harmonic by harmonic on the
    [dynamics] ``samples`` grid: what ``camjax dynamics`` reports as ``nominal.max_tracking_error``
    (:func:`camjax.dynamics.report.nominal`). ``profile`` (a translating train only) adds the form
    error of ``phases`` to the cam's harmonics (a harmonic above [dynamics] ``harmonics`` is left
    out, as the dynamics' series leaves the law's out). Traceable in the plant, the cam speed and
    the phases; a maximum over the grid, differentiable where one sample holds it."""
    from camjax.dynamics import context as dc
    from camjax.dynamics.harmonics import TWO_PI, CamHarmonics, cam_grid, max_abs
    from camjax.dynamics.plant import tracking_error_harmonics

    spec = scene.dynamics
    cam = dc.program_cam(scene)
    if profile is not None and spec.follower == "translating":
        kept = [(j, h) for j, h in enumerate(profile.harmonics) if h <= spec.harmonics]
        if kept:
            rows = jnp.asarray([h for _, h in kept])
            ph = jnp.stack([phases[j] for j, _ in kept])
            a = jnp.asarray(profile.amplitude_mm * spec.motion_scale)
            # a cos(h phi + p) = a cos p cos(h phi) - a sin p sin(h phi)
            cam = CamHarmonics(cam.cos.at[rows].add(a * jnp.cos(ph)), cam.sin.at[rows].add(-a * jnp.sin(ph)))
    err = tracking_error_harmonics(cam, cam, dc.plant_of(spec), TWO_PI * jnp.asarray(spec.cam_speed_hz))
    return max_abs(err, cam_grid(spec.samples))


def contact_load(scene, arrays) -> jax.Array:
    """(N,) the load that holds the follower on the cam: a translating follower's contact force (N),
    a rocker's moment about its pivot (N m); zeros without loads. Contact is lost where it is < 0."""
    from camjax import loads

    kin = arrays.kin
    if followers.of(scene).rocking:
        return (jnp.zeros_like(kin.s) if scene.follower.train is None
                else loads.rocker_torque(scene.follower.train, kin, arrays.cam_speed_rad_s))
    return jnp.zeros_like(kin.s) if arrays.force_N is None else arrays.force_N


def sample(nom: Nominal, values, phases, g: Grid | None = None) -> Sample:
    """Evaluate the nominal design with toleranced ``values`` ((k,) array) and form-error
    ``phases`` ((H,), rad); ``g``: the nominal's :func:`grid` (computed here when None). Pure JAX:
    jit/vmap/grad over ``values`` (and ``phases``)."""
    scene0 = nom.scene
    kind = followers.of(scene0)
    fam = kind.problem_module()
    dtype = jnp.result_type(float)
    n = scene0.motion.samples
    scene, design, arrays, eps = drawn(nom, values, phases, g)
    kin = arrays.kin
    problem = fam.problem_from_scene(scene, arrays)
    d = fam.Design(**{k: jnp.asarray(design[k], dtype) for k in fam.Design._fields})
    weights = weights_of(scene0.design.alpha, scene0.design.gamma, dtype)
    ev = fam.evaluate(problem, weights, d)
    omega = arrays.cam_speed_rad_s
    load = contact_load(scene, arrays)
    accel = kin.d2s * omega**2 if kind.rocking else arrays.motion.accel
    out = []
    names = output_names(scene0, nom.tolerances)
    for name in names:
        if name == "peak_stress_MPa":
            out.append(ev.stress_max_MPa)
        elif name.startswith("least_contact"):
            out.append(jnp.min(load))
        elif name == "peak_pressure_angle_deg":
            out.append(ev.pressure_angle_max_deg)
        elif name == "least_curvature_radius_mm":
            out.append(getattr(ev, next(f for f in CURVATURE_FIELDS if f in ev._fields)))
        elif name == "dwell_position_error_mm":
            mask = jnp.asarray(dwell_mask(scene0, n))
            out.append(jnp.max(jnp.where(mask, jnp.abs(eps[0]), 0.0)))
        elif name == "residual_vibration":
            out.append(residual_vibration(scene, nom.tolerances.profile, phases))
        else:
            out.append(jnp.max(jnp.abs(accel)))
    broken = []
    for lim in limit_names(scene0):
        if lim == "contact_lost":
            broken.append(jnp.min(load) < 0.0)
            continue
        field = next(f for f in LIMIT_FIELDS[lim] if f in ev.violation._fields)
        v = getattr(ev.violation, field)
        tol = (FEASIBILITY_TOL_RAD if lim == "pressure_angle" else
               FEASIBILITY_RTOL_STRESS * problem.sigma_max_MPa if lim == "stress" else FEASIBILITY_TOL_MM)
        broken.append(v > tol)
    return Sample(jnp.stack([jnp.asarray(o, dtype) for o in out]),
                  jnp.stack(broken) if broken else jnp.zeros((0,), bool), kin.s, accel, load)


def dwell_mask(scene, n: int) -> np.ndarray:
    """(n,) bool: the grid samples inside a dwell segment (ends included)."""
    theta = np.arange(n) * (360.0 / n)
    prog = scene.motion.program
    mask = np.zeros(n, bool)
    for (lo, hi), kind in zip(program.segment_bounds_deg(prog), prog.kinds, strict=True):
        if kind == "dwell":
            mask |= (theta >= lo - 1e-9) & (theta <= hi + 1e-9)
    return mask


def values_of(nom: Nominal, unit):
    """Drawn values from standard variates ``unit`` (..., k): nominal + scale * unit."""
    return jnp.asarray(nom.values) + jnp.asarray(nom.scales) * unit


# samples vmapped at once inside the batch program: (block, N) intermediates that stay in the CPU's
# cache (measured on the default scene, N = 360: 38-45 us/sample at 256-512, 75-95 at 2048-8192)
BLOCK = 256


_PROGRAMS: dict = {}  # (what, content of the nominal, ...) -> jitted function, newest last
_PROGRAMS_KEPT = 8


class Numbers(NamedTuple):
    """The numbers of a :class:`Nominal` that its programs take as arguments (arrays), so that one
    compiled program serves every design, every spread and every form-error amplitude of a scene."""

    design: dict[str, Any]  # the nominal design's variables (mm)
    values: Any  # (k,) nominal of each toleranced value
    scales: Any  # (k,) spread of each
    amplitude_mm: Any  # the form error's amplitude (mm); None without one


def numbers(nom: Nominal) -> Numbers:
    """The :class:`Numbers` of a nominal (NumPy float64)."""
    profile = nom.tolerances.profile
    f = lambda x: np.asarray(x, np.float64).reshape(-1)  # noqa: E731
    return Numbers({k: np.float64(v) for k, v in nom.design.items()}, f(nom.values), f(nom.scales),
                   None if profile is None else np.float64(profile.amplitude_mm))


def with_numbers(nom: Nominal, n: Numbers) -> Nominal:
    """``nom`` with its numbers replaced by ``n`` (traced inside a program)."""
    k = len(nom.values)
    tol = nom.tolerances
    if tol.profile is not None:
        tol = tol._replace(profile=tol.profile._replace(amplitude_mm=n.amplitude_mm))
    return nom._replace(tolerances=tol, design=dict(n.design), values=tuple(n.values[i] for i in range(k)),
                        scales=tuple(n.scales[i] for i in range(k)))


def _cached(what: str, nom: Nominal, make, *extra):
    """The jitted program ``make()`` of a nominal, reused by any nominal of the same form (the scene
    but its [tolerances], which values are toleranced, the form error's harmonics, the design's
    variables), so that a second run in a process (another design, spread, seed or sample count of
    the same shape) compiles nothing: the program takes the nominal's :class:`Numbers` as an
    argument (:func:`with_numbers`)."""
    tol = nom.tolerances
    harmonics = None if tol.profile is None else tol.profile.harmonics
    form = (tuple((t.name, t.section) for t in tol.values), harmonics, tuple(sorted(nom.design)))
    key = (what, repr(dataclasses.replace(nom.scene, tolerances=None)), form, *extra)
    fn = _PROGRAMS.pop(key, None) or make()
    _PROGRAMS[key] = fn
    while len(_PROGRAMS) > _PROGRAMS_KEPT:
        _PROGRAMS.pop(next(iter(_PROGRAMS)))
    return fn


def _outputs_program(nom: Nominal, block: int):
    """One jitted program for every sample: ``lax.map`` over blocks of ``block`` vmapped samples
    (outputs and broken limits only), of the nominal's :class:`Numbers` ``n``."""
    def run(u, p, g, n):
        at = with_numbers(nom, n)

        def one(x):
            s = sample(at, values_of(at, x[0]), x[1], g)
            return s.outputs, s.broken
        return jax.lax.map(one, (u, p), batch_size=block)
    return jax.jit(run)


def _curves_program(nom: Nominal):
    """The jitted, vmapped evaluation of a batch with its curves (lift, acceleration, load), of the
    nominal's :class:`Numbers` ``n``."""
    def run(u, p, g, n):
        at = with_numbers(nom, n)
        return jax.vmap(lambda ui, pi: sample(at, values_of(at, ui), pi, g))(u, p)
    return jax.jit(run)


def _grid_program(nom: Nominal):
    """The jitted :func:`grid` of a nominal (its scene's motion and form error's harmonics only)."""
    return jax.jit(lambda: grid(nom))


def batch(nom: Nominal, unit, phases, *, chunk: int = 131072, curves: int = 2048, block: int = BLOCK):
    """Every sample's :class:`Sample` (NumPy, leading axis N): the outputs and broken limits of
    ``chunk`` samples at a time through one compiled program (blocks of ``block`` vmapped samples
    in a ``lax.map``); the curves (lift, accel, load; the envelope's) of the first ``curves``
    samples only, to bound memory (None when ``curves`` is 0)."""
    unit, phases = np.asarray(unit), np.asarray(phases)
    total = unit.shape[0]
    g = _cached("grid", nom, lambda: _grid_program(nom))()
    program = _cached("outputs", nom, lambda: _outputs_program(nom, block), block)
    n = numbers(nom)
    outs, broken = [], []
    for start in range(0, total, chunk):
        o, b = program(jnp.asarray(unit[start:start + chunk]), jnp.asarray(phases[start:start + chunk]), g, n)
        outs.append(np.asarray(o))
        broken.append(np.asarray(b))
    lift = accel = load = None
    if curves:
        m = min(curves, total)
        curves_of = _cached("curves", nom, lambda: _curves_program(nom))
        c = curves_of(jnp.asarray(unit[:m]), jnp.asarray(phases[:m]), g, n)
        lift, accel, load = np.asarray(c.lift), np.asarray(c.accel), np.asarray(c.load)
    return Sample(np.concatenate(outs), np.concatenate(broken), lift, accel, load)


def sensitivities(nom: Nominal) -> tuple[np.ndarray, np.ndarray]:
    """d(output)/d(value) at the nominal cam (no form error) by forward-mode autodiff, shape
    (n_out, k), and, with a form error, d(output)/d(amplitude) at the scene's amplitude with every
    phase 0, shape (n_out,) (else empty; at amplitude 0 the dwell error max |eps| has no
    derivative). The outputs are maxima/minima over the grid: their derivatives are
    those of the curve at the extremal sample."""
    k = len(nom.values)
    names = output_names(nom.scene, nom.tolerances)
    n_out = len(names)
    x0 = jnp.asarray(nom.values, float)
    profile = nom.tolerances.profile
    clean = nom._replace(tolerances=nom.tolerances._replace(profile=None))
    drop = [j for j, n in enumerate(names) if n == "dwell_position_error_mm"]

    def values_only(x):
        out = sample(clean, x, jnp.zeros((0,))).outputs
        return out if not drop else jnp.insert(out, drop[0], 0.0)  # no form error: no dwell error
    jacobian = _cached("jacobian", nom, lambda: jax.jit(jax.jacfwd(values_only)))
    jac = jacobian(x0) if k else jnp.zeros((n_out, 0))
    prof = np.zeros((0,))
    if profile is not None:
        h = len(profile.harmonics)

        def scaled(a):
            n2 = nom._replace(tolerances=nom.tolerances._replace(profile=profile._replace(amplitude_mm=a)))
            return sample(n2, x0, jnp.zeros((h,))).outputs
        d_amplitude = _cached("d_amplitude", nom, lambda: jax.jit(jax.jacfwd(scaled)))
        prof = np.asarray(d_amplitude(jnp.asarray(profile.amplitude_mm, float)))
    return np.asarray(jac), prof
