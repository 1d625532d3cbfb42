"""The ``camjax`` command line. One subcommand per job; each replaces its output folder whole.

One module per command (:mod:`camjax.cli.laws`, :mod:`~camjax.cli.design`, :mod:`~camjax.cli.sweep`,
:mod:`~camjax.cli.check_extremes`, :mod:`~camjax.cli.dynamics`,
:mod:`~camjax.cli.synthesize`); each registers itself in ``COMMANDS``
with :func:`camjax.cli.common.command`: a function that adds its arguments to an argparse parser
and returns the function that runs it. What several commands share is in :mod:`camjax.cli.common`.

Exit status: 0 done; 2 bad input (scene, arguments or output location: one line naming the
field, checked before any computation, nothing written); 3 ``design --strict`` wrote geometry that
breaks a constraint; 1 a failure while running (one line; ``CAMJAX_DEBUG=1`` shows the
traceback); 130 interrupted (Ctrl-C), 143 terminated (SIGTERM). The output folder holds exactly
the new run's files, or, on any failure or interruption, exactly what it held before
(:mod:`camjax.output.folder`).
"""

from __future__ import annotations

__all__ = ["COMMANDS", "STRICT_EXIT", "UsageError", "build_parser", "entry", "main"]


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (see the module docstring). Never a traceback:
    every failure is one line on stderr (``CAMJAX_DEBUG=1`` re-raises unexpected errors)."""
    from camjax.cli.app import main as run

    return run(argv)


def build_parser():
    """The ``camjax`` argument parser, every command registered."""
    from camjax.cli.app import build_parser as build

    return build()


def entry() -> None:
    """The ``camjax`` command (and ``python -m camjax.cli``).

    The command line's own set-up happens here, not at ``import camjax``: until the commands'
    handlers are installed, Ctrl-C or SIGTERM ends the process with one line instead of a traceback
    from inside ``import jax``; XLA's CPU flags are chosen (:func:`camjax.runtime.use_cpu_xla_flags`)
    and full garbage collections made rarer (:func:`camjax.runtime.fewer_full_collections`);
    then :func:`camjax.cli.app.entry` runs the command.
    """
    from camjax.cli.timings import mark_entry
    from camjax.runtime import fewer_full_collections, quiet_startup_interrupts, use_cpu_xla_flags

    mark_entry()  # the start of ``--timings``' first phase
    quiet_startup_interrupts()
    use_cpu_xla_flags()  # before JAX starts its backend
    fewer_full_collections()
    from camjax.cli.app import entry as run

    run()


def __getattr__(name):
    if name in ("COMMANDS", "STRICT_EXIT", "UsageError"):  # the commands registered: the app loaded
        from camjax.cli import app

        return getattr(app, name)
    raise AttributeError(f"module 'camjax.cli' has no attribute {name!r}")
