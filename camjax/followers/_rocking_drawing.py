"""Figures, profile table and animation of a rocking follower: what every such type shares.

A rocking follower's ``drawing.py`` supplies its own part of the profile figure (``draw_follower``)
and of the animation (its point at an arm angle and its shape); everything else is drawn here from
the run's :class:`camjax.followers._rocking.RockerCurves` (or a namespace with the same fields: the
drawing processes rebuild them without JAX). The outline is in cam coordinates (the convention of
:mod:`camjax.followers._pitch`). NumPy and matplotlib only.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
from matplotlib.figure import Figure

from camjax.followers._closure_drawing import draw_closure, second_outline, second_roller
from camjax.output import animation
from camjax.output.animation import ANGLE_RTOL, LENGTH_TOL_MM, FollowerArtists, Mechanism
from camjax.output.export import profile_columns
from camjax.output.plots import (
    cam_outline,
    clip_axis,
    closed,
    cycle_axis,
    mark_extremes,
    rho_axis_limit_mm,
    title_figure,
)


def to_cam_frame(x_f, y_f, theta_rad, rotation: str) -> tuple[float, float]:
    """A follower-frame point (mm) at cam angle theta in cam coordinates: R(-sigma theta) (x, y),
    sigma = +1 ccw, -1 cw (:func:`camjax.followers._pitch.to_cam_frame`, in NumPy)."""
    a = -(1.0 if rotation == "ccw" else -1.0) * theta_rad
    c, s = np.cos(a), np.sin(a)
    return float(x_f * c - y_f * s), float(x_f * s + y_f * c)


def rows_figure(curves, rows, what: str, title: str = "") -> Figure:
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
        mark_extremes(ax, t, np.where(cut, np.nan, values), "{:.4g} @ {:g}°", which)
        if clip is not None:
            ax.plot(t[i], values[i], "s", color="C2", markersize=4, zorder=4)
            right = t[i] > 250
            ax.annotate(f"smallest |ρ| {abs(values[i]):.4g} mm @ {t[i]:g}°", (t[i], values[i]), fontsize=7,
                        xytext=(-5 if right else 5, 5), textcoords="offset points", va="bottom",
                        ha="right" if right else "left")
        if not cut.any():  # a clipped axis keeps its stated bounds
            ax.margins(y=0.12)
        ax.set_ylabel(name)
        cycle_axis(ax, curves, label=k == len(rows) - 1)
    title_figure(fig, title, what)
    return fig


def svaj_figure(curves, title: str = "") -> Figure:
    """Arm swing (deg), angular velocity, acceleration and jerk over the cycle."""
    c = curves
    return rows_figure(c, [(c.swing_deg, "swing (deg)", None), (c.angular_velocity_rad_s, "ω (rad/s)", None),
                            (c.angular_accel_rad_s2, "α (rad/s²)", None),
                            (c.angular_jerk_rad_s3, "jerk (rad/s³)", None)],
                        "Arm motion over one cycle (dotted: segment joints; dots: extremes)", title)


def geometry_figure(curves, title: str = "") -> Figure:
    """Pressure angle (deg) and the cam surface's radius of curvature (mm), the latter's axis held
    within 4 times the cam's largest radius (:func:`camjax.output.plots.rho_axis_limit_mm`)."""
    c = curves
    clip = rho_axis_limit_mm(c.profile_x_mm, c.profile_y_mm)
    return rows_figure(c, [(c.pressure_angle_deg, "φ (deg)", None), (c.rho_mm, "ρ cam (mm)", clip)],
                        f"Pressure angle and curvature at R_b = {c.base_radius_mm:.3f} mm", title)


def loads_figure(curves, title: str = "") -> Figure:
    """Torque about the pivot, contact force, cam torque and (with [contact]) the Hertz stress."""
    c = curves
    rows = [(c.pivot_torque_Nm, "M pivot (N·m)", None), (c.contact_force_N, "P (N)", None),
            (c.torque_Nm, "T cam (N·m)", None)]
    if c.stress_MPa is not None:
        rows.append((c.stress_MPa, "σ (MPa)", None))
    return rows_figure(c, rows, "Loads about the pivot (M < 0: the spring cannot hold the arm on the cam)",
                        title)



