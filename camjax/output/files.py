"""Strict JSON files (the output folder itself is staged and swapped by :mod:`camjax.output.folder`)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from camjax.numerics import NonFiniteError


def write_json(path: Path, data) -> None:
    """JSON with a trailing newline; NaN/inf are refused (they would not be valid JSON).

    Raises :class:`camjax.numerics.NonFiniteError` naming the first key that holds one.
    """
    try:
        text = json.dumps(data, indent=2, allow_nan=False)
    except ValueError:
        raise NonFiniteError(f"non-finite value at {non_finite_key(data)} of {path.name}") from None
    path.write_text(text + "\n")


def non_finite_key(data, at: str = "") -> str | None:
    """Dotted path of the first inf or NaN in nested dicts and lists (None when there is none)."""
    if isinstance(data, float) and not math.isfinite(data):
        return at or "the top level"
    if isinstance(data, dict):
        items = data.items()
    else:
        items = enumerate(data) if isinstance(data, list | tuple) else ()
    for key, value in items:
        found = non_finite_key(value, f"{at}[{key}]" if isinstance(key, int) else f"{at}.{key}".lstrip("."))
        if found:
            return found
    return None
