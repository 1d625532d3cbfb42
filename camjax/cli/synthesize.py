"""``camjax synthesize``: design the laws of a scene's ``design = true`` segments (law only)."""

from __future__ import annotations

import argparse

from camjax.cli.common import OUT_HELP, UsageError, check_dpi, command
from camjax.output.files import write_json
from camjax.output.folder import check_output_dir, replaced_folder


@command("synthesize", "design the B-spline laws of a scene's design = true segments for [synthesis]'s "
         "objective (law only)")
def _setup_synthesize(p: argparse.ArgumentParser):
    p.add_argument("scene", help="scene TOML file with designed segments and [synthesis], or a built-in "
                   "name (e.g. synthesis)")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    p.add_argument("--dpi", type=int, default=100, help="resolution of svaj.png (default 100)")

    def run(args) -> int:
        from camjax import followers, runtime
        from camjax.output.synthesis import synthesis_figure, synthesis_report, train_report, write_curves_csv
        from camjax.scene import load_scene
        from camjax.scene.designed import law_from_control
        from camjax.synthesis.segments import synthesize_segments
        from camjax.units import report_to

        out = check_output_dir(args.out)
        check_dpi(args.dpi)
        scene = load_scene(args.scene)
        if not scene.motion.designed:
            raise UsageError(f"scene '{scene.name}' has no segment with design = true: nothing to "
                             "synthesize (allowed: a scene like the built-in 'synthesis')")
        if scene.synthesis is None or not scene.synthesis.objective:  # (spring keys alone: co-design)
            raise UsageError(f"scene '{scene.name}' has no [synthesis] objective (allowed: [synthesis] "
                             "objective = { peak_accel = 1.0, ... })")
        runtime.enable_caches()
        weights = dict(scene.synthesis.objective)
        train = None
        if scene.dynamics is not None:  # the follower train's terms and figures
            from camjax.dynamics.context import synthesis_train

            train = synthesis_train(scene)
        results = runtime.interruptible(synthesize_segments, scene.motion.designed, weights,
                                        scene.synthesis.samples_per_span, train)
        bad = [r for r in results if not r.converged]
        if bad:
            r = bad[0]
            raise RuntimeError(f"{r.segment.path}: the synthesis did not converge (residual "
                               f"{r.residual:.3g}); nothing written")
        lift_key = "lift_deg" if followers.of(scene).rocking else "lift_mm"
        controls = [law_from_control(r.segment, r.control)[1] for r in results]
        report = synthesis_report(scene.name, weights, results, controls, lift_key)
        if train is not None:
            report["synthesis"]["train"] = train_report(train)
        curves, panels = law_curves(results, [r.best_builtin[0] if r.best_builtin else None for r in results],
                                    "best built-in")
        fig = synthesis_figure(panels)
        with replaced_folder(out) as tmp:
            write_json(tmp / "result.json", report_to(report, scene.units))  # camjax.units
            write_curves_csv(tmp / "synthesis.csv", curves)
            fig.savefig(tmp / "svaj.png", dpi=args.dpi)
        for r in results:
            best = (f"; best built-in {r.best_builtin[0]}: {r.best_builtin[1]:.5g}" if r.best_builtin
                    else "; no built-in law meets its conditions")
            print(f"segments[{r.segment.index}] {r.segment.kind}: objective {r.objective:.5g}{best}")
        print(f"wrote result.json, synthesis.csv, svaj.png to {args.out}")
        return 0

    return run


def law_curves(results, builtin_names, note: str):
    """(curves, panels) of designed laws for synthesis.csv and their figure: each result's
    normalized s, v, a, j on CURVE_POINTS points, beside the built-in law named for it (None:
    none), labelled ``"<law> (<note>)"``. ``results``: objects with ``segment``, ``knots`` and
    ``control`` (camjax synthesize's and the co-design's)."""
    import numpy as np

    from camjax.laws import LAWS
    from camjax.laws.bspline import evaluate_derivatives_numpy
    from camjax.output.synthesis import CURVE_POINTS
    from camjax.synthesis.segments import builtin_q

    x = np.linspace(0.0, 1.0, CURVE_POINTS)
    curves, panels = [], []
    for r, name in zip(results, builtin_names, strict=True):
        seg = r.segment
        q = evaluate_derivatives_numpy(r.knots, np.asarray(r.control), seg.degree, x, 3)
        curves.append((seg.index, x, q))
        panels.append((f"segments[{seg.index}] {seg.kind}", x, q,
                       builtin_q(LAWS[name], seg.kind, x) if name else None,
                       f"{name} ({note})" if name else None))
    return curves, panels
