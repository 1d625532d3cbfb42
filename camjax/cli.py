"""The ``camjax`` command line. One subcommand per job; each replaces its output folder whole.

Subcommands register themselves in ``COMMANDS`` via :func:`command`: a function that adds its
arguments to an argparse parser and returns the function that runs it.

Exit status: 0 done; 2 bad input (scene, arguments or output location: one line naming the
field, checked before any computation, nothing written); 3 ``design --strict`` wrote geometry that
breaks a constraint; 1 a failure while running (one line; ``CAMJAX_DEBUG=1`` shows the
traceback); 130 interrupted (Ctrl-C), 143 terminated (SIGTERM). The output folder holds exactly
the new run's files, or, on any failure or interruption, exactly what it held before
(:mod:`camjax.output.folder`).
"""

from __future__ import annotations

import _thread
import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path

import camjax  # noqa: F401  (turns on x64 before any array is made)
from camjax import runtime
from camjax.numerics import NonFiniteError
from camjax.output.files import write_json
from camjax.output.folder import (
    OutputError,
    check_output_dir,
    check_output_file,
    merged_files,
    replaced_folder,
    write_file_atomic,
)
from camjax.scene import SceneError, cut, quote

COMMANDS: dict[str, tuple[str, Callable[[argparse.ArgumentParser], Callable]]] = {}


def command(name: str, help: str):
    """Register a subcommand: ``setup(parser) -> run(args) -> int``."""

    def deco(setup):
        COMMANDS[name] = (help, setup)
        return setup

    return deco


class UsageError(ValueError):
    """Bad command-line input; the message names the option, the value and what is allowed."""


OUT_HELP = "output folder, replaced whole when the run succeeds (left as it was otherwise)"
STRICT_EXIT = 3  # design --strict: the files were written, but their geometry breaks a constraint
MAX_BASE_RADIUS_MM = 1e6  # --base-radius: a 2 km cam is no cam; beyond this the figures lose meaning


def parse_float_list(option: str, text: str) -> list[float]:
    """'1,2.5,10' -> [1.0, 2.5, 10.0], with a clear error naming the option."""
    out = []
    for item in text.split(","):
        try:
            v = float(item)
        except ValueError:
            raise UsageError(f"{option} = {quote(text)}: {quote(item)} is not a number "
                             "(allowed: comma-separated numbers, e.g. 0.1,1,10)") from None
        if v != v or v in (float("inf"), float("-inf")):
            raise UsageError(f"{option} = {quote(text)}: values must be finite")
        out.append(v)
    return out


# ------------------------------------------------------------------------------ commands


