"""Making the cam: the exact cam surface densely, the cutter's centre path, the gouge check, a biarc
fit of the path and the G-code that cuts it (``[manufacture]``, SPEC 3 "Making the cam").

Frame: the cam frame of profile.csv's ``x_mm, y_mm`` (cam centre at the origin, the cam at angle 0,
:mod:`camjax.followers._pitch`). The cam surface is evaluated by the follower's own closed forms
at a dense grid of cam angles (:func:`cam_surface`), with its tangent and curvature from forward-mode
derivatives in the cam angle (exact, not finite differences). A cutter (or grinding wheel) of radius
R_t cutting the outside of the cam moves its centre on the surface offset outward by R_t
(:func:`tool_path`); a concave stretch tighter than R_t would be gouged (:func:`gouge_check`). The
path is replaced by tangent-continuous circular arcs within a tolerance (:func:`fit_biarcs`) and
written as G2/G3 blocks (:func:`write_gcode`).

:func:`cam_surface` runs JAX once (one compiled call); everything else is host-side NumPy that
writes files, not meant for jit/vmap/grad. Every writer takes ``units``: ``"mm"`` (default) or
``"in"`` (G20, lengths divided by 25.4).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from camjax.errors import SceneError
from camjax.output.export import CSV_FORMAT

DENSE_SAMPLES_MIN = 7200  # at least 0.05 deg between the dense samples of the surface
DENSE_SPACING_MM = 0.05  # and at most about this far apart along the outline
DENSE_SAMPLES_MAX = 400_000
SAFE_Z_MM = 5.0  # rapid height above the cam's top face (Z0)
APPROACH_MM = 2.0  # the lead-in starts this far outside the path, along its normal
LINE_SAG = 1e-3  # an arc whose sagitta is below LINE_SAG * tolerance is written as a line (G1)


def signed_area2(x: np.ndarray, y: np.ndarray) -> float:
    """Twice the signed area of the closed polygon through (x, y) (shoelace; > 0 counter-clockwise)."""
    return float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def unit_scale(units: str) -> float:
    """Factor from mm to ``units`` ("mm": 1, "in": 1/25.4; :func:`camjax.units.length_scale`'s inverse)."""
    from camjax.units import UNITS, length_scale

    if units not in UNITS:
        raise ValueError(f"units: {units!r} is not one of {', '.join(UNITS)}")
    return 1.0 / length_scale(units)


# ------------------------------------------------------------------------------ the exact surface


class Surface(NamedTuple):
    """The cam surface at dense cam angles, NumPy arrays of shape (M,), mm.

    ``tx, ty``: unit tangent in the direction of increasing cam angle; ``nx, ny``: unit normal
    pointing out of the cam; ``rho_mm``: signed radius of curvature, > 0 convex, < 0 concave
    (+/-inf where the surface is straight).
    """

    theta_deg: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    tx: np.ndarray
    ty: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    rho_mm: np.ndarray


def dense_samples(samples: int, x_mm: np.ndarray, y_mm: np.ndarray) -> int:
    """Dense grid size: a multiple of the scene's ``samples`` (each sample stays a sample) with at
    least :data:`DENSE_SAMPLES_MIN` points and about :data:`DENSE_SPACING_MM` between them along the
    outline (``x_mm, y_mm``: the drawn profile, for its length), at most :data:`DENSE_SAMPLES_MAX`
    (or ``samples`` where it is larger)."""
    length = float(np.sum(np.hypot(np.diff(x_mm, append=x_mm[:1]), np.diff(y_mm, append=y_mm[:1]))))
    target = min(max(DENSE_SAMPLES_MIN, math.ceil(length / DENSE_SPACING_MM)), DENSE_SAMPLES_MAX)
    return samples * max(1, math.ceil(target / samples))


def profile_function(scene, design: dict | None, base_radius_mm: float):
    """``f(theta_deg) -> (x_mm, y_mm)``: the cam outline the scene's follower draws at
    ``base_radius_mm`` with ``design``'s dimensions (result.json's ``design`` block; None: the
    scene's own), at any cam angles (deg); traceable in ``theta_deg``."""
    import jax
    import jax.numpy as jnp

    from camjax import followers, program
    from camjax.evaluate import arrays_from_kinematics

    kind = followers.of(scene)
    drawn = kind.drawn_follower(scene, design or {})
    prog = jax.tree_util.tree_map(lambda v: jnp.asarray(v, jnp.float64), scene.motion.program)
    radius = float(base_radius_mm)

    bounds = program.segment_bounds_deg(prog)

    def motion(theta_deg):
        # each segment's closed form, selected by angle as program.motion_at does, but without its
        # clip: jax.jvp then differentiates the segment's formula also at a sample on its joint
        # (the clip's derivative there is halved)
        outs = None
        for i, (lo, hi) in enumerate(bounds):
            inside = theta_deg >= lo if i == len(bounds) - 1 else (theta_deg >= lo) & (theta_deg < hi)
            k = program.segment_motion(prog, i, theta_deg)
            if outs is not None:
                k = type(k)(*(jnp.where(inside, v, o) for v, o in zip(k, outs, strict=True)))
            outs = k
        return outs

    def profile(theta_deg):
        kin = motion(theta_deg)
        if kind.rocking:
            g = kind.geometry(replace(scene, follower=drawn), kin, radius)
        else:
            g = kind.geometry(drawn, scene.motion.rotation, arrays_from_kinematics(scene, kin), radius)
        return jnp.stack([g.profile_x_mm, g.profile_y_mm])

    return profile


def cam_surface(scene, design: dict | None, base_radius_mm: float, samples: int) -> Surface:
    """The cam surface at ``samples`` equally spaced cam angles (k * 360 / samples deg), exact:
    points from the follower's closed forms, tangent and curvature from their first and second
    derivatives in the cam angle (``jax.jvp``; at a joint, the segment that starts there).
    ``design``, ``base_radius_mm`` as in :func:`profile_function`. One compiled call."""
    import jax
    import jax.numpy as jnp

    profile = profile_function(scene, design, base_radius_mm)

    def derivatives(t):
        ones = jnp.ones_like(t)

        def first(u):
            return jax.jvp(profile, (u,), (ones,))

        (p, d1), (_, d2) = jax.jvp(first, (t,), (ones,))
        return p, d1, d2

    theta = np.arange(samples) * (360.0 / samples)
    p, d1, d2 = (np.asarray(a) for a in jax.jit(derivatives)(jnp.asarray(theta, jnp.float64)))
    x, y = p
    dx, dy = d1  # mm/deg
    ddx, ddy = d2
    speed = np.hypot(dx, dy)
    if not np.all(np.isfinite(p)) or not np.all(speed > 0):
        bad = int(np.argmin(np.where(np.isfinite(speed), speed, -1.0)))
        raise SceneError("manufacture", float(theta[bad]), "the cam surface is not a smooth curve at "
                         "this cam angle (deg): its outline has a cusp or is not finite; it cannot be cut")
    area2 = signed_area2(x, y)
    orient = 1.0 if area2 > 0 else -1.0  # +1: increasing angle runs counter-clockwise
    tx, ty = dx / speed, dy / speed
    turn = tx * np.roll(tx, -1) + ty * np.roll(ty, -1)
    if np.any(turn < 0):  # the tangent reverses between two dense samples: a cusp
        bad = int(np.argmin(turn))
        raise SceneError("manufacture", float(theta[bad]), "the cam outline has a cusp near this cam angle "
                         "(deg): it folds back on itself (its radius of curvature passes through 0) and "
                         "cannot be cut; draw it at a larger base radius")
    kappa = (dx * ddy - dy * ddx) / speed**3 * orient  # 1/mm per deg^0: deg cancels; > 0 convex
    with np.errstate(divide="ignore"):
        rho = 1.0 / kappa
    # outward normal: the tangent turned clockwise for a counter-clockwise outline
    return Surface(theta, x, y, tx, ty, orient * ty, -orient * tx, rho)


# ------------------------------------------------------------------------------ cutter path


def largest_cutter(surface: Surface) -> tuple[float, float | None]:
    """(largest cutter diameter that cuts every concave stretch without gouging, mm, and the cam
    angle of the tightest concave stretch, deg): twice the smallest concave radius on the dense
    samples; (inf, None) for a convex cam."""
    concave = surface.rho_mm < 0
    if not np.any(concave):
        return math.inf, None
    radii = np.where(concave, -surface.rho_mm, np.inf)
    k = int(np.argmin(radii))
    return 2.0 * float(radii[k]), float(surface.theta_deg[k])


def gouge_check(surface: Surface, cutter_diameter_mm: float) -> tuple[float, float | None]:
    """:func:`largest_cutter` of the surface; raise :class:`SceneError` naming
    ``manufacture.cutter_diameter_mm``, the largest diameter that fits and the cam angle when the
    cutter is too large for a concave stretch (its centre path would fold back: the cutter would
    cut into the cam there)."""
    largest, at = largest_cutter(surface)
    if cutter_diameter_mm > largest:
        raise SceneError("manufacture.cutter_diameter_mm", cutter_diameter_mm,
                         f"the cutter would gouge the concave stretch at cam angle {at:.4g} deg "
                         f"(radius {largest / 2:.6g} mm)", f"a diameter <= {largest:.6g} mm")
    return largest, at


class ToolPath(NamedTuple):
    """The cutter's centre at the dense samples (mm) and the surface point each one cuts."""

    theta_deg: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    tx: np.ndarray  # unit tangent (the surface's) in the direction of increasing cam angle
    ty: np.ndarray
    surface_x_mm: np.ndarray
    surface_y_mm: np.ndarray
    nx: np.ndarray  # outward unit normal of the surface
    ny: np.ndarray


def tool_path(surface: Surface, cutter_radius_mm: float) -> ToolPath:
    """The surface offset outward along its normal by the cutter radius (mm). For a roller
    follower and a cutter of the roller's radius this is the pitch curve."""
    r = float(cutter_radius_mm)
    return ToolPath(surface.theta_deg, surface.x_mm + r * surface.nx, surface.y_mm + r * surface.ny,
                    surface.tx, surface.ty, surface.x_mm, surface.y_mm, surface.nx, surface.ny)


def write_cutter_path_csv(path: Path, tp: ToolPath, units: str = "mm") -> Path:
    """cutter_path.csv: ``theta_deg, x_mm, y_mm`` (the tool centre), ``surface_x_mm,
    surface_y_mm`` (the point of the cam it cuts), ``normal_x, normal_y`` (outward unit normal), one
    row per dense sample; ``_in`` columns and inches with ``units = "in"``."""
    k = unit_scale(units)
    u = units
    names = ["theta_deg", f"x_{u}", f"y_{u}", f"surface_x_{u}", f"surface_y_{u}", "normal_x", "normal_y"]
    table = np.column_stack([tp.theta_deg, k * tp.x_mm, k * tp.y_mm, k * tp.surface_x_mm,
                             k * tp.surface_y_mm, tp.nx, tp.ny])
    np.savetxt(path, table, delimiter=",", header=",".join(names), comments="", fmt=CSV_FORMAT)
    return path


# ------------------------------------------------------------------------------ biarc fit


class Primitive(NamedTuple):
    """A line or a circular arc of the fitted path (mm). ``centre`` None: a line; ``ccw``: the arc
    turns counter-clockwise (G3) or clockwise (G2)."""

    start: np.ndarray  # (2,)
    end: np.ndarray  # (2,)
    centre: np.ndarray | None
    ccw: bool = False


def _arc(p, t, q, line_sag: float):
    """The arc leaving ``p`` along unit tangent ``t`` that ends at ``q`` (a line where it is
    straight to within ``line_sag``); None where no forward arc exists."""
    u = q - p
    uu = float(u @ u)
    if uu == 0.0:
        return None
    n = np.array([-t[1], t[0]])  # left normal
    den = 2.0 * float(n @ u)
    chord = math.sqrt(uu)
    if abs(den) <= 1e-14 * chord or (uu / abs(den)) > 1e12:
        return Primitive(p, q, None) if float(t @ u) > 0 else None
    r = uu / den  # signed: > 0 the centre lies to the left (counter-clockwise)
    half = 0.5 * chord / abs(r)
    sag = abs(r) * (1.0 - math.sqrt(max(0.0, 1.0 - min(half, 1.0) ** 2)))
    if float(t @ u) > 0 and sag < line_sag:
        return Primitive(p, q, None)
    return Primitive(p, q, p + r * n, r > 0)


def biarc(p1, t1, p2, t2, line_sag: float = 0.0):
    """Two tangent-continuous arcs from ``p1`` (unit tangent ``t1``) to ``p2`` (``t2``), the joint
    chosen with equal tangent lengths (Bolton 1975); None where they do not exist."""
    v = p2 - p1
    vt, vv, t12 = float(v @ (t1 + t2)), float(v @ v), float(t1 @ t2)
    denom = 2.0 * (1.0 - t12)
    if denom < 1e-12:
        vt2 = float(v @ t2)
        if vt2 <= 0:
            return None
        d = vv / (4.0 * vt2)
    else:
        d = (-vt + math.sqrt(vt * vt + denom * vv)) / denom
    if not d > 0:
        return None
    pm = 0.5 * (p1 + p2 + d * (t1 - t2))
    a = _arc(p1, t1, pm, line_sag)
    b = _arc(p2, -t2, pm, line_sag)  # built backwards from p2, then reversed
    if a is None or b is None:
        return None
    b = Primitive(pm, p2, b.centre, not b.ccw)
    return [a, b]


def _sweep(prim: Primitive) -> tuple[float, float, float]:
    """(radius, start angle, signed sweep) of an arc (rad; > 0 counter-clockwise)."""
    c = prim.centre
    a0 = math.atan2(prim.start[1] - c[1], prim.start[0] - c[0])
    a1 = math.atan2(prim.end[1] - c[1], prim.end[0] - c[0])
    r = float(np.hypot(*(prim.start - c)))
    if prim.ccw:
        return r, a0, (a1 - a0) % (2 * math.pi)
    return r, a0, -((a0 - a1) % (2 * math.pi))


def primitive_length(prim: Primitive) -> float:
    """Length of a line or arc (mm)."""
    if prim.centre is None:
        return float(np.hypot(*(prim.end - prim.start)))
    r, _, sweep = _sweep(prim)
    return r * abs(sweep)


def distance_to(prim: Primitive, pts: np.ndarray) -> np.ndarray:
    """Distance (mm) from points (K, 2) to a line segment or an arc (its radius taken at the start,
    as a controller does)."""
    if prim.centre is None:
        d = prim.end - prim.start
        dd = float(d @ d)
        s = np.clip(((pts - prim.start) @ d) / dd, 0.0, 1.0) if dd > 0 else np.zeros(len(pts))
        return np.hypot(*(pts - prim.start - s[:, None] * d).T)
    r, a0, sweep = _sweep(prim)
    rel = pts - prim.centre
    ang = np.arctan2(rel[:, 1], rel[:, 0])
    along = (ang - a0) % (2 * math.pi) if sweep > 0 else (a0 - ang) % (2 * math.pi)
    inside = along <= abs(sweep)
    ends = np.minimum(np.hypot(*(pts - prim.start).T), np.hypot(*(pts - prim.end).T))
    return np.where(inside, np.abs(np.hypot(rel[:, 0], rel[:, 1]) - r), ends)


class ArcFit(NamedTuple):
    """A closed path as lines and arcs; ``spans[i] = (a, b)``: primitives ``2i``, ``2i + 1`` (one
    biarc; a single primitive where the biarc degenerated) stand for points ``a .. b``."""

    primitives: list
    spans: list  # of (first point, last point, number of primitives)


def fit_biarcs(points: np.ndarray, tangents: np.ndarray, tolerance_mm: float) -> ArcFit:
    """Biarcs through a closed sequence of points (K, 2) with unit tangents (K, 2), every point
    within ``tolerance_mm`` of the arcs; greedy: each biarc reaches as far along the points as the
    tolerance allows, at most half the path (found by doubling then bisection; a candidate is kept
    only when every point it stands for lies within the tolerance and the arcs are no longer than
    those points' polyline, so that no arc loops between two points); a biarc straight to within
    :data:`LINE_SAG` of the tolerance is one line. The path ends where it starts."""
    pts = np.vstack([points, points[:1]])
    tans = np.vstack([tangents, tangents[:1]])
    seg = np.hypot(*np.diff(pts, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    last = len(pts) - 1
    line_sag = LINE_SAG * tolerance_mm

    def candidate(i, j):
        arcs = biarc(pts[i], tans[i], pts[j], tans[j], line_sag)
        if arcs is None:
            return None
        if all(a.centre is None for a in arcs):  # straight: one line
            arcs = [Primitive(pts[i], pts[j], None)]
        length = sum(primitive_length(a) for a in arcs)
        if length > (cum[j] - cum[i]) * (1 + 1e-3) + 10 * tolerance_mm:
            return None
        if j > i + 1:
            inner = pts[i + 1:j]
            dev = np.min([distance_to(a, inner) for a in arcs], axis=0)
            if float(dev.max()) > tolerance_mm:
                return None
        return arcs

    prims, spans, i, step = [], [], 0, 8
    longest = max(1, last // 2)  # a biarc spans at most half the path (a whole turn has none)
    while i < last:
        good_j, good = i + 1, candidate(i, i + 1)
        if good is None:  # two neighbouring samples: a line at worst
            good = [Primitive(pts[i], pts[i + 1], None)]
        bad_j = None
        end = min(i + longest, last)
        j = min(i + step, end)
        while j > good_j:  # doubling
            arcs = candidate(i, j)
            if arcs is None:
                bad_j = j
                break
            good_j, good = j, arcs
            if j == end:
                break
            j = min(i + 2 * (j - i), end)
        while bad_j is not None and bad_j - good_j > 1:  # bisection
            mid = (good_j + bad_j) // 2
            arcs = candidate(i, mid)
            if arcs is None:
                bad_j = mid
            else:
                good_j, good = mid, arcs
        prims.extend(good)
        spans.append((i, good_j, len(good)))
        step = max(2, good_j - i)
        i = good_j
    return ArcFit(prims, spans)


def fit_deviation(fit: ArcFit, points: np.ndarray) -> float:
    """Largest distance (mm) from the closed sequence of points to the primitives that stand for them."""
    pts = np.vstack([points, points[:1]])
    worst, k = 0.0, 0
    for a, b, count in fit.spans:
        group = fit.primitives[k:k + count]
        k += count
        sub = pts[a:b + 1]
        worst = max(worst, float(np.min([distance_to(p, sub) for p in group], axis=0).max()))
    return worst


# ------------------------------------------------------------------------------ G-code


def decimals(tolerance_mm: float, units: str) -> int:
    """Decimals the G-code writes: a resolution of at most a twentieth of the tolerance (4 to 6
    in mm, 5 to 7 in inches)."""
    tol = tolerance_mm * unit_scale(units)
    low = 4 if units == "mm" else 5
    return min(low + 2, max(low, math.ceil(-math.log10(tol / 20.0))))


def rounded(fit: ArcFit, dec: int, scale: float) -> ArcFit:
    """The primitives as a controller reads them after writing with ``dec`` decimals in units of
    ``scale`` per mm: each starts where the previous ended (rounded), its centre the rounded
    start plus the rounded I, J; back in mm."""
    q = lambda v: np.round(np.asarray(v) * scale, dec) / scale  # noqa: E731
    out, start = [], q(fit.primitives[0].start)
    for p in fit.primitives:
        end = q(p.end)
        centre = None if p.centre is None else start + q(p.centre - start)
        out.append(Primitive(start, end, centre, p.ccw))
        start = end
    return ArcFit(out, fit.spans)


class Program(NamedTuple):
    """A fitted path ready to write, and the figures result.json reports about it."""

    fit: ArcFit  # as written (rounded)
    max_deviation_mm: float  # largest distance of the exact tool path's samples from the written arcs
    max_radius_mismatch_mm: float  # largest | |end - centre| - |start - centre| | of an arc as written
    arcs: int
    lines: int
    decimals: int
    tolerance_mm: float
    order: np.ndarray  # the dense samples' indices in the order the contour runs them


def plan_program(tp: ToolPath, tolerance_mm: float, units: str = "mm") -> Program:
    """Order the path clockwise from its sample farthest from the cam centre (climb milling round
    the outside with a clockwise spindle, M3), fit biarcs within ``tolerance_mm`` less the rounding
    allowance, round as written, and measure the written arcs against the exact samples."""
    xy = np.column_stack([tp.x_mm, tp.y_mm])
    t = np.column_stack([tp.tx, tp.ty])
    start = int(np.argmax(np.hypot(tp.x_mm, tp.y_mm)))
    order = np.roll(np.arange(len(xy)), -start)
    area2 = signed_area2(xy[:, 0], xy[:, 1])
    if area2 > 0:  # counter-clockwise by increasing angle: run it backwards
        order = np.concatenate([order[:1], order[1:][::-1]])
        t = -t
    xy, t = xy[order], t[order]
    dec = decimals(tolerance_mm, units)
    scale = unit_scale(units)
    resolution_mm = 10.0**-dec / scale
    fit = rounded(fit_biarcs(xy, t, tolerance_mm - 4 * resolution_mm), dec, scale)
    dev = fit_deviation(fit, xy)
    mismatch = max((abs(float(np.hypot(*(p.end - p.centre)) - np.hypot(*(p.start - p.centre))))
                    for p in fit.primitives if p.centre is not None), default=0.0)
    arcs = sum(p.centre is not None for p in fit.primitives)
    return Program(fit, dev, mismatch, arcs, len(fit.primitives) - arcs, dec, float(tolerance_mm), order)


def gcode_lines(program: Program, tp: ToolPath, *, feed_mm_per_min: float, width_mm: float,
                cutter_diameter_mm: float, scene_name: str = "", units: str = "mm") -> list[str]:
    """The lines of cam.nc: one closed contour of the tool centre as G2/G3 arcs (I, J incremental from each
    arc's start) and G1 lines, in absolute coordinates (G90) of profile.csv's frame, XY plane (G17),
    no cutter compensation (G40: the path is the centre). The top face of the cam is Z0; the tool
    comes down outside the cam, :data:`APPROACH_MM` out along the path's normal at the start, feeds
    in along that normal, runs the contour at full depth (Z = -width) and leaves the same way.
    Spindle and coolant are left to the operator (no M3/M8)."""
    k, dec = unit_scale(units), program.decimals
    f = lambda v: f"{v * k:.{dec}f}".replace(f"-{0:.{dec}f}", f"{0:.{dec}f}")  # noqa: E731
    unit_word, unit_name = ("G21", "mm") if units == "mm" else ("G20", "inch")
    first = program.fit.primitives[0].start
    i0 = program.order[0]
    normal = np.array([tp.nx[i0], tp.ny[i0]])
    approach = first + APPROACH_MM * normal
    feed = feed_mm_per_min * k
    lines = [
        "%",
        f"(camjax cam.nc: {scene_name or 'scene'}; tool centre path of a D{cutter_diameter_mm * k:.4f} "
        f"{unit_name} cutter round the cam)",
        "(frame: profile.csv, cam centre X0 Y0, cam at angle 0; top face Z0)",
        f"({program.arcs} arcs, {program.lines} lines; largest deviation from the exact path "
        f"{program.max_deviation_mm * k:.3g} {unit_name}, tolerance {program.tolerance_mm * k:.3g} "
        f"{unit_name})",
        "(G2 clockwise, G3 counter-clockwise; I J incremental from the arc start; start spindle first)",
        f"{unit_word} G90 G17 G40 G94",
        f"G0 Z{f(SAFE_Z_MM)}",
        f"G0 X{f(approach[0])} Y{f(approach[1])}",
        f"G1 Z{f(-width_mm)} F{feed:.{max(1, dec - 3)}f}",
        f"G1 X{f(first[0])} Y{f(first[1])}",
    ]
    for p in program.fit.primitives:
        if p.centre is None:
            lines.append(f"G1 X{f(p.end[0])} Y{f(p.end[1])}")
        else:
            ij = p.centre - p.start
            lines.append(f"{'G3' if p.ccw else 'G2'} X{f(p.end[0])} Y{f(p.end[1])} I{f(ij[0])} J{f(ij[1])}")
    lines += [f"G1 X{f(approach[0])} Y{f(approach[1])}", f"G0 Z{f(SAFE_Z_MM)}", "M30", "%"]
    return lines


def program_blocks(lines: list[str]) -> int:
    """Blocks of a G-code program: its lines that are neither comments nor the % tape marks."""
    return sum(1 for line in lines if line != "%" and not line.startswith("("))


def write_gcode(path: Path, lines: list[str]) -> Path:
    """cam.nc from :func:`gcode_lines` (newline-terminated lines)."""
    Path(path).write_text("\n".join(lines) + "\n")
    return path