def profile_figure(curves, title: str = "", draw_follower=None) -> Figure:
    """Cam outline (mm) with base circle, pivot, arm and roller (or face) at one cam angle;
    ``draw_follower(ax, curves, theta_rad, psi_rad)`` (the follower's drawing module) draws the
    follower and returns the pivot's position in cam coordinates."""
    c = curves
    fig = Figure(figsize=(6.4, 6.8), layout="constrained")
    ax = fig.subplots()
    x, y, rb = c.profile_x_mm, c.profile_y_mm, c.base_radius_mm
    cam_outline(ax, x, y, rb)
    theta = np.deg2rad(c.theta_deg)
    psi = np.deg2rad(c.arm_angle_deg)
    px, py = draw_follower(ax, c, theta, psi)
    draw_closure(ax, c)
    ax.plot([px], [py], "o", color="k", markersize=6, markerfacecolor="w",
            label=f"pivot, d = {c.pivot_distance_mm:g} mm")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.set_xlabel("X (mm)")
    ax.set_ylabel("Y (mm)")
    title_figure(fig, title, f"Cam profile in cam coordinates, {c.follower_type.replace('_', ' ')} follower "
                       f"({c.rotation}): pivot, arm and {'roller' if c.pitch_x_mm is not None else 'face'} "
                       "at one cam angle")
    fig.legend(fontsize=7, loc="outside lower center", ncols=2)
    return fig


def figure_builders(curves, draw_follower) -> dict[str, Callable]:
    """{file name: figure function (curves, title) -> Figure}: motion, profile, pressure
    angle/curvature and (with loads) loads; ``draw_follower``: the follower's part of the profile
    figure (see :func:`profile_figure`)."""
    out = {"svaj.png": svaj_figure, "profile.png": partial(profile_figure, draw_follower=draw_follower),
           "geometry.png": geometry_figure}
    if curves.pivot_torque_Nm is not None:
        out["loads.png"] = loads_figure
    return out


def profile_table(curves) -> tuple[list[str], np.ndarray]:
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
    return profile_columns(names, cols, optional, c)



def rocker_artists(ax, m: Mechanism, poses, r_max: float, shape: str, points) -> FollowerArtists:
    """A rocker: the pivot, the arm swinging about it, a circle at the arm's end (``shape =
    "circle"``: a roller or a curved face) or a face at its offset (``shape = "face"``), and the
    path of the follower point in contact; ``points(m, psi)``: the follower's point at arm angles
    psi (its drawing module's ``follower_points``)."""
    from matplotlib.patches import Circle

    d = m.pivot_distance_mm
    roller = shape == "circle"
    # the whole turn, for the fixed parts and the axis limits
    every = animation.frame_poses(m, len(m.theta_deg))
    psi = np.deg2rad(every.arm_angle_deg)
    ax.plot([d], [0.0], "o", color="k", markersize=7, markerfacecolor="w", zorder=4,
            label=f"pivot, d = {d:g} mm")
    if roller:
        rf, arm = m.roller_radius_mm, m.arm_length_mm
        arc = np.linspace(psi.min(), psi.max(), 60)
        ax.plot(*points(m, arc), color="0.45", linewidth=0.8, linestyle=":",
                label="arc of the roller centre")
        circle = Circle((0.0, 0.0), rf, fill=False, color="C1", linewidth=2.0,
                        label=f"roller, R_f = {rf:g} mm")
        ax.add_patch(circle)
        (centre,) = ax.plot([], [], "o", color="C1", markersize=3)
        (arm_line,) = ax.plot([], [], color="C1", linewidth=3.0, solid_capstyle="round",
                              label=f"arm, l = {arm:g} mm")
        xs = np.concatenate([every.follower_x_mm - rf, every.follower_x_mm + rf])
        ys = np.concatenate([every.follower_y_mm - rf, every.follower_y_mm + rf])
        face = None
    else:
        f = m.face_offset_mm
        # the stretch of the face the contact sweeps, measured along u = (-cos psi, sin psi) from
        # the pivot's foot (positive towards the cam centre), drawn with a margin and from the foot
        u = np.stack([-np.cos(psi), np.sin(psi)])
        xi = np.sum((np.stack([every.contact_x_mm, every.contact_y_mm])
                     - np.stack([every.follower_x_mm, every.follower_y_mm])) * u, axis=0)
        lo, hi = min(0.0, float(xi.min())), float(xi.max())
        pad = 0.1 * (hi - lo) + 0.02 * r_max
        span = np.array([lo - pad, hi + pad])
        (face,) = ax.plot([], [], color="C1", linewidth=4.0, solid_capstyle="butt",
                          label=f"flat face, offset f = {f:g} mm")
        (arm_line,) = ax.plot([], [], color="C1", linewidth=2.0, label="arm (pivot to face)")
        circle = centre = None
        ends_x = every.follower_x_mm[:, None] + span[None, :] * u[0][:, None]
        ends_y = every.follower_y_mm[:, None] + span[None, :] * u[1][:, None]
        xs, ys = ends_x.ravel(), ends_y.ravel()
    (path,) = ax.plot([], [], color="0.35", linewidth=1.0, linestyle=":",
                      label="path of the " + ("roller centre" if roller else "face point in contact"))

    def update(i):
        fx, fy = poses.follower_x_mm[i], poses.follower_y_mm[i]
        p = np.deg2rad(poses.arm_angle_deg[i])
        arm_line.set_data([d, fx], [0.0, fy])
        if roller:
            circle.center = (fx, fy)
            centre.set_data([fx], [fy])
            ox, oy = fx, fy
        else:
            face.set_data(fx - span * np.cos(p), fy + span * np.sin(p))
            ox, oy = poses.contact_x_mm[i], poses.contact_y_mm[i]
        # the point turns about the pivot with the arm (clockwise as psi grows): its path is
        # perpendicular to pivot -> point; phi is the angle between it and the force line
        rx, ry = ox - d, oy
        n = np.hypot(rx, ry)
        reach = 0.45 * r_max - (m.roller_radius_mm if roller else 0.0)
        path.set_data([ox, ox + reach * ry / n], [oy, oy - reach * rx / n])
        return (arm_line, path) + ((circle, centre) if roller else (face,))

    def normal(i):
        if roller:  # from the contact point through the roller centre
            nx = poses.follower_x_mm[i] - poses.contact_x_mm[i]
            ny = poses.follower_y_mm[i] - poses.contact_y_mm[i]
            n = np.hypot(nx, ny)
            return nx / n, ny / n
        p = np.deg2rad(poses.arm_angle_deg[i])
        return np.sin(p), np.cos(p)  # the face normal m, away from the cam

    moving = [arm_line, path] + ([circle, centre] if roller else [face])
    xs = np.concatenate([xs, [d, -r_max, r_max]])
    ys = np.concatenate([ys, [0.0, -r_max, r_max]])
    pad = 0.06 * max(np.ptp(xs), np.ptp(ys))
    artists = {"follower": circle if roller else face, "arm": arm_line, "path": path}
    if not roller:
        artists["face"] = face
    return FollowerArtists(artists, moving, update, normal, (xs.min() - pad, xs.max() + pad),
                            (ys.min() - pad, ys.max() + pad))