@command("laws", "peak values, joint classes against dwells and an optional chart of every motion law")
def _setup_laws(p: argparse.ArgumentParser):
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.epilog = LAWS_COLUMNS
    p.add_argument("--json", metavar="FILE", help="write the table as JSON instead of printing it")
    p.add_argument("--plot", metavar="FILE.png",
                   help="also draw normalized s, v, a, j of every law overlaid (one panel each)")
    p.add_argument("--dpi", type=int, default=110, help="resolution of the --plot image (default 110)")

    def run(args) -> int:
        import jax.numpy as jnp

        from camjax.laws import LAWS, summarize
        from camjax.program import classify_jump

        plot = check_output_file(args.plot, "--plot") if args.plot is not None else None
        check_dpi(args.dpi)
        if plot is not None:
            from matplotlib.figure import Figure

            kinds = Figure().canvas.get_supported_filetypes()
            if plot.suffix.lstrip(".").lower() not in kinds:
                raise UsageError(f"--plot = {args.plot!r}: unknown image type '{plot.suffix}' "
                                 f"(allowed: {', '.join('.' + k for k in sorted(kinds))})")

        def dwell_joints(law) -> tuple[str, str]:
            # the law as a rise from a dwell and into a dwell: the jumps at the joints are its end
            # values (a dwell has zero derivatives); normalized, so every scale is 1
            v = law(jnp.asarray([0.0, 1.0]))
            start = classify_jump([0.0, float(v.dp[0]), float(v.d2p[0]), float(v.d3p[0])], [1.0] * 4)
            end = classify_jump([0.0, -float(v.dp[1]), -float(v.d2p[1]), -float(v.d3p[1])], [1.0] * 4)
            return start, end

        path = check_output_file(args.json, "--json") if args.json is not None else None
        rows = []
        for law in LAWS.values():
            s = summarize(law)
            start, end = dwell_joints(law)
            rows.append({
                "law": s.name,
                "peak_velocity": s.peak_velocity,
                "peak_accel_pos": s.peak_accel_pos,
                "peak_accel_neg": s.peak_accel_neg,
                "peak_jerk": s.peak_jerk,
                "joint_after_dwell": start,
                "joint_before_dwell": end,
                "flcd_against_dwells": s.flcd_against_dwells,
                "perturbation_against_dwells": s.perturbation_against_dwells,
            })
        if plot is not None:
            import numpy as np

            from camjax.output.plots import laws_figure

            x = np.linspace(0.0, 1.0, 501)
            # legend label: the name and its joint classes after / before a dwell
            curves = {f"{r['law']} [{r['joint_after_dwell']} / {r['joint_before_dwell']}]":
                      tuple(np.asarray(v) for v in LAWS[r["law"]](jnp.asarray(x))) for r in rows}
            kind = plot.suffix.lstrip(".").lower()
            write_file_atomic(plot, lambda tmp: laws_figure(x, curves).savefig(tmp, dpi=args.dpi,
                                                                               format=kind))
        if args.json:
            write_file_atomic(path, lambda tmp: write_json(tmp, {"normalized": True, "laws": rows}))
            print(f"wrote {args.json}" + (f", {args.plot}" if plot else ""))
            return 0
        head = (f"{'law':20s} {'max|v|':>7s} {'max a':>8s} {'min a':>8s} {'max|j|':>8s}  "
                f"{'after dwell':12s} {'before dwell':12s} FLCD")
        print(head)
        print("-" * len(head))
        for r in rows:
            print(f"{r['law']:20s} {r['peak_velocity']:7.4f} {r['peak_accel_pos']:8.4f} "
                  f"{r['peak_accel_neg']:8.4f} {r['peak_jerk']:8.3f}  {r['joint_after_dwell']:12s} "
                  f"{r['joint_before_dwell']:12s} {'yes' if r['flcd_against_dwells'] else 'no'}")
        print(LAWS_COLUMNS)
        if plot is not None:
            print(f"wrote {plot}")
        return 0

    return run


LAWS_COLUMNS = """\
columns (normalized law p(x): lift 1 over x in [0, 1]):
  max|v|, max a, min a, max|j|   peaks of |p'|, p'', p'' (most negative) and |p'''|; scale to a
                                 rise h over beta rad by h/beta, h/beta^2, h/beta^3
  after dwell, before dwell      class of the joint when the law is a rise starting from / ending
                                 at a dwell: ok (smooth), perturbation (jerk jumps; allowed),
                                 jerk (acceleration jumps), shock (velocity jumps)
  FLCD                           yes = velocity and acceleration continuous at both joints with
                                 dwells (the law's class there is ok or perturbation)"""


