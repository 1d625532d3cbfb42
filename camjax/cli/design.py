"""``camjax design``: a scene's design, its report, figures, profile CSV and DXF (and animation)."""

from __future__ import annotations

import argparse
import builtins
import sys
import threading
from contextlib import ExitStack

from camjax import runtime
from camjax.cli.common import (
    MAX_BASE_RADIUS_MM,
    OUT_HELP,
    STRICT_EXIT,
    UsageError,
    add_design_options,
    add_samples_option,
    apply_design_options,
    apply_samples,
    check_dpi,
    command,
)
from camjax.cli.environment import drawing_processes, show_progress
from camjax.output.files import write_json
from camjax.output.folder import check_output_dir, replaced_folder


@command("design", "report, plots, profile CSV and DXF (and an animation) of a scene's cam design")
def _setup_design(p: argparse.ArgumentParser):
    p.add_argument("scene", nargs="?", default=None,
                   help="scene TOML file or built-in scene name (default: the embedded default scene)")
    p.add_argument("--out", required=True, metavar="DIR", help=OUT_HELP)
    p.add_argument("--base-radius", type=float, default=None, metavar="MM",
                   help="evaluate and draw at this base radius instead of the design's (in the "
                   "scene's units: mm, or inches for a scene with units = \"in\")")
    p.add_argument("--dpi", type=int, default=100, help="resolution of the PNG figures (default 100)")
    add_samples_option(p)
    p.add_argument("--strict", action="store_true",
                   help="exit with status 3 (after writing) when the geometry written breaks a "
                   "constraint; without it such a run warns on stderr and exits 0")
    p.add_argument("--animate", action="store_true",
                   help="also write motion.gif: one turn of the cam with the follower, the contact "
                        "point and the pressure angle (a broken constraint is named and drawn red)")
    p.add_argument("--timings", action="store_true",
                   help="after the run, print on stderr each phase's wall seconds (start-up, scene, "
                        "computing, files, figures) and the seconds JAX spent tracing and compiling")
    p.add_argument("--cam-table-points", type=int, default=None, metavar="N",
                   help="also write cam_table.csv and cam_table.json: the motion at N equally spaced master "
                        "angles for a servo drive (overrides [export] cam_table_points)")
    add_design_options(p)

    def run(args) -> int:
        from camjax.cli.timings import PhaseClock, entry_time

        # --timings: the phases from the command's entry (or from this call, as a function)
        clock = PhaseClock(entry_time(), count_jax=args.timings)
        clock.mark("scene")
        try:
            code = _run(args, clock)
        finally:
            clock.stop()
        if args.timings:
            for line in clock.lines("camjax design"):
                sys.stderr.write(line + "\n")
            sys.stderr.flush()
        return code

    def _run(args, clock) -> int:
        from camjax import followers
        from camjax.pipeline import analyse
        from camjax.scene import load_scene
        from camjax.scene.manufacture import CAM_TABLE_POINTS_MAX
        from camjax.units import length_scale

        out = check_output_dir(args.out)
        r = args.base_radius
        if r is not None and not (r == r and r > 0):
            raise UsageError(f"--base-radius = {r!r}: out of range (allowed: a number > 0)")
        check_dpi(args.dpi)
        n = args.cam_table_points
        if n is not None and not 2 <= n <= CAM_TABLE_POINTS_MAX:
            raise UsageError(f"--cam-table-points = {n}: out of range (allowed: 2 to {CAM_TABLE_POINTS_MAX})")
        scene = apply_design_options(apply_samples(load_scene(args.scene), args), args)
        if r is not None:  # given in the scene's units (camjax.units): the limit holds in mm
            scale = length_scale(scene.units)
            if r * scale > MAX_BASE_RADIUS_MM:
                raise UsageError(f"--base-radius = {r!r}: out of range (allowed: a number > 0 and "
                                 f"<= {MAX_BASE_RADIUS_MM / scale:g}, {scene.units})")
            r = r * scale
        rad_lifts = scene.dynamics is not None and scene.dynamics.follower == "oscillating"
        if rad_lifts and not followers.of(scene).rocking:
            rocking = " or ".join(repr(f.name) for f in followers.all_followers() if f.rocking)
            raise UsageError(f"scene {scene.name}: dynamics.follower = 'oscillating' (motion in rad); the "
                             "geometry of this scene's follower.type is for lifts in mm "
                             f"(allowed: follower.type = {rocking} with "
                             f"lift_deg, or `camjax dynamics {args.scene or scene.name}`)")
        runtime.enable_caches()

        # a run takes seconds: on a terminal (or with CAMJAX_PROGRESS=1) say what it is doing;
        # piped, stderr keeps its contract of one line on failure
        show = show_progress()

        def progress(phase: str) -> None:
            clock.mark(phase)
            if show:
                sys.stderr.write(f"camjax design: {phase}\n")
                sys.stderr.flush()

        codesign = None
        if scene.motion.designed and scene.design is not None:  # laws and geometry together
            codesign = _codesign(scene, progress)
        progress("computing")
        with ExitStack() as stack:
            # the drawing processes import matplotlib and ezdxf while JAX computes; without them
            # or for an animation they load in a second thread here
            workers = _drawing_workers(stack)
            preload = None
            if workers is None or args.animate:
                preload = threading.Thread(target=_import_drawing_modules, daemon=True)
                preload.start()
            result = runtime.interruptible(analyse, scene if codesign is None else codesign.scene,
                                           base_radius_mm=r)
            extra = None
            if codesign is not None:
                from camjax.output.synthesis import codesign_report

                result.data["synthesis"] = codesign_report(scene, codesign, result.data)
            if preload is not None:
                preload.join()
            if codesign is not None:
                extra = _law_files(codesign, args.dpi)
            extra = _shop_files(scene if codesign is None else codesign.scene, result, args, extra)
            return _write_design(args, out, scene, result, workers, progress, extra)

    return run


