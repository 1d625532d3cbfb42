"""Size and compile cost of the design program (:func:`camjax.solvers.base.solve_batch` jitted as one
program; ``camjax design`` compiles its search and judgement apart) per solver.

For each registered follower type (its example scene as ``camjax design`` loads it, one weighting
(1, 1), global mode) and each solver of ``--solvers``: the equations of the traced program
(``jaxpr_eqns``: every equation, those of nested jaxprs (loop bodies, conditionals, calls)
included), the seconds to trace, to lower and to compile it with XLA (wall), the CPU seconds
of the process over the three (``cpu_s``: user + system of every thread; less distorted by other
jobs on a shared machine than wall time, which its load inflates; the load average is recorded),
and the fastest of three warm runs of the compiled program (``run_s``, wall).
A solver whose answer comes without a KKT certificate (the gradient solver's) has ``camjax design``
compile a second program to write result.json's ``certificate`` block
(:func:`camjax.solvers.certificate.point_certificate_json`): that program is measured too, in the
same process right after the search (``certificate_compile_s``, ``certificate_cpu_s``), and
``design_cpu_s`` is the CPU seconds of both (the search's alone for a solver that certifies in its
own program).
Each program is measured in a fresh process with the command line's CPU XLA flags
(:data:`camjax.runtime.CPU_XLA_FLAGS`) and no compilation cache: every program is compiled.

``python -m benchmarks.newton_compile --out benchmarks/results/newton_compile.json``
(``--label`` names the code measured, e.g. a commit; ``--combine A.json B.json ...`` writes the
runs of several result files side by side, e.g. two versions of the code measured in one session:
run the file with PYTHONPATH pointing at each version's checkout).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time


def equation_count(jaxpr) -> int:
    """Equations of a (closed) jaxpr, those of every nested jaxpr in its equations' parameters included."""
    from jax.extend import core

    inner = jaxpr.jaxpr if isinstance(jaxpr, core.ClosedJaxpr) else jaxpr
    total = 0
    for eqn in inner.eqns:
        total += 1
        for value in eqn.params.values():
            for sub in value if isinstance(value, list | tuple) else (value,):
                if isinstance(sub, core.ClosedJaxpr | core.Jaxpr):
                    total += equation_count(sub)
    return total


def measure(problem, solver: str) -> dict:
    """Trace, lower and compile ``solve_batch`` of ``problem`` for one weighting with ``solver``, then
    run it three times (``run_s``: the fastest, wall)."""
    import jax

    from camjax.family import weights_of
    from camjax.solvers.base import solve_batch, weighting_keys

    weights, keys = weights_of([1.0], [1.0]), weighting_keys(0, 1)
    cpu0, t0 = time.process_time(), time.perf_counter()
    traced = jax.jit(solve_batch, static_argnames=("mode", "solver", "settings")).trace(
        problem, weights, keys, "global", solver)
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    program = lowered.compile()
    t3 = time.perf_counter()
    cpu = time.process_time() - cpu0
    runs = []
    for _ in range(3):
        t4 = time.perf_counter()
        jax.block_until_ready(program(problem, weights, keys))
        runs.append(time.perf_counter() - t4)
    out = {"jaxpr_eqns": equation_count(traced.jaxpr), "trace_s": round(t1 - t0, 3),
           "lower_s": round(t2 - t1, 3), "compile_s": round(t3 - t2, 3), "cpu_s": round(cpu, 3),
           "run_s": round(min(runs), 4)}
    solution = program(problem, weights, keys)
    out["design_cpu_s"] = out["cpu_s"]
    if solution.certificate is None:  # the design compiles the certificate's program as well
        out.update(measure_certificate(problem, solution))
        out["design_cpu_s"] = round(cpu + out["certificate_cpu_s"], 3)
    return out


def measure_certificate(problem, solution) -> dict:
    """Trace, lower and compile the program that certifies a solution's design
    (:func:`camjax.solvers.certificate.point_certificate_json`'s), for its first weighting."""
    import jax
    import jax.numpy as jnp

    from camjax.family import weights_of
    from camjax.solvers import certificate

    design = jax.tree.map(lambda x: jnp.asarray(x[0]), solution.design)
    weights = weights_of(solution.alpha[0], solution.gamma[0], problem.lower[0].dtype)
    cpu0 = time.process_time()
    lowered = certificate._certify_point.trace(problem, weights, design, solution.iterations[0]).lower()
    t1 = time.perf_counter()
    lowered.compile()
    t2 = time.perf_counter()
    return {"certificate_compile_s": round(t2 - t1, 3),
            "certificate_cpu_s": round(time.process_time() - cpu0, 3)}


def measure_one(name: str, solver: str) -> dict:
    """:func:`measure` of one follower type's example scene and one solver (in this process)."""
    from camjax import runtime

    runtime.use_cpu_xla_flags()
    import camjax
    from camjax import followers
    from camjax.solvers.base import problem_from_scene

    problem = problem_from_scene(camjax.load_scene(followers.get(name).example_scene))
    return measure(problem, solver)


def run(solvers=("gradient", "newton"), names=None, label: str = "") -> dict:
    """Every follower type and solver, each in a fresh process (no trace or compile cache shared
    between the programs measured: a second program would reuse the traces of the first's jitted
    parts)."""
    from camjax import followers

    out = {"label": label, "loadavg_before": round(os.getloadavg()[0], 2), "followers": {}}
    for name in names or followers.names():
        row = {"scene": followers.get(name).example_scene}
        for solver in solvers:
            done = subprocess.run([sys.executable, __file__, "--one", name, solver], check=True,
                                  capture_output=True, text=True)
            row[solver] = json.loads(done.stdout.strip().splitlines()[-1])
        out["followers"][name] = row
        print(name, json.dumps(row), flush=True)
    out["loadavg_after"] = round(os.getloadavg()[0], 2)
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="benchmarks/results/newton_compile.json")
    parser.add_argument("--solvers", default="gradient,newton")
    parser.add_argument("--followers", default="", help="comma-separated names (default: every type)")
    parser.add_argument("--label", default="")
    parser.add_argument("--combine", nargs="+", metavar="FILE",
                        help="write these result files' runs side by side under 'runs' (no measuring)")
    parser.add_argument("--one", nargs=2, metavar=("FOLLOWER", "SOLVER"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(measure_one(*args.one)))
        return
    if args.combine:
        runs = []
        for path in args.combine:
            with open(path) as f:
                other = json.load(f)
            runs += other.get("runs", [other])
        result = {"runs": runs}
    else:
        names = [n for n in args.followers.split(",") if n] or None
        result = run(tuple(args.solvers.split(",")), names, args.label)
    with open(args.out, "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