def mechanism(curves, title: str = "", violation: str | None = None, bad=None) -> Mechanism:
    """The :class:`camjax.output.animation.Mechanism` of a rocking follower's curves
    (:class:`camjax.followers._rocking.RockerCurves`; ``bad``: default :func:`violation_samples`)."""
    roller = curves.arm_length_mm is not None
    return Mechanism(
        np.asarray(curves.theta_deg), np.asarray(curves.profile_x_mm), np.asarray(curves.profile_y_mm),
        None, curves.follower_type, float(curves.base_radius_mm),
        roller_radius_mm=curves.roller_radius_mm if roller else None,
        pressure_angle_deg=np.asarray(curves.pressure_angle_deg), title=title, violation=violation,
        bad=violation_samples(curves) if bad is None else bad, rotation=curves.rotation, pivot_distance_mm=float(curves.pivot_distance_mm),
        arm_length_mm=curves.arm_length_mm if roller else None,
        face_offset_mm=None if roller else curves.face_offset_mm,
        arm_start_angle_deg=float(curves.arm_start_angle_deg), swing_deg=np.asarray(curves.swing_deg),
        second_outline=second_outline(curves), second_roller=second_roller(curves),
    )


def violation_samples(curves, max_pressure_angle_deg: float | None = None) -> np.ndarray:
    """(N,) booleans: where a rocker's outline breaks a constraint, to be drawn red.

    Roller: undercut (margin < 0, the margin holds the scene's smallest radius of curvature) and
    |pressure angle| over its limit (deg; default the curves' ``pressure_angle_limit_deg``); flat
    face: rho < 0 (the outline crosses itself), as :func:`violation_samples`. Within the solvers'
    tolerances nothing is marked.
    """
    if max_pressure_angle_deg is None:
        max_pressure_angle_deg = getattr(curves, "pressure_angle_limit_deg", None)
    bad = np.zeros(np.shape(curves.theta_deg), bool)
    if curves.undercut_margin_mm is not None:
        bad |= np.asarray(curves.undercut_margin_mm) < -LENGTH_TOL_MM
    else:
        bad |= np.asarray(curves.rho_mm) < -LENGTH_TOL_MM
    if max_pressure_angle_deg is not None and curves.undercut_margin_mm is not None:
        bad |= np.abs(np.asarray(curves.pressure_angle_deg)) > max_pressure_angle_deg * (1.0 + ANGLE_RTOL)
    return bad
