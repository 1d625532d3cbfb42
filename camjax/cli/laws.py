"""``camjax laws``: the motion laws' peak coefficients, joint classes against dwells and a chart."""

from __future__ import annotations

import argparse

from camjax.cli.common import UsageError, check_dpi, command
from camjax.output.files import write_json
from camjax.output.folder import check_output_file, write_file_atomic


@command("laws", "peak values, joint classes against dwells and an optional chart of every motion law")
def _setup_laws(p: argparse.ArgumentParser):
    p.formatter_class = argparse.RawDescriptionHelpFormatter
    p.epilog = LAWS_COLUMNS
    p.add_argument("--json", metavar="FILE", help="write the table as JSON instead of printing it")
    p.add_argument("--plot", metavar="FILE.png",
                   help="also draw normalized s, v, a, j of every law overlaid (one panel each)")
    p.add_argument("--dpi", type=int, default=110, help="resolution of the --plot image (default 110)")
    p.add_argument("--scene", metavar="SCENE",
                   help="also list the scene's own laws (B-spline and table segments), normalized, "
                        "named segments[i] <law>")

    def run(args) -> int:
        import jax.numpy as jnp

        from camjax import runtime
        from camjax.laws import LAWS, summarize_all
        from camjax.program import classify_jump

        runtime.enable_compilation_cache()  # the table is one program: read it, do not recompile it

        plot = check_output_file(args.plot, "--plot") if args.plot is not None else None
        check_dpi(args.dpi)
        if plot is not None:
            from matplotlib.figure import Figure

            kinds = Figure().canvas.get_supported_filetypes()
            if plot.suffix.lstrip(".").lower() not in kinds:
                raise UsageError(f"--plot = {args.plot!r}: unknown image type '{plot.suffix}' "
                                 f"(allowed: {', '.join('.' + k for k in sorted(kinds))})")

        def dwell_joints(s) -> tuple[str, str]:
            # the law as a rise from a dwell and into a dwell: the jumps at the joints are its end
            # values (a dwell has zero derivatives); normalized, so every scale is 1
            start = classify_jump([0.0, s.end_velocity[0], s.end_accel[0], s.end_jerk[0]], [1.0] * 4)
            end = classify_jump([0.0, -s.end_velocity[1], -s.end_accel[1], -s.end_jerk[1]], [1.0] * 4)
            return start, end

        path = check_output_file(args.json, "--json") if args.json is not None else None
        laws = dict(LAWS)
        if args.scene is not None:
            from camjax.scene import load_scene

            program = load_scene(args.scene).motion.program
            known = {id(law) for law in LAWS.values()}
            for i, law in enumerate(program.laws):
                if law is not None and id(law) not in known:
                    laws[f"segments[{i}] {law.name}"] = law
        rows = []
        for label, s in zip(laws, summarize_all(laws.values()), strict=True):
            start, end = dwell_joints(s)
            rows.append({
                "law": label,
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
                      tuple(np.asarray(v) for v in laws[r["law"]](jnp.asarray(x))) for r in rows}
            kind = plot.suffix.lstrip(".").lower()
            write_file_atomic(plot, lambda tmp: laws_figure(x, curves).savefig(tmp, dpi=args.dpi,
                                                                               format=kind))
        if args.json:
            write_file_atomic(path, lambda tmp: write_json(tmp, {"normalized": True, "laws": rows}))
            print(f"wrote {args.json}" + (f", {args.plot}" if plot else ""))
            return 0
        width = max(20, *(len(r["law"]) for r in rows))
        head = (f"{'law':{width}s} {'max|v|':>7s} {'max a':>8s} {'min a':>8s} {'max|j|':>8s}  "
                f"{'after dwell':12s} {'before dwell':12s} FLCD")
        print(head)
        print("-" * len(head))
        for r in rows:
            print(f"{r['law']:{width}s} {r['peak_velocity']:7.4f} {r['peak_accel_pos']:8.4f} "
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


