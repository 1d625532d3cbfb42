"""What ``camjax synthesize`` writes: result.json's ``synthesis`` block, the s/v/a/j table and
the figure of each designed law against the best built-in law of its joint class.

The curves are computed by the caller (JAX) and handed here as NumPy arrays; this module formats.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

CURVE_POINTS = 401  # points per segment in synthesis.csv and svaj.png


def scene_segment(seg, scene_control, lift_key: str) -> dict:
    """The designed law as a [motion] segment (``law = "bspline"`` with its control values and
    knots): pasted into a scene in place of the designed segment it reproduces the design."""
    out = {"kind": seg.kind, "angle_deg": seg.angle_deg, lift_key: seg.lift, "law": "bspline",
           "degree": seg.degree, "control": [float(v) for v in scene_control]}
    if seg.knots is not None:
        out["knots"] = list(seg.knots)
    return out


def synthesis_report(scene_name: str, weights: dict, results, scene_controls, lift_key: str) -> dict:
    """result.json: the objective and, per designed segment, its dimensionless figures (units
    h / beta^k on x in [0, 1]; l2 terms integrals over x), control values and knots."""
    segments = []
    for r, sc in zip(results, scene_controls, strict=True):
        seg = r.segment
        best = None
        if r.best_builtin is not None:
            name, obj, m = r.best_builtin
            best = {"law": name, "objective": obj, **m}
        segments.append({
            "segment": seg.index, "kind": seg.kind, "angle_deg": seg.angle_deg, lift_key: seg.lift,
            "status": "optimal" if r.converged else "not_converged",
            "objective": r.objective, "objective_discretized": r.model_objective, **r.measures,
            "degree": seg.degree, "control_count": seg.control_count,
            "knots": [float(v) for v in r.knots[seg.degree + 1: seg.control_count]],
            "knot_vector": [float(v) for v in r.knots],
            "control": [float(v) for v in sc],
            "control_normalized": [float(v) for v in r.control],
            "conditions": [{"at": c.label, "x": c.x, "order": c.order, "value": v}
                           for c, v in zip(seg.conditions, seg.values, strict=True)],
            "best_builtin": best,
            "scene_segment": scene_segment(seg, sc, lift_key),
        })
    return {"scene": scene_name, "normalized": True,
            "synthesis": {"objective": dict(weights), "segments": segments}}


def codesign_report(scene, outcome, data: dict) -> dict:
    """result.json's ``synthesis`` block of ``camjax design``'s co-design: the designed laws per
    segment as ``camjax synthesize`` writes them (their ``scene_segment`` the chosen law: the
    designed B-spline, or the built-in law when the search did not beat it) and ``codesign``.

    ``codesign.objective``: the co-design objective (the [design] objective at the optimal
    geometry plus the [synthesis] terms) of the chosen laws on the search's grid, the footing
    ``best_builtin.objective`` is measured on; ``objective_exact``: the design written (exact
    extrema) plus the same terms."""
    lift_key = "lift_deg" if "lift_deg" in outcome.tables[0] else "lift_mm"
    controls = [table.get("control") for table in outcome.tables]
    if outcome.chosen != "codesign":  # the B-spline found is still reported, as normalized values
        controls = [1.0 - r.control if r.segment.kind == "return" else r.control for r in outcome.segments]
    weights = dict(scene.synthesis.objective) if scene.synthesis is not None else {}
    report = synthesis_report(scene.name, weights, outcome.segments, controls, lift_key)
    segments = report["synthesis"]["segments"]
    for seg, table in zip(segments, outcome.tables, strict=True):
        seg["status"] = "optimal" if outcome.chosen == "codesign" else "not_chosen"
        seg["scene_segment"] = table
    design_f = data["design"]["objective"]
    best = outcome.best_builtin
    train = getattr(outcome, "train", None)
    extra = {} if train is None else {"train": train_report(train)}
    return {
        "objective": weights,
        "segments": segments,
        **extra,
        "codesign": {
            "objective": outcome.objective,
            "objective_exact": design_f + outcome.law_objective,
            "design_objective": design_f,
            "law_objective": outcome.law_objective,
            "chosen": outcome.chosen,
            # None: no start of the search had a feasible geometry (the built-in laws are written)
            "codesign_objective": (outcome.codesign_objective if np.isfinite(outcome.codesign_objective)
                                   else None),
            "best_builtin": None if best is None else {"law": list(best[0]), "objective": best[1]},
            "improvement": None if best is None else (best[1] - outcome.objective) / best[1],
            "iterations": outcome.iterations,
            "start": outcome.start,
            "inner_solves": outcome.evaluations,
            "samples": outcome.samples,
            # the search: "joint" (laws and geometry in one program) or "bilevel" (BFGS on F(z))
            "method": outcome.method,
            # the designed spring (camjax.codesign.spring), None when [synthesis] designs none
            "spring": getattr(outcome, "spring", None),
            "history": [float(v) for v in outcome.history],
        },
    }


def train_report(train) -> dict:
    """result.json's ``synthesis.train``: the follower train the residual vibration and the peak
    force are measured on (camjax.synthesis.vibration; ``spring``: whether the peak force is, with
    the train's spring), as ``camjax synthesize`` and the co-design write it."""
    import math

    return {"natural_frequency_hz": train.natural_frequency_rad_s / (2 * math.pi),
            "damping_ratio": train.damping_ratio, "cam_speed_hz": train.cam_speed_rad_s / (2 * math.pi),
            "speed_factors": list(train.speed_factors), "spring": train.spring_rate is not None}


def write_curves_csv(path: Path, curves: list[tuple[int, np.ndarray, tuple[np.ndarray, ...]]]) -> None:
    """synthesis.csv: segment, x, s, v, a, j of each designed law (normalized: lift 1 over x in [0, 1],
    derivatives with respect to x)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["segment", "x", "s", "v", "a", "j"])
        for index, x, (s, v, a, j) in curves:
            for row in zip(x, s, v, a, j, strict=True):
                w.writerow([index, *(f"{val:.12g}" for val in row)])


def synthesis_figure(panels: list[tuple[str, np.ndarray, tuple, tuple | None, str | None]]) -> Figure:
    """One row of s, v, a, j panels per designed segment: the designed law (solid) against the best
    built-in law of its joint class (dashed). ``panels``: (title, x, designed, builtin or None, name)."""
    rows = len(panels)
    fig = Figure(figsize=(12.0, 2.6 * rows + 0.6), layout="constrained")
    axes = np.atleast_2d(fig.subplots(rows, 4, sharex=True))
    names = ["s", "v = ds/dx", "a", "j"]
    for row, (title, x, designed, builtin, bname) in enumerate(panels):
        for k in range(4):
            ax = axes[row, k]
            ax.plot(x, designed[k], color="C0", linewidth=1.3, label="designed")
            if builtin is not None:
                ax.plot(x, builtin[k], color="C1", linestyle="--", linewidth=1.1, label=bname)
            ax.axhline(0.0, color="0.3", linewidth=0.5)
            ax.grid(True, alpha=0.3)
            ax.set_xlim(0.0, 1.0)
            ax.set_title(f"{title}: {names[k]}" if k == 0 else names[k], fontsize=9)
            if row == rows - 1:
                ax.set_xlabel("x")
        axes[row, 0].legend(fontsize=7, loc="upper left")
    fig.suptitle("Designed laws against the best built-in law of the same joint class (normalized)",
                 fontsize=11)
    return fig