@command("design", "report, plots, profile CSV and DXF (and an animation) of a scene's cam design")
def _setup_design(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None,
                   help="scene TOML file or built-in scene name (default: the embedded default scene)")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    p.add_argument("--base-radius", type=float, default=None, metavar="MM",
                   help="evaluate and draw at this base radius instead of the design's")
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNG figures (default 100)")
    add_samples_option(p)
    p.add_argument("--strict", action="store_true",
                   help="exit with status 3 (after writing) when the geometry written breaks a "
                   "constraint; without it such a run warns on stderr and exits 0")
    p.add_argument("--animate", action="store_true",
                   help="also write motion.gif: one turn of the cam with the follower, the contact "
                        "point and the pressure angle (a broken constraint is named and drawn red)")
    add_design_options(p)

    def run(args) -> int:
        from camjax.pipeline import analyse
        from camjax.scene import load_scene

        out = check_output_dir(args.out)
        r = args.base_radius
        if r is not None and not (r == r and 0 < r <= MAX_BASE_RADIUS_MM):
            raise UsageError(f"--base-radius = {r!r}: out of range (allowed: a number > 0 and "
                             f"<= {MAX_BASE_RADIUS_MM:g}, mm)")
        check_dpi(args.dpi)
        scene = apply_design_options(apply_samples(load_scene(args.scene), args), args)
        rad_lifts = scene.dynamics is not None and scene.dynamics.follower == "oscillating"
        if rad_lifts and not scene.follower.oscillating:
            raise UsageError(f"scene {scene.name}: dynamics.follower = 'oscillating' (motion in rad); the "
                             "geometry of this scene's follower.type is for lifts in mm "
                             f"(allowed: follower.type = 'oscillating_roller' or 'oscillating_flat' with "
                             f"lift_deg, or `camjax dynamics {args.scene or scene.name}`)")
        runtime.enable_caches()

        # a run takes seconds: on a terminal (or with CAMJAX_PROGRESS=1) say what it is doing;
        # piped, stderr keeps its contract of one line on failure
        show = sys.stderr.isatty() or os.environ.get("CAMJAX_PROGRESS") == "1"

        def progress(phase: str) -> None:
            if show:
                sys.stderr.write(f"camjax design: {phase}\n")
                sys.stderr.flush()

        progress("computing")
        with ExitStack() as stack:
            # the drawing processes import matplotlib and ezdxf while JAX computes; without them
            # (an oscillating follower) or for an animation they load in a second thread here
            workers = None if scene.follower.oscillating else _drawing_workers(stack)
            preload = None
            if workers is None or args.animate:
                preload = threading.Thread(target=_import_drawing_modules, daemon=True)
                preload.start()
            result = runtime.interruptible(analyse, scene, base_radius_mm=r)
            if preload is not None:
                preload.join()
            return _write_design(args, out, scene, result, workers, progress)

    return run


def _drawing_workers(stack):
    """Started :class:`camjax.output.drawing.DrawingWorkers` (closed with ``stack``), or None
    where processes cannot be started or $CAMJAX_DRAWING_PROCESSES is 0 (the figures and the DXF
    are then drawn in this one). $CAMJAX_DRAWING_PROCESSES: how many."""
    from camjax.output.drawing import DEFAULT_PROCESSES, MAX_PROCESSES, DrawingWorkers

    text = os.environ.get("CAMJAX_DRAWING_PROCESSES", str(DEFAULT_PROCESSES))
    if not (text.isdigit() and int(text) <= MAX_PROCESSES):
        raise UsageError(f"CAMJAX_DRAWING_PROCESSES = {quote(text)}: not a count (allowed: 0 to "
                         f"{MAX_PROCESSES}; 0 draws in the command's own process)")
    if int(text) == 0:
        return None
    try:
        return stack.enter_context(DrawingWorkers(int(text)))
    except OSError:
        return None


