"""One weighting or many: the batched solve behind ``camjax design`` and ``camjax sweep``.

:func:`solve_batch` solves a batch of weightings (alpha, gamma) with one solver in one compiled
program and condenses every raw result into a :class:`DesignResult` (the reported design, its
objective, peak stress, feasibility and, in pointwise mode, the per-angle designs).
:func:`solve` is a batch of one; :func:`sweep` takes every (alpha, gamma) pair of two lists, in
fixed-size chunks (one compiled program, reused; a progress bar when there is more than one) and
adds the Pareto analysis. :func:`plot_pareto` draws cam size against peak contact stress.

Pointwise designs. Per angle the problem is solved separately; the design is the largest R_b and
the largest L over the angles (SPEC 5), reported with the angles where they occur (the first such
angle on ties, e.g. when many angles sit on a bound), and judged as a whole-cam design: its
objective, peak stress and feasibility are those of that one (R_b, L) over every angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from camjax import problem as P
from camjax.problem import Design, Problem, Violation, Weights
from camjax.solvers import ga, gradient

SOLVERS = ("gradient", "ga", "hybrid")
MODES = gradient.MODES
DEFAULT_CHUNK = 128  # weightings per compiled call of a sweep


@partial(jax.tree_util.register_dataclass,
         data_fields=["alpha", "gamma", "base_radius_mm", "face_width_mm", "objective", "feasible",
                      "iterations", "converged", "stress_max_MPa", "stress_max_deg", "rho_min_mm",
                      "violation", "base_radius_deg", "face_width_deg", "pointwise", "theta_deg"],
         meta_fields=["mode", "solver"])
@dataclass(frozen=True)
class DesignResult:
    """A solved design (scalars), or a batch of them (leading axis w on every array).

    ``base_radius_deg``, ``face_width_deg``, ``pointwise`` and ``theta_deg`` are None in global
    mode; ``converged`` is None for the GA (it runs a fixed number of generations).
    """

    mode: str
    solver: str
    alpha: jax.Array
    gamma: jax.Array
    base_radius_mm: jax.Array  # the design's R_b, mm
    face_width_mm: jax.Array  # the design's L, mm
    objective: jax.Array  # F of the design (true max over angles)
    feasible: jax.Array  # bool
    iterations: jax.Array  # int: gradient steps, GA generations, or their sum (hybrid)
    converged: jax.Array | None  # bool: the gradient stopping rule was met (every angle)
    stress_max_MPa: jax.Array  # peak contact stress of the design
    stress_max_deg: jax.Array  # where it occurs
    rho_min_mm: jax.Array  # smallest radius of curvature of the design
    violation: Violation  # worst violation per constraint, mm / MPa
    base_radius_deg: jax.Array | None = None  # pointwise: angle of the largest R_b
    face_width_deg: jax.Array | None = None  # pointwise: angle of the largest L
    pointwise: Design | None = None  # pointwise: per-angle optimum, (n,) each
    theta_deg: jax.Array | None = None  # pointwise: the angles, (n,)

    def __getitem__(self, i) -> DesignResult:
        """Entry i of a batch."""
        return jax.tree.map(lambda x: x[i], self)

    @property
    def batch_size(self) -> int | None:
        """w for a batch, None for a single result."""
        return None if np.ndim(self.objective) == 0 else int(np.shape(self.objective)[0])

    def violated(self, problem: Problem) -> list[str]:
        """Names of the violated constraints (single result)."""
        return P.violated_constraints(problem, self.violation)

    def to_json(self, problem: Problem) -> dict[str, Any]:
        """Plain dict (floats, bools, lists) of a single result; strict JSON (no NaN/inf)."""
        out = {
            "mode": self.mode,
            "solver": self.solver,
            "alpha": _f(self.alpha),
            "gamma": _f(self.gamma),
            "base_radius_mm": _f(self.base_radius_mm),
            "face_width_mm": _f(self.face_width_mm),
            "size_mm": _f(self.base_radius_mm + self.face_width_mm),
            "objective": _f(self.objective),
            "feasible": bool(self.feasible),
            "violated": self.violated(problem),
            "constraint_violation": {"curvature_mm": _f(self.violation.curvature),
                                     "stress_MPa": _f(self.violation.stress),
                                     "face_width_mm": _f(self.violation.face_width),
                                     "bounds_mm": _f(self.violation.bounds)},
            "iterations": int(self.iterations),
            "converged": None if self.converged is None else bool(self.converged),
            "stress_max_MPa": _f(self.stress_max_MPa),
            "stress_max_deg": _f(self.stress_max_deg),
            "rho_min_mm": _f(self.rho_min_mm),
            "sigma_max_MPa": _f(problem.sigma_max_MPa),
            "base_radius_bounds_mm": [_f(problem.lower.base_radius_mm), _f(problem.upper.base_radius_mm)],
            "face_width_bounds_mm": [_f(problem.lower.face_width_mm), _f(problem.upper.face_width_mm)],
        }
        if self.mode == "pointwise":
            out["base_radius_deg"] = _f(self.base_radius_deg)
            out["face_width_deg"] = _f(self.face_width_deg)
            out["pointwise"] = {
                "theta_deg": np.asarray(self.theta_deg, float).tolist(),
                "base_radius_mm": np.asarray(self.pointwise.base_radius_mm, float).tolist(),
                "face_width_mm": np.asarray(self.pointwise.face_width_mm, float).tolist(),
            }
        return out


def _f(x) -> float:
    v = float(np.asarray(x))
    if not math.isfinite(v):
        raise ValueError(f"non-finite value {v} in a design result")
    return v


# ------------------------------------------------------------------------------ condense


def _summary(problem: Problem, weights: Weights, design: Design, iterations, converged,
             mode: str, solver: str, per_angle: Design | None) -> DesignResult:
    """Judge one design on the whole grid; traceable."""
    extra = {}
    if per_angle is not None:
        i = jnp.argmax(per_angle.base_radius_mm)
        j = jnp.argmax(per_angle.face_width_mm)
        design = Design(per_angle.base_radius_mm[i], per_angle.face_width_mm[j])
        extra = dict(base_radius_deg=problem.theta_deg[i], face_width_deg=problem.theta_deg[j],
                     pointwise=per_angle, theta_deg=problem.theta_deg)
    ev = P.evaluate(problem, weights, design)
    return DesignResult(mode, solver, weights.alpha, weights.gamma, design.base_radius_mm,
                        design.face_width_mm, ev.objective, ev.feasible, iterations, converged,
                        ev.stress_max_MPa, ev.stress_max_deg, ev.rho_min_mm, ev.violation, **extra)


def _solve_one(problem: Problem, weights: Weights, key: jax.Array, mode: str, solver: str,
               ga_settings: ga.GASettings, gradient_settings: gradient.GradientSettings) -> DesignResult:
    """One weighting, any solver and mode; traceable (vmapped over weightings by the caller)."""
    pointwise = mode == "pointwise"
    converged = None
    init = None
    iterations = jnp.asarray(0)
    if solver in ("ga", "hybrid"):
        run = ga.run_pointwise if pointwise else ga.run
        res = run(key, problem, weights, ga_settings)
        init, iterations = res.design, jnp.max(res.iterations)
    if solver in ("gradient", "hybrid"):
        run = gradient.minimize_pointwise if pointwise else gradient.minimize
        res = run(problem, weights, init, gradient_settings)
        iterations = iterations + jnp.max(res.iterations)
        converged = jnp.all(res.converged)
    per_angle = res.design if pointwise else None
    return _summary(problem, weights, res.design, iterations, converged, mode, solver, per_angle)


@partial(jax.jit, static_argnames=("mode", "solver", "ga_settings", "gradient_settings"))
def solve_batch(problem: Problem, weights: Weights, keys: jax.Array, mode: str = "global",
                solver: str = "gradient", ga_settings: ga.GASettings = ga.DEFAULT_SETTINGS,
                gradient_settings: gradient.GradientSettings = gradient.DEFAULT_SETTINGS) -> DesignResult:
    """Every weighting of a batch in one compiled program.

    Args:
      problem: the problem (grid arrays (n,)).
      weights: alpha, gamma of shape (w,).
      keys: (w,) PRNG keys (used by the GA and hybrid solvers), e.g. ``ga.weighting_keys``.
      mode: "global" or "pointwise".
      solver: "gradient", "ga" or "hybrid" (GA, then a gradient polish from its best design).
    Returns:
      a :class:`DesignResult` with leading axis w.
    """
    check_choice("mode", mode, MODES)
    check_choice("solver", solver, SOLVERS)
    one = partial(_solve_one, mode=mode, solver=solver, ga_settings=ga_settings,
                  gradient_settings=gradient_settings)
    return jax.vmap(one, in_axes=(None, 0, 0))(problem, weights, keys)


def check_choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    """Raise ValueError naming the option when ``value`` is not allowed."""
    if value not in allowed:
        raise ValueError(f"{name}: {value!r} is not allowed; use {', '.join(allowed)}")


def solve(problem: Problem, alpha: float = 1.0, gamma: float = 1.0, *, mode: str = "global",
          solver: str = "gradient", seed: int = 0, ga_settings: ga.GASettings = ga.DEFAULT_SETTINGS,
          gradient_settings: gradient.GradientSettings = gradient.DEFAULT_SETTINGS) -> DesignResult:
    """Solve one weighting (a batch of one); returns a single :class:`DesignResult`.

    A Python entry point (it checks the weights on concrete values); trace :func:`solve_batch`.
    """
    _check_weights([alpha], [gamma])
    dtype = problem.q_mm.dtype
    weights = P.weights_of([alpha], [gamma], dtype)
    res = solve_batch(problem, weights, ga.weighting_keys(seed, 1), mode, solver, ga_settings,
                      gradient_settings)
    return res[0]


def _check_weights(alphas, gammas) -> None:
    a, g = np.asarray(alphas, float), np.asarray(gammas, float)
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(g))):
        raise ValueError("alpha, gamma: weights must be finite")
    if np.any(a < 0) or np.any(g < 0):
        raise ValueError("alpha, gamma: weights must be >= 0")
    if np.any((a == 0) & (g == 0)):
        raise ValueError("alpha, gamma: a weighting with alpha = gamma = 0 has nothing to minimize")


# --------------------------------------------------------------------------------- sweep


@dataclass(frozen=True)
class SweepResult:
    """Every weighting of a sweep (a batched :class:`DesignResult`) and its Pareto analysis."""

    results: DesignResult  # leading axis w
    pareto: np.ndarray = field(repr=False)  # (w,) bool: non-dominated in (size, peak stress)

    def records(self) -> list[dict[str, Any]]:
        """One plain dict per weighting (the rows of pareto.json)."""
        r = self.results
        out = []
        for i in range(r.batch_size):
            out.append({
                "alpha": _f(r.alpha[i]), "gamma": _f(r.gamma[i]),
                "base_radius_mm": _f(r.base_radius_mm[i]), "face_width_mm": _f(r.face_width_mm[i]),
                "size_mm": _f(r.base_radius_mm[i] + r.face_width_mm[i]),
                "stress_max_MPa": _f(r.stress_max_MPa[i]), "stress_max_deg": _f(r.stress_max_deg[i]),
                "objective": _f(r.objective[i]), "feasible": bool(r.feasible[i]),
                "pareto": bool(self.pareto[i]),
            })
        return out

    def to_json(self) -> dict[str, Any]:
        """{"mode", "solver", "records": [...]} (strict JSON)."""
        return {"mode": self.results.mode, "solver": self.results.solver, "records": self.records()}


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


def sweep(problem: Problem, alphas, gammas, *, mode: str = "global", solver: str = "gradient",
          seed: int = 0, chunk_size: int = DEFAULT_CHUNK, progress: bool | None = None,
          ga_settings: ga.GASettings = ga.DEFAULT_SETTINGS,
          gradient_settings: gradient.GradientSettings = gradient.DEFAULT_SETTINGS) -> SweepResult:
    """Solve every (alpha, gamma) pair of two lists, ``chunk_size`` weightings per compiled call.

    Every chunk has the same shape (the last is padded by repeating its final weighting), so the
    program compiles once; a tqdm progress bar (stderr) runs over the chunks when there is more
    than one (``progress`` forces it on or off). Weighting i uses the key fold_in(key(seed), i),
    so results do not depend on the chunk size. Python (chunks, NumPy results): not traceable;
    :func:`solve_batch` is the traceable core.
    """
    from tqdm.auto import tqdm

    check_choice("mode", mode, MODES)
    check_choice("solver", solver, SOLVERS)
    a, g = weight_grid(alphas, gammas)
    if a.size == 0:
        raise ValueError("alpha, gamma: the sweep needs at least one weighting")
    _check_weights(a, g)
    total = a.size
    chunk = max(1, min(int(chunk_size), total))
    n_chunks = -(-total // chunk)
    dtype = problem.q_mm.dtype
    parts = []
    keys_all = ga.weighting_keys(seed, total)  # one key per weighting: independent of chunking
    show = n_chunks > 1 if progress is None else progress
    for c in tqdm(range(n_chunks), desc=f"sweep ({solver}, {mode})", unit="chunk", disable=not show):
        lo, hi = c * chunk, min((c + 1) * chunk, total)
        idx = np.minimum(np.arange(lo, lo + chunk), hi - 1)  # pad by repeating the last weighting
        weights = P.weights_of(a[idx], g[idx], dtype)
        res = solve_batch(problem, weights, keys_all[idx], mode, solver, ga_settings, gradient_settings)
        parts.append(jax.tree.map(lambda x, n=hi - lo: np.asarray(x)[:n], res))
    results = jax.tree.map(lambda *xs: np.concatenate(xs, axis=0), *parts)
    mask = pareto_mask(results.base_radius_mm + results.face_width_mm, results.stress_max_MPa,
                       results.feasible)
    return SweepResult(results, mask)


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


def plot_pareto(sweep_result: SweepResult, path=None, *, max_labels: int = 24, title: str | None = None):
    """Cam size (R_b + L, mm) against peak contact stress (MPa), one point per weighting.

    Points are coloured by log10(alpha / gamma) and labelled "alpha/gamma" (every point of the
    non-dominated front, others thinned to about ``max_labels`` labels); the front is drawn as a
    line; infeasible weightings are hollow. Returns the matplotlib Figure; saves it when ``path``.
    """
    from matplotlib.figure import Figure  # no pyplot: no global state, any backend

    r = sweep_result.results
    size = np.asarray(r.base_radius_mm + r.face_width_mm, float)
    stress = np.asarray(r.stress_max_MPa, float)
    alpha, gamma = np.asarray(r.alpha, float), np.asarray(r.gamma, float)
    feasible, front = np.asarray(r.feasible, bool), np.asarray(sweep_result.pareto, bool)
    with np.errstate(divide="ignore"):
        ratio = np.log10(np.where(gamma > 0, alpha / np.where(gamma > 0, gamma, 1.0), np.inf))
    finite = np.isfinite(ratio)
    span = (ratio[finite].min(), ratio[finite].max()) if finite.any() else (0.0, 1.0)
    colour = np.clip(np.where(finite, ratio, span[1]), *span) if span[0] < span[1] else np.zeros_like(ratio)

    fig = Figure(figsize=(7.5, 5.5), layout="constrained")
    ax = fig.subplots()
    sc = ax.scatter(size[feasible], stress[feasible], c=colour[feasible], cmap="viridis", s=28,
                    vmin=span[0], vmax=max(span[1], span[0] + 1e-9), zorder=3, label="feasible")
    if (~feasible).any():
        ax.scatter(size[~feasible], stress[~feasible], facecolors="none", edgecolors="tab:red", s=34,
                   zorder=3, label="infeasible")
    if front.any():
        order = np.argsort(size[front])
        ax.plot(size[front][order], stress[front][order], "-", color="black", lw=1.2, zorder=2,
                label="non-dominated front")
    fig.colorbar(sc, ax=ax, label="log10(alpha / gamma)")
    for i, extra in _label_points(size, stress, front, max_labels):
        more = f" (+{extra})" if extra else ""
        ax.annotate(f"{alpha[i]:.3g}/{gamma[i]:.3g}{more}", (size[i], stress[i]),
                    textcoords="offset points", xytext=(4, 3), fontsize=7, color="0.25")
    ax.set_xlabel("cam size R_b + L (mm)")
    ax.set_ylabel("peak contact stress (MPa)")
    ax.set_title(title or f"size vs stress over {size.size} weightings ({r.solver}, {r.mode}); "
                 "labels alpha/gamma", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
