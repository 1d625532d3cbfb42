"""What the co-design tests share: ``camjax design`` of a co-design scene run once, keeping the
co-design it computed on the way, so that one search serves the command's end-to-end checks and the
checks of the search itself (a second search of the same scene would repeat the first)."""

from __future__ import annotations

import contextlib
import io

import pytest

from camjax.cli import main


def design_keeping_codesign(args: list[str]):
    """``camjax design`` with ``args`` (exit 0 asserted) and the co-design it computed
    (:func:`camjax.codesign.codesign_scene`'s :class:`~camjax.codesign.Outcome`, kept as it
    returns) and its stdout: (outcome, stdout)."""
    import camjax.codesign

    outcomes = []
    search = camjax.codesign.codesign_scene

    def kept(scene, *more, **kwargs):
        outcomes.append(search(scene, *more, **kwargs))
        return outcomes[-1]

    stdout = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(stdout):
        mp.setattr(camjax.codesign, "codesign_scene", kept)
        assert main(["design", *args]) == 0
    assert len(outcomes) == 1
    return outcomes[0], stdout.getvalue()
