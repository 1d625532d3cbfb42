"""The README's contract (set-up lines first, size, a Python quickstart that runs) and the docs'
generated figures (every placeholder resolves against the committed JSON)."""

import ast
import importlib.util
import itertools
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
SETUP_LINES = [
    "python3 -m pip install -e . && camjax design --out out/",
    'python3 -m pip install -e ".[dev]" && python3 -m pytest -q -n auto --dist loadfile',
]


def _gen_tables():
    spec = importlib.util.spec_from_file_location("gen_tables", ROOT / "docs" / "gen_tables.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _code_blocks(text: str, language: str = "") -> list[str]:
    return re.findall(r"^```" + language + r"\n(.*?)^```", text, flags=re.S | re.M)


def test_readme_starts_with_title_then_the_setup_lines_that_ci_runs():
    text = README.read_text()
    assert text.startswith("# camjax\n")
    first_block = _code_blocks(text)[0].strip().splitlines()
    assert first_block == SETUP_LINES
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    for line in SETUP_LINES:
        assert line in ci  # verbatim, as whole lines


def test_readme_is_short():
    # The README is an entry point; the documentation lives in docs/ (8 KB is the agreed budget).
    assert len(README.read_bytes()) <= 8 * 1024


@pytest.mark.slow
def test_readme_python_quickstart_runs_as_written(tmp_path, compilation_cache_env):
    code = _code_blocks(README.read_text(), "python")[0]
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                         timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT), **compilation_cache_env})
    assert run.returncode == 0, run.stderr
    (min_rb, design_rb), (peak, dpeak) = [[float(v) for v in line.split()] for line in
                                          run.stdout.strip().splitlines()]
    # The optimized radius must admit the geometry: at least the smallest admissible radius.
    assert 0 < min_rb <= design_rb
    # sigma = C / sqrt(R_b + q): positive, and falling as R_b grows (rho grows with R_b).
    assert math.isfinite(peak) and peak > 0
    assert dpeak < 0


def test_every_docs_placeholder_resolves():
    gen = _gen_tables()
    pages = sorted((ROOT / "docs").rglob("*.md"))
    assert pages
    for page in pages:
        text = re.sub(r"\\\{\{.*?\}\}", "", page.read_text())  # escaped examples stay literal
        out = gen.render(text, str(page))
        assert not re.search(r"\{\{\s*(table|list|" + "|".join(gen.SOURCES) + "):", out), page


def test_unknown_placeholder_is_an_error():
    gen = _gen_tables()
    with pytest.raises(gen.PlaceholderError):
        gen.render("{{ bench: no.such.key }}")
    with pytest.raises(gen.PlaceholderError):
        gen.render("{{ table: no_such_table }}")
    with pytest.raises(gen.PlaceholderError):
        gen.render("{{ list: no_such_list }}")


@pytest.mark.parametrize("page, names", [
    ("index.md", "followers"), ("extending.md", "folders"), ("architecture.md", "folders"),
    ("cli.md", "scenes"), ("scenes.md", "scenes"), ("optimize.md", "solvers"), ("gallery.md", "scenes"),
    ("cli.md", "commands"), ("laws.md", "laws"),
])
def test_pages_that_list_followers_or_scenes_name_every_registered_one(page, names):
    """The lists come from the registries when the site is built: every follower type (its title,
    or its folder), every built-in scene file and every solver is named on the rendered page."""
    from camjax import followers
    from camjax.cli.app import COMMANDS
    from camjax.laws import LAWS
    from camjax.scene import BUILTIN_SCENES
    from camjax.solvers.registry import SOLVERS

    out = _gen_tables().render((ROOT / "docs" / page).read_text(), page)
    expected = {"followers": [f.title for f in followers.all_followers()],
                "folders": [f"`{name}/`" for name in followers.names()],
                "scenes": [f"`{name}`" for name in BUILTIN_SCENES],
                "solvers": [f"`{name}`" for name in SOLVERS],
                "commands": [f"`camjax {name}`" for name in COMMANDS],
                "laws": [f"`{name}`" for name in LAWS]}[names]
    missing = [name for name in expected if name not in out]
    assert not missing, f"{page} does not name {missing}"


