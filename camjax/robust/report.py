"""A robust run: the nominal design, the samples' statistics, the limits' probabilities and the
ranked sensitivities, as a JSON-ready dict and a text table (no files written here).

:func:`run` designs the scene (``camjax design``'s run: :func:`camjax.pipeline.design_report`),
draws the samples (:func:`camjax.robust.tolerances.draw`), evaluates them in batches
(:func:`camjax.robust.evaluate.batch`) and differentiates the outputs at the nominal
(:func:`camjax.robust.evaluate.sensitivities`).
"""

from __future__ import annotations

import time
from typing import Any, NamedTuple

import numpy as np

from camjax.robust import evaluate as ev
from camjax.robust.tolerances import Tolerances, draw

FIRST_SAMPLES = 20  # samples written out whole (drawn values and outputs), to recompute them
ENVELOPE_SAMPLES = 2048  # the P1-P99 envelopes over the cam angle are those of the first samples
STATS = ("mean", "sd", "p1", "p50", "p99", "min", "max")


class RobustRun(NamedTuple):
    """Everything a robust run computed (NumPy arrays; leading axis: samples)."""

    data: dict[str, Any]  # robust.json
    outputs: np.ndarray  # (N, n_out)
    broken: np.ndarray  # (N, n_lim) bool
    envelope: dict[str, np.ndarray]  # name -> (3, n): P1, P50, P99 over the cam angle; "theta_deg"


def limits_of(scene) -> dict[str, float | None]:
    """Each output's limit (what its histogram marks): sigma_max, 0 force, phi_max, rho_min."""
    f, d = scene.follower, scene.design
    return {"peak_stress_MPa": None if d is None else d.sigma_max_MPa,
            "least_contact_force_N": 0.0, "least_contact_moment_Nm": 0.0,
            "peak_pressure_angle_deg": getattr(f, "max_pressure_angle_deg", None),
            "least_curvature_radius_mm": getattr(f, "min_curvature_radius_mm", None)}


def nominal_design(scene) -> tuple[dict[str, float], dict[str, Any]]:
    """The design ``camjax design`` solves for the scene: its variables (mm) and the report dict."""
    from camjax import followers, pipeline

    data = pipeline.design_report(scene)
    fields = followers.of(scene).problem_module().Design._fields
    return {k: float(data["design"][k]) for k in fields}, data


def run(scene, samples: int, seed: int, *, tolerances: Tolerances | None = None,
        design: dict[str, float] | None = None) -> RobustRun:
    """Sample the scene's [tolerances] (or ``tolerances``) ``samples`` times with ``seed`` and
    evaluate its nominal design (``design``: solved here when None) for every sample."""
    t0 = time.perf_counter()
    tol = scene.tolerances if tolerances is None else tolerances
    if design is None:
        design, _ = nominal_design(scene)
    t_design = time.perf_counter()
    nom = ev.nominal(scene, tol, design)
    draws = draw(tol, samples, seed)
    res = ev.batch(nom, draws.unit, draws.phases, curves=ENVELOPE_SAMPLES)
    t_batch = time.perf_counter()
    jac, prof = ev.sensitivities(nom)
    t_sens = time.perf_counter()
    names, lims = ev.output_names(scene, tol), ev.limit_names(scene)
    h = 0 if tol.profile is None else len(tol.profile.harmonics)
    clean = nom._replace(tolerances=tol._replace(profile=None))
    nominal_out = np.asarray(ev.sample(clean, np.asarray(nom.values, float), np.zeros((0,))).outputs)
    if tol.profile is not None:  # the dwell error is the form error's alone: 0 without it
        nominal_out = np.insert(nominal_out, names.index("dwell_position_error_mm"), 0.0)
    out, broken = res.outputs, res.broken
    limit_of = limits_of(scene)
    values = np.asarray(draws.unit) * np.asarray(nom.scales) + np.asarray(nom.values)
    data = {
        "scene": scene.name,
        "follower_type": scene.follower.type,
        "samples": int(samples),
        "seed": int(seed),
        "design": dict(design),
        "tolerances": [{"name": t.name, "section": t.section, "dist": t.dist, "nominal": v,
                        "spread": t.spread, "spread_percent": t.relative, "scale": sc, "sd": sd}
                       for t, v, sc, sd in zip(tol.values, nom.values, nom.scales, nom.sds, strict=True)],
        "profile_error_mm": None if tol.profile is None else {
            "amplitude": tol.profile.amplitude_mm, "harmonics": list(tol.profile.harmonics)},
        "outputs": {n: {"nominal": float(nominal_out[j]), "limit": limit_of.get(n),
                        **_stats(out[:, j]), **_unit_of(scene, n)} for j, n in enumerate(names)},
        "limits": {lim: {"probability": float(broken[:, i].mean()), "broken": int(broken[:, i].sum())}
                   for i, lim in enumerate(lims)},
        "any_limit_probability": float(broken.any(axis=1).mean()) if lims else 0.0,
        "sensitivities": _ranked(names, tol, nom, jac, prof),
        "first_samples": [
            {"index": i, "values": {t.name: float(values[i, k]) for k, t in enumerate(tol.values)},
             "form_error_phases_rad": [float(x) for x in np.asarray(draws.phases)[i, :h]],
             "outputs": {n: float(out[i, j]) for j, n in enumerate(names)},
             "broken": {lim: bool(broken[i, k]) for k, lim in enumerate(lims)}}
            for i in range(min(FIRST_SAMPLES, samples))],
        "envelope_samples": int(min(samples, ENVELOPE_SAMPLES)),
        "timings_s": {"design": t_design - t0, "samples": t_batch - t_design,
                      "sensitivities": t_sens - t_batch},
    }
    env = {"theta_deg": np.arange(scene.motion.samples) * (360.0 / scene.motion.samples)}
    for key, curves in (("lift", res.lift), ("accel", res.accel), ("load", res.load)):
        env[key] = np.percentile(curves, [1, 50, 99], axis=0)
    return RobustRun(data, out, broken, env)


