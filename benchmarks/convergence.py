"""Gradient against hybrid solver on every built-in scene with a [design] section (and no designed
laws: those are co-designs) and on the oscillating roller with all four variables free:
objectives, their relative gap and the gradient solver's iterations per follower type. Writes
benchmarks/results/convergence.json.

    PYTHONPATH=$PWD CAMJAX_PROGRAM_CACHE=0 python3 -m benchmarks.convergence
"""

from __future__ import annotations

import json
import os
import pathlib
import time
from importlib import resources

import jax

jax.config.update("jax_enable_x64", True)

from camjax import load_scene  # noqa: E402
from camjax.scene import parse_scene  # noqa: E402
from camjax.solvers.base import DEFAULT_SETTINGS, problem_from_scene, solve  # noqa: E402

OUT = pathlib.Path(__file__).parent / "results" / "convergence.json"


def four_free_roller():
    text = resources.files("camjax.scenes").joinpath("oscillating-roller.toml").read_text()
    old = "pivot_distance_mm = [65.0, 110.0]\n"
    extra = "roller_radius_mm = [4.0, 12.0]\narm_length_mm = [40.0, 80.0]\n"
    return parse_scene(text.replace(old, old + extra))


def scenes():
    for path in sorted(resources.files("camjax.scenes").iterdir()):
        if path.name.endswith(".toml"):
            scene = load_scene(path.name[:-5])
            # a scene with designed laws is a co-design (camjax design), not a geometry problem
            if scene.design is not None and not scene.motion.designed:
                yield path.name[:-5], scene
    yield "oscillating-roller-4-free", four_free_roller()


def by_follower(rows):
    """The gradient solver's largest iteration count per follower type."""
    out = {}
    for row in rows:
        out[row["follower"]] = max(out.get(row["follower"], 0), row["gradient"]["iterations"])
    return dict(sorted(out.items()))


def main():
    load_start = os.getloadavg()
    rows = []
    for name, scene in scenes():
        problem = problem_from_scene(scene)
        weights = (scene.design.alpha, scene.design.gamma)
        row = {"scene": name, "follower": scene.follower.type}
        for solver in ("gradient", "hybrid"):
            t0 = time.perf_counter()
            sol = solve(problem, weights, solver=solver, seed=0, settings=DEFAULT_SETTINGS)
            row[solver] = {"objective": float(sol.objective), "iterations": int(sol.iterations),
                           "status": sol.status_name, "feasible": bool(sol.feasible),
                           "seconds": time.perf_counter() - t0}
        h = row["hybrid"]["objective"]
        row["relative_gap"] = (row["gradient"]["objective"] - h) / abs(h)
        print(json.dumps(row), flush=True)
        rows.append(row)
    report = {"goal_relative_gap": 1e-6,
              "max_relative_gap": max(abs(r["relative_gap"]) for r in rows),
              "gradient_iterations_by_follower": by_follower(rows),
              # 1-minute load average of the machine at the start and the end (seconds are wall times)
              "load_average": [round(load_start[0], 2), round(os.getloadavg()[0], 2)],
              "cpu_count": os.cpu_count(), "scenes": rows}
    OUT.write_text(json.dumps(report, indent=1) + "\n")


if __name__ == "__main__":
    main()
