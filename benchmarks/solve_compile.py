"""Compile cost of the gradient solver's design program, per follower type's example scene.

The program is :func:`camjax.solvers.base.solve_batch` in global mode with the default
``gradient`` solver and one weighting (alpha = gamma = 1), jitted as one program (``camjax design``
compiles it as two, the search and its judgement: :func:`~camjax.solvers.base.search_batch`,
:func:`~camjax.solvers.base.judge_batch`).
Each scene is measured in a fresh process (no compilation cache, no program cache) with:

* ``eqns``: equations of its jaxpr, nested ones (loop bodies, conds, custom rules) included;
* ``trace_s``: wall seconds of ``solve_batch.trace``; ``lower_s`` of ``.lower()``;
  ``compile_s`` of ``.compile()`` (XLA);
* ``cpu_s``: CPU seconds of the process for trace + lower + compile (both cores count).

With several ``--tree LABEL=PATH`` (checkouts of other commits) every scene is measured with each
tree, the trees alternating scene by scene so that the machine's load falls on all alike; the
JSON has one column per label. Writes benchmarks/results/solve_compile.json. ``--parts`` counts
the equations of the program's pieces instead (the family's evaluate and polish, L_A and its
gradient, the refinement's loop, :func:`camjax.solvers.gradient.minimize`: both loops and the
judgement of their designs), written to benchmarks/results/solve_compile_parts.json.

    python3 benchmarks/solve_compile.py [--tree before=/tmp/base@15abba3 --tree after=.] [--scenes default]
    python3 benchmarks/solve_compile.py --parts --out benchmarks/results/solve_compile_parts.json
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benchmarks" / "results" / "solve_compile.json"
# one example scene with a [design] section per follower type
SCENES = ("default", "roller", "curved-face", "knife-edge", "oscillating-flat", "oscillating-roller",
          "oscillating-curved-face")


def count_eqns(jaxpr) -> int:
    """Equations of a jaxpr and of every jaxpr nested in its equations' parameters."""
    from jax.extend import core

    def subjaxprs(value):
        if isinstance(value, core.ClosedJaxpr):
            yield value.jaxpr
        elif isinstance(value, core.Jaxpr):
            yield value
        elif isinstance(value, (tuple, list)):
            for v in value:
                yield from subjaxprs(v)

    total = 0
    for eqn in jaxpr.eqns:
        total += 1
        for param in eqn.params.values():
            for sub in subjaxprs(param):
                total += count_eqns(sub)
    return total


def measure(scene_name: str) -> dict:
    """One scene's design program, traced, lowered and compiled in this process."""
    import jax

    jax.config.update("jax_enable_x64", True)
    from camjax.family import weights_of
    from camjax.pipeline import design_problem
    from camjax.scene import load_scene
    from camjax.solvers.base import Settings, solve_batch, weighting_keys

    problem = design_problem(load_scene(scene_name))
    dtype = jax.tree.leaves(problem)[0].dtype
    args = (problem, weights_of([1.0], [1.0], jax.numpy.float64), weighting_keys(0, 1))
    jax.block_until_ready(args)
    cpu0, t0 = time.process_time(), time.perf_counter()
    traced = jax.jit(solve_batch, static_argnames=("mode", "solver", "settings")).trace(
        *args, "global", "gradient", Settings())
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    lowered.compile()
    t3 = time.perf_counter()
    cpu = time.process_time() - cpu0
    return {"eqns": count_eqns(traced.jaxpr.jaxpr), "trace_s": t1 - t0, "lower_s": t2 - t1,
            "compile_s": t3 - t2, "cpu_s": cpu, "dtype": str(dtype)}


def parts(scene_name: str) -> dict:
    """Equations of the pieces the design program is made of, for one scene (jaxprs only)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    from camjax.family import weights_of
    from camjax.pipeline import design_problem
    from camjax.scene import load_scene
    from camjax.solvers import box, gradient
    from camjax.solvers.base import family_of

    problem = design_problem(load_scene(scene_name))
    family, settings = family_of(problem), gradient.DEFAULT_SETTINGS
    weights = jax.tree.map(lambda x: x[0], weights_of([1.0], [1.0], jax.numpy.float64))
    design = box.midpoint(problem)
    u = box.to_unit(problem, design)
    zeros = jax.tree.map(jax.numpy.zeros_like, gradient.scaled_constraints(problem, design, True))

    def eqns(fn, *args) -> int:
        return count_eqns(jax.make_jaxpr(fn)(*args).jaxpr)

    def lagrangian(v):
        return gradient.augmented_lagrangian(v, problem, weights, zeros, settings.penalty, True)[0]

    return {"evaluate": eqns(lambda d: family.evaluate(problem, weights, d), design),
            "polish": eqns(lambda d: family.polish(problem, weights, d), design),
            "lagrangian_value_and_grad": eqns(jax.value_and_grad(lagrangian), u),
            "refine_bfgs": eqns(lambda v: gradient.refine_bfgs(problem, weights, v, settings)[0], u),
            "minimize": eqns(lambda w: gradient.minimize(problem, w, None, settings).design, weights)}


def in_fresh_process(tree: Path, scene_name: str) -> dict:
    env = dict(os.environ, PYTHONPATH=str(tree), CAMJAX_COMPILATION_CACHE="0", CAMJAX_PROGRAM_CACHE="0",
               JAX_ENABLE_COMPILATION_CACHE="false", JAX_PLATFORMS=os.environ.get("JAX_PLATFORMS", "cpu"))
    out = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--worker", scene_name],
                         env=env, cwd=tree, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def git_head(tree: Path) -> str:
    return subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()


def parse_tree(text: str) -> tuple[str, Path, str]:
    """``LABEL=PATH`` or ``LABEL=PATH@COMMIT`` (the commit of a tree that is not a git checkout)."""
    label, _, rest = text.partition("=")
    path, _, commit = rest.partition("@")
    return label, Path(path).resolve(), commit or git_head(Path(path))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--tree", action="append", type=parse_tree, metavar="LABEL=PATH[@COMMIT]",
                        help="a tree to measure (repeat to compare; default: this one, as 'after')")
    parser.add_argument("--scenes", nargs="+", default=list(SCENES))
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--parts", action="store_true",
                        help="equations of each piece of the program instead (this tree; to --out)")
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(measure(args.worker)))
        return
    if args.parts:
        rows = {name: parts(name) for name in args.scenes}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps({"commit": git_head(ROOT), "eqns": rows}, indent=2) + "\n")
        return
    trees = args.tree or [("after", ROOT, git_head(ROOT))]
    rows = {}
    for name in args.scenes:  # the trees alternate scene by scene: the machine's load falls on all alike
        rows[name] = {label: in_fresh_process(path, name) for label, path, _ in trees}
        print(name, json.dumps(rows[name]), flush=True)
    result = {"program": "solve_batch(problem, 1 weighting, 'global', 'gradient', Settings())",
              "trees": {label: {"path": str(path), "commit": commit} for label, path, commit in trees},
              "loadavg_1_5_15": [round(x, 2) for x in os.getloadavg()], "cpu_count": os.cpu_count(),
              "scenes": rows,
              "total_cpu_s": {label: sum(r[label]["cpu_s"] for r in rows.values()) for label, _, _ in trees}}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
