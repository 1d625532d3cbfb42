"""Figures, the profile CSV and the DXF written by processes of their own, started before the
computation they draw.

Drawing a design's four PNG figures takes about as long on 2 CPU cores as computing the design
when JAX's caches are warm, and importing matplotlib and ezdxf half of that again.
:class:`DrawingWorkers` starts fresh Python processes that import NumPy, matplotlib and ezdxf (not
JAX: they enter the camjax package without running its ``__init__``) while the caller computes;
:meth:`DrawingWorkers.draw` then hands them the curves and each draws and writes its share of
the figures of the follower's ``figure_builders`` (:func:`camjax.followers.drawing`); the last
one also writes profile.csv (its ``profile_table``) and profile.dxf, so that the calling process
never imports a drawing module, nor matplotlib with it. The files are the ones
:func:`camjax.output.export.write_figures`, :func:`camjax.output.export.write_profile_csv` and
:func:`camjax.output.export.write_profile_dxf` write in-process, byte for byte.

A worker that cannot start, or fails, is reported as an exception from :meth:`DrawingWorkers.wait`
(one line); :meth:`DrawingWorkers.close` ends every worker still running (the caller's ``with``).
"""

from __future__ import annotations

import pickle
import subprocess
import sys
import types
from pathlib import Path

# A worker: this very camjax first on its path (``import camjax`` loads no JAX, so the figure
# modules are all it imports), then serve(k, n).
_BOOT = ("import sys; sys.path.insert(0, sys.argv[1]); from camjax.output.drawing import serve; "
         "serve(int(sys.argv[2]), int(sys.argv[3]))")
PACKAGE_DIR = Path(__file__).resolve().parent.parent
DEFAULT_PROCESSES = 2  # on 2 cores: two figures drawn at a time once the computation is done
MAX_PROCESSES = 16


class DrawingError(RuntimeError):
    """A figure worker failed: its one-line reason."""


class DrawingWorkers:
    """``count`` drawing processes, started now, importing matplotlib and ezdxf while the caller
    computes.

    Use as a context manager; :meth:`draw` once, then :meth:`wait` for the written paths.
    """

    def __init__(self, count: int = DEFAULT_PROCESSES):
        self._procs: list[subprocess.Popen] = []
        try:
            for k in range(count):
                self._procs.append(subprocess.Popen(
                    [sys.executable, "-c", _BOOT, str(PACKAGE_DIR.parent), str(k), str(count)],
                    stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                    start_new_session=True))
        except OSError:
            self.close()
            raise

    def draw(self, folder: str | Path, curves, dpi: int = 100, banner: str | None = None,
             title: str = "", units: str = "mm") -> None:
        """Send the job: worker k of n draws figures k, k + n, ... and the last one also writes
        profile.csv and profile.dxf, of the curves into ``folder`` (``curves``: a follower
        family's curves, e.g. :class:`camjax.followers._translating.DesignCurves`; the rest as
        :func:`camjax.output.export.write_figures`; ``units``: the curves', which the figures, the
        CSV and the DXF then name)."""
        fields = {k: _plain(v) for k, v in curves._asdict().items()}
        job = pickle.dumps({"folder": str(folder), "curves": fields, "dpi": dpi, "banner": banner,
                            "title": title, "units": units})
        for proc in self._procs:
            try:
                proc.stdin.write(job)
                proc.stdin.close()
            except OSError:  # the worker is gone: wait() says why
                pass

    def wait(self) -> list[Path]:
        """The written files: the figures in the follower's ``figure_builders`` order, then
        profile.csv and profile.dxf; :class:`DrawingError` if a worker failed."""
        written: dict[int, Path] = {}
        for proc in self._procs:
            out = proc.stdout.read()
            code = proc.wait()
            try:
                reply = pickle.loads(out)
            except Exception:
                raise DrawingError(f"a drawing process exited with status {code} and no reply") from None
            if "error" in reply:
                raise DrawingError(f"drawing the figures and the DXF failed: {reply['error']}")
            written.update({int(i): Path(p) for i, p in reply["written"]})
        return [written[i] for i in sorted(written)]

    def close(self) -> None:
        """End every worker still running (after :meth:`wait` there are none)."""
        for proc in self._procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            for stream in (proc.stdin, proc.stdout):
                if stream is not None and not stream.closed:
                    stream.close()

    def __enter__(self) -> DrawingWorkers:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _plain(value):
    """A curve field as something a worker unpickles without JAX: NumPy arrays, floats, str."""
    if value is None or isinstance(value, (str, bool, int, float)):
        return value
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (tuple, list)):
        return type(value)(_plain(v) for v in value)
    import numpy as np

    return np.asarray(value)


def serve(k: int = 0, n: int = 1) -> None:
    """Worker ``k`` of ``n``: import matplotlib (and ezdxf, the last worker, which writes the
    CSV and the DXF), read one job from stdin, draw figures k, k + n, ..., reply on stdout (pickled
    ``{"written": [(index, path), ...]}`` or ``{"error": "one line"}``; the CSV's and the DXF's
    indices follow the figures')."""
    writes_dxf = k == n - 1
    if writes_dxf:
        import ezdxf  # noqa: F401  (imported before the job arrives, as matplotlib)
    from matplotlib.backends import backend_agg  # noqa: F401

    from camjax import followers
    from camjax.output import export

    reply: dict
    try:
        job = pickle.loads(sys.stdin.buffer.read())
        curves = types.SimpleNamespace(**job["curves"])
        folder = Path(job["folder"])
        figures = list(followers.drawing(curves.follower_type).figure_builders(curves).items())
        written = []
        for i, (name, build) in enumerate(figures):
            if i % n != k:
                continue
            path = export.save_figure(build(curves, job["title"]), folder / name, job["dpi"], job["banner"],
                                      job["units"])
            written.append((i, str(path)))
        if writes_dxf:
            # after the figures, the CSV then the DXF, as write_design_files writes them in-process
            csv = export.write_profile_csv(folder / export.PROFILE_CSV, curves, job["units"])
            dxf = export.write_profile_dxf(folder / export.PROFILE_DXF, curves, job["units"])
            written += [(len(figures), str(csv)), (len(figures) + 1, str(dxf))]
        reply = {"written": written}
    except BaseException as exc:  # reported to the caller as one line
        reply = {"error": f"{type(exc).__name__}: {exc}"[:300]}
    sys.stdout.buffer.write(pickle.dumps(reply))
    sys.stdout.buffer.flush()
