"""Strict JSON files (the output folder itself is staged and swapped by :mod:`camjax.output.folder`)."""

from __future__ import annotations

import json
from pathlib import Path


def write_json(path: Path, data) -> None:
    """JSON with a trailing newline; NaN/inf are refused (they would not be valid JSON)."""
    path.write_text(json.dumps(data, indent=2, allow_nan=False) + "\n")
