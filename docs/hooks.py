"""MkDocs hooks: measured figures and lists in the pages come from the committed JSON and the
registries (docs/gen_tables.py); the architecture figure is drawn from the code being documented
(docs/gen_architecture.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

_DOCS = Path(__file__).parent


def _load(name: str):
    """A script of docs/ as a module (docs/ is not a package: load it by path)."""
    spec = importlib.util.spec_from_file_location(f"camjax_docs_{name}", _DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gen_tables = _load("gen_tables")


def on_page_markdown(markdown, page, config, files):
    """Replace the table, value, list and status placeholders of a page."""
    return gen_tables.render(markdown, page.file.src_uri)


def on_post_build(config):
    """Draw architecture.png into the built site from the package's imports as they are now (the
    committed docs/architecture.png is the copy a source checkout shows; the site never shows a
    stale one)."""
    _load("gen_architecture").main(str(Path(config["site_dir"]) / "architecture.png"))
