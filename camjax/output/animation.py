"""Animation of the mechanism: the cam turning, the follower moving, contact and pressure angle.

Written against plain arrays (:class:`Mechanism`: the outline in cam coordinates, s(theta) and
the follower's type and sizes); each follower type's drawing module (:mod:`camjax.followers`)
supplies its point in :func:`frame_poses` (``follower_points``) and its artists in
:func:`motion_frames` (``artists``, a :class:`FollowerArtists`), and builds the Mechanism from its
curves (``mechanism``). Conventions are those of
:mod:`camjax.geometry`: in cam coordinates the follower axis is +Y at theta = 0 and the contact
point at cam angle theta lies at polar angle theta clockwise from +Y. In the fixed (frame)
coordinates drawn here the follower slides along +Y and the cam turns counter-clockwise: a cam
point P is drawn at R(theta) P, R the rotation by +theta (a clockwise cam: R(-theta) P).

Oscillating (rocker) followers are drawn in the fixed frame of :mod:`camjax.followers.oscillating_roller.geometry`
(the same rotation of the outline): the pivot at (d, 0), the arm at psi = psi0 + s from the line
of centres; the roller centre, the face line and their start angles come from that module.

Figures are built without pyplot (Agg through ``Figure``), like :mod:`camjax.output.plots`;
matplotlib is imported only when drawing. Functions here take NumPy arrays and are not traced
by JAX (nothing here is differentiated).
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import NamedTuple

import numpy as np

from camjax import followers

# violations smaller than the solvers' feasibility tolerances (camjax.followers.flat.problem.FEASIBILITY_TOL_MM
# and its relative one) are not drawn as such: an optimum sits on its active limits
LENGTH_TOL_MM = 1e-6
ANGLE_RTOL = 1e-6


class UndrawableGeometry(ValueError):
    """The outline or the motion has non-finite points: there is no mechanism to draw."""


class Mechanism(NamedTuple):
    """What the animation draws, per sample (shape (N,) arrays) and per follower.

    Attributes:
      theta_deg: cam angle of each sample, deg, increasing over one turn.
      profile_x_mm, profile_y_mm: cam outline in cam coordinates (the contact point of sample k).
      s_mm: follower displacement s(theta), mm; None for an oscillating follower (see swing_deg).
      follower_type: "flat", "roller", "oscillating_roller" or "oscillating_flat".
      base_radius_mm: R_b, mm.
      face_width_mm: flat face width L, mm (flat only).
      roller_radius_mm: R_f, mm (roller only).
      offset_mm: offset e of the roller's axis from the cam centre, mm (roller only).
      pressure_angle_deg: angle between the contact normal and the follower axis, deg, (N,);
        None means 0 (a flat face perpendicular to its stem).
      title: drawn above the mechanism (a title block: one or more lines).
      violation: one line drawn in red when the geometry breaks a constraint (None: feasible).
      bad: (N,) booleans, samples where the outline breaks a constraint (drawn red); None: none.
      rotation: "ccw" (the cam turns counter-clockwise) or "cw" (its outline is the mirror image,
        X -> -X, and it turns clockwise).
      pivot_distance_mm: d, the pivot's distance from the cam centre, mm (oscillating only).
      arm_length_mm: l, pivot to roller centre, mm (oscillating roller only).
      face_offset_mm: f, the face's distance from the pivot, mm (oscillating flat only).
      arm_start_angle_deg: psi0, the arm's angle from the line of centres at s = 0, deg
        (oscillating only).
      swing_deg: (N,) the arm's swing s(theta) from psi0, deg (oscillating only): psi = psi0 + s.
      second_outline: a positive drive's second flank or cam (X, Y), cam coordinates, turning with
        the first (:func:`camjax.followers._closure_drawing.second_outline`); None: spring-closed.
      second_roller: a conjugate pair's second roller: its centre's path (X, Y), cam coordinates,
        and its radius, mm (:func:`camjax.followers._closure_drawing.second_roller`); None: none.
    """

    theta_deg: np.ndarray
    profile_x_mm: np.ndarray
    profile_y_mm: np.ndarray
    s_mm: np.ndarray
    follower_type: str
    base_radius_mm: float
    face_width_mm: float | None = None
    roller_radius_mm: float | None = None
    offset_mm: float = 0.0
    pressure_angle_deg: np.ndarray | None = None
    title: str = ""
    violation: str | None = None
    bad: np.ndarray | None = None
    rotation: str = "ccw"
    pivot_distance_mm: float | None = None
    arm_length_mm: float | None = None
    face_offset_mm: float | None = None
    arm_start_angle_deg: float | None = None
    swing_deg: np.ndarray | None = None
    second_outline: tuple[np.ndarray, np.ndarray] | None = None
    second_roller: tuple[np.ndarray, np.ndarray, float] | None = None

    @property
    def oscillating(self) -> bool:
        """True for a rocker: the arm swings about the pivot instead of sliding."""
        return self.swing_deg is not None

    def motion(self) -> tuple[np.ndarray, str]:
        """(N,) the follower's motion over the turn and its axis label: s in mm, or the swing in deg."""
        if self.oscillating:
            return np.asarray(self.swing_deg), "arm swing s (deg)"
        return np.asarray(self.s_mm), "follower displacement s (mm)"


