"""The output folder of a command: checked before any work, written aside, swapped in whole.

Every command that writes a folder (``design``, ``sweep``, ``dynamics``, ``check-extremes``) and
``laws --json`` (one file) goes through this module:

1. :func:`check_output_dir` / :func:`check_output_file` run before any computation: an empty path,
   a file where a folder is wanted (or a folder where a file is), a path under a file, a link
   whose target is missing, a parent in which nothing can be made (tried: an empty folder is made
   and removed there), or a non-empty folder that camjax did not write is one
   :class:`OutputError` (the CLI prints it and exits 2).
2. :func:`replaced_folder` yields a staging folder ``.<DIR>.camjax-staging-<pid>`` beside DIR;
   when the block succeeds the old DIR is renamed aside (``.<DIR>.camjax-old-<pid>``), the staging
   folder renamed into place and the old one deleted. Afterwards DIR holds exactly this run's
   files; on any exception (an interrupt included) it holds exactly what it held before and the
   staging folder is gone. SIGINT/SIGTERM are blocked during the two renames, so an interrupt
   cannot fall between them.
3. A staging or set-aside folder left by a killed run (SIGKILL, power loss) is cleaned by the next
   run into the same place once its process is gone: a set-aside DIR is renamed back when DIR is
   missing, every other leftover is deleted.
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
import shutil
import signal
from collections.abc import Iterator
from pathlib import Path

from camjax.scene import quote

STAGING = "camjax-staging"
OLD = "camjax-old"
PROBE = "camjax-probe"  # the empty folder made and removed to learn that a place is writable
# A folder holding one of these was written by camjax (or is empty) and may be replaced whole;
# any other non-empty folder is refused rather than deleted (e.g. --out ~ or --out .).
OUTPUT_MARKERS = ("result.json", "pareto.json", "extremes.json", "dynamics.json", "manifest.json",
                  "robust.json")


class OutputError(ValueError):
    """An output location that cannot be used; the message names the option and the path."""


def _leftover_name(out: Path, kind: str, pid: int) -> Path:
    return out.parent / f".{out.name}.{kind}-{pid}"


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return False  # ours from an earlier (failed) run in this process: not in use now
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # another user's process (or a pid we cannot ask about): leave it alone
    return True


def clean_stale(out: Path) -> None:
    """Remove staging folders of dead runs beside ``out``; put back a DIR a killed run set aside."""
    pattern = re.compile(rf"^\.{re.escape(out.name)}\.({STAGING}|{OLD})-(\d+)$")
    try:
        entries = list(out.parent.iterdir())
    except OSError:
        return
    for entry in entries:
        m = pattern.match(entry.name)
        if not m or _pid_alive(int(m.group(2))):
            continue
        if m.group(1) == OLD and not out.exists():
            os.replace(entry, out)  # killed between the two renames: DIR comes back as it was
        else:
            shutil.rmtree(entry, ignore_errors=True)


def _display(option: str, path: str) -> str:
    return f"{option} = {quote(path)}"


def _check_parent(option: str, text: str, out: Path) -> None:
    """The nearest existing ancestor of ``out`` must be a folder we can write in."""
    parent = out.parent
    while not parent.exists():
        if parent.is_symlink():  # a dangling link: mkdir would fail
            raise OutputError(f"{_display(option, text)}: {parent} is a broken link")
        parent = parent.parent
    if not parent.is_dir():
        raise OutputError(f"{_display(option, text)}: {parent} is a file, not a folder "
                          "(allowed: a path whose parents are folders)")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{_display(option, text)}: cannot write in {parent} (permission denied)")
    _probe(option, text, parent)


def _probe(option: str, text: str, parent: Path) -> None:
    """Create and remove an empty folder in ``parent``: the staging folder will be made there.

    ``os.access`` answers from the permission bits only; it says yes for root everywhere, and for a
    read-only file system, /proc or /sys, where making anything fails. Trying is the only answer
    that holds, and it costs a millisecond before a run of seconds.
    """
    import tempfile

    try:
        os.rmdir(tempfile.mkdtemp(prefix=f".{PROBE}-", dir=parent))
    except OSError as exc:
        raise OutputError(f"{_display(option, text)}: cannot write in {parent} "
                          f"({exc.strerror or type(exc).__name__})") from None


def _absolute(option: str, text: str) -> Path:
    if not text.strip():
        raise OutputError(f"{option} = {text!r}: empty path (allowed: a folder name or path)")
    if "\x00" in text:
        raise OutputError(f"{_display(option, text)}: a path cannot hold a NUL character")
    out = Path(os.path.abspath(os.path.expanduser(text)))
    if out.parent == out:
        raise OutputError(f"{_display(option, text)}: the root folder cannot be replaced "
                          "(allowed: a folder below it)")
    return out


def _checked(check):
    """An OSError while looking at the path (name too long, I/O error) is one :class:`OutputError`."""

    @functools.wraps(check)
    def wrapper(text: str, option: str = "--out", *args, **kwargs) -> Path:
        try:
            return check(text, option, *args, **kwargs)
        except OSError as exc:
            raise OutputError(f"{_display(option, text)}: {exc.strerror or exc}") from None

    return wrapper


@_checked
def check_output_dir(text: str, option: str = "--out", replace: bool = True) -> Path:
    """The absolute output folder for ``text``, or :class:`OutputError` saying why it cannot be.

    ``replace``: the folder will be replaced whole, so an existing non-empty folder must be one
    camjax wrote (it holds one of :data:`OUTPUT_MARKERS`).
    """
    out = _absolute(option, text)
    if replace and out in (cwd := Path.cwd(), *cwd.parents):
        raise OutputError(f"{_display(option, text)}: is the current folder or holds it; it would be "
                          "replaced whole (allowed: a folder below the current one, e.g. out)")
    if out.is_symlink() and not out.exists():
        raise OutputError(f"{_display(option, text)}: is a link whose target is missing "
                          f"({quote(os.readlink(out))}) (allowed: a new folder, one camjax wrote, or "
                          "a link to an existing folder)")
    if out.exists():
        if not out.is_dir():
            raise OutputError(f"{_display(option, text)}: is a file, not a folder "
                              "(allowed: a new folder or one camjax wrote)")
        if not os.access(out, os.W_OK | os.X_OK):
            raise OutputError(f"{_display(option, text)}: cannot write in this folder (permission denied)")
        if replace:
            if out.is_symlink():
                raise OutputError(f"{_display(option, text)}: is a link; it would be replaced by a "
                                  "folder (allowed: the folder it points to)")
            try:
                names = {p.name for p in out.iterdir()}
            except OSError as exc:
                raise OutputError(f"{_display(option, text)}: cannot list it ({exc.strerror})") from None
            if names and not names & set(OUTPUT_MARKERS):
                raise OutputError(f"{_display(option, text)}: holds files camjax did not write; it "
                                  "would be replaced whole (allowed: a new or empty folder, or one "
                                  "camjax wrote)")
    _check_parent(option, text, out)
    return out


@_checked
def check_output_file(text: str, option: str) -> Path:
    """The absolute path of a file to write, or :class:`OutputError` saying why it cannot be."""
    out = _absolute(option, text)
    if out.is_dir():
        raise OutputError(f"{_display(option, text)}: is a folder (allowed: a file path)")
    if out.exists() and not os.access(out, os.W_OK):
        raise OutputError(f"{_display(option, text)}: cannot write this file (permission denied)")
    _check_parent(option, text, out)
    return out


@contextlib.contextmanager
def _signals_blocked() -> Iterator[None]:
    """SIGINT and SIGTERM wait (they are delivered at the end) while the block runs."""
    sigs = {signal.SIGINT, signal.SIGTERM}
    old = signal.pthread_sigmask(signal.SIG_BLOCK, sigs)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def swap_in(staging: Path, out: Path, keep: tuple[str, ...] = ()) -> None:
    """Replace folder ``out`` (if any) by ``staging``; on failure ``out`` is as it was.

    ``keep``: names of entries of ``out`` carried over into the new folder (moved into ``staging``
    first, each by one rename, unless ``staging`` has its own); everything else of ``out`` goes.
    """
    old = _leftover_name(out, OLD, os.getpid()) if out.exists() else None
    with _signals_blocked():
        moved: list[str] = []
        try:
            for name in keep if old is not None else ():
                if (out / name).exists() and not (staging / name).exists():
                    os.replace(out / name, staging / name)
                    moved.append(name)
            if old is not None:
                if old.exists():
                    shutil.rmtree(old)
                os.replace(out, old)
            try:
                os.replace(staging, out)
            except BaseException:
                if old is not None:
                    os.replace(old, out)
                raise
        except BaseException:
            for name in moved:  # ``out`` is the old folder again: its kept entries go back
                os.replace(staging / name, out / name)
            raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _fresh_staging(out: Path) -> Path:
    """An empty staging folder beside ``out`` for this process, stale ones of dead runs removed."""
    clean_stale(out)
    staging = _leftover_name(out, STAGING, os.getpid())
    if staging.exists():
        shutil.rmtree(staging)
    staging.mkdir()
    return staging


@contextlib.contextmanager
def replaced_folder(out: str | Path, keep: tuple[str, ...] = ()) -> Iterator[Path]:
    """Yield an empty staging folder; replace ``out`` with it when the block succeeds.

    ``out`` should have passed :func:`check_output_dir`. Missing parents are created. ``keep``:
    entries of ``out`` that the new folder takes over (a block sweep's checkpoint, written into
    ``out`` while it ran: ``manifest.json`` and ``blocks/``); nothing else of ``out`` is left.
    """
    out = Path(os.path.abspath(out))
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = _fresh_staging(out)
    try:
        yield staging
        swap_in(staging, out, keep)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def write_file_atomic(path: Path, write) -> None:
    """``write(tmp_path)`` then rename onto ``path``: the file is whole or as it was."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = _leftover_name(path, STAGING, os.getpid())
    try:
        write(tmp)
        with _signals_blocked():
            os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
