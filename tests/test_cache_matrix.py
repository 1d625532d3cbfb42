"""The saved-program cache against the same programs traced afresh (tests/cache_matrix.py says
how): the full sequence of one follower type, the quick sequence of another (its own runs among
them), and the dynamics command. Every other follower type's own runs:
tests/test_cache_matrix_types_*.py."""

from __future__ import annotations

import pytest
from cache_matrix import _check_sequence, _edit, full_runs, quick_runs


@pytest.mark.slow
def test_flat_face_mode_solver_and_seed_never_reuse_another_runs_program(tmp_path, quiet_files, monkeypatch):
    """The runs the stale cache got wrong (a pointwise run after a global one, a GA run after
    another seed), in one folder with the type's own runs, then again in reverse order with every
    program loaded."""
    runs, warm = quick_runs(tmp_path)
    _check_sequence(runs, tmp_path, monkeypatch, warm)


@pytest.mark.slow
def test_every_option_scene_edit_and_sweep_gives_the_freshly_traced_result(tmp_path, quiet_files, monkeypatch):
    # one pass in order: every program saved by an earlier run of the sequence is loaded by the
    # later runs that share its key (the flat face's test above adds the reverse, all-warm pass;
    # cache_matrix.full_runs: the runs of the sequence left out, and why)
    _check_sequence(full_runs(tmp_path), tmp_path, monkeypatch)


@pytest.mark.slow
def test_dynamics_with_its_scene_edited_gives_the_freshly_traced_result(tmp_path, monkeypatch):
    from camjax.scene import builtin_scene_text

    # the bench with ten times its load's damping: the same programs (the cycle count is data),
    # its RK4 runs 23 cycles to settle instead of 215 (the eight runs 44 -> 30 CPU s)
    text = _edit(builtin_scene_text("thesis-bench"), ("c3 = 0.205", "c3 = 2.05"))
    # two edits left out run the same programs on the same argument values as the scene itself
    # (measured: each run's program keys and the digests of the arguments each program ran on):
    # fewer outputs in `compute` (a subset of its programs) and other [motion] samples (the
    # dynamics runs on a grid of its own)
    edits = [None, ("I3 = 0.357", "I3 = 0.394"), ("rpm = 177.6", "rpm = 160.0")]
    runs = []
    for k, edit in enumerate(edits):
        path = tmp_path / f"bench{k}.toml"
        path.write_text(text if edit is None else _edit(text, edit))
        runs.append(["dynamics", str(path)])
    # the inertia edit is a value: its run saves no program of its own, so it already ran with every
    # program loaded from the folder; the scene's own run and the speed's (which saves one program
    # of its own) then run again with every program loaded
    saved = _check_sequence(runs, tmp_path, monkeypatch, warm=[0, 2])
    assert saved[1] == saved[0], saved
