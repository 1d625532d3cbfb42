"""What every command shares: the registry of subcommands, the usage error, and the options that
several commands take (--samples, --mode/--solver/--seed/--alpha/--gamma, --dpi)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from camjax.scene import SceneError, quote

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
                   help="augmented-Lagrangian gradient solver, vectorized GA, GA + interior-point polish, "
                   "or primal-dual interior point (newton)" + tail)
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




def warn_starting_laws(scene, command: str) -> None:
    """One warning line on stderr when the scene has designed segments (``design = true``): this
    command moves them by their starting laws, not by designed ones (``camjax synthesize`` designs
    the laws alone, ``camjax design`` with the geometry)."""
    import sys

    if not scene.motion.designed:
        return
    where = ", ".join(ds.path for ds in scene.motion.designed)
    print(f"camjax {command}: warning: {where} {'has' if len(scene.motion.designed) == 1 else 'have'} "
          "design = true: this command moves them by their starting laws (the control values nearest "
          "the uniform law's that meet their conditions); camjax synthesize designs the laws, camjax "
          "design designs them with the cam", file=sys.stderr)