class FramePoses(NamedTuple):
    """Pose of the mechanism at each animated sample (shape (F,) each, fixed coordinates, mm)."""

    index: np.ndarray  # sample index k of each frame
    theta_deg: np.ndarray  # cam angle, deg
    # flat: centre of the face; roller and oscillating roller: centre of the roller; oscillating
    # flat: the foot of the pivot on the face (A - f m)
    follower_x_mm: np.ndarray
    follower_y_mm: np.ndarray
    contact_x_mm: np.ndarray
    contact_y_mm: np.ndarray
    pressure_angle_deg: np.ndarray
    arm_angle_deg: np.ndarray | None = None  # oscillating: psi = psi0 + s, deg from the line of centres


def check_drawable(curves) -> None:
    """Raise :class:`UndrawableGeometry` naming the first of the outline (profile_x_mm,
    profile_y_mm) and the motion (s_mm, or a rocker's swing_deg) of ``curves`` (a Mechanism,
    DesignCurves or RockerCurves) that has non-finite points."""
    for name in ("profile_x_mm", "profile_y_mm", "s_mm", "swing_deg"):
        if getattr(curves, name, None) is None:  # s_mm of a rocker, swing_deg of a slider
            continue
        bad = ~np.isfinite(np.asarray(getattr(curves, name), dtype=float))
        if bad.any():
            raise UndrawableGeometry(f"{name} is not finite at {np.count_nonzero(bad)} of {bad.size} "
                                     "samples: the cam cannot be drawn")


def frame_indices(samples: int, frames: int) -> np.ndarray:
    """Indices of ``frames`` samples evenly spread over one turn of ``samples`` (shape (F,))."""
    if not 1 <= frames <= samples:
        raise ValueError(f"frames: {frames} must be in 1..{samples} (the samples of one turn)")
    return np.floor(np.arange(frames) * samples / frames + 1e-9).astype(int)


def rotate(x, y, theta_rad):
    """(x, y) turned counter-clockwise by theta (rad): cam coordinates -> fixed coordinates."""
    c, s = np.cos(theta_rad), np.sin(theta_rad)
    return x * c - y * s, x * s + y * c


def _turn(m: Mechanism) -> float:
    """+1 for a counter-clockwise cam, -1 for a clockwise one (the sign of its rotation)."""
    if m.rotation not in ("ccw", "cw"):
        raise ValueError(f"rotation: '{m.rotation}' is not allowed; use ccw or cw")
    return 1.0 if m.rotation == "ccw" else -1.0


