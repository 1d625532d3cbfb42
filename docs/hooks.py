"""MkDocs hook: measured figures in the pages come from the committed JSON (docs/gen_tables.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

_GEN_TABLES = Path(__file__).with_name("gen_tables.py")  # docs/ is not a package: load it by path
_spec = importlib.util.spec_from_file_location("camjax_docs_gen_tables", _GEN_TABLES)
gen_tables = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(gen_tables)


def on_page_markdown(markdown, page, config, files):
    """Replace the table and value placeholders of a page by figures read from the JSON."""
    return gen_tables.render(markdown, page.file.src_uri)
