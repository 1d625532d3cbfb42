"""``camjax dynamics``: follower-train vibration, compensation, robustness and jump of a scene."""

from __future__ import annotations

import argparse
import sys

from camjax import runtime
from camjax.cli.common import OUT_HELP, UsageError, check_dpi, command, warn_starting_laws
from camjax.cli.environment import show_progress
from camjax.output.files import write_json
from camjax.output.folder import check_output_dir, replaced_folder


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
        warn_starting_laws(scene, "dynamics")
        runtime.enable_caches()
        work = estimate_work(scene)  # counts (and the cam's FFT when a drive runs): no analysis yet
        if (refused := refusal(scene, work, args.force)) is not None:
            raise UsageError(refused)
        # a bar with an ETA on a terminal (or with CAMJAX_PROGRESS=1); a piped stderr gets none
        bar = WorkProgress(work) if show_progress() else None

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


