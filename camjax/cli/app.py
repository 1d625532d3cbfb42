"""The command line's parser, its commands and :func:`main` (loaded by :mod:`camjax.cli` when a
command runs: the commands import JAX)."""

from __future__ import annotations

import _thread
import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable

import camjax  # noqa: F401  (turns on x64 before any array is made)
from camjax import runtime

# the commands register themselves, in the order of `camjax --help`
from camjax.cli import check_extremes, design, dynamics, laws, robust, sweep, synthesize  # noqa: F401
from camjax.cli.common import COMMANDS, STRICT_EXIT, UsageError
from camjax.cli.environment import check_environment
from camjax.numerics import NonFiniteError
from camjax.output.folder import OutputError
from camjax.scene import SceneError, cut

# as `camjax --help` lists them
HELP_ORDER = ("laws", "design", "synthesize", "sweep", "check-extremes", "dynamics", "robust")

__all__ = ["COMMANDS", "STRICT_EXIT", "UsageError", "build_parser", "entry", "main"]


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
    for name in sorted(COMMANDS, key=lambda n: HELP_ORDER.index(n) if n in HELP_ORDER else len(HELP_ORDER)):
        help_text, setup = COMMANDS[name]
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
        check_environment()  # the variables camjax reads and JAX's platform, before any work
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
        if os.environ.get("CAMJAX_DEBUG", "").strip() == "1":
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