def test_extremes_tables_account_for_every_case():
    gen = _gen_tables()
    data = gen.load("extremes")
    rows = gen.extremes_groups(data).splitlines()[2:]
    counted = sum(int(r.split("|")[2]) for r in rows)
    passed = sum(int(r.split("|")[3]) for r in rows)
    assert counted == data["summary"]["cases"] == len(data["cases"])
    assert passed == data["summary"]["passed"]


def _documented_modules() -> list[str]:
    """Every module of the package with a module docstring (an empty ``__init__`` is data only)."""
    names = []
    for path in sorted((ROOT / "camjax").rglob("*.py")):
        if path.name.startswith("_") and path.name != "__init__.py":
            continue
        parts = path.relative_to(ROOT).with_suffix("").parts
        name = ".".join(parts[:-1] if path.name == "__init__.py" else parts)
        if ast.get_docstring(ast.parse(path.read_text())):
            names.append(name)
    return names


def test_every_public_module_is_on_one_api_page_in_the_nav():
    """The API reference is grouped by concept: each public module (and the followers' shared
    family modules) has its ``::: module`` block on exactly one page of docs/api/, every page is in
    mkdocs.yml's nav, and no page names a module that does not exist."""
    modules = _documented_modules()
    assert "camjax.followers.flat.problem" in modules and "camjax" in modules  # the walk finds the package
    nav = (ROOT / "mkdocs.yml").read_text()
    blocks: dict[str, list[str]] = {}
    for page in sorted((ROOT / "docs" / "api").glob("*.md")):
        assert f"api/{page.name}" in nav, f"{page.name} is not in mkdocs.yml's nav"
        for name in re.findall(r"^::: ([\w.]+)$", page.read_text(), flags=re.M):
            blocks.setdefault(name, []).append(page.name)
    for name in modules:
        assert len(blocks.get(name, [])) == 1, f"{name} is on {blocks.get(name, [])} (one API page wanted)"
    unknown = [n for n in blocks if importlib.util.find_spec(n) is None]
    assert not unknown, f"API pages name modules that do not exist: {unknown}"


def test_every_builtin_scene_has_gallery_figures():
    """The gallery page shows committed images (the build does not run ``camjax design``): each
    built-in scene needs its profile and s/v/a/j figures, drawn by docs/gen_gallery.py."""
    from camjax.scene import BUILTIN_SCENES

    gallery = ROOT / "docs" / "gallery"
    missing = [f"{name} (run: {command})" for name, command in _gen_tables().gallery_missing().items()]
    assert not missing, "built-in scenes without gallery figures: " + "; ".join(missing)
    assert all((gallery / f"{name}-svaj.png").exists() for name in BUILTIN_SCENES)
    # the gallery stays small enough to commit: PNGs at low dpi, ~0.2 MB a scene
    total = sum(p.stat().st_size for p in gallery.glob("*"))
    assert total < 6 * 2**20, f"docs/gallery holds {total / 2**20:.1f} MB (budget 6 MB)"
    drawn = ({p.name.rsplit("-", 1)[0] for pattern in ("*.png", "*.gif") for p in gallery.glob(pattern)}
             | {p.stem for p in gallery.glob("*.json")})
    stale = sorted(drawn - set(BUILTIN_SCENES))
    assert not stale, f"gallery figures of scenes that are not built in: {stale}"


def test_gallery_page_shows_each_scene_file_beside_its_figures():
    from camjax.scene import BUILTIN_SCENES, builtin_scene_text

    out = _gen_tables().render((ROOT / "docs" / "gallery.md").read_text(), "gallery.md")
    for name in BUILTIN_SCENES:
        section = out.split(f"## `{name}`", 1)[1].split("\n## ", 1)[0]
        assert builtin_scene_text(name).splitlines()[1] in section, name
        assert f"(gallery/{name}-svaj.png)" in section, name
        if " design " in json.loads((ROOT / "docs" / "gallery" / f"{name}.json").read_text())["command"]:
            assert f"(gallery/{name}-motion.gif)" in section, name  # the designed mechanism turning


