"""The error a bad scene raises, and how a message quotes what it was given (one readable line).

Low in the package (imports nothing of camjax) so that every module that reads a scene's data can
raise it: the scene parser, the laws' own parsers, the followers' sections.
"""

from __future__ import annotations

from typing import Any

MISSING = object()  # a key the scene does not give (a message then shows no value)


class SceneError(ValueError):
    """A scene that cannot be used. ``field`` is the dotted path of the offending key."""

    def __init__(self, field: str, value: Any, problem: str, allowed: str | None = None,
                 source: str | None = None):
        self.field, self.value, self.problem, self.allowed = field, value, problem, allowed
        self.source = source
        where = f"{cut(source)}: " if source else ""
        shown = "" if value is MISSING else f" = {quote(value)}"
        tail = f" (allowed: {cut(allowed, 4 * QUOTE_CHARS)})" if allowed else ""
        super().__init__(f"{where}{cut(field)}{shown}: {cut(problem, 4 * QUOTE_CHARS)}{tail}")


QUOTE_CHARS = 100  # a message quotes at most this many characters of a value (one readable line)


def cut(text: str, limit: int = QUOTE_CHARS) -> str:
    """``text`` cut to about ``limit`` characters for a one-line message, saying how long it was.

    An unknown 50 MB section name must not become a 50 MB error line.
    """
    head = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text[:limit])  # one line
    return head if len(text) <= limit else f"{head}... ({len(text)} characters)"


def quote(value: Any, limit: int = QUOTE_CHARS) -> str:
    """``repr(value)`` cut by :func:`cut`."""
    return cut(repr(value), limit)
