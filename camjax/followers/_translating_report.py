"""result.json of a translating follower's run: the assembly every such type shares.

A translating follower's ``report.py`` calls :func:`report` with its own blocks (a module or any
object with these functions):

- ``min_base_radius_block(follower, minimum, exact) -> dict``: the smallest cam and its rule;
- ``design_sentences(spec, solution, out) -> dict``: one sentence per constraint the design can
  violate (the keys of the solver's ``violated``) besides stress and bounds;
- ``evaluated_block(curves, extremes) -> dict``: its own figures at the evaluated design;
- ``extra_blocks(scene, run, extremes, data) -> None``: anything else it adds to ``data``.

Formatting only, as :mod:`camjax.output.report`, whose shared blocks this uses.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from camjax import followers
from camjax.evaluate import curve_extremes, curve_names
from camjax.family import FEASIBILITY_TOL_RAD
from camjax.followers import _closure_report
from camjax.output.report import feasibility_block, follower_scene_block, header_block, loads_block


def design_block(spec, solution, sentences: dict[str, str]) -> dict[str, Any]:
    """The solver's result with the report's additions.

    Added to the solver's JSON: ``peak_stress_MPa`` (the design's peak stress computed exactly as
    the report's stress curve; null without [contact]), the smallest admissible R_b (and, flat
    face, L) (``required_*``) with the constraint that binds there, and ``violations`` as
    readable sentences (``sentences``: the follower's own, besides stress and bounds).
    """
    out = dict(solution.result)
    sigma_peak, required = solution.peak_stress_MPa, solution.required_base_radius_mm
    rb_hi = spec.bounds("base_radius_mm")[1]
    messages = {
        "stress": f"peak stress {sigma_peak or 0.0:.6g} MPa > sigma_max {spec.sigma_max_MPa or 0.0:g} MPa",
        "bounds": "a design variable is outside its bounds",
        **sentences,
    }
    violations = (list(out["robust"]["violations"]) if "robust" in out  # a robust design's rows
                  else [messages[name] for name in out["violated"]])
    if required > rb_hi:
        violations.insert(0, f"base radius needs {required:.6g} mm > upper bound {rb_hi:g} mm")
    out.update({
        "peak_stress_MPa": sigma_peak,
        "violations": violations,
        "required_base_radius_mm": required,
        "required_base_radius_deg": solution.required_base_radius_deg,
        "binding_constraint": solution.binding_constraint,
    })
    if solution.required_face_width_mm is not None:
        out["required_face_width_mm"] = solution.required_face_width_mm
    return out


def evaluated_block(curves, extremes) -> dict[str, Any]:
    """Curvature and stress at the evaluated design (rho = R_b + q, q = s + s''), where the follower
    has them."""
    out: dict[str, Any] = {}
    if curves.rho_mm is not None:
        q = extremes["q"]
        out["rho_mm"] = {"min": curves.base_radius_mm + q.min, "min_deg": q.min_deg}
    if curves.stress_MPa is not None:
        e = extremes["stress"]
        out["stress_MPa"] = {"max": e.max, "max_deg": e.max_deg}
    return out


def pressure_angle_sentence(out) -> str:
    """The design sentence of a pressure angle over its limit, from the design block ``out``."""
    return (f"pressure angle {out['pressure_angle_max_deg']:.6g} deg at "
            f"{out['pressure_angle_max_at_deg']:g} deg > limit {out['max_pressure_angle_deg']:g} deg")


def circle_sentences(who: str, out, solution) -> dict[str, str]:
    """The design sentences of a circle follower (``who``: "the roller", "the face"): its pressure
    angle over the limit (:func:`pressure_angle_sentence`) and the circle undercutting the cam."""
    return {"pressure_angle": pressure_angle_sentence(out),
            "undercut": f"{who} undercuts the cam: smallest convex cam-surface radius "
                        f"{out['cam_rho_min_mm']:.6g} mm < {solution.rho_min_limit_mm:g} mm"}


def limit_rules(follower) -> dict[str, str]:
    """The sizing limits of a circle follower (roller, curved face) as the rules name them: the
    pressure angle and the undercut (the convex cam-surface radius)."""
    f = follower
    return {"pressure_angle": f"pressure angle |phi| <= {f.max_pressure_angle_deg:g} deg",
            "undercut": f"no undercut (convex cam-surface radius >= {f.min_curvature_radius_mm:g} mm)"}


def min_base_radius_keys(minimum, rule: str, prime: bool = True) -> dict[str, Any]:
    """The smallest cam's keys: its base radius (mm) and the cam angle (deg) where it binds, its prime
    radius (mm, a circle follower: ``prime``), the ``rule`` naming the binding limit and its name."""
    out = {"min_base_radius_mm": minimum.radius_mm, "min_base_radius_deg": minimum.angle_deg}
    if prime:
        out["min_prime_radius_mm"] = minimum.prime_radius_mm
    return {**out, "min_base_radius_rule": rule, "min_base_radius_binding": minimum.binding}


def signed_extremes(e, scale: float = 1.0) -> dict[str, float]:
    """A signed curve's :class:`camjax.results.Extremes` times ``scale``: max, min, the largest
    |value| (``max_abs``) and their cam angles (deg)."""
    worst = (e.max, e.max_deg) if e.max >= -e.min else (-e.min, e.min_deg)
    return {"max": scale * e.max, "max_deg": e.max_deg, "min": scale * e.min, "min_deg": e.min_deg,
            "max_abs": scale * worst[0], "max_abs_deg": worst[1]}


def pressure_angle_keys(curves, phi) -> dict[str, Any]:
    """A follower block's pressure-angle keys from its extremes ``phi`` (rad): the signed extremes in
    degrees, the limit, and whether the largest |phi| is within it to the solvers' tolerance (as
    the run's geometry violations judge it)."""
    block = signed_extremes(phi, math.degrees(1.0))
    return {"pressure_angle_deg": block, "pressure_angle_limit_deg": curves.pressure_angle_limit_deg,
            "pressure_angle_ok": bool(block["max_abs"] <= curves.pressure_angle_limit_deg
                                      + math.degrees(FEASIBILITY_TOL_RAD))}


def pitch_rho_block(curves, rho) -> dict[str, Any]:
    """The smallest |pitch-curve radius| (mm, from its extremes ``rho``), its angle, and whether the
    pitch curve has concave parts."""
    return {"min_abs": rho.min, "min_abs_deg": rho.min_deg,
            "concave": bool(np.any(curves.pitch_rho_mm < 0))}


def undercut_keys(curves, margin) -> dict[str, Any]:
    """A circle follower's undercut keys: the least margin rho_c - rho_min (mm, from its extremes
    ``margin``), its angle, and whether the circle undercuts the cam (on the extremes or a sample)."""
    return {"undercut_margin_mm": {"min": margin.min, "min_deg": margin.min_deg},
            "undercut": bool(margin.min <= 0 or np.any(curves.undercut_margin_mm <= 0))}


def report(scene, run, blocks) -> dict[str, Any]:
    """The report of a translating follower's design run as a plain, JSON-ready dict; ``blocks``:
    the follower's own (see the module docstring)."""
    follower = followers.of(scene)
    arrays = run.arrays
    drawn = follower.drawn_follower(scene, run.design.result if run.design is not None else {})
    extremes = run.extremes
    if extremes is None:  # a run built without them: the samples' own
        extremes = curve_extremes(scene, arrays._replace(model=None), curve_names(scene, arrays),
                                  run.base_radius_mm, follower=drawn)
    data = header_block(scene, arrays if run.extremes is not None else arrays._replace(model=None), extremes)
    block = loads_block(scene, arrays, extremes)
    if block is not None:
        data["loads"] = block
    blocks.extra_blocks(scene, run, extremes, data)
    # sized with the dimensions the cam is drawn with (a design's)
    data.update(blocks.min_base_radius_block(drawn, run.min_base_radius,
                                             run.extremes is not None and arrays.model is not None))
    if run.design is not None:
        out = run.design.result
        sentences = blocks.design_sentences(scene.design, run.design, out)
        data["design"] = design_block(scene.design, run.design, sentences)
        own = follower_scene_block(follower, scene.follower)
        if own:
            data["follower_scene"] = own
    data["evaluated_at"] = {"base_radius_mm": run.base_radius_mm,
                            "face_width_mm": run.curves.face_width_mm,
                            "source": run.base_radius_source,
                            **feasibility_block(run.violations)}
    data.update(evaluated_block(run.curves, extremes))
    data.update(blocks.evaluated_block(run.curves, extremes))
    closure = scene.follower.closure.designed(run.design.result if run.design is not None else {})
    if closure.positive:  # a groove or conjugate cams: no spring to lose, the load changes contact
        c = run.curves
        data["closure"] = _closure_report.closure_block(closure, c, c.force_N, c.pressure_angle_deg)
        if "loads" in data:
            data["loads"]["contact"] = _closure_report.positive_contact(closure)
    return data
