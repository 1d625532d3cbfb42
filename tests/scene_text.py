"""A scene written back as TOML text, for tests that edit a parsed scene and run it as a file."""

from __future__ import annotations

import json


def toml_of(data: dict) -> str:
    """A scene dict as TOML (numbers, strings, lists and inline tables: what the scenes hold)."""
    def value(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        return repr(v)

    return "\n".join(f"[{name}]\n" + "\n".join(f"{k} = {value(v)}" for k, v in table.items()) + "\n"
                     for name, table in data.items())