def _write_design(args, out, scene, result, workers, progress) -> int:
    """Check, write and report a computed design run (``camjax design``'s second half)."""
    from camjax.output.animation import UndrawableGeometry, check_drawable
    from camjax.output.export import write_design_files
    from camjax.output.titles import title_block

    try:  # before anything is written: figures and animation need a finite outline
        check_drawable(result.curves)
    except UndrawableGeometry as exc:
        raise UsageError(f"scene {scene.name} at R_b = {result.curves.base_radius_mm:g} mm: "
                         f"{exc}") from None
    d = result.data
    at = d["evaluated_at"]
    broken = [v["constraint"] for v in at["violations"]]
    banner = (f"INFEASIBLE GEOMETRY at R_b = {at['base_radius_mm']:.4g} mm: "
              f"{', '.join(broken)} violated" if broken else None)
    with replaced_folder(out) as tmp:
        write_json(tmp / "result.json", d)
        written = write_design_files(tmp, result.curves, args.dpi, banner, title_block(d),
                                     animate=args.animate, progress=progress, workers=workers)
        names = ["result.json"] + [p.name for p in written]
    print(f"scene {d['scene']}: min base radius {d['min_base_radius_mm']:.4f} mm at "
          f"{d['min_base_radius_deg']:g} deg")
    if "design" in d:
        g = d["design"]
        if "face_width_mm" in g:
            sizes = f"L = {g['face_width_mm']:.4f} mm"
        elif "arm_length_mm" in g:
            sizes = (f"R_f = {g['roller_radius_mm']:.4f} mm, pivot {g['pivot_distance_mm']:.4f} mm, "
                     f"arm {g['arm_length_mm']:.4f} mm, R_p = {g['prime_radius_mm']:.4f} mm")
        elif "face_offset_mm" in g:
            sizes = (f"pivot {g['pivot_distance_mm']:.4f} mm, face offset {g['face_offset_mm']:.4f} mm, "
                     f"face {g['face_length_mm']:.4f} mm")
        else:
            sizes = (f"R_f = {g['roller_radius_mm']:.4f} mm, offset {g['offset_mm']:.4f} mm, "
                     f"R_p = {g['prime_radius_mm']:.4f} mm")
        print(f"design ({g['solver']}): R_b = {g['base_radius_mm']:.4f} mm, {sizes}, "
              f"objective {g['objective']:.5f}, feasible {g['feasible']}")
    width = f", L = {at['face_width_mm']:.4f} mm" if at.get("face_width_mm") is not None else ""
    if "roller" in d:
        roller = d["roller"]
        width = f", R_f = {roller['roller_radius_mm']:.4f} mm, offset {roller['offset_mm']:.4f} mm"
    state = f"INFEASIBLE ({', '.join(broken)})" if broken else "feasible"
    print(f"files drawn at R_b = {at['base_radius_mm']:.4f} mm{width} ({at['source']}): {state}")
    print(f"wrote {', '.join(names)} to {args.out}")
    for v in at["violations"]:
        print(f"camjax design: warning: the geometry written breaks {v['constraint']}: {v['message']}",
              file=sys.stderr)
    return STRICT_EXIT if broken and args.strict else 0


def _import_drawing_modules() -> None:
    """Import what drawing and the DXF need (run in a thread beside the computation)."""
    import ezdxf  # noqa: F401
    import matplotlib.backends.backend_agg  # noqa: F401

    import camjax.output.plots  # noqa: F401


def add_samples_option(p: argparse.ArgumentParser) -> None:
    """--samples N: the cam-angle grid instead of the scene's motion.samples."""
    from camjax.scene import SAMPLES_MAX, SAMPLES_PER_SEGMENT

    p.add_argument("--samples", type=int, default=None, metavar="N",
                   help=f"cam-angle grid size (default: the scene's motion.samples); at most {SAMPLES_MAX}, "
                   f"and at least {SAMPLES_PER_SEGMENT} samples in the shortest segment")


def apply_samples(scene, args):
    """The scene on the --samples grid (checked by the scene's own rules), or unchanged."""
    from camjax.scene import with_samples

    if getattr(args, "samples", None) is None:
        return scene
    try:
        return with_samples(scene, args.samples)
    except SceneError as exc:
        allowed = f" (allowed: {exc.allowed})" if exc.allowed else ""
        raise UsageError(f"--samples = {exc.value!r}: {exc.problem}{allowed}") from None


def add_design_options(p: argparse.ArgumentParser, weights: bool = True) -> None:
    """--mode, --solver, --seed (and --alpha, --gamma): overrides of the scene's [design] section."""
    tail = " (default: the scene's [design] value)"
    from camjax.solvers.registry import MODES, SOLVERS

    p.add_argument("--mode", choices=MODES, default=None,
                   help="one R_b, L for the whole cam, or the source's per-angle method" + tail)
    p.add_argument("--solver", choices=SOLVERS, default=None,
                   help="augmented-Lagrangian gradient solver, vectorized GA, or GA + gradient polish" + tail)
    p.add_argument("--seed", type=int, default=None, help="seed of the GA and hybrid solvers" + tail)
    if weights:
        p.add_argument("--alpha", type=float, default=None, help="weight of the size term" + tail)
        p.add_argument("--gamma", type=float, default=None, help="weight of the stress term" + tail)


