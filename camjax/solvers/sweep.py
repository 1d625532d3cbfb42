"""Many weightings: ``camjax sweep``'s chunked batch solve, its Pareto analysis and plot.

:func:`sweep` takes every (alpha, gamma) pair of two lists and solves them with
:func:`camjax.solvers.base.solve_batch` in fixed-size chunks (one compiled search and judgement, reused; a
progress bar when there is more than one), then marks the non-dominated designs in (size, peak
stress). :func:`plot_pareto` draws cam size against peak contact stress. :func:`solve` (one
weighting given as alpha, gamma) and :func:`solve_batch` are kept here for the callers that
import them from this module; both are :mod:`camjax.solvers.base`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import jax
import numpy as np

from camjax import runtime
from camjax.family import weights_of
from camjax.solvers.base import (
    SEARCH_CHUNK,
    Settings,
    Solution,
    compiled_batch,
    family_of,
    solve_batch,
    weighting_keys,
)
from camjax.solvers.base import solve as solve_weights
from camjax.solvers.registry import DEFAULT_SOLVER, MODES, SOLVERS, check_choice, check_weights

__all__ = ["DEFAULT_CHUNK", "MODES", "SOLVERS", "SweepResult", "default_chunk", "pareto_mask", "plot_pareto",
           "solve", "solve_batch", "sweep", "weight_grid"]

DEFAULT_CHUNK = 128  # weightings per compiled call of a sweep on an accelerator


def default_chunk() -> int:
    """A sweep's weightings per compiled call: the search's own chunk on the CPU
    (:data:`~camjax.solvers.base.SEARCH_CHUNK`, which a larger batch is searched in anyway), else
    :data:`DEFAULT_CHUNK`. Every chunk is padded to this size, so sweeps of any size run one
    compiled program: measured on the built-in scenes (newton, gradient, GA and hybrid), a
    weighting's design is the same to the bit whether its chunk holds 6 weightings or 10, or 121
    in one call."""
    return SEARCH_CHUNK if jax.default_backend() == "cpu" else DEFAULT_CHUNK


def _settings(ga_settings=None, gradient_settings=None) -> Settings:
    return Settings.of_solvers(ga=ga_settings, gradient=gradient_settings)


def solve(problem, alpha: float = 1.0, gamma: float = 1.0, *, mode: str = "global", solver: str = DEFAULT_SOLVER,
          seed: int = 0, ga_settings=None, gradient_settings=None) -> Solution:
    """:func:`camjax.solvers.base.solve` of the weighting (alpha, gamma): one :class:`Solution`."""
    return solve_weights(problem, (alpha, gamma), mode=mode, solver=solver, seed=seed,
                         settings=_settings(ga_settings, gradient_settings))


# --------------------------------------------------------------------------------- sweep


@dataclass(frozen=True)
class SweepResult:
    """Every weighting of a sweep as pareto.json rows, its Pareto mask and (when solved here) Solutions."""

    mode: str
    solver: str
    rows: list[dict[str, Any]] = field(repr=False)  # one record per weighting, without "pareto"
    pareto: np.ndarray = field(repr=False)  # (w,) bool: non-dominated in (size, peak stress)
    results: Solution | None = field(default=None, repr=False)  # batched, leading axis w

    def records(self) -> list[dict[str, Any]]:
        """One plain dict per weighting (the rows of pareto.json)."""
        return [{**row, "pareto": bool(on)} for row, on in zip(self.rows, self.pareto, strict=True)]

    def to_json(self) -> dict[str, Any]:
        """{"mode", "solver", "records": [...]} (strict JSON)."""
        return {"mode": self.mode, "solver": self.solver, "records": self.records()}

    def column(self, key: str, dtype=float) -> np.ndarray:
        """One key of every record as an array, shape (w,)."""
        return np.array([row[key] for row in self.rows], dtype)


def records_of(problem, results: Solution) -> list[dict[str, Any]]:
    """pareto.json rows (without "pareto") of a batched :class:`Solution` (NumPy leaves)."""
    return [results[i].record(problem) for i in range(results.batch_size)]


def weight_grid(alphas, gammas) -> tuple[np.ndarray, np.ndarray]:
    """Every (alpha, gamma) pair of two lists, alpha-major: shapes (len(a) * len(g),)."""
    a, g = np.meshgrid(np.asarray(alphas, float), np.asarray(gammas, float), indexing="ij")
    return a.ravel(), g.ravel()


def pareto_mask(size, stress, feasible=None) -> np.ndarray:
    """Non-dominated points when both size and stress are minimized (NumPy; not traceable).

    A point is dominated when another (feasible) point is no worse in both and better in one.
    Infeasible points are never on the front. Duplicates are all kept.
    """
    size, stress = np.asarray(size, float), np.asarray(stress, float)
    ok = np.ones(size.shape, bool) if feasible is None else np.asarray(feasible, bool)
    le = (size[:, None] <= size[None, :]) & (stress[:, None] <= stress[None, :])
    lt = (size[:, None] < size[None, :]) | (stress[:, None] < stress[None, :])
    dominated = np.any(le & lt & ok[:, None], axis=0)
    return ok & ~dominated


def sweep(problem, alphas, gammas, *, mode: str = "global", solver: str = DEFAULT_SOLVER,
          seed: int = 0, chunk_size: int | None = None, progress: bool | None = None,
          ga_settings=None, gradient_settings=None) -> SweepResult:
    """Solve every (alpha, gamma) pair of two lists, ``chunk_size`` weightings per compiled call
    (None: :func:`default_chunk`).

    Every chunk has the same shape (a sweep smaller than a chunk, and the last chunk, are padded by
    repeating the final weighting), so the program compiles once for sweeps of any size; a tqdm
    progress bar (stderr) runs over the chunks when there is more than one (``progress`` forces it
    on or off). Weighting i uses the key fold_in(key(seed), i),
    so results do not depend on the chunk size, but for a chunk of one weighting: that is a design's
    own program (:func:`~camjax.solvers.base.solve_batch` traces it without vmap), whose last bits
    may differ from a batch's. Python (chunks, NumPy results): not traceable;
    :func:`solve_batch` is the traceable core.
    """
    from tqdm.auto import tqdm

    check_choice("mode", mode, MODES)
    check_choice("solver", solver, SOLVERS)
    a, g = weight_grid(alphas, gammas)
    if a.size == 0:
        raise ValueError("alpha, gamma: the sweep needs at least one weighting")
    check_weights(a, g)
    settings = _settings(ga_settings, gradient_settings)
    total = a.size
    # a single weighting is a design's own program (unbatched); more fill chunks of one shape
    chunk = 1 if total == 1 else max(1, int(default_chunk() if chunk_size is None else chunk_size))
    n_chunks = -(-total // chunk)
    dtype = jax.tree.leaves(family_of(problem).bounds(problem)[0])[0].dtype
    parts = []
    show = n_chunks > 1 if progress is None else progress
    for c in tqdm(range(n_chunks), desc=f"sweep ({solver}, {mode})", unit="chunk", disable=not show):
        lo, hi = c * chunk, min((c + 1) * chunk, total)
        idx = np.minimum(np.arange(lo, lo + chunk), hi - 1)  # pad by repeating the last weighting
        weights = weights_of(a[idx], g[idx], dtype)
        # weighting i's key is fold_in(key(seed), i) whatever its chunk (one program for every
        # chunk; a padded lane's key is its own index's, dropped with the lane)
        keys = weighting_keys(seed, chunk, lo)
        if runtime.program_cache_on():  # the command line: the chunk's saved programs, no tracing
            run = compiled_batch(problem, weights, keys, mode=mode, solver=solver, settings=settings)[0]
            parts.append((run(problem, weights, keys), hi - lo))
        else:
            parts.append((solve_batch(problem, weights, keys, mode, solver, settings), hi - lo))
        if c:  # the chunk before done (this one already dispatched): the bar counts finished chunks
            jax.block_until_ready(parts[-2][0])
    results = jax.tree.map(lambda *xs: np.concatenate(xs, axis=0),
                           *[jax.tree.map(lambda x, n=n: np.asarray(x)[:n], res) for res, n in parts])
    rows = records_of(problem, results)
    column = SweepResult(mode, solver, rows, np.zeros(len(rows), bool)).column
    mask = pareto_mask(column("size_mm"), column("stress_max_MPa"), column("feasible", bool))
    return SweepResult(mode, solver, rows, mask, results)


# ---------------------------------------------------------------------------------- plot


def _label_points(size, stress, front, max_labels: int, near: float = 0.025) -> list[tuple[int, int]]:
    """(index, number of other weightings it stands for) of the points to label.

    Points closer than ``near`` (fraction of each axis range) share one label, e.g. weightings
    with the same alpha/gamma ratio; points of the front are labelled first, then the others,
    up to about ``max_labels`` labels.
    """
    x = (size - size.min()) / max(np.ptp(size), 1e-12)
    y = (stress - stress.min()) / max(np.ptp(stress), 1e-12)
    order = [*np.flatnonzero(front), *np.flatnonzero(~front)]
    labels: list[list[int]] = []  # [index, count]
    for i in order:
        for lab in labels:
            if abs(x[i] - x[lab[0]]) < near and abs(y[i] - y[lab[0]]) < near:
                lab[1] += 1
                break
        else:
            if len(labels) < max_labels or front[i]:
                labels.append([int(i), 0])
    return [(i, k) for i, k in labels]


def place_labels(anchors_px, sizes_px, obstacles_px=(), bounds_px=None, gap_px: float = 7.0,
                 pad_px: float = 1.5) -> list[tuple[float, float] | None]:
    """Greedy, overlap-free placement of text boxes next to their anchor points (display pixels).

    Each label tries, in order, the places right, left, above, below and on the diagonals of its
    anchor at ``gap_px`` (then at twice that) and takes the first box that overlaps no placed box
    and no obstacle (e.g. marker boxes, points along a curve) and lies inside ``bounds_px``
    (x0, y0, x1, y1) when given; a label with no free place gets None (the caller leaves it out
    and says so). Returns, per label, the lower-left corner of its box or None.
    """
    placed = [np.asarray(b, float) for b in obstacles_px]  # (x0, y0, x1, y1)
    out: list[tuple[float, float] | None] = []
    for (x, y), (w, h) in zip(anchors_px, sizes_px, strict=True):
        spot = None
        for g in (gap_px, 2.0 * gap_px):
            candidates = [(x + g, y - h / 2), (x - g - w, y - h / 2), (x - w / 2, y + g),
                          (x - w / 2, y - g - h), (x + g, y + g / 2), (x - g - w, y + g / 2),
                          (x + g, y - g / 2 - h), (x - g - w, y - g / 2 - h)]
            for x0, y0 in candidates:
                box = np.array([x0 - pad_px, y0 - pad_px, x0 + w + pad_px, y0 + h + pad_px])
                if bounds_px is not None and not (bounds_px[0] <= box[0] and box[2] <= bounds_px[2]
                                                  and bounds_px[1] <= box[1] and box[3] <= bounds_px[3]):
                    continue
                if all(box[2] <= o[0] or box[0] >= o[2] or box[3] <= o[1] or box[1] >= o[3]
                       for o in placed):
                    placed.append(box)
                    spot = (float(x0), float(y0))
                    break
            if spot is not None:
                break
        out.append(spot)
    return out


def plot_pareto(sweep_result: SweepResult, path=None, *, max_labels: int = 24, title: str | None = None,
                units: str = "mm"):
    """Cam size (R_b + L, mm) against peak contact stress (MPa), one point per weighting (``units``
    "in": in inches and psi, :mod:`camjax.units`).

    Points are coloured by log10(alpha / gamma) and labelled "alpha/gamma" (every point of the
    non-dominated front first, others thinned to about ``max_labels`` labels; "(+n)" counts the
    other weightings that land on the same point); labels are placed so that none overlaps
    another label or a marker, and one that finds no free place is left out (the count is
    printed in the figure). The front is drawn as a line; infeasible weightings are hollow red.
    Returns the matplotlib Figure; saves it when ``path``.
    """
    from matplotlib.figure import Figure  # no pyplot: no global state, any backend
    from matplotlib.lines import Line2D

    r = sweep_result
    from camjax.units import MPA_PER_PSI, length_scale, relabel

    size = r.column("size_mm") / length_scale(units)
    stress = r.column("stress_max_MPa") / (MPA_PER_PSI if units == "in" else 1.0)
    alpha, gamma = r.column("alpha"), r.column("gamma")
    feasible, front = r.column("feasible", bool), np.asarray(sweep_result.pareto, bool)
    with np.errstate(divide="ignore"):
        ratio = np.log10(np.where(gamma > 0, alpha / np.where(gamma > 0, gamma, 1.0), np.inf))
    finite = np.isfinite(ratio)
    span = (ratio[finite].min(), ratio[finite].max()) if finite.any() else (0.0, 1.0)
    colour = np.clip(np.where(finite, ratio, span[1]), *span) if span[0] < span[1] else np.zeros_like(ratio)

    fig = Figure(figsize=(8.0, 5.8), dpi=100)
    left = 0.11 if units == "in" else 0.09  # room for psi's five-digit ticks
    ax = fig.add_axes((left, 0.1, 0.83 - left, 0.8))
    cax = fig.add_axes((0.85, 0.1, 0.02, 0.8))
    sc = ax.scatter(size[feasible], stress[feasible], c=colour[feasible], cmap="viridis", s=28,
                    vmin=span[0], vmax=max(span[1], span[0] + 1e-9), zorder=3)
    if (~feasible).any():
        ax.scatter(size[~feasible], stress[~feasible], facecolors="none", edgecolors="tab:red", s=34,
                   zorder=3)
    if front.any():
        order = np.argsort(size[front])
        ax.plot(size[front][order], stress[front][order], "-", color="black", lw=1.2, zorder=2)
    fig.colorbar(sc, cax=cax, label="log10(α / γ)   (low: stress-weighted, high: size-weighted)")
    ax.margins(0.08)
    ax.autoscale_view()
    # labels: measured in display pixels against the final limits, placed without overlap
    chosen = _label_points(size, stress, front, max_labels)
    texts = [f"{alpha[i]:.3g}/{gamma[i]:.3g}" + (f" (+{extra})" if extra else "") for i, extra in chosen]
    font_px = 7 * fig.dpi / 72
    sizes = [(0.6 * font_px * len(t), 1.2 * font_px) for t in texts]  # DejaVu Sans ~0.6 em/char
    xy = ax.transData.transform(np.column_stack([size, stress]))
    marker = 4.0  # half size of a marker box, pixels
    obstacles = [(x - marker, y - marker, x + marker, y + marker) for x, y in xy]
    if front.any():  # keep labels off the front line: its points every ~3 px are obstacles too
        line = xy[front][np.argsort(size[front])]
        for p, q in zip(line[:-1], line[1:], strict=True):
            for f in np.linspace(0.0, 1.0, int(np.hypot(*(q - p)) // 3) + 2):
                c = p + f * (q - p)
                obstacles.append((c[0] - 1.0, c[1] - 1.0, c[0] + 1.0, c[1] + 1.0))
    spots = place_labels([xy[i] for i, _ in chosen], sizes, obstacles, ax.bbox.extents)
    left_out = 0
    for text, spot in zip(texts, spots, strict=True):
        if spot is None:
            left_out += 1
            continue
        ax.annotate(text, ax.transData.inverted().transform(spot), fontsize=7, color="0.25",
                    va="bottom", ha="left", annotation_clip=False)
    ax.set_xlabel("cam size R_b + L (mm)")
    ax.set_ylabel("peak contact stress (MPa)")
    ax.set_title(title or f"Size vs stress over {size.size} weightings ({r.solver}, {r.mode})", fontsize=10)
    ax.grid(True, alpha=0.3)
    handles = [Line2D([], [], marker="o", linestyle="", color="C2", label="feasible weighting (colour: α/γ)"),
               Line2D([], [], marker="o", linestyle="", markerfacecolor="none", markeredgecolor="tab:red",
                      label="infeasible weighting"),
               Line2D([], [], color="black", label="non-dominated front"),
               Line2D([], [], linestyle="", label="label α/γ: weights of size and stress"),
               Line2D([], [], linestyle="", label="(+n): n more weightings at that point")]
    if left_out:
        handles.append(Line2D([], [], linestyle="", label=f"{left_out} label(s) left out: no free place"))
    ax.legend(handles=handles, loc="upper right", fontsize=7, handlelength=1.2)
    relabel(fig, units)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
