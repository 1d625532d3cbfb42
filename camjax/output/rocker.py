"""A rocker (oscillating-follower) design's report dict, profile.csv, profile.dxf, figures and
motion.gif (:mod:`camjax.output.animation`).

The same files as a translating follower's (:mod:`camjax.export`): the outline in cam coordinates
(convention of :mod:`camjax.followers._pitch`), one DXF polyline, and figures built without pyplot.
profile.png draws the pivot, the arm and the roller (or the face) at the angle of the largest
pressure angle (roller) or of the contact's furthest reach along the face (flat face).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from camjax.evaluate import SceneArrays
from camjax.followers._pitch import to_cam_frame
from camjax.output.export import CSV_FORMAT, save_figure, write_profile_dxf
from camjax.output.plots import (  # _cycle_axis reads only segment_starts_deg
    _cycle_axis,
    _mark_extremes,
    _title,
    clip_axis,
    closed,
    rho_axis_limit_mm,
)
from camjax.output.report import (
    extrema,
    feasibility_block,
    follower_scene_block,
    header_block,
    negative_ranges_deg,
)
from camjax.rocker import RockerCurves, RockerRun
from camjax.scene import Scene

ROCKER_FLCD_UNITS = {"jump_s": "rad", "jump_v": "rad/rad", "jump_a": "rad/rad^2", "jump_j": "rad/rad^3"}

def _f(x) -> float:
    """A scalar as a Python float (JSON)."""
    return float(np.asarray(x))


def rocker_profile_table(curves: RockerCurves) -> tuple[list[str], np.ndarray]:
    """Column names and an (N, k) table: angle, outline X/Y, arm swing and angle, curvature, phi,
    pitch curve (roller) or contact point on the face (flat), then (appended, in this order) s''
    (rad/rad^2), the arm's angular velocity, acceleration and jerk (SI), the pitch curve's radius
    of curvature (roller) and with loads the pivot torque, contact force, cam torque and stress."""
    c = curves
    names = ["theta_deg", "x_mm", "y_mm", "swing_deg", "arm_angle_deg", "ds_rad_per_rad", "rho_mm",
             "pressure_angle_deg"]
    cols = [c.theta_deg, c.profile_x_mm, c.profile_y_mm, c.swing_deg, c.arm_angle_deg, c.ds, c.rho_mm,
            c.pressure_angle_deg]
    if c.pitch_x_mm is not None:
        names += ["pitch_x_mm", "pitch_y_mm"]
        cols += [c.pitch_x_mm, c.pitch_y_mm]
    if c.contact_distance_mm is not None:
        names.append("contact_on_face_mm")
        cols.append(c.contact_distance_mm)
    # appended after the columns above: every curve whose extrema result.json reports
    names += ["d2s_rad_per_rad2", "angular_velocity_rad_s", "angular_accel_rad_s2", "angular_jerk_rad_s3"]
    cols += [c.d2s, c.angular_velocity_rad_s, c.angular_accel_rad_s2, c.angular_jerk_rad_s3]
    optional = (("pitch_rho_mm", c.pitch_rho_mm), ("pivot_torque_Nm", c.pivot_torque_Nm),
                ("contact_force_N", c.contact_force_N), ("torque_Nm", c.torque_Nm),
                ("stress_MPa", c.stress_MPa))
    for name, values in optional:
        if values is not None:
            names.append(name)
            cols.append(values)
    return names, np.column_stack(cols)


def write_rocker_profile_csv(path: Path, curves: RockerCurves) -> Path:
    names, table = rocker_profile_table(curves)
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt=CSV_FORMAT)
    return path


def _rows_figure(curves: RockerCurves, rows, what: str, title: str = "") -> Figure:
    """One panel per row (values, axis label, clip): the closed cycle, its extremes marked; a row
    with a clip (mm) holds its axis within +-clip and marks what runs beyond
    (:func:`camjax.output.plots.clip_axis`). ``what`` and the run's ``title`` block head the figure."""
    fig = Figure(figsize=(7.0, 1.6 * len(rows) + 1.2), layout="constrained")
    axes = np.atleast_1d(fig.subplots(len(rows), 1, sharex=True))
    t = curves.theta_deg
    for k, (ax, (values, name, clip)) in enumerate(zip(axes, rows, strict=True)):
        ax.plot(*closed(t, values), color=f"C{k}", linewidth=1.2)
        ax.axhline(0.0, color="0.3", linewidth=0.5)
        cut = clip_axis(ax, t, values, clip) if clip is not None else np.zeros(t.shape, bool)
        which = ["max", "min"]
        if clip is not None:
            # an extreme beyond the clip is written at its edge (clip_axis), and the smallest |rho|,
            # the radius the limits and the stress are judged on, gets a mark of its own
            i = int(np.argmin(np.abs(values)))
            which = [w for w, beyond in (("max", values > clip), ("min", values < -clip)) if not beyond.any()]
            if "min" in which and int(np.argmin(values)) == i:
                which.remove("min")
        _mark_extremes(ax, t, np.where(cut, np.nan, values), "{:.4g} @ {:g}°", which)
        if clip is not None:
            ax.plot(t[i], values[i], "s", color="C2", markersize=4, zorder=4)
            right = t[i] > 250
            ax.annotate(f"smallest |ρ| {abs(values[i]):.4g} mm @ {t[i]:g}°", (t[i], values[i]), fontsize=7,
                        xytext=(-5 if right else 5, 5), textcoords="offset points", va="bottom",
                        ha="right" if right else "left")
        if not cut.any():  # a clipped axis keeps its stated bounds
            ax.margins(y=0.12)
        ax.set_ylabel(name)
        _cycle_axis(ax, curves, label=k == len(rows) - 1)
    _title(fig, title, what)
    return fig