def check_dpi(dpi: int) -> None:
    """--dpi must be 10..1000."""
    if not 10 <= dpi <= 1000:
        raise UsageError(f"--dpi = {dpi}: out of range (allowed: 10..1000)")


def apply_design_options(scene, args):
    """The scene with its [design] overridden by --mode/--alpha/--gamma/--solver/--seed."""
    from camjax.scene import with_design

    given = {k: getattr(args, k, None) for k in ("mode", "alpha", "gamma", "solver", "seed")}
    given = {k: v for k, v in given.items() if v is not None}
    if not given:
        return scene
    if scene.design is None:
        options = ", ".join(f"--{k}" for k in given)
        raise UsageError(f"{options}: scene '{scene.name}' has no [design] section to override "
                         "(add one with bounds and sigma_max_MPa)")
    try:  # the scene parser's own checks: one set of rules for the file and the options
        return with_design(scene, **given)
    except SceneError as exc:
        option, allowed = exc.field.rpartition(".")[2], f" (allowed: {exc.allowed})" if exc.allowed else ""
        raise UsageError(f"--{option} = {exc.value!r}: {exc.problem}{allowed}") from None


@command("sweep", "solve every (alpha, gamma) pair of two lists: pareto.json and pareto.png")
def _setup_sweep(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None,
                   help="scene TOML file or built-in scene name (default: the embedded default scene)")
    p.add_argument("--alpha", required=True, metavar="LIST",
                   help="size weights, comma-separated, e.g. 0.1,1,10")
    p.add_argument("--gamma", required=True, metavar="LIST", help="stress weights, comma-separated")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    add_design_options(p, weights=False)
    p.add_argument("--chunk-size", type=int, default=128, metavar="W",
                   help="weightings per compiled call (default 128; a progress bar when there are more)")
    p.add_argument("--dpi", type=int, default=120, help="resolution of pareto.png (default 120)")
    add_samples_option(p)
    from camjax.scaleout import command as scaleout

    scaleout.add_options(p)

    def run(args) -> int:
        import time

        from camjax.pipeline import sweep_scene
        from camjax.scene import load_scene
        from camjax.solvers.sweep import plot_pareto

        # a scale-out sweep keeps its blocks in --out between runs (--resume): merged, not replaced
        out = check_output_dir(args.out, replace=not scaleout.requested(args))
        alphas = parse_float_list("--alpha", args.alpha)
        gammas = parse_float_list("--gamma", args.gamma)
        for option, values in (("--alpha", alphas), ("--gamma", gammas)):
            bad = [v for v in values if v < 0]
            if bad:
                raise UsageError(f"{option} = {','.join(f'{v:g}' for v in values)}: {bad[0]:g} is "
                                 "negative (allowed: numbers >= 0)")
        if 0.0 in alphas and 0.0 in gammas:
            raise UsageError("--alpha/--gamma: the pair alpha = 0, gamma = 0 leaves nothing to "
                             "minimize (drop 0 from one of the lists)")
        if not 1 <= args.chunk_size <= 100_000:
            raise UsageError(f"--chunk-size = {args.chunk_size}: out of range (allowed: 1..100000)")
        check_dpi(args.dpi)
        scene = apply_samples(load_scene(args.scene), args)
        if scene.design is None:
            raise UsageError(f"scene '{scene.name}' has no [design] section: a sweep needs its bounds "
                             "and sigma_max_MPa")
        # --alpha/--gamma are lists here: only mode, solver and seed override the scene
        overrides = argparse.Namespace(mode=args.mode, solver=args.solver, seed=args.seed)
        d = apply_design_options(scene, overrides).design
        mode, solver, seed = d.mode, d.solver, d.seed
        scaleout.check(args, UsageError)
        runtime.enable_caches()
        start = time.perf_counter()
        if scaleout.requested(args):  # blocks on a backend, stored in --out as they finish
            import jax

            result = scaleout.run_sweep(args, scene, scaleout.scene_text(args.scene), alphas, gammas,
                                        mode=mode, solver=solver, seed=seed, usage_error=UsageError,
                                        cache_dir=jax.config.jax_compilation_cache_dir)
        else:
            result = runtime.interruptible(sweep_scene, scene, alphas, gammas, mode=mode, solver=solver,
                                           seed=seed, chunk_size=args.chunk_size)
        seconds = time.perf_counter() - start
        data = {"scene": scene.name, "mode": mode, "solver": solver, "seed": seed,
                "alphas": alphas, "gammas": gammas, "seconds": seconds, "records": result.records()}
        with (merged_files(out) if scaleout.requested(args) else replaced_folder(out)) as tmp:
            write_json(tmp / "pareto.json", data)
            fig = plot_pareto(result)
            fig.savefig(tmp / "pareto.png", dpi=args.dpi)
        recs = data["records"]
        feasible = sum(r["feasible"] for r in recs)
        front = sum(r["pareto"] for r in recs)
        print(f"sweep ({solver}, {mode}) of {len(recs)} weightings in {seconds:.2f} s: "
              f"{feasible} feasible, {front} on the non-dominated front")
        print(f"wrote pareto.json, pareto.png to {args.out}")
        return 0

    return run