def frame_poses(m: Mechanism, frames: int) -> FramePoses:
    """Follower, contact point and pressure angle at ``frames`` evenly spread cam angles."""
    if m.follower_type not in followers.names():
        raise ValueError(f"follower_type: '{m.follower_type}' is not drawn; allowed: "
                         f"{', '.join(followers.names())}")
    drawing = followers.drawing(m.follower_type)
    check_drawable(m)
    k = frame_indices(len(m.theta_deg), frames)
    th = np.deg2rad(np.asarray(m.theta_deg)[k])
    cx, cy = rotate(np.asarray(m.profile_x_mm)[k], np.asarray(m.profile_y_mm)[k], _turn(m) * th)
    phi = np.zeros(len(k)) if m.pressure_angle_deg is None else np.asarray(m.pressure_angle_deg)[k]
    if m.oscillating:
        psi_deg = m.arm_start_angle_deg + np.asarray(m.swing_deg)[k]
        fx, fy = drawing.follower_points(m, np.deg2rad(psi_deg))
        return FramePoses(k, np.rad2deg(th), fx, fy, cx, cy, phi, psi_deg)
    fx, fy = drawing.follower_points(m, np.asarray(m.s_mm)[k])
    return FramePoses(k, np.rad2deg(th), fx, fy, cx, cy, phi)


class MotionFrames(NamedTuple):
    """A figure and the function that poses it at frame i (0..F-1)."""

    figure: object  # matplotlib Figure
    update: object  # i -> tuple of the moved artists
    poses: FramePoses
    # "cam", "bad" (the outline breaking a constraint), "follower", "contact", "normal", "label",
    # "marker"; a rocker's "arm", "path" and "face"; "moving": all that move
    artists: dict