def _codesign(scene, progress):
    """The co-design of a scene's designed laws with its [design] geometry
    (:func:`camjax.codesign.codesign_scene`); what it cannot take is bad input (exit 2)."""
    from camjax.codesign import CodesignError, codesign_scene

    progress("co-designing the laws and the geometry")
    try:
        return runtime.interruptible(codesign_scene, scene)
    except CodesignError as exc:
        raise UsageError(f"scene {scene.name}: {exc}") from None


def _shop_files(scene, result, args, extra):
    """The cutter path, G-code, solid and cam table of a scene with [manufacture] or a cam table
    (:mod:`camjax.output.shop`), computed now (a cutter that gouges exits 2 before anything is
    written) and written by the returned ``write(folder) -> names`` after ``extra``'s files; their
    result.json blocks are added to ``result.data``. ``extra`` unchanged when there is nothing."""
    points = args.cam_table_points
    if scene.manufacture is None and points is None and (scene.export is None or
                                                          scene.export.cam_table_points is None):
        return extra
    from camjax.output import shop

    shop_plan = runtime.interruptible(shop.plan, scene, result.data, result.curves, cam_table_points=points,
                                     units=scene.units)
    result.data.update(shop_plan.report)

    def write(folder) -> list[str]:
        return (extra(folder) if extra is not None else []) + shop.write(folder, shop_plan)

    return write


def _drawing_workers(stack):
    """Started :class:`camjax.output.drawing.DrawingWorkers` (closed with ``stack``), or None
    where processes cannot be started or $CAMJAX_DRAWING_PROCESSES is 0 (the figures and the DXF
    are then drawn in this one). $CAMJAX_DRAWING_PROCESSES: how many."""
    from camjax.output.drawing import DrawingWorkers

    count = drawing_processes()
    if count == 0:
        return None
    try:
        return stack.enter_context(DrawingWorkers(count))
    except OSError:
        return None


def _law_files(codesign, dpi: int):
    """``write(folder) -> names``: synthesis.csv and synthesis.png of a co-design's designed laws
    (normalized s, v, a, j; drawn against the best built-in law of each one's class), as
    ``camjax synthesize`` writes them."""
    from camjax.cli.synthesize import law_curves
    from camjax.output.synthesis import synthesis_figure, write_curves_csv

    builtin = codesign.best_builtin[0] if codesign.best_builtin is not None else None
    names = [builtin[k] if builtin is not None else None for k in range(len(codesign.segments))]
    curves, panels = law_curves(codesign.segments, names, "best built-in with its geometry")
    fig = synthesis_figure(panels)

    def write(folder) -> list[str]:
        write_curves_csv(folder / "synthesis.csv", curves)
        fig.savefig(folder / "synthesis.png", dpi=dpi)
        return ["synthesis.csv", "synthesis.png"]

    return write