def _stability_matrix():
    """``validation.extremes`` from the source checkout this package runs from (it is not installed)."""
    import importlib

    source = Path(__file__).resolve().parents[1] / "validation" / "extremes.py"
    if not source.is_file():
        raise UsageError(f"{source} is missing: check-extremes runs from a source checkout "
                         "(git clone, then pip install -e .), not from an installed wheel")
    if str(source.parents[1]) not in sys.path:
        sys.path.insert(0, str(source.parents[1]))
    module = importlib.import_module("validation.extremes")
    if Path(module.__file__).resolve() != source:  # another package named 'validation' came first
        raise UsageError(f"import validation.extremes found {module.__file__}, not {source}")
    return module


@command("check-extremes", "run the numerical-stability matrix and write extremes.json")
def _setup_check_extremes(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None, help="scene file or built-in name (default: default)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (replaced whole)")
    add_samples_option(p)

    def run(args) -> int:
        from camjax.scene import load_scene

        out = check_output_dir(args.out)
        matrix = _stability_matrix()
        scene = apply_samples(load_scene(args.scene), args)
        skipped = matrix.skipped_groups(scene)
        for s in skipped:
            print(f"  skipping {s['group']}: {s['reason']}", file=sys.stderr)
        cases = runtime.interruptible(matrix.run_matrix, scene,
                                      progress=lambda g: print(f"  running {g} ...", file=sys.stderr))
        failed = [c for c in cases if not c.passed]
        with replaced_folder(out) as tmp:
            write_json(tmp / "extremes.json", {
                "scene": scene.name,
                "cases": [c.as_dict() for c in cases],
                "skipped": skipped,
                "summary": {"cases": len(cases), "passed": len(cases) - len(failed), "failed": len(failed)},
            })
            (tmp / "extremes.txt").write_text(matrix.format_table(cases) + "\n")
            (tmp / "extremes.md").write_text(matrix.format_markdown(cases) + "\n")
        print(matrix.format_table(failed) if failed else f"all {len(cases)} cases pass")
        written = out / "extremes.json"
        print(f"{len(cases) - len(failed)} passed, {len(failed)} failed; wrote {written}")
        return 1 if failed else 0

    return run


