"""Benchmark 1: pointwise design (the source's method), 360 per-angle problems, reference case.

camjax: :func:`camjax.solvers.gradient.solve_pointwise` (one jitted call, ``vmap`` over the
angles). SciPy: SLSQP looping over the angles from the box centre (``ftol`` 1e-12, analytic
gradients). Both are checked against the closed-form per-angle optimum
(:func:`camjax.followers.flat.problem.pointwise_optimum`) and against each other.
"""

from __future__ import annotations

import numpy as np

from benchmarks import baselines
from benchmarks.harness import compile_for, profile_thunks, time_jit, time_python
from camjax.family import weights_of
from camjax.followers.flat import optimum
from camjax.followers.flat import problem as P
from camjax.solvers import gradient


def run(scene, quick: bool) -> dict:
    """Benchmark 1 (alpha = gamma = 1, N = 360, float64)."""
    problem = P.problem_from_scene(scene, extrema="grid")
    weights = weights_of(1.0, 1.0)
    loop = baselines.pointwise_slsqp(problem, 1.0, 1.0)
    # Interleave the two (rounds of: camjax median of 10 calls, one SciPy loop) so that a change
    # of load on a shared machine hits both sides of the ratio alike; speedup = ratio of medians.
    jax_s, scipy_s = [], []
    compile_s = None
    for _ in range(1 if quick else 3):
        t_jax, res = time_jit(gradient.minimize_pointwise, problem, weights, repeats=5 if quick else 10)
        t_sp, x_sp = time_python(loop.solve, repeats=1, warmup=0)
        compile_s = t_jax.compile_s if compile_s is None else compile_s
        jax_s.append(t_jax.median_s)
        scipy_s.append(t_sp.median_s)
    t_jax = t_jax._replace(median_s=float(np.median(jax_s)), compile_s=compile_s)
    t_sp = t_sp._replace(median_s=float(np.median(scipy_s)))
    exact = optimum.pointwise_optimum(problem, weights)
    r_jax, l_jax = np.asarray(res.design.base_radius_mm), np.asarray(res.design.face_width_mm)
    r_ex, l_ex = np.asarray(exact.base_radius_mm), np.asarray(exact.face_width_mm)
    return {
        "angles": int(r_jax.size),
        "camjax_s": t_jax.median_s,
        "camjax_compile_s": t_jax.compile_s,
        "scipy_s": t_sp.median_s,
        "scipy_per_angle_s": t_sp.median_s / r_jax.size,
        "scipy_source": loop.source,
        "rounds_camjax_s": jax_s,
        "rounds_scipy_s": scipy_s,
        "speedup": t_sp.median_s / t_jax.median_s,
        "max_abs_diff_base_radius_mm": float(np.max(np.abs(r_jax - x_sp[:, 0]))),
        "max_abs_diff_face_width_mm": float(np.max(np.abs(l_jax - x_sp[:, 1]))),
        "camjax_vs_closed_form_mm": float(max(np.max(np.abs(r_jax - r_ex)), np.max(np.abs(l_jax - l_ex)))),
        "scipy_vs_closed_form_mm": float(
            max(np.max(np.abs(x_sp[:, 0] - r_ex)), np.max(np.abs(x_sp[:, 1] - l_ex)))
        ),
        "camjax_max_iterations": int(np.max(np.asarray(res.iterations))),
        "camjax_median_iterations": float(np.median(np.asarray(res.iterations))),
        "camjax_s_per_iteration": t_jax.median_s / max(int(np.max(np.asarray(res.iterations))), 1),
        "camjax_all_converged": bool(np.all(np.asarray(res.converged))),
        "camjax_iterations_histogram": np.histogram(
            np.asarray(res.iterations), bins=[0, 10, 25, 50, 100, 200, 300, 400, 10**6]
        )[0].tolist(),
        "camjax_thunks": profile_thunks(compile_for(gradient.minimize_pointwise, problem, weights), problem,
                                        weights, calls=2),
        "design_base_radius_mm": float(np.max(r_jax)),
        "design_face_width_mm": float(np.max(l_jax)),
    }
