"""Benchmark 5: cost of objective + gradient vs objective alone; jax.grad vs central differences.

Two functions of the design, both in float64 on the default N = 360 grid (alpha = gamma = 1):

* ``objective``: F with the true max over angles (what reports show);
* ``lagrangian``: the augmented Lagrangian the gradient solver differentiates
  (:func:`camjax.solvers.gradient.augmented_lagrangian`, with non-zero multipliers so that every
  term is active).

Timings: one design (dispatch-bound: what one solver step costs) and a population of designs
(``vmap``; throughput). Agreement: ``jax.grad`` vs the central difference
(f(x + h) - f(x - h)) / 2h with h = 1e-6 (relative to the variable's scale), at random designs of
the box, as the largest relative difference over designs and components.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks import fitness as fz
from benchmarks.harness import time_jit
from camjax.family import weights_of
from camjax.followers.flat import problem as P
from camjax.solvers import box, gradient

FD_STEP = 1e-6


def _functions(problem, weights):
    """name -> f(design) -> scalar (closures over the problem's arrays, passed as arguments)."""
    lam = jax.tree.map(lambda g: jnp.full_like(g, 1e-3), P.constraints(problem, box.midpoint(problem)))

    def objective(prob, w, d):
        return P.objective(prob, w, d)

    def lagrangian(prob, w, d):
        u = box.to_unit(prob, d)
        return gradient.augmented_lagrangian(u, prob, w, lam, gradient.DEFAULT_SETTINGS.penalty)[0]

    return {"objective": objective, "lagrangian": lagrangian}


def _grad_fn(f):
    return jax.value_and_grad(f, argnums=2)


def central_difference(f, problem, weights, design, step: float) -> np.ndarray:
    """Central-difference gradient (d/dR_b, d/dL) of f at one design, float64."""
    fj = jax.jit(f)
    out = []
    for i in range(2):
        x = np.array([float(design.base_radius_mm), float(design.face_width_mm)])
        h = step * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        fp, fm = (
            fj(problem, weights, P.Design(*map(jnp.asarray, xp))),
            fj(problem, weights, P.Design(*map(jnp.asarray, xm))),
        )
        out.append((float(fp) - float(fm)) / (2 * h))
    return np.array(out)


def agreement(f, problem, weights, designs: P.Design) -> dict:
    """Largest relative difference between jax.grad and central differences over designs."""
    g = jax.jit(jax.grad(f, argnums=2))
    worst, worst_abs = 0.0, 0.0
    count = designs.base_radius_mm.shape[0]
    for k in range(count):
        d = jax.tree.map(lambda x, k=k: x[k], designs)
        ad = np.array([float(v) for v in g(problem, weights, d)])
        fd = central_difference(f, problem, weights, d, FD_STEP)
        err = np.abs(ad - fd)
        worst_abs = max(worst_abs, float(err.max()))
        worst = max(worst, float(np.max(err / np.maximum(np.abs(fd), 1e-8))))
    return {"designs": count, "fd_step_rel": FD_STEP, "max_rel_diff": worst, "max_abs_diff": worst_abs}


def run(scene, quick: bool) -> dict:
    """Benchmark 5."""
    problem = P.problem_from_scene(scene, extrema="grid")
    weights = weights_of(1.0, 1.0)
    one = P.Design(jnp.asarray(30.0), jnp.asarray(20.0))
    population = 10**3 if quick else 10**4
    designs = fz.random_designs(problem, population)
    fd_designs = fz.random_designs(problem, 8 if quick else 32, seed=1)
    # keep FD points on the smooth, feasible side (rho > 0 everywhere): R_b above the curvature need
    fd_designs = fd_designs._replace(
        base_radius_mm=jnp.maximum(fd_designs.base_radius_mm, P.required_base_radius(problem) + 0.5)
    )
    out = {}
    for name, f in _functions(problem, weights).items():
        t_f, _ = time_jit(f, problem, weights, one, repeats=20)
        t_g, _ = time_jit(_grad_fn(f), problem, weights, one, repeats=20)
        vf = jax.vmap(f, in_axes=(None, None, 0))
        vg = jax.vmap(_grad_fn(f), in_axes=(None, None, 0))
        t_vf, _ = time_jit(vf, problem, weights, designs, repeats=5)
        t_vg, _ = time_jit(vg, problem, weights, designs, repeats=5)
        out[name] = {
            "single_value_s": t_f.median_s,
            "single_value_and_grad_s": t_g.median_s,
            "single_ratio": t_g.median_s / t_f.median_s,
            "population": population,
            "population_value_s": t_vf.median_s,
            "population_value_and_grad_s": t_vg.median_s,
            "population_ratio": t_vg.median_s / t_vf.median_s,
            "compile_value_s": t_f.compile_s,
            "compile_value_and_grad_s": t_g.compile_s,
            "fd_agreement": agreement(f, problem, weights, fd_designs),
        }
    out["max_fd_rel_diff"] = max(out[k]["fd_agreement"]["max_rel_diff"] for k in ("objective", "lagrangian"))
    out["grad_cost_ratio"] = out["objective"]["population_ratio"]
    return out