@command("dynamics", "follower-train vibration, compensation, robustness and jump of a scene")
def _setup_dynamics(p: argparse.ArgumentParser):
    p.add_argument("scene", help="scene TOML file with a [dynamics] section, or a built-in name "
                   "(e.g. thesis-bench)")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNG figures (default 100)")
    p.add_argument("--force", action="store_true",
                   help="run even when the estimated work exceeds the budget (without it such a scene is "
                   "refused, exit 2, naming the [dynamics] fields that drive the cost)")

    def run(args) -> int:
        from camjax.dynamics import scene_dynamics
        from camjax.dynamics.budget import WorkProgress, estimate_work, refusal
        from camjax.scene import load_scene

        out = check_output_dir(args.out)
        check_dpi(args.dpi)
        scene = load_scene(args.scene)
        if scene.dynamics is None:
            raise UsageError(f"scene '{scene.name}' has no [dynamics] section: nothing to compute "
                             "(allowed: a scene with [dynamics], e.g. thesis-bench)")
        runtime.enable_caches()
        work = estimate_work(scene)  # counts (and the cam's FFT when a drive runs): no analysis yet
        if (refused := refusal(scene, work, args.force)) is not None:
            raise UsageError(refused)
        # a bar with an ETA on a terminal (or with CAMJAX_PROGRESS=1); a piped stderr gets none
        bar = WorkProgress(work) if sys.stderr.isatty() or os.environ.get("CAMJAX_PROGRESS") == "1" else None

        def progress(line: str) -> None:  # one write per line: two threads report
            if bar is not None:
                bar.write(f"camjax dynamics: {line}")
                return
            sys.stderr.write(f"camjax dynamics: {line}\n")
            sys.stderr.flush()

        rendered: dict[str, bytes] = {}

        def figures(so_far):  # runs while the time-domain analyses finish in other threads
            from camjax.output.plots_dynamics import render_dynamics_figures  # matplotlib: ~0.5 s

            if not rendered:
                progress("figures")
            rendered.update(render_dynamics_figures(so_far.curves, so_far.summary, args.dpi, skip=rendered))

        try:
            report = runtime.interruptible(scene_dynamics, scene, progress, figures, tracker=bar)
        finally:
            if bar is not None:
                bar.close()
        if report.settling is not None and not report.settling.settled:
            st = report.settling
            needs = (f"needs {st.cycles_needed} cycles" if st.cycles_needed is not None
                     else "an undamped train never settles")
            progress(f"warning: max_cycles = {st.cycles} stopped the time-domain runs before the "
                     f"transient decayed ({needs}; residual factor {st.residual_factor:.3g} > "
                     f"transient_tolerance = {scene.dynamics.transient_tolerance:g}); raise max_cycles")
        from camjax.output.plots_dynamics import write_dynamics_figures

        with replaced_folder(out) as tmp:
            write_json(tmp / "dynamics.json", report.summary)
            names = ["dynamics.json"] + [f.name for f in write_dynamics_figures(
                tmp, report.curves, report.summary, args.dpi, rendered)]
        s = report.summary
        unit = s["units"]["motion"]
        print(f"scene {s['scene']}: f_n = {s['natural_frequency_hz']:.3f} Hz, zeta = "
              f"{s['damping_ratio']:.5f}, harmonic {s['resonant_harmonic']['n']} of the cam at "
              f"{s['resonant_harmonic']['frequency_ratio']:.4f} f_n")
        line = f"max tracking error: nominal {s['nominal']['max_tracking_error']:.4g} {unit}"
        if "compensated" in s:
            line += f", compensated {s['compensated']['max_tracking_error']:.3g} {unit}"
        print(line)
        print(f"wrote {', '.join(names)} to {args.out}")
        return 0

    return run