def _unit_of(scene, name: str) -> dict[str, str]:
    """The unit of an output whose name does not carry it: the residual vibration's is the
    [dynamics] train's motion unit (m, or rad for an oscillating train)."""
    if name != "residual_vibration":
        return {}
    return {"unit": "m" if scene.dynamics.follower == "translating" else "rad"}


def _stats(x: np.ndarray) -> dict[str, float]:
    p1, p50, p99 = np.percentile(x, [1, 50, 99])
    return {"mean": float(x.mean()), "sd": float(x.std(ddof=1)) if x.size > 1 else 0.0,
            "p1": float(p1), "p50": float(p50), "p99": float(p99),
            "min": float(x.min()), "max": float(x.max())}


def _ranked(names, tol: Tolerances, nom, jac, prof) -> dict[str, list[dict[str, Any]]]:
    """Per output: every toleranced value's derivative, sd and effect (derivative x sd), ranked by
    |effect| (the form error: d/d(amplitude) at zero phases, times the amplitude)."""
    out = {}
    for j, n in enumerate(names):
        rows = [{"value": t.name, "derivative": float(jac[j, k]), "sd": nom.sds[k],
                 "effect": float(jac[j, k]) * nom.sds[k]} for k, t in enumerate(tol.values)]
        if tol.profile is not None:
            rows.append({"value": "profile_error_mm", "derivative": float(prof[j]),
                         "sd": tol.profile.amplitude_mm, "effect": float(prof[j]) * tol.profile.amplitude_mm})
        out[n] = sorted(rows, key=lambda r: -abs(r["effect"]))
    return out


def text(data: dict[str, Any]) -> str:
    """robust.txt: the statistics, the limits' probabilities and the sensitivity ranking."""
    lines = [f"camjax robust: scene {data['scene']} ({data['follower_type']}), {data['samples']} samples, "
             f"seed {data['seed']}",
             "nominal design: " + ", ".join(f"{k} = {v:.6g}" for k, v in data["design"].items()), "",
             f"{'output':28s} {'nominal':>11s} {'mean':>11s} {'sd':>10s} {'P1':>11s} {'P50':>11s} "
             f"{'P99':>11s} {'min':>11s} {'max':>11s} {'limit':>9s}"]
    for n, s in data["outputs"].items():
        lim = "" if s["limit"] is None else f"{s['limit']:.4g}"
        lines.append(f"{n:28s} " + " ".join(f"{s[k]:>11.5g}" if k != "sd" else f"{s[k]:>10.3g}"
                                            for k in ("nominal", *STATS)) + f" {lim:>9s}")
    lines += ["", "probability of each limit broken:"]
    for lim, p in data["limits"].items():
        lines.append(f"  {lim:16s} {p['probability']:.4%} ({p['broken']} of {data['samples']})")
    lines.append(f"  {'any':16s} {data['any_limit_probability']:.4%}")
    lines += ["", "which tolerance matters most (d output / d value x sd, ranked):"]
    for n, rows in data["sensitivities"].items():
        lines.append(f"  {n}:")
        for r in rows:
            lines.append(f"    {r['value']:24s} effect {r['effect']:>+12.4g}   "
                         f"d/dvalue {r['derivative']:>+12.4g}   sd {r['sd']:.4g}")
    return "\n".join(lines) + "\n"


def design_summary(block: dict) -> str:
    """The text summary's lines of a robust design's ``robust`` block
    (:func:`camjax.robust.design.design_json`)."""
    n, r = block["nominal"], block["robust"]
    p = block["probability"]

    def line(name, side):
        worst = min(side["probability_kept"]["limits"].items(), key=lambda kv: kv[1], default=("-", 1.0))
        return (f"  {name:8s} size {side['size_mm']:.4f} mm, all limits kept in "
                f"{side['probability_kept']['all']:.4%} (least: {worst[0]} {worst[1]:.4%})")
    inc = block["size_increase_percent"]
    return "\n".join([
        f"robust design: each limit kept over {p:g} of {block['samples']} samples (seed {block['seed']}); "
        f"measured on {block['check']['samples']} fresh samples (seed {block['check']['seed']}):",
        line("nominal", n), line("robust", r),
        "  size +" + (f"{inc:.2f} %" if inc is not None else "n/a") + " for the robust design"])