def svaj_figure(curves: RockerCurves, title: str = "") -> Figure:
    """Arm swing (deg), angular velocity, acceleration and jerk over the cycle."""
    c = curves
    return _rows_figure(c, [(c.swing_deg, "swing (deg)", None), (c.angular_velocity_rad_s, "ω (rad/s)", None),
                            (c.angular_accel_rad_s2, "α (rad/s²)", None),
                            (c.angular_jerk_rad_s3, "jerk (rad/s³)", None)],
                        "Arm motion over one cycle (dotted: segment joints; dots: extremes)", title)


def geometry_figure(curves: RockerCurves, title: str = "") -> Figure:
    """Pressure angle (deg) and the cam surface's radius of curvature (mm), the latter's axis held
    within 4 times the cam's largest radius (:func:`camjax.output.plots.rho_axis_limit_mm`)."""
    c = curves
    clip = rho_axis_limit_mm(c.profile_x_mm, c.profile_y_mm)
    return _rows_figure(c, [(c.pressure_angle_deg, "φ (deg)", None), (c.rho_mm, "ρ cam (mm)", clip)],
                        f"Pressure angle and curvature at R_b = {c.base_radius_mm:.3f} mm", title)


def loads_figure(curves: RockerCurves, title: str = "") -> Figure:
    """Torque about the pivot, contact force, cam torque and (with [contact]) the Hertz stress."""
    c = curves
    rows = [(c.pivot_torque_Nm, "M pivot (N·m)", None), (c.contact_force_N, "P (N)", None),
            (c.torque_Nm, "T cam (N·m)", None)]
    if c.stress_MPa is not None:
        rows.append((c.stress_MPa, "σ (MPa)", None))
    return _rows_figure(c, rows, "Loads about the pivot (M < 0: the spring cannot hold the arm on the cam)",
                        title)


