"""result.json's ``closure`` block of a positive drive (groove or conjugate cams), for either family.

Formatting only (NumPy): the curves of :mod:`camjax.followers._closure` come in the follower's
``own_curves``, and the load the follower needs (a translating follower's axial force, a rocker's
pivot torque over its arm) decides which contact carries it: the first (inner flank, first cam)
where it is > 0, the second (outer flank, second cam) where it is < 0. Where it changes sign the
roller leaves one contact for the other and reverses its spin: the switch angles, the load's rate
there and, in a groove with clearance, the roller's free travel across the gap are reported.
"""

from __future__ import annotations

from typing import Any

import numpy as np

NO_JUMP = ("positive drive: the follower is held on its cam both ways, it cannot leave it (no jump "
           "analysis); the load changes contact where it changes sign")


def _max(values, t) -> dict[str, float]:
    i = int(np.argmax(values))
    return {"max": float(values[i]), "max_deg": float(t[i])}


def _min(values, t) -> dict[str, float]:
    i = int(np.argmin(values))
    return {"min": float(values[i]), "min_deg": float(t[i])}


def switches(theta_deg, load, pressure_angle_deg, clearance_mm: float, names: tuple[str, str],
             rel_tol: float = 1e-9) -> list[dict[str, Any]]:
    """Every angle where the load changes sign (cyclic), in order: the angle (deg; linear between the
    two samples around it, or where a run of unloaded samples starts), the contact that takes over
    (``names``: first, second), the load's rate there (N/deg; across an unloaded run its mean), the
    unloaded span (deg) and the free travel c / cos phi (mm) of a groove with clearance c.

    |load| <= ``rel_tol`` max|load| counts as unloaded (a dwell of a rocker without a spring)."""
    t, f, phi = (np.asarray(v, float) for v in (theta_deg, load, pressure_angle_deg))
    n = len(f)
    step = 360.0 / n
    loaded = np.flatnonzero(np.abs(f) > rel_tol * max(float(np.max(np.abs(f))), 1e-300))
    out = []
    if len(loaded) < 2:
        return out
    nxt = np.roll(loaded, -1)
    for i, j in zip(loaded.tolist(), nxt.tolist(), strict=True):
        if np.sign(f[i]) == np.sign(f[j]):
            continue
        gap = (j - i) % n
        if gap == 1:
            frac = f[i] / (f[i] - f[j])
            angle, unloaded = (t[i] + frac * step) % 360.0, 0.0
        else:
            angle, unloaded = t[(i + 1) % n], (gap - 2) * step  # from the first unloaded sample to the last
        out.append({"angle_deg": float(angle), "to": names[0] if f[j] > 0 else names[1],
                    "load_rate_N_per_deg": float((f[j] - f[i]) / (gap * step)), "unloaded_deg": float(unloaded),
                    "free_travel_mm": float(clearance_mm / np.cos(np.radians(phi[i])))})
    return sorted(out, key=lambda s: s["angle_deg"])


def closure_block(closure, curves, load_N, pressure_angle_deg) -> dict[str, Any]:
    """The ``closure`` block: kind, each contact's extrema (normal force, Hertz stress, the second's
    margin and pressure angle), the switches (:func:`switches`) and the words for the missing jump
    analysis. ``closure``: the scene's :class:`camjax.scene.spec.ClosureSpec`; ``load_N``: the force
    along the roller's path the follower needs (None without loads)."""
    own, t = curves.own_curves or {}, np.asarray(curves.theta_deg)
    groove = closure.kind == "groove"
    names = ("inner", "outer") if groove else ("first", "second")
    out: dict[str, Any] = {"kind": closure.kind, "positive_drive": True, "jump": NO_JUMP}
    if groove:
        out["clearance_mm"] = closure.clearance_mm
    else:
        out.update({k: v for k, v in (("yoke_span_mm", closure.yoke_span_mm),
                                      ("second_arm_length_mm", closure.second_arm_length_mm),
                                      ("second_arm_angle_deg", closure.second_arm_angle_deg)) if v is not None})
        out["second_roller_radius_mm"] = closure.second_roller_radius_mm
        # the distance between the two roller centres: the yoke's span, or the chord between the arms' ends
        span = np.hypot(np.asarray(curves.pitch_x_mm) - own["conjugate_pitch_x_mm"],
                        np.asarray(curves.pitch_y_mm) - own["conjugate_pitch_y_mm"])
        out["roller_centre_distance_mm"] = {"max": float(np.max(span)), "min": float(np.min(span))}
    contacts: dict[str, Any] = {}
    for name in names:
        block: dict[str, Any] = {"carries": "load > 0 (pushes the follower away from the shaft)" if name == names[0]
                                 else "load < 0 (pulls the follower back towards the shaft)"}
        if f"{name}_force_N" in own:
            block["normal_force_N"] = _max(own[f"{name}_force_N"], t)
        if f"{name}_stress_MPa" in own:
            block["stress_MPa"] = _max(own[f"{name}_stress_MPa"], t)
        contacts[name] = block
    if groove:
        margin = own["outer_margin_mm"]
        finite = margin < np.finfo(float).max
        contacts["outer"]["concave_margin_mm"] = (_min(margin, t) if finite.any() else
                                                  {"min": None, "min_deg": None, "note": "the pitch curve is convex "
                                                   "at every angle: the outer flank has no concave part"})
    else:
        contacts["second"]["pressure_angle_deg"] = _max(np.abs(own["conjugate_pressure_angle_deg"]), t)
        contacts["second"]["undercut_margin_mm"] = _min(own["conjugate_margin_mm"], t)
        contacts["second"]["min_radius_mm"] = float(np.min(np.hypot(own["conjugate_x_mm"], own["conjugate_y_mm"])))
    out["contacts"] = contacts
    if load_N is not None:
        out["switches"] = switches(t, load_N, pressure_angle_deg, closure.clearance_mm, names)
        out["switch_angles_deg"] = [s["angle_deg"] for s in out["switches"]]
    return out


def positive_contact(closure) -> dict[str, Any]:
    """What replaces the contact-loss check of the loads block in a positive drive."""
    return {"lost": False, "closure": closure.kind, "note": NO_JUMP}


def sizing_rules(follower) -> dict[str, str]:
    """The smallest cam's rule where a positive drive's second contact binds (result.json's
    ``min_base_radius_rule``), by the binding's name."""
    f, c = follower, follower.closure
    return {
        "outer_flank": f"the groove's outer flank binds: the pitch curve's concavity radius >= R_f + clearance "
                       f"({c.clearance_mm:g} mm) + {f.min_curvature_radius_mm:g} mm, and the first contact's "
                       "pressure angle and undercut hold",
        "conjugate": f"the conjugate cam binds: its |pressure angle| <= {f.max_pressure_angle_deg:g} deg and no "
                     "undercut, and the first cam's hold",
    }