def motion_frames(m: Mechanism, frames: int = 72) -> MotionFrames:
    """The mechanism's figure and an ``update(i)`` that draws frame i (theta of poses.index[i]).

    The cam turns counter-clockwise (clockwise for ``rotation = "cw"``); the small s(theta) panel
    marks where in the cycle the frame is. ``artists`` lets a caller (or a test) read back what
    frame i shows; a rocker adds "arm" (pivot to roller centre, or pivot to the face's foot),
    "face" (oscillating flat) and "path" (the direction the follower point in contact moves).
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyArrowPatch

    poses = frame_poses(m, frames)
    x, y = np.asarray(m.profile_x_mm), np.asarray(m.profile_y_mm)
    r_max = float(np.max(np.hypot(x, y)))
    x2 = y2 = None
    if m.second_outline is not None:  # a groove's outer flank or a conjugate cam
        x2, y2 = (np.asarray(v) for v in m.second_outline)
        r_max = max(r_max, float(np.max(np.hypot(x2, y2))))
    s, s_label = m.motion()

    fig = Figure(figsize=(7.2, 5.0), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=[1.5, 1.0], height_ratios=[1.3, 1.0])
    ax = fig.add_subplot(grid[:, 0])
    ax_s = fig.add_subplot(grid[0, 1])
    ax_key = fig.add_subplot(grid[1, 1])  # holds the legend
    ax_key.set_axis_off()
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.grid(True, alpha=0.25)
    ax.plot([0.0], [0.0], "+", color="k", markersize=8)
    cam_fill = ax.fill(x, y, color="C0", alpha=0.18, label="cam")[0]
    (cam_line,) = ax.plot(x, y, color="C0", linewidth=1.4)
    (second_line,) = ax.plot([], [], color="C4", linewidth=1.4,
                             **({"label": "second flank or cam"} if x2 is not None else {}))
    bad = np.zeros(len(x), bool) if m.bad is None else np.asarray(m.bad, bool)
    (bad_line,) = ax.plot([], [], color="C3", linewidth=2.2, label="outline breaking a constraint")
    (key,) = ax.plot([0.0, 0.0], [0.0, 0.6 * m.base_radius_mm], color="C0", linewidth=2.0)
    # direction of rotation: an arc arrow below the centre, left to right for counter-clockwise
    turn = _turn(m)
    ax.add_patch(FancyArrowPatch((-0.35 * turn * m.base_radius_mm, -0.2 * m.base_radius_mm),
                                 (0.35 * turn * m.base_radius_mm, -0.2 * m.base_radius_mm),
                                 connectionstyle=f"arc3,rad={0.8 * turn}", arrowstyle="-|>",
                                 mutation_scale=12, color="0.25", linewidth=1.2))
    ax.text(0.0, -0.62 * m.base_radius_mm, "ω", ha="center", va="center", fontsize=9, color="0.25")
    follower = followers.drawing(m.follower_type).artists(ax, m, poses, r_max)
    # a conjugate pair's second roller, and the link that carries it: the yoke from the first
    # roller's centre, or the rocker's second arm from the pivot
    second = None
    if m.second_roller is not None:
        from matplotlib.patches import Circle

        second_px, second_py, second_radius = m.second_roller
        second = Circle((0.0, 0.0), second_radius, fill=False, color="C4", linewidth=1.4, label="second roller")
        ax.add_patch(second)
        (second_link,) = ax.plot([], [], color="C4", linewidth=2.0,
                                 label="second arm" if m.oscillating else "yoke")
    (contact,) = ax.plot([], [], "o", color="C3", markersize=5, label="contact point")
    (normal,) = ax.plot([], [], color="C3", linewidth=1.0, linestyle="--",
                        label="contact normal (force line)")
    label = ax.text(0.02, 0.02, "", transform=ax.transAxes, va="bottom", fontsize=8,
                    bbox={"boxstyle": "round", "fc": "white", "ec": "0.7", "alpha": 0.9})
    handles, names = ax.get_legend_handles_labels()
    keep = [(h, n) for h, n in zip(handles, names, strict=True) if n != bad_line.get_label() or bad.any()]
    if m.violation:  # above the s panel, where it covers nothing that moves
        ax_s.set_title(textwrap.fill(m.violation, 44), fontsize=8, color="C3", loc="left")
    fig.suptitle(m.title or "Cam mechanism", fontsize=9)

    t = np.asarray(m.theta_deg)
    ax_s.plot(np.append(t, 360.0), np.append(s, s[0]), color="C1", linewidth=1.2)
    (marker,) = ax_s.plot([], [], "o", color="C3", markersize=5)
    ax_s.set_xlim(0.0, 360.0)
    ax_s.set_xticks(np.arange(0, 361, 90))
    ax_s.set_xlabel("cam angle θ (deg)")
    ax_s.set_ylabel(s_label)
    ax_s.grid(True, alpha=0.3)
    ax_key.legend(*zip(*keep, strict=True), fontsize=7, loc="center")
    length = 0.45 * r_max  # of the drawn force line

    def update(i):
        th = turn * np.deg2rad(poses.theta_deg[i])
        xr, yr = rotate(x, y, th)
        cam_line.set_data(xr, yr)
        cam_fill.set_xy(np.column_stack([xr, yr]))
        if x2 is not None:
            second_line.set_data(*rotate(x2, y2, th))
        bad_line.set_data(np.where(bad, xr, np.nan), np.where(bad, yr, np.nan))
        key.set_data(*rotate(np.array([0.0, 0.0]), np.array([0.0, 0.6 * m.base_radius_mm]), th))
        moved = follower.update(i)
        extra = ()
        if second is not None:
            centre = rotate(np.array([second_px[poses.index[i]]]), np.array([second_py[poses.index[i]]]), th)
            second.center = (float(centre[0][0]), float(centre[1][0]))
            if m.oscillating:
                (x0, _), (y0, _) = follower.artists["arm"].get_data()  # from the pivot
            else:
                x0, y0 = follower.artists["follower"].center  # from the first roller's centre
            second_link.set_data([x0, second.center[0]], [y0, second.center[1]])
            extra = (second, second_link)
        cx, cy = poses.contact_x_mm[i], poses.contact_y_mm[i]
        contact.set_data([cx], [cy])
        nx, ny = follower.normal(i)
        normal.set_data([cx, cx + length * nx], [cy, cy + length * ny])
        phi = poses.pressure_angle_deg[i]
        k = poses.index[i]
        where = (f"s = {s[k]:6.2f}°, ψ = {poses.arm_angle_deg[i]:6.2f}°" if m.oscillating
                 else f"s = {s[k]:6.3f} mm")
        label.set_text(f"θ = {poses.theta_deg[i]:5.1f}°\n{where}\npressure angle φ = {phi:5.1f}°")
        marker.set_data([poses.theta_deg[i]], [s[k]])
        return cam_line, cam_fill, second_line, bad_line, key, *moved, *extra, contact, normal, label, marker

    ax.set_xlim(*follower.xlim)
    ax.set_ylim(*follower.ylim)
    update(0)
    extra = [] if second is None else [second, second_link]
    artists = {"cam": cam_line, "second_cam": second_line, "bad": bad_line, "contact": contact, "normal": normal,
               "label": label, "marker": marker, **follower.artists,
               **({} if second is None else {"second_roller": second, "second_link": second_link}),
               "moving": [cam_fill, cam_line, second_line, bad_line, key, *follower.moving, *extra, contact, normal,
                          label, marker]}
    return MotionFrames(fig, update, poses, artists)


class FollowerArtists(NamedTuple):
    """A follower type's drawing: its artists, how frame i moves them, the axis limits."""

    artists: dict  # names a test reads back ("follower", "arm", ...)
    moving: list  # every artist update() moves (blitted by the GIF writer)
    update: object  # i -> tuple of the moved artists
    normal: object  # i -> (n_x, n_y), unit contact normal at frame i, from the cam towards the follower
    xlim: tuple[float, float]
    ylim: tuple[float, float]