def profile_figure(curves: RockerCurves, title: str = "") -> Figure:
    """Cam outline (mm) with base circle, pivot, arm and roller (or face) at one cam angle."""
    c = curves
    fig = Figure(figsize=(6.4, 6.8), layout="constrained")
    ax = fig.subplots()
    x, y = c.profile_x_mm, c.profile_y_mm
    ax.fill(x, y, color="C0", alpha=0.12)
    ax.plot(np.append(x, x[0]), np.append(y, y[0]), color="C0", linewidth=1.5, label="cam profile")
    a = np.linspace(0.0, 2.0 * np.pi, 361)
    rb = c.base_radius_mm
    ax.plot(rb * np.sin(a), rb * np.cos(a), color="0.5", linestyle="--", linewidth=0.8,
            label=f"base circle R_b = {rb:.3f} mm")
    ax.plot([0.0], [0.0], "+", color="k")
    theta = np.deg2rad(c.theta_deg)
    psi = np.deg2rad(c.arm_angle_deg)
    if c.pitch_x_mm is not None:
        i = int(np.argmax(np.abs(c.pressure_angle_deg)))
        ax.plot(c.pitch_x_mm, c.pitch_y_mm, color="C2", linestyle="-.", linewidth=0.8, label="pitch curve")
        cx, cy = c.pitch_x_mm[i], c.pitch_y_mm[i]
        rf = c.roller_radius_mm
        ax.plot(cx + rf * np.sin(a), cy + rf * np.cos(a), color="C1", linewidth=1.5,
                label=f"roller R_f = {rf:g} mm at θ = {c.theta_deg[i]:g}° "
                      f"(φ = {c.pressure_angle_deg[i]:.1f}°)")
        px, py = (float(v) for v in to_cam_frame(c.pivot_distance_mm, 0.0, theta[i], c.rotation))
        ax.plot([px, cx], [py, cy], color="C1", linewidth=2.5, label=f"arm l = {c.arm_length_mm:g} mm")
    else:
        xi = c.contact_distance_mm
        i = int(np.argmax(xi))
        d, f, p = c.pivot_distance_mm, c.face_offset_mm, psi[i]
        foot = np.array([d - f * np.sin(p), -f * np.cos(p)])  # follower frame
        u = np.array([-np.cos(p), np.sin(p)])
        ends = [foot + xi.min() * u, foot + xi.max() * u]
        pts = [np.array([d, 0.0]), foot, *ends]
        px, fx, e0, e1 = (np.array([float(v) for v in to_cam_frame(q[0], q[1], theta[i], c.rotation)])
                          for q in pts)
        ax.plot([e0[0], e1[0]], [e0[1], e1[1]], color="C1", linewidth=3,
                label=f"face ({xi.max() - xi.min():.3f} mm swept) at θ = {c.theta_deg[i]:g}°")
        ax.plot([px[0], fx[0]], [px[1], fx[1]], color="C1", linewidth=1.5,
                label=f"face offset f = {f:g} mm")
        ax.plot([px[0], e0[0]], [px[1], e0[1]], color="C1", linewidth=1.0, linestyle=":")
        ax.plot(x[i], y[i], "o", color="C3", markersize=4, label="contact point")
        px, py = px
    ax.plot([px], [py], "o", color="k", markersize=6, markerfacecolor="w",
            label=f"pivot, d = {c.pivot_distance_mm:g} mm")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    _title(fig, title, f"Cam profile in cam coordinates, {c.follower_type.replace('_', ' ')} follower "
                       f"({c.rotation}): pivot, arm and {'roller' if c.pitch_x_mm is not None else 'face'} "
                       "at one cam angle")
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    return fig


def rocker_figures(curves: RockerCurves, title: str = "") -> dict[str, Figure]:
    """{file name: figure}: motion, profile, pressure angle/curvature and (with loads) loads, each
    headed by the run's ``title`` block (:func:`camjax.output.titles.title_block`)."""
    out = {"svaj.png": svaj_figure(curves, title), "profile.png": profile_figure(curves, title),
           "geometry.png": geometry_figure(curves, title)}
    if curves.pivot_torque_Nm is not None:
        out["loads.png"] = loads_figure(curves, title)
    return out