def _write_design(args, out, scene, result, workers, progress, extra=None) -> int:
    """Check, write and report a computed design run (``camjax design``'s second half)."""
    from camjax import followers
    from camjax.output.animation import UndrawableGeometry, check_drawable
    from camjax.output.export import write_design_files
    from camjax.output.titles import title_block
    from camjax.units import convert_text, report_to

    units = scene.units

    def print(text, **kw):  # every line in the scene's units (numbers written with a unit converted)
        builtins.print(convert_text(text, units), **kw)

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
        write_json(tmp / "result.json", report_to(d, units))
        written = write_design_files(tmp, result.curves, args.dpi, convert_text(banner, units),
                                     convert_text(title_block(d), units), animate=args.animate,
                                     progress=progress, workers=workers, units=units)
        names = ["result.json"] + [p.name for p in written] + (extra(tmp) if extra is not None else [])
    print(f"scene {d['scene']}: min base radius {d['min_base_radius_mm']:.4f} mm at "
          f"{d['min_base_radius_deg']:g} deg")
    follower = followers.of(scene)
    if "design" in d:
        g = d["design"]
        print(f"design ({g['solver']}): R_b = {g['base_radius_mm']:.4f} mm, {follower.summary(g)}, "
              f"objective {g['objective']:.5f}, feasible {g['feasible']}")
        if "certificate" in g:  # the newton solver's
            c = g["certificate"]
            print(f"{c['limited_by']} (KKT residuals {c['stationarity']:.1e}, {c['primal_feasibility']:.1e}, "
                  f"{c['complementarity']:.1e} after {c['iterations']} iterations)")
        if "robust" in g:  # [design] robust: the nominal and the robust optimum on fresh samples
            from camjax.robust.report import design_summary

            print(design_summary(g["robust"]))
    if "synthesis" in d:
        c = d["synthesis"]["codesign"]
        b = c["best_builtin"]
        best = "" if b is None else f"; best built-in ({', '.join(b['law'])}): {b['objective']:.5f}"
        print(f"co-design: laws {c['chosen']}, objective {c['objective']:.5f} on the search grid{best}")
        if c.get("spring") is not None and c["spring"].get("designed", True):
            print(_spring_line(c["spring"]))
        _print_helical((c.get("spring") or {}).get("helical"), units)
    width = follower.drawn_summary(d)
    state = f"INFEASIBLE ({', '.join(broken)})" if broken else "feasible"
    print(f"files drawn at R_b = {at['base_radius_mm']:.4f} mm{width} ({at['source']}): {state}")
    if "closure" in d:  # a groove or conjugate cams
        c = d["closure"]
        switches = ", ".join(f"{a:.4g}" for a in c.get("switch_angles_deg", []))
        print(f"positive drive ({c['kind']}): no spring, no jump analysis"
              + (f"; the load changes contact at {switches} deg" if switches else ""))
    print(f"wrote {', '.join(names)} to {args.out}")
    for v in at["violations"]:
        print(f"camjax design: warning: the geometry written breaks {v['constraint']}: {v['message']}",
              file=sys.stderr)
    return STRICT_EXIT if broken and args.strict else 0


def _print_helical(h, units: str = "mm") -> None:
    """The helical spring sized for the co-design's spring (synthesis.codesign.spring.helical): one
    line, or a warning on stderr where no spring in the ranges works (in the scene's ``units``)."""
    from camjax.units import convert_text

    if h is None:
        return

    def print(text, **kw):
        builtins.print(convert_text(text, units), **kw)
    if h["status"] != "optimal":
        print(f"camjax design: warning: synthesis.helical_spring: {h['message']}", file=sys.stderr)
        return
    print(f"helical spring: wire {h['wire_mm']:.4g} mm, mean coil {h['coil_mm']:.4g} mm, "
          f"{h['active_coils']:.4g} active coils (C = {h['index']:.4g}), {1e3 * h['mass_kg']:.4g} g; "
          f"shear {h['shear_MPa']:.4g} MPa, surge {h['surge_hz']:.4g} Hz "
          f"(>= {h['required_surge_hz']:.4g} Hz); "
          f"binds: {', '.join(h['binding']) or 'none'}")


def _spring_line(sp: dict) -> str:
    """The co-design's designed spring (result.json's ``synthesis.codesign.spring``) in one line: a
    translating follower's in N/m and N, a rocker's (a torsion spring) in N m/rad and N m."""
    at = f"{sp['overspeed']:g} x rpm"
    if "rate_N_m_per_rad" in sp:
        least = sp["min_contact_torque_at_overspeed_N_m"]
        return (f"co-design spring: {sp['rate_N_m_per_rad']:.6g} N m/rad, preload "
                f"{sp['preload_N_m']:.6g} N m ({sp['preload_rad']:.6g} rad); least contact torque "
                f"{least:.6g} N m at {at} (margin "
                f"{sp['min_contact_torque_N_m']:g} N m, binds: {sp['binding']})")
    least = sp["min_contact_force_at_overspeed_N"]
    return (f"co-design spring: {sp['rate_N_per_m']:.6g} N/m, preload {sp['preload_N']:.6g} N "
            f"({sp['preload_mm']:.6g} mm); least contact force {least:.6g} N at {at} "
            f"(margin {sp['min_contact_force_N']:g} N, binds: {sp['binding']})")


def _import_drawing_modules() -> None:
    """Import what drawing and the DXF need (run in a thread beside the computation)."""
    import ezdxf  # noqa: F401
    import matplotlib.backends.backend_agg  # noqa: F401

    import camjax.output.plots  # noqa: F401


