"""The environment a command runs in, checked before any work: every variable camjax reads, and the
platform JAX is asked to run on. A bad setting is one :class:`~camjax.cli.common.UsageError`
naming the variable, its value and what is allowed (exit status 2).

=============================  ===================================================================
variable                       allowed
=============================  ===================================================================
``CAMJAX_DRAWING_PROCESSES``   an ASCII integer 0 to 16 (0: draw in the command's own process)
``CAMJAX_PROGRESS``            ``1`` progress on stderr, ``0`` none, unset or empty: on a terminal
``CAMJAX_DEBUG``               ``1`` tracebacks of unexpected errors, ``0`` or unset: one line
``CAMJAX_PROGRAM_CACHE_VERIFY``  ``1`` trace every saved program again and compare, ``0`` or unset
``CAMJAX_COMPILATION_CACHE``   ``0`` or empty (off), or a folder path (not an existing file)
``CAMJAX_PROGRAM_CACHE``       ``0`` or empty (off), or a folder path (not an existing file)
``CAMJAX_XLA_FLAGS``           ``0`` XLA_FLAGS left as set, ``1`` or unset: camjax's CPU flags added
``CAMJAX_COMPILE_AHEAD``       ``0`` one compiling thread, ``1`` or unset: the drawing's programs compiled
                               beside the solver's where there are two cores (``camjax.runtime.ahead``)
``JAX_PLATFORMS``              platforms JAX can start on this machine (e.g. ``cpu``), or unset
=============================  ===================================================================
"""

from __future__ import annotations

import os
import sys

from camjax.cli.common import UsageError
from camjax.scene import cut, quote

FLAGS = ("CAMJAX_PROGRESS", "CAMJAX_DEBUG", "CAMJAX_PROGRAM_CACHE_VERIFY", "CAMJAX_XLA_FLAGS",
         "CAMJAX_COMPILE_AHEAD")
FOLDERS = ("CAMJAX_COMPILATION_CACHE", "CAMJAX_PROGRAM_CACHE")
PLATFORMS = "JAX_PLATFORMS"


def _shown(name: str, text: str) -> str:
    return f"{name} = {quote(text)}"


def drawing_processes() -> int:
    """``$CAMJAX_DRAWING_PROCESSES`` (default :data:`camjax.output.drawing.DEFAULT_PROCESSES`):
    an ASCII integer 0 to :data:`~camjax.output.drawing.MAX_PROCESSES`, else :class:`UsageError`.

    ``str.isdigit`` alone would take '²' or '٣' (Unicode digits) that ``int`` then refuses or reads
    as another number; only the characters 0-9 are a count here.
    """
    from camjax.output.drawing import DEFAULT_PROCESSES, MAX_PROCESSES

    name = "CAMJAX_DRAWING_PROCESSES"
    text = os.environ.get(name, str(DEFAULT_PROCESSES))
    digits = text.strip()
    if not (digits.isascii() and digits.isdigit() and len(digits) <= 3 and int(digits) <= MAX_PROCESSES):
        raise UsageError(f"{_shown(name, text)}: not a count (allowed: 0 to {MAX_PROCESSES}, ASCII "
                         "digits; 0 draws in the command's own process)")
    return int(digits)


def flag(name: str) -> bool | None:
    """A 0/1 variable: True for ``1``, False for ``0``, None when unset or empty; else
    :class:`UsageError`."""
    text = os.environ.get(name)
    if text is None or text == "":
        return None
    if text.strip() not in ("0", "1"):
        raise UsageError(f"{_shown(name, text)}: not a switch (allowed: 1 on, 0 off, or unset)")
    return text.strip() == "1"


def show_progress() -> bool:
    """Whether a command reports its progress on stderr: ``$CAMJAX_PROGRESS`` when set, else
    whether stderr is a terminal (piped, stderr keeps its contract of one line on failure)."""
    wanted = flag("CAMJAX_PROGRESS")
    return sys.stderr.isatty() if wanted is None else wanted


def _check_folder(name: str) -> None:
    text = os.environ.get(name)
    if text is None or text in ("", "0"):
        return
    if "\x00" in text:  # pragma: no cover  (the OS does not pass NUL in the environment)
        raise UsageError(f"{_shown(name, text)}: a path cannot hold a NUL character")
    path = os.path.expanduser(text)
    try:
        is_file = os.path.exists(path) and not os.path.isdir(path)
    except (OSError, ValueError) as exc:
        raise UsageError(f"{_shown(name, text)}: cannot be used as a path ({exc})") from None
    if is_file:
        raise UsageError(f"{_shown(name, text)}: is a file, not a folder (allowed: 0 to switch the "
                         "cache off, or a folder path)")


def _check_platform() -> None:
    """Start JAX's backend now, so that a platform this machine lacks is one line naming the
    setting, not an internal error in the middle of the first computation."""
    import jax

    try:
        jax.devices()
    except Exception as exc:  # noqa: BLE001  (JAX raises RuntimeError, or AssertionError for cuda)
        given = os.environ.get(PLATFORMS)
        if given is None and not jax.config.jax_platforms:
            raise  # not a setting of the user's: a failure while running
        name, value = (PLATFORMS, given) if given is not None else ("jax_platforms", jax.config.jax_platforms)
        reason = cut(str(exc).split(" (set JAX_PLATFORMS")[0], 200) or type(exc).__name__
        raise UsageError(f"{_shown(name, value)}: JAX cannot start this platform here ({reason}) "
                         "(allowed: a platform this machine has, e.g. cpu, or unset to let JAX "
                         "choose)") from None


def check_environment() -> None:
    """Every setting above, in the order listed; the first bad one is a :class:`UsageError`."""
    drawing_processes()
    for name in FLAGS:
        flag(name)
    for name in FOLDERS:
        _check_folder(name)
    _check_platform()