def write_rocker_files(folder: str | Path, curves: RockerCurves, dpi: int = 100,
                       banner: str | None = None, title: str = "", animate: bool = False,
                       progress=None) -> list[Path]:
    """Figures, profile.csv and profile.dxf (and motion.gif when ``animate``) into ``folder``
    (created if needed); the written paths.

    ``banner``: text of a red banner stamped on every figure (the constraints the geometry breaks)
    and drawn in red on the animation; ``title``: the run's title block on every figure and the
    animation; ``progress(phase)``
    (optional) is told "figures", "files" and "animation" as each starts.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda phase: None)
    say("figures")
    figures = rocker_figures(curves, title)
    out = [save_figure(fig, folder / name, dpi, banner) for name, fig in figures.items()]
    say("files")
    # the DXF writer reads only the outline (profile_x_mm, profile_y_mm)
    out += [write_rocker_profile_csv(folder / "profile.csv", curves),
            write_profile_dxf(folder / "profile.dxf", curves)]
    if animate:
        say("animation")
        out.append(write_rocker_animation(folder / "motion.gif", curves, title, banner))
    return out


def write_rocker_animation(path: Path, curves: RockerCurves, title: str = "",
                           banner: str | None = None) -> Path:
    """motion.gif: one turn of the cam with the rocker; ``banner`` (the broken constraints) drawn
    in red and the outline where it undercuts or passes the pressure-angle limit (roller) or crosses
    itself (flat face) drawn red."""
    from camjax.output.animation import mechanism_from_rocker, rocker_violation_samples, write_motion_gif

    return write_motion_gif(path, mechanism_from_rocker(curves, title, banner,
                                                        rocker_violation_samples(curves)))


# ------------------------------------------------------------------------------ report


def rocker_report(scene: Scene, arrays: SceneArrays, run: RockerRun,
                  design: dict | None = None, violations=()) -> dict[str, Any]:
    """The report of a rocker scene as a plain, JSON-ready dict (strict JSON: no NaN or infinity).

    The common header (:func:`camjax.output.report.header_block`) with the motion in rad (swing
    in deg, angular velocity ... in SI), the smallest admissible cam and its binding limit, the
    evaluated cam (pressure angle, curvature, undercut or face length), loads about the pivot and
    the contact stress; with a solved [design], its block (``design``: the solver's keys) and the
    scene's own [follower] dimensions (``follower_scene``): ``oscillating_follower`` gives those
    the drawn cam was computed with.
    """
    sizing, c, f = run.sizing, run.curves, scene.follower
    t = c.theta_deg
    phi = c.pressure_angle_deg
    i = int(np.argmax(np.abs(phi)))
    # the dimensions the drawn cam was computed with (a [design]'s where it solved them), not the
    # scene's [follower] table: those stay visible under follower_scene
    follower = {"type": f.type, "pivot_distance_mm": c.pivot_distance_mm, "rotation": c.rotation}
    if c.arm_length_mm is not None:
        follower.update(arm_length_mm=c.arm_length_mm, roller_radius_mm=c.roller_radius_mm,
                        max_pressure_angle_deg=f.max_pressure_angle_deg)
    else:
        follower["face_offset_mm"] = c.face_offset_mm
    follower["min_curvature_radius_mm"] = f.min_curvature_radius_mm
    out = header_block(scene, arrays)
    out.update({
        "flcd_units": ROCKER_FLCD_UNITS,
        "kinematics": {
            "swing_deg": extrema(c.swing_deg, t),
            "angular_velocity_rad_s": extrema(c.angular_velocity_rad_s, t),
            "angular_accel_rad_s2": extrema(c.angular_accel_rad_s2, t),
            "angular_jerk_rad_s3": extrema(c.angular_jerk_rad_s3, t),
            "velocity_rad_per_rad": extrema(c.ds, t),
            "accel_rad_per_rad2": extrema(c.d2s, t),
        },
        "oscillating_follower": follower,
        "min_base_radius_mm": sizing.min_base_radius_mm,
        "min_base_radius_deg": sizing.angle_deg,
        "min_base_radius_rule": {
            "pressure_angle": f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg (binding) and no "
                              "undercut",
            "undercut": f"no undercut (binding; cam-surface radius >= {f.min_curvature_radius_mm:g} mm) and "
                        f"|pressure angle| <= {f.max_pressure_angle_deg:g} deg",
            "curvature": f"cam radius of curvature >= {f.min_curvature_radius_mm:g} mm",
            "none": "no admissible cam for the design's pivot and arm: the design's own radius",
        }[sizing.binding],
        "min_base_radius_binding": sizing.binding,
        "evaluated_at": {"base_radius_mm": run.base_radius_mm, "source": run.base_radius_source,
                         **feasibility_block(violations)},
    })
    if sizing.min_prime_radius_mm is not None:
        out["min_prime_radius_mm"] = sizing.min_prime_radius_mm
    evaluated: dict[str, Any] = {
        "base_radius_mm": c.base_radius_mm,
        "arm_start_angle_deg": c.arm_start_angle_deg,
        "arm_angle_deg": extrema(c.arm_angle_deg, t),
        "pressure_angle_deg": {**extrema(phi, t), "max_abs": _f(abs(phi[i])), "max_abs_deg": _f(t[i])},
        "rho_mm": {"min": _f(np.min(c.rho_mm)), "min_deg": _f(t[int(np.argmin(c.rho_mm))])},
    }
    if c.prime_radius_mm is not None:
        j = int(np.argmin(np.abs(c.pitch_rho_mm)))
        evaluated.update(
            prime_radius_mm=c.prime_radius_mm,
            pressure_angle_ok=bool(abs(phi[i]) <= f.max_pressure_angle_deg),
            pitch_rho_mm={"min_abs": _f(abs(c.pitch_rho_mm[j])), "min_abs_deg": _f(t[j]),
                          "concave": bool(np.any(c.pitch_rho_mm < 0))},
            undercut_margin_mm={"min": _f(np.min(c.undercut_margin_mm)),
                                "min_deg": _f(t[int(np.argmin(c.undercut_margin_mm))])},
            undercut=bool(np.any(c.undercut_margin_mm <= 0)),
        )
    else:
        xi = c.contact_distance_mm
        evaluated.update(
            curvature_ok=bool(np.min(c.rho_mm) >= f.min_curvature_radius_mm),
            face={"contact_min_mm": _f(np.min(xi)), "contact_max_mm": _f(np.max(xi)),
                  "min_length_mm": _f(np.max(xi) - np.min(xi)),
                  "note": "contact point along the face from the foot of the pivot, towards the cam centre"},
        )
    out["evaluated"] = evaluated
    if c.pivot_torque_Nm is not None:
        m = c.pivot_torque_Nm
        out["loads"] = {
            "pivot_torque_Nm": extrema(m, t),
            "contact_force_N": extrema(c.contact_force_N, t),
            "torque_Nm": extrema(c.torque_Nm, t),
            "contact": {"min_pivot_torque_Nm": _f(np.min(m)),
                        "min_pivot_torque_deg": _f(t[int(np.argmin(m))]),
                        "lost": bool(np.any(m < 0)), "lost_ranges_deg": negative_ranges_deg(m, t)},
        }
    if c.stress_MPa is not None:
        k = int(np.argmax(c.stress_MPa))
        out["stress_MPa"] = {"max": _f(c.stress_MPa[k]), "max_deg": _f(t[k])}
    if design is not None:
        out["design"] = design
        out["follower_scene"] = follower_scene_block(f)
    return out

