"""``python -m camjax.cli``: the ``camjax`` command."""

from camjax.cli import entry

entry()
