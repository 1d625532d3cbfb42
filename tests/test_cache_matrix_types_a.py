"""The saved-program cache against the same programs traced afresh for the runs that trace each
follower type's own code (tests/cache_matrix.py: own_runs), share 1 of 2 of the types (two
files: two workers)."""

import pytest
from cache_matrix import _check_sequence, followers_share, own_runs


@pytest.mark.slow
@pytest.mark.parametrize("follower", followers_share(0, 2))
def test_the_types_own_runs_give_the_freshly_traced_result(follower, tmp_path, quiet_files, monkeypatch):
    _check_sequence(own_runs(follower, tmp_path), tmp_path, monkeypatch)