def test_gallery_generator_refuses_an_unknown_scene():
    run = subprocess.run([sys.executable, str(ROOT / "docs" / "gen_gallery.py"), "--scene", "no-such-scene"],
                         capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert run.returncode == 2
    assert "no-such-scene" in run.stderr and "default" in run.stderr  # names the known scenes


def test_performance_table_gives_each_target_one_machine_and_the_status_its_figures_give():
    """One row per measurement: a goal, a measured figure, one machine, and the status that
    follows from them (a speed-up whose accuracy is not matched is a miss); ``{{ status: KEY }}``
    on any page says what the table says."""
    gen = _gen_tables()
    rows = gen.targets()
    assert len({r["key"] for r in rows}) == len(rows)
    number = lambda text: float(re.sub(r"[^0-9.e+-]", "", text.replace(",", "")))  # noqa: E731
    for r in rows:
        assert r["machine"] and r["machine"] != "not recorded" and " and " not in r["machine"], r
        if r["met"] is None:
            continue
        goal, measured = number(r["goal"]), number(r["measured"])
        ok = measured >= goal if r["goal"].startswith("≥") else measured <= goal
        assert r["met"] == (ok and r["note"] != "accuracy not matched"), r
        assert gen.render("{{ status: " + r["key"] + " }}") == ("met" if r["met"] else "missed")
    table = gen.render("{{ table: performance }}")
    assert len(table.splitlines()) == len(rows) + 2
    with pytest.raises(gen.PlaceholderError):
        gen.render("{{ status: no.such.target }}")


# ------------------------------------------------------------------------ numbers that agree
# The site states some quantities on several pages: the reference design's base radius (and the
# figures of that design carry it in their title blocks), and each speed-up of the performance
# table. The pages are rendered as the build renders them (placeholders filled), and every
# statement of one quantity must agree with the others at the precision it is written to.

# a statement of another variant of the quantity, not a contradiction: the sampled (grid) or
# pointwise figure, or the source's
OTHER_VARIANT = re.compile(r"grid|samples|source|pointwise|1°", re.I)
NUMBER = r"([0-9][0-9,]*\.?[0-9]*)"


def _rendered_pages(docs: Path) -> dict[str, str]:
    """Every user-facing page of ``docs`` (not the API pages) rendered, code blocks removed."""
    gen = _gen_tables()
    pages = {}
    for page in sorted(docs.glob("*.md")):
        text = gen.render(page.read_text(), page.name)
        pages[page.name] = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return pages


def _cells(text: str):
    """(context, text) for every table cell (context: the column's header and the row's label) and
    every other line (context: the line itself)."""
    header = None
    for line in text.splitlines():
        if not line.startswith("|"):
            header = None
            yield line, line
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            header = cells
        elif not set(line) <= set("|-: "):
            for i, cell in enumerate(cells):
                yield f"{header[i] if i < len(header) else ''} {cells[0]}", cell


def _agrees(stated: str, value: float) -> bool:
    """``stated`` (a number as written) is ``value`` rounded to the digits written."""
    decimals = len(stated.split(".")[1]) if "." in stated else 0
    return abs(float(stated.replace(",", "")) - value) <= 0.5 * 10.0 ** -decimals * (1 + 1e-9)


def reference_radius_statements(docs: Path) -> list[tuple[str, str]]:
    """(where, number as written) for every statement of the reference design's optimal R_b
    (α = γ = 1, exact extrema): numbers between 28.3 and 28.5 mm said of R_b, on a page or in the
    title block of a gallery figure, leaving out the sampled, pointwise and source's figures."""
    found = []
    for name, text in _rendered_pages(docs).items():
        for context, cell in _cells(text):
            if "R_b" not in context and "R_b" not in cell:
                continue
            for m in re.finditer(r"(?<![\d.])(28\.[0-9]+)", cell):
                before = cell[:m.start()].rsplit(". ", 1)[-1]  # the sentence up to the number
                if 28.3 <= float(m.group(1)) < 28.5 and not OTHER_VARIANT.search(before) \
                        and not (OTHER_VARIANT.search(context) and context != cell):
                    found.append((name, m.group(1)))
    meta = docs / "gallery" / "default.json"
    if meta.exists():
        title = json.loads(meta.read_text())["title_block"]
        found += [(f"gallery/{meta.stem} figures' title block", v) for v in re.findall(r"R_b = ([0-9.]+) mm", title)]
    return found


def speedup_statements(docs: Path) -> dict[str, list[tuple[str, str]]]:
    """Target key -> (page, number as written) wherever a page writes ``KEY`` = N (or a table
    cell N beside ``KEY``), for every target of the performance table."""
    keys = [r["key"] for r in _gen_tables().targets()]
    found: dict[str, list[tuple[str, str]]] = {k: [] for k in keys}
    for name, text in _rendered_pages(docs).items():
        for key in keys:
            for m in re.finditer(r"`" + re.escape(key) + r"`\s*(?:=|\|)\s*\**\s*" + NUMBER, text):
                found[key].append((name, m.group(1).rstrip(".")))
    return found


def contradictions(docs: Path) -> list[str]:
    """Every statement that disagrees with the measured value of its quantity, with where."""
    gen = _gen_tables()
    out = []
    radius = gen.load("result")["design"]["base_radius_mm"]
    out += [f"reference R_b: {where} says {v} mm, result.json {radius:.6f} mm"
            for where, v in reference_radius_statements(docs) if not _agrees(v, radius)]
    measured = {}
    for r in gen.targets():
        m = re.match(r"[0-9,.]+(?:e[+-]?\d+)?", r["measured"])
        measured[r["key"]] = float(m.group(0).replace(",", "")) if m else None
    exact = {k: gen.lookup(gen.load(src), path) for k, (src, path) in SPEEDUP_SOURCES.items()}
    for key, statements in speedup_statements(docs).items():
        value = exact.get(key, measured[key])
        for where, v in statements:
            if value is not None and not _agrees(v, value) and not _agrees(v, measured[key]):
                out.append(f"{key}: {where} says {v}, the measurement is {value:.4g}")
    return out


# the unrounded measurement behind a performance-table row, where a page may write more digits
SPEEDUP_SOURCES = {
    "codesign.slsqp_speedup": ("codesign", "codesign.slsqp_speedup"),
    "synthesis.linprog_speedup": ("synthesis", "synthesis.linprog_speedup"),
    "roller.gradient_speedup": ("roller", "roller.gradient_speedup"),
    "roller.ga_speedup": ("roller", "roller.ga_speedup"),
    "cli.design_over_import": ("cli", "cli.design_over_import"),
    "cli.dynamics_over_import": ("cli", "cli.dynamics_over_import"),
    "cli.laws_over_import": ("cli", "cli.laws_over_import"),
    "cli.cold_max_s": ("cli", "cli.cold_max_s"),
}


def test_the_site_states_each_quantity_once_over():
    """The reference R_b is stated on several pages and in its figures' title blocks, each
    speed-up wherever a page names it: all agree with the committed measurement."""
    statements = reference_radius_statements(ROOT / "docs")
    pages = {where for where, _ in statements}
    assert {"getting-started.md", "optimize.md", "accuracy.md"} <= pages, pages  # the collector finds them
    assert any("title block" in where for where in pages)
    assert any(speedup_statements(ROOT / "docs").values())
    assert contradictions(ROOT / "docs") == []


@pytest.mark.parametrize("plant, expected", [
    ("The reference cam has R_b = 28.397 mm.\n", "reference R_b: index.md says 28.397"),
    ("Co-design: `codesign.slsqp_speedup` = 34.1 against SLSQP.\n", "codesign.slsqp_speedup: index.md says 34.1"),
])
def test_a_planted_contradiction_fails(tmp_path, plant, expected):
    """The same check on a copy of docs/ with one contradicting sentence planted in the home page."""
    import shutil

    docs = tmp_path / "docs"
    shutil.copytree(ROOT / "docs", docs, ignore=shutil.ignore_patterns("api", "*.png", "*.gif"))
    (docs / "gallery").mkdir(exist_ok=True)
    shutil.copy(ROOT / "docs" / "gallery" / "default.json", docs / "gallery")
    (docs / "index.md").write_text((docs / "index.md").read_text() + "\n" + plant)
    found = contradictions(docs)
    assert any(line.startswith(expected) for line in found), found


# ------------------------------------------------------------------------ readable at 1280 px
# With the page's contents in the left sidebar (toc.integrate), the content column is about
# 990 px wide in a 1280 px window. A table cell wraps at spaces, so a table cannot be narrower than
# the sum of its columns' longest words: about 7.5 px a character at the tables' 0.64rem font
# (code a little wider, counted the same) plus 2 x 12 px of cell padding. docs/screenshot.py
# measures the built pages in Chromium; this is the check CI can afford.
CONTENT_PX, CHAR_PX, PAD_PX, MAX_COLUMNS = 960, 7.5, 24, 6


def _tables(text: str):
    """(first header cell, rows as lists of cells) for every Markdown table of ``text``."""
    lines = text.splitlines()
    for k, line in enumerate(lines):
        if k and re.match(r"^\|[-:| ]+\|$", line) and lines[k - 1].startswith("|"):
            rows = [lines[k - 1]]
            rows += [row for row in itertools.takewhile(lambda s: s.startswith("|"), lines[k + 1:])]
            cells = [[c.strip() for c in re.split(r"(?<!\\)\|", r.strip().strip("|"))] for r in rows]
            yield cells[0][0], cells


def _min_width_px(rows: list[list[str]]) -> float:
    columns = max(len(r) for r in rows)
    longest = [0] * columns
    for row in rows:
        for i, cell in enumerate(row):
            words = re.sub(r"\*\*|`|\\", "", re.sub(r"\[([^]]*)\]\([^)]*\)", r"\1", cell)).split()
            longest[i] = max([longest[i]] + [len(w) for w in words])
    return sum(n * CHAR_PX + PAD_PX for n in longest)


def test_no_table_is_wider_than_the_content_column():
    wide = []
    for name, text in _rendered_pages(ROOT / "docs").items():
        for head, rows in _tables(text):
            columns, width = len(rows[0]), _min_width_px(rows)
            if columns > MAX_COLUMNS or width > CONTENT_PX:
                wide.append(f"{name}: table '{head}' has {columns} columns, at least {width:.0f} px")
    assert not wide, "split or transpose: " + "; ".join(wide)


def test_a_wide_table_is_caught():
    rows = [[f"column {i}" for i in range(9)], ["a_rather_long_identifier_in_code"] * 9]
    assert len(rows[0]) > MAX_COLUMNS and _min_width_px(rows) > CONTENT_PX


# ------------------------------------------------------------------------ user pages
DEVELOPMENT_NOTES = re.compile(
    r"tests/test_\w+|\bSPEC\b|\b[Cc]ommit `?[0-9a-f]{7}|[Ll]oad average|\b[Tt]he issue\b|\bPR #\d|git show")


def _user_pages() -> list[str]:
    """The pages of every nav section but "Developing camjax" (and the API pages, docstrings)."""
    import yaml

    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]

    def walk(items):
        for item in items:
            for title, value in (item.items() if isinstance(item, dict) else [(None, item)]):
                if title == "Developing camjax":
                    continue
                yield from (walk(value) if isinstance(value, list) else [value])

    return [page for page in walk(nav) if not page.startswith("api/")]


