"""Griffe extension for the API pages: Sphinx roles in docstrings rendered as code.

The docstrings name other objects the Sphinx way (``:func:`solve```, ``:class:`~camjax.followers.flat.problem.Design```);
Markdown has no such roles, so this rewrites them to code spans at build time (``solve``, ``Design``)
without touching the source.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

_ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|attr|data|obj|exc|const):`(~?)([^`<]+?)`")


def _plain(match: re.Match) -> str:
    tilde, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if tilde else target}`"


class SphinxRoles(griffe.Extension):
    """Rewrite ``:role:`target``` to a Markdown code span in every docstring."""

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        if obj.docstring is not None:
            obj.docstring.value = _ROLE.sub(_plain, obj.docstring.value)
