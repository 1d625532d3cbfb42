"""A scene's [design] section solved: the one dispatch behind every follower family's design.

Both follower bases (:mod:`camjax.followers._translating`, :mod:`camjax.followers._rocking`) call
:func:`design_block`; it reaches the solvers through the registry (:func:`camjax.solvers.base.solve`),
the robust design through :mod:`camjax.robust.design`, and a conjugate pair's span or arm angle
through :mod:`camjax.followers._closure_design`.
"""

from __future__ import annotations

from typing import Any

from camjax.errors import SceneError


def design_block(scene, problem) -> tuple[dict, Any]:
    """result.json's design block of the scene's [design] for its ``problem``
    (:func:`camjax.solvers.base.problem_from_scene`), and the problem the design is judged on: a
    plain design, solved through the solver registry (:func:`camjax.solvers.base.solve` with the
    section's alpha, gamma, mode, solver and seed; the solution's JSON with its certificate,
    :func:`camjax.solvers.certificate.solution_json`), a robust one (``[design] robust``:
    :func:`camjax.robust.design.design_json`, the nominal and robust optima side by side) or a
    conjugate pair's yoke span or second arm angle set or chosen in [design]
    (:func:`camjax.followers._closure_design.solve_with_dimension`, whose problem carries the value)."""
    from camjax.followers._closure_design import free_dimension, solve_with_dimension

    d = scene.design
    free = free_dimension(d)
    if d.robust is not None:
        if free is not None:
            raise SceneError(f"design.{free[0]}", list(free[1:]), "cannot be set in a robust design (its "
                             "samples hold the [follower]'s)", "the value in [follower] only")
        from camjax.robust.design import design_json

        return design_json(scene, problem), problem
    if free is not None:
        return solve_with_dimension(scene, problem, free)
    from camjax.solvers.base import solve
    from camjax.solvers.certificate import solution_json

    return solution_json(problem, solve(problem, (d.alpha, d.gamma), mode=d.mode, solver=d.solver,
                                        seed=d.seed)), problem