def motion_animation(m: Mechanism, frames: int = 72, interval_ms: int = 60):
    """A matplotlib ``FuncAnimation`` of one turn (for notebooks and interactive backends)."""
    from matplotlib.animation import FuncAnimation

    mf = motion_frames(m, frames)
    return FuncAnimation(mf.figure, mf.update, frames=len(mf.poses.index), interval=interval_ms)


def _blitting_pillow_writer(moving, fps: int):
    """A PillowWriter that draws the still parts once and only the ``moving`` artists per frame.

    The stock writer redraws the whole figure for every frame (~0.2 s each with ticks, grid and
    the s panel on a busy 2-core machine); restoring a saved background and drawing the handful
    of moving artists costs a few ms. Frames are stored as 64-colour palette images.
    """
    from matplotlib.animation import PillowWriter
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    class BlittingPillowWriter(PillowWriter):
        def setup(self, fig, outfile, dpi=None):
            super().setup(fig, outfile, dpi=dpi)
            fig.set_dpi(self.dpi)
            self._canvas = FigureCanvasAgg(fig)
            for artist in moving:
                artist.set_animated(True)  # left out of canvas.draw: the background
            self._canvas.draw()
            fig.set_layout_engine("none")  # keep the layout of that draw for every frame
            self._background = self._canvas.copy_from_bbox(fig.bbox)

        def grab_frame(self, **savefig_kwargs):
            self._canvas.restore_region(self._background)
            for artist in moving:
                self.fig.draw_artist(artist)
            w, h = self._canvas.get_width_height()
            rgb = Image.frombuffer("RGBA", (w, h), self._canvas.buffer_rgba(), "raw", "RGBA", 0,
                                   1).convert("RGB")
            # one palette for every frame, taken from the first (it holds every colour drawn):
            # no flicker between frames, and mapping to it is ~30x faster than a fresh quantize
            if not self._frames:
                self._palette = rgb.quantize(colors=64, method=Image.Quantize.FASTOCTREE)
            self._frames.append(rgb.quantize(palette=self._palette, dither=Image.Dither.NONE))

    return BlittingPillowWriter(fps=fps)


def write_motion_gif(path: str | Path, m: Mechanism, frames: int = 72, fps: int = 18,
                     dpi: int = 72, units: str = "mm") -> Path:
    """motion.gif of one turn (matplotlib's Pillow writer, loops forever); returns the path.
    ``units``: those of the mechanism's lengths, which its labels then name."""
    from camjax.units import relabel

    mf = motion_frames(m, frames)
    relabel(mf.figure, units)
    path = Path(path)
    writer = _blitting_pillow_writer(mf.artists["moving"], fps)
    with writer.saving(mf.figure, path, dpi):
        for i in range(len(mf.poses.index)):
            mf.update(i)
            writer.grab_frame()
    return path
