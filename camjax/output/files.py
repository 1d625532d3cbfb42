"""Writing a job's files: strict JSON, and a staging folder so a failed job leaves nothing behind."""

from __future__ import annotations

import contextlib
import json
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def staged_output(out_dir: str | Path) -> Iterator[Path]:
    """Write into a temporary folder; move the files into ``out_dir`` only if the block succeeds."""
    out = Path(out_dir)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".camjax-", dir=out.parent))
    try:
        yield tmp
        out.mkdir(parents=True, exist_ok=True)
        for item in tmp.iterdir():
            target = out / item.name
            if target.is_dir():
                shutil.rmtree(target)
            shutil.move(str(item), target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def write_json(path: Path, data) -> None:
    """JSON with a trailing newline; NaN/inf are refused (they would not be valid JSON)."""
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")
