"""``camjax sweep``: every (alpha, gamma) pair of two lists solved; pareto.json and pareto.png."""

from __future__ import annotations

import argparse
import dataclasses

from camjax import runtime
from camjax.cli.common import (
    OUT_HELP,
    UsageError,
    add_design_options,
    add_samples_option,
    apply_design_options,
    apply_samples,
    check_dpi,
    command,
    parse_float_list,
)
from camjax.output.files import write_json
from camjax.output.folder import check_output_dir, replaced_folder
from camjax.scene import cut
from camjax.scene.ranges import allowed_text, outside

@command("sweep", "solve every (alpha, gamma) pair of two lists: pareto.json and pareto.png")
def _setup_sweep(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None,
                   help="scene TOML file or built-in scene name (default: the embedded default scene)")
    p.add_argument("--alpha", required=True, metavar="LIST",
                   help="size weights, comma-separated, e.g. 0.1,1,10")
    p.add_argument("--gamma", required=True, metavar="LIST", help="stress weights, comma-separated")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    add_design_options(p, weights=False)
    p.add_argument("--chunk-size", type=int, default=None, metavar="W",
                   help="weightings per compiled call, a smaller sweep padded to it (default: 10 on the CPU, "
                   "128 on an accelerator; a progress bar when there are more); a scene with designed laws "
                   "co-designs one weighting at a time")
    p.add_argument("--dpi", type=int, default=120, help="resolution of pareto.png (default 120)")
    add_samples_option(p)
    from camjax.scaleout import command as scaleout

    scaleout.add_options(p)

    def run(args) -> int:
        import time

        from camjax.pipeline import sweep_scene
        from camjax.scene import load_scene
        from camjax.solvers.sweep import plot_pareto
        from camjax.units import report_to

        out = check_output_dir(args.out)
        alphas = parse_float_list("--alpha", args.alpha)
        gammas = parse_float_list("--gamma", args.gamma)
        for option, values in (("--alpha", alphas), ("--gamma", gammas)):
            bad = [v for v in values if v < 0]
            if bad:
                raise UsageError(f"{option} = {','.join(f'{v:g}' for v in values)}: {bad[0]:g} is "
                                 "negative (allowed: numbers >= 0)")
            bad = [v for v in values if outside(option.lstrip("-"), v)]
            if bad:  # the range of design.alpha / design.gamma
                raise UsageError(f"{option} = {cut(','.join(f'{v:g}' for v in values), 200)}: {bad[0]:g} is "
                                 "outside the physical range (allowed: "
                                 f"{allowed_text(option.lstrip('-'), zero=True, signed=False)})")
        if 0.0 in alphas and 0.0 in gammas:
            raise UsageError("--alpha/--gamma: the pair alpha = 0, gamma = 0 leaves nothing to "
                             "minimize (drop 0 from one of the lists)")
        if args.chunk_size is not None and not 1 <= args.chunk_size <= 100_000:
            raise UsageError(f"--chunk-size = {args.chunk_size}: out of range (allowed: 1..100000)")
        check_dpi(args.dpi)
        scene = apply_samples(load_scene(args.scene), args)
        if scene.design is None:
            raise UsageError(f"scene '{scene.name}' has no [design] section: a sweep needs its bounds "
                             "and sigma_max_MPa")
        from camjax.robust.design import refuse_sweep

        refuse_sweep(scene)  # a robust [design] is solved by camjax design, one weighting at a time
        # --alpha/--gamma are lists here: only mode, solver and seed override the scene
        overrides = argparse.Namespace(mode=args.mode, solver=args.solver, seed=args.seed)
        d = apply_design_options(scene, overrides).design
        mode, solver, seed = d.mode, d.solver, d.seed
        scaleout.check(args, UsageError)
        codesign = bool(scene.motion.designed)
        if codesign:
            _check_codesign(args, scene, mode)
        runtime.enable_caches()
        start = time.perf_counter()
        if codesign:  # the laws co-designed at every weighting (camjax.codesign.sweep)
            from camjax.codesign import CodesignError

            try:
                result = runtime.interruptible(sweep_scene, scene, alphas, gammas, mode=mode, solver=solver,
                                               seed=seed)
            except CodesignError as exc:
                raise UsageError(f"scene {scene.name}: {exc}") from None
        elif scaleout.requested(args):  # blocks on a backend, stored in --out as they finish
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
        if codesign:  # what the laws' search used (each row's "codesign": the laws chosen there)
            from camjax.codesign.joint import search_solver

            search = search_solver(dataclasses.replace(scene, design=dataclasses.replace(scene.design,
                                                                                         solver=solver)))
            terms = dict(scene.synthesis.objective) if scene.synthesis is not None else {}
            data["codesign"] = {"laws": [ds.path for ds in scene.motion.designed],
                                "search_solver": search, "synthesis_objective": terms}
        # replaced whole; a block sweep's checkpoint (written into --out as its blocks finished, for
        # --resume) is carried over, and nothing else of the folder: no earlier run's files
        keep = scaleout.CHECKPOINT if scaleout.requested(args) else ()
        with replaced_folder(out, keep) as tmp:
            write_json(tmp / "pareto.json", report_to(data, scene.units))  # camjax.units
            title = (f"Size vs stress over {len(data['records'])} weightings, laws co-designed at each "
                     f"({solver}, {mode})") if codesign else None
            fig = plot_pareto(result, title=title, units=scene.units)
            fig.savefig(tmp / "pareto.png", dpi=args.dpi)
        recs = data["records"]
        feasible = sum(r["feasible"] for r in recs)
        front = sum(r["pareto"] for r in recs)
        what = f"co-design sweep (laws: {search} search; geometry: " if codesign else "sweep ("
        print(f"{what}{solver}, {mode}) of {len(recs)} weightings in {seconds:.2f} s: "
              f"{feasible} feasible, {front} on the non-dominated front")
        if codesign:
            chosen = sum(r["codesign"]["chosen"] == "codesign" for r in recs)
            rest = "" if chosen == len(recs) else " (the best built-in combination at the others)"
            print(f"co-designed laws chosen at {chosen} of {len(recs)} weightings{rest}")
        print(f"wrote pareto.json, pareto.png to {args.out}")
        return 0

    return run


def _check_codesign(args, scene, mode: str) -> None:
    """What a co-design sweep (a scene with designed laws) refuses, before any work: a pointwise
    mode (as ``camjax design`` refuses it), the scale-out options and --chunk-size (the laws are
    co-designed one weighting at a time, in this process)."""
    from camjax.scaleout import command as scaleout

    where = f"scene {scene.name} designs its laws ({', '.join(ds.path for ds in scene.motion.designed)})"
    if mode != "global":
        head = (f"--mode = '{mode}'" if args.mode is not None
                else f"scene {scene.name}: design.mode = '{mode}'")
        raise UsageError(f"{head}: co-design designs one cam for the whole turn (allowed: 'global')")
    if scaleout.requested(args):
        given = next(o for o, v in (("--backend", args.backend), ("--address", args.address),
                                    ("--workers", args.workers), ("--block-size", args.block_size),
                                    ("--resume", args.resume or None)) if v is not None)
        raise UsageError(f"{given}: {where}: its sweep co-designs them at each weighting in this process "
                         "(allowed: leave out --backend, --address, --workers, --block-size, --resume)")
    if args.chunk_size is not None:
        raise UsageError(f"--chunk-size = {args.chunk_size}: {where}: its sweep co-designs them one "
                         "weighting at a time (allowed: leave out --chunk-size)")