# ---------------------------------------------------------------------------------- main


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``camjax design: error: ... (see camjax design --help)``."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {cut(message, 400)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="camjax", description="Disc cam design with JAX.",
                     epilog="exit status: 0 done, 1 failed while running, 2 bad input (nothing "
                     "written), 3 design --strict wrote infeasible geometry, 130 interrupted, "
                     "143 terminated")
    parser.add_argument("--version", action="version", version=f"camjax {camjax.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)
    for name, (help_text, setup) in COMMANDS.items():
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.set_defaults(_run=setup(p))
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that the same clean-up as Ctrl-C runs."""


def _raise_terminated(signum, frame):
    raise Terminated()


_INTERRUPT_HANDLED = threading.Event()  # set once main() has caught an interrupt


def _signal_later(sig: int, delay_s: float = 0.01) -> None:
    """Send ``sig`` to this process after ``delay_s`` (run in a thread of its own), unless the
    interrupt has reached ``main`` meanwhile by another path (then a second copy would kill the
    process after its one-line message)."""
    import time

    time.sleep(delay_s)
    if not _INTERRUPT_HANDLED.is_set():
        os.kill(os.getpid(), sig)


def _install_signal_handlers() -> Callable[[], None]:
    """SIGINT -> KeyboardInterrupt, SIGTERM -> :class:`Terminated`; returns the undo function."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    for sig, handler in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, _raise_terminated)):
        if previous[sig] is not signal.SIG_IGN:  # an ignored signal (nohup, `&`) stays ignored
            signal.signal(sig, handler)
    previous_hook = sys.unraisablehook
    _INTERRUPT_HANDLED.clear()

    def redeliver(unraisable):
        # A signal that lands inside a garbage-collection callback (XLA registers one) raises there,
        # where Python can only print "Exception ignored" and drop it: send it again, so that the
        # handler runs at the next safe point and the interrupt is neither lost nor a second line.
        exc = unraisable.exc_value
        if isinstance(exc, KeyboardInterrupt):
            sig = signal.SIGTERM if isinstance(exc, Terminated) else signal.SIGINT
            # from another thread, a moment later (a signal sent here would run its handler inside
            # this hook; threading.Thread.start would wait here too, so the low-level start is used)
            _thread.start_new_thread(_signal_later, (sig,))
            return
        previous_hook(unraisable)

    sys.unraisablehook = redeliver

    def undo():
        _INTERRUPT_HANDLED.set()  # no re-sent signal after the handlers are gone
        sys.unraisablehook = previous_hook
        for sig, handler in previous.items():
            signal.signal(sig, handler if handler is not None else signal.SIG_DFL)

    return undo


def _os_error(exc: OSError) -> str:
    where = f": {cut(str(exc.filename))}" if exc.filename else ""
    return f"{exc.strerror or type(exc).__name__}{where}"


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (see the module docstring). Never a traceback:
    every failure is one line on stderr (``CAMJAX_DEBUG=1`` re-raises unexpected errors)."""
    undo = _install_signal_handlers()
    prog = "camjax"
    try:
        args = build_parser().parse_args(argv)
        prog = f"camjax {args.command}"
        return int(args._run(args) or 0)
    except (SceneError, UsageError, OutputError) as exc:
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return 2
    except NonFiniteError as exc:  # finite inputs whose magnitudes overflow float64
        print(f"{prog}: error: {cut(str(exc), 300)}: the scene's magnitudes overflow float64 (allowed: "
              "physical values: lifts, masses, stiffnesses and sigma_max within a few orders of the "
              "default scene's)", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        _INTERRUPT_HANDLED.set()  # a re-sent copy of this signal (see _signal_later) is void now
        code, what = (143, "terminated") if isinstance(exc, Terminated) else (130, "interrupted")
        print(f"{prog}: {what}; the output folder is left as it was", file=sys.stderr)
        if argv is None and runtime.computing():  # a computation cannot be stopped: leave now
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
        return code
    except OSError as exc:
        print(f"{prog}: error: {_os_error(exc)}", file=sys.stderr)
        return 1
    except MemoryError:
        print(f"{prog}: error: out of memory (allowed: fewer --samples, or a smaller job)", file=sys.stderr)
        return 1
    except Exception as exc:
        if os.environ.get("CAMJAX_DEBUG"):
            raise
        print(f"{prog}: error: {type(exc).__name__}: {cut(str(exc), 300)} (CAMJAX_DEBUG=1 shows the "
              "traceback)", file=sys.stderr)
        return 1
    finally:
        undo()


def entry() -> None:
    """The ``camjax`` command (and ``python -m camjax.cli``): :func:`main`, then leave at once.

    The interpreter's teardown after a JAX computation (its backends and about a thousand
    modules) takes 0.2 s, a tenth of a warm design run; every file is written and closed and
    every child process waited for by then, so the process ends with ``os._exit`` after flushing
    its output. Ray, when a command used it, shuts down through the normal exit.
    """
    code = main()
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    except OSError:  # a closed pipe: nothing more can be said
        pass
    if "ray" in sys.modules:
        sys.exit(code)
    os._exit(code)


if __name__ == "__main__":
    entry()
