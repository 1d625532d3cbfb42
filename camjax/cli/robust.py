"""``camjax robust``: a scene's [tolerances] sampled, its nominal design evaluated for every sample
(:mod:`camjax.robust`), robust.json, robust.txt and the figures written."""

from __future__ import annotations

import argparse

from camjax.cli.common import OUT_HELP, UsageError, check_dpi, command

SAMPLES_MAX = 10_000_000


@command("robust", "sample the scene's [tolerances] and evaluate its design for every sample")
def _setup_robust(p: argparse.ArgumentParser):
    p.add_argument("scene", help="scene file or built-in name (needs [design] and [tolerances])")
    p.add_argument("--samples", type=int, default=10_000, help="samples drawn (default 10000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the draws (default 0)")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNG figures (default 100)")
    p.add_argument("--no-figures", action="store_true", help="write robust.json and robust.txt only")
    p.add_argument("--design", metavar="RESULT_JSON", default=None,
                   help="take the nominal design from this result.json of `camjax design` (or a robust.json) "
                   "instead of solving the scene's [design]")

    def run(args) -> int:
        from camjax import runtime
        from camjax.errors import MISSING
        from camjax.output.files import write_json
        from camjax.output.folder import check_output_dir, replaced_folder
        from camjax.robust import report
        from camjax.scene import SceneError, load_scene

        if not 1 <= args.samples <= SAMPLES_MAX:
            raise UsageError(f"--samples: {args.samples} is out of range (allowed: 1..{SAMPLES_MAX})")
        if not 0 <= args.seed < 2**32:
            raise UsageError(f"--seed: {args.seed} is out of range (allowed: 0..{2**32 - 1})")
        check_dpi(args.dpi)
        out = check_output_dir(args.out)
        runtime.enable_caches()  # compiled programs kept between runs, as camjax design does
        scene = load_scene(args.scene)
        if scene.design is None:
            raise SceneError("design", MISSING, "camjax robust evaluates the design of a [design] section; "
                             "add one")
        if scene.tolerances is None or not (scene.tolerances.values or scene.tolerances.profile):
            raise SceneError("tolerances", MISSING, "nothing to sample: add a [tolerances] section",
                             "e.g. rpm = { sd_percent = 2 }")
        design = None if args.design is None else _design_from(args.design, scene)
        result = runtime.interruptible(report.run, scene, args.samples, args.seed, design=design)
        text = report.text(result.data)
        with replaced_folder(out) as tmp:
            write_json(tmp / "robust.json", result.data)
            (tmp / "robust.txt").write_text(text)
            if not args.no_figures:
                from camjax.robust.drawing import figures

                figures(result.data, result.outputs, result.envelope, tmp, args.dpi)
        d = result.data
        print(text.split("\n\n")[2].strip())
        print(f"wrote {out / 'robust.json'} ({d['samples']} samples in {d['timings_s']['samples']:.2f} s)")
        return 0

    return run


def _design_from(path: str, scene) -> dict[str, float]:
    """The design variables of the scene's follower type from a result.json (its ``design`` block)
    or a robust.json (its ``design``); UsageError naming --design when they are not there."""
    import json
    import math
    from pathlib import Path

    from camjax import followers

    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise UsageError(f"--design: {path}: cannot be read as JSON ({type(exc).__name__})") from None
    block = data.get("design") if isinstance(data, dict) else None
    names = followers.of(scene).problem_module().Design._fields
    if not isinstance(block, dict) or data.get("follower_type", scene.follower.type) != scene.follower.type:
        raise UsageError(f"--design: {path} holds no design of a {scene.follower.type} follower "
                         f"(allowed: a result.json of camjax design of such a scene, or a robust.json)")
    out = {}
    for name in names:
        v = block.get(name)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise UsageError(f"--design: {path}: design.{name} = {v!r} is not a finite number "
                             f"(allowed: the variables {', '.join(names)})")
        out[name] = float(v)
    return out