def test_user_pages_speak_of_camjax_not_of_its_development():
    """Test file names, SPEC section numbers, commit hashes, load averages and issue talk belong
    on the developing pages (architecture, development, benchmark details) or in the JSON."""
    pages = _user_pages()
    assert {"index.md", "getting-started.md", "performance.md", "scenes.md"} <= set(pages)
    assert "benchmarks.md" not in pages and "development.md" not in pages
    gen = _gen_tables()
    found = []
    for page in pages:  # prose only: the scene files the gallery shows are camjax's own text
        text = re.sub(r"^```.*?^```", "", gen.render((ROOT / "docs" / page).read_text(), page), flags=re.S | re.M)
        found += [f"{page}: {m.group(0)!r}" for m in DEVELOPMENT_NOTES.finditer(text)]
    assert not found, found


def test_the_home_page_links_every_section_and_task_of_the_nav():
    """A reader on the home page reaches every task in one click (the list is read from the nav:
    a task page added to mkdocs.yml appears there without editing the home page)."""
    import yaml

    out = _gen_tables().render((ROOT / "docs" / "index.md").read_text(), "index.md")
    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]
    tasks = next(item["Tasks"] for item in nav if "Tasks" in item)
    for entry in tasks:
        (title, page), = entry.items()
        assert f"[{title}]({page})" in out, title
    assert "(gallery.md)" in out and "(getting-started.md)" in out
