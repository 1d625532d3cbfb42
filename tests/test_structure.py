"""Package layout: data flows one way (scene -> evaluate -> pipeline -> output -> cli), and the
result comparison script behind "behaviour unchanged" finds every difference it should."""

import ast
import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "camjax"

# module (dotted prefix) -> modules it must not import: the stages after it in the chain
# scene -> evaluate -> followers (geometry, problem, run) -> solvers -> pipeline -> output -> cli
MODELS = ("camjax.errors", "camjax.results", "camjax.numerics", "camjax.extrema", "camjax.laws", "camjax.program",
          "camjax.synthesis",
          "camjax.contact", "camjax.loads")
ABOVE_MODELS = ("camjax.scene", "camjax.evaluate", "camjax.followers", "camjax.solvers", "camjax.pipeline",
                "camjax.output", "camjax.cli", "camjax.scaleout", "camjax.dynamics")
LATER = {
    **{model: ABOVE_MODELS for model in MODELS},
    "camjax.scene": ("camjax.evaluate", "camjax.solvers.base", "camjax.pipeline", "camjax.output", "camjax.cli"),
    "camjax.evaluate": ("camjax.solvers", "camjax.pipeline", "camjax.output", "camjax.cli"),
    "camjax.followers": ("camjax.pipeline", "camjax.cli", "camjax.scaleout"),
    "camjax.solvers": ("camjax.pipeline", "camjax.output", "camjax.cli"),
    "camjax.pipeline": ("camjax.output", "camjax.cli", "camjax.scaleout"),
    "camjax.codesign": ("camjax.output", "camjax.cli", "camjax.scaleout"),  # the pipeline's layer
    "camjax.output": ("camjax.cli", "camjax.scaleout"),
    "camjax.runtime": ("camjax.",),  # set-up only: must load before anything it could configure
}
# a follower folder's computing layers (and the families' shared maths) never reach the output layer;
# its report.py and drawing.py (and the families' _*_report.py, _*_drawing.py) are that layer
OUTPUT_LAYERS = ("report", "drawing", "_translating_report", "_translating_drawing", "_rocking_report",
                 "_rocking_drawing", "_closure_report", "_closure_drawing")


def _runtime_imports(path: Path) -> set[str]:
    """Modules a file imports at run time (``if TYPE_CHECKING:`` blocks are annotations only)."""
    tree = ast.parse(path.read_text())
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for n in ast.walk(node))
    names = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{a.name}" for a in node.names)  # from camjax import x
    return names


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _later_stages_imported(path: Path) -> list[str]:
    """The modules of a later stage of the chain that the file imports at run time."""
    name = _module_name(path)
    forbidden = [bad for prefix, bads in LATER.items() if name == prefix or name.startswith(prefix + ".")
                 for bad in bads]
    if name.startswith("camjax.followers.") and name.rsplit(".", 1)[-1] not in OUTPUT_LAYERS:
        forbidden.append("camjax.output")
    return sorted(m for m in _runtime_imports(path) for bad in forbidden
                  if m == bad.rstrip(".") or m.startswith(bad if bad.endswith(".") else bad + "."))


def test_no_module_reaches_back_up_the_chain():
    # every module of the package in one test, each offender named in the message (one test per
    # module cost more in the suite's set-up and tear-down per test than in the check itself)
    wrong = {_module_name(p): bad for p in sorted(PACKAGE.rglob("*.py")) if (bad := _later_stages_imported(p))}
    assert not wrong, "\n".join(f"{name} imports {bad}: a later stage of scene -> pipeline -> output -> cli"
                                 for name, bad in wrong.items())


def test_the_chain_check_sees_a_violation(tmp_path):
    # the check above must be able to fail: a TYPE_CHECKING import is ignored, a real one is not
    f = tmp_path / "m.py"
    f.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from camjax.pipeline import A\n"
                 "from camjax import pipeline\n")
    assert _runtime_imports(f) >= {"camjax", "camjax.pipeline"}
    f.write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from camjax.pipeline import A\n")
    assert not any(m.startswith("camjax") for m in _runtime_imports(f))


# ------------------------------------------------------------------------ compare_results


@pytest.fixture(scope="module")
def compare():
    spec = importlib.util.spec_from_file_location("compare_results",
                                                  ROOT / "validation" / "compare_results.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


OLD = {"a": 1.0, "b": {"c": [1, 2.5, {"d": "x"}], "seconds": 3.0}, "flag": True}


def test_identical_documents_have_no_differences(compare):
    assert compare.differences(OLD, {**OLD}) == []


def test_every_kind_of_difference_is_listed_by_key_path(compare):
    new = {"a": 1.0 + 2.0**-52, "b": {"c": [1, 2.5, {"d": "y"}], "seconds": 3.0}, "flag": 1, "e": 0}
    assert compare.differences(OLD, new) == [
        "a: 1.0 != 1.0000000000000002",  # one ulp: floats compare exactly by default
        "b.c[2].d: 'x' != 'y'",
        "e: only in NEW",
        "flag: True != 1",  # bool and int differ in JSON even though True == 1 in Python
    ]
    assert compare.differences(OLD, {"b": OLD["b"]}) == ["a: only in OLD", "flag: only in OLD"]
    assert compare.differences([1, 2], [1, 2, 3]) == ["<root>: list length 2 != 3"]
    assert compare.differences(1, 1.0) == ["<root>: 1 (int) != 1.0 (float)"]


def test_rtol_and_ignore(compare):
    new = {**OLD, "a": 1.0 + 1e-10, "b": {**OLD["b"], "seconds": 9.0}}
    assert compare.differences(OLD, new, rtol=1e-9, ignore=frozenset({"seconds"})) == []
    assert compare.differences(OLD, new, rtol=1e-11, ignore=frozenset({"b.seconds"})) == \
        ["a: 1.0 != 1.0000000001"]


def test_script_exit_status(compare, tmp_path, capsys):
    import json

    old, new = tmp_path / "old.json", tmp_path / "new.json"
    old.write_text(json.dumps(OLD))
    new.write_text(json.dumps({**OLD, "a": 2.0}))
    assert compare.main([str(old), str(old)]) == 0
    assert compare.main([str(old), str(new)]) == 1
    assert "a: 1.0 != 2.0" in capsys.readouterr().out
    assert compare.main([str(old), str(new), "--ignore", "a"]) == 0


def test_folders_compare_file_by_file(compare, tmp_path, capsys):
    import json

    old, new = tmp_path / "old", tmp_path / "new"
    old.mkdir()
    new.mkdir()
    for folder in (old, new):
        (folder / "same.json").write_text(json.dumps(OLD))
    (old / "moved.json").write_text(json.dumps(OLD))
    (new / "moved.json").write_text(json.dumps({**OLD, "flag": False}))
    (old / "gone.json").write_text("{}")
    assert compare.main([str(old), str(new), "--dirs"]) == 1
    out = capsys.readouterr().out
    assert "moved.json: flag: True != False" in out and "gone.json: only in OLD" in out
    assert "same.json" not in out
    (old / "gone.json").unlink()
    (new / "moved.json").write_text(json.dumps(OLD))
    assert compare.main([str(old), str(new), "--dirs"]) == 0


# ------------------------------------------------------------------------------- the package


MODULES = {}  # dotted name -> path, of every module of the package


def _package_modules() -> dict[str, Path]:
    if not MODULES:
        MODULES.update({_module_name(p): p for p in PACKAGE.rglob("*.py")})
    return MODULES


def _module_imports(path: Path, modules: dict[str, Path] | None = None) -> set[str]:
    """camjax modules a file imports, at its top level or inside a function (an import a function
    makes when it runs is a dependency all the same; ``if TYPE_CHECKING:`` blocks are not).

    ``from camjax.pkg import name`` depends on the module ``camjax.pkg.name`` where that is one,
    else on ``camjax.pkg``; relative imports are resolved against the file's package.
    """
    modules = _package_modules() if modules is None else modules
    name = next((n for n, p in modules.items() if p == path), None) or _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    tree = ast.parse(path.read_text())
    skip = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for n in ast.walk(node))
    names = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1] + ([base] if base else []))
            for a in node.names:
                names.add(f"{base}.{a.name}" if f"{base}.{a.name}" in modules else base)
    return {n for n in names if n.startswith("camjax.")}


def _import_graph(modules: dict[str, Path]) -> dict[str, set[str]]:
    """module -> the package's modules it imports (the root package, camjax/__init__.py, loads its
    names on first use and is not a node)."""
    return {name: {m for m in _module_imports(path, modules) if m in modules and m not in (name, "camjax")}
            for name, path in modules.items() if name != "camjax"}


def _find_circle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}

    def visit(node, stack):
        state[node] = 1
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt, stack + [nxt])):
                return found
        state[node] = 2
        return None

    for name in sorted(graph):
        if name not in state and (found := visit(name, [name])):
            return found
    return None


def test_no_import_circle():
    """The import graph of the package's modules, function-level imports counted, has no cycle:
    every module can be imported on its own, and the layers stay one-way."""
    circle = _find_circle(_import_graph(_package_modules()))
    assert circle is None, "import circle: " + " -> ".join(circle)


def test_the_circle_check_finds_a_circle(tmp_path):
    # one edge at the top level, the other inside a function: a circle all the same
    a, b = tmp_path / "camjax" / "a.py", tmp_path / "camjax" / "b.py"
    a.parent.mkdir()
    a.write_text("import camjax.b\n")
    b.write_text("def f():\n    from camjax import a\n")
    modules = {"camjax.a": a, "camjax.b": b}
    assert _module_imports(a, modules) == {"camjax.b"} and _module_imports(b, modules) == {"camjax.a"}
    assert _find_circle({"camjax.a": {"camjax.b"}, "camjax.b": {"camjax.a"}}) == ["camjax.a", "camjax.b", "camjax.a"]


def test_import_camjax_loads_no_jax():
    """``import camjax`` is the same for every program and light: no JAX, no model, no command
    line set-up (that belongs to the ``camjax`` entry point), and 64-bit mode on for JAX."""
    import subprocess

    code = ("import sys, camjax; assert 'jax' not in sys.modules, 'jax'; "
            "assert not [m for m in sys.modules if m.startswith('camjax.')], 'submodules'; "
            "import jax; print(jax.config.jax_enable_x64)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True"
    assert "argv" not in (PACKAGE / "__init__.py").read_text()


def test_the_title_block_is_worded_without_matplotlib():
    """The command line words the figures' title block where the design ran, before its drawing
    processes draw: for every follower type that costs no matplotlib import (~0.3 CPU s of a warm
    `camjax design`'s own process when the follower's words lived in its drawing module)."""
    import subprocess

    from camjax import followers

    code = ("import sys; from camjax import followers; from camjax.output.titles import title_block\n"
            "dims = {'roller_radius_mm': 8.0, 'offset_mm': 1.0, 'face_radius_mm': 40.0, 'face_width_mm': 12.0,\n"
            "        'pivot_distance_mm': 80.0, 'arm_length_mm': 60.0, 'face_offset_mm': 10.0}\n"
            "data = {'evaluated_at': {'base_radius_mm': 30.0}, 'roller': dims, 'knife_edge': dims,\n"
            "        'curved_face': dims, 'oscillating_follower': dims}\n"
            "for name in followers.names():\n"
            "    followers.get(name)\n"
            "    print(name, '|', title_block({**data, 'follower_type': name}).splitlines()[-1])\n"
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    lines = dict(line.split(" | ") for line in out.stdout.strip().splitlines())
    assert set(lines) == set(followers.names())
    assert lines["roller"] == "R_b = 30.000 mm, R_f = 8 mm, e = 1 mm"
    assert lines["oscillating_roller"] == "R_b = 30.000 mm, d = 80 mm, l = 60 mm, R_f = 8 mm"


def test_no_module_over_600_lines():
    long = {str(p.relative_to(ROOT)): n for p in PACKAGE.rglob("*.py") if (n := len(p.read_text().splitlines())) > 600}
    assert not long, f"modules over 600 lines: {long}"


FOLLOWER_NAMES = {"flat", "roller", "oscillating_roller", "oscillating_flat", "knife_edge", "curved_face",
                  "oscillating_curved_face"}


def _type_name_comparisons(path: Path) -> list[str]:
    """Comparisons (==, !=, in, not in) with a follower type's name as a string constant."""
    tree = ast.parse(path.read_text())
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Compare):
            for sub in ast.walk(node):
                if isinstance(sub, ast.Constant) and sub.value in FOLLOWER_NAMES:
                    out.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return out


def test_no_code_outside_the_follower_folders_compares_a_follower_type_name():
    """Everything outside camjax/followers reaches a follower through the registry and the contract."""
    found = [hit for p in PACKAGE.rglob("*.py") if "followers" not in p.parts for hit in _type_name_comparisons(p)]
    assert not found, "\n".join(found)


def test_the_type_name_check_sees_a_comparison(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def g(scene):\n    return scene.follower.type == 'roller'\n")
    assert len(_type_name_comparisons(f)) == 1


def test_every_follower_folder_is_registered_and_complete():
    """A folder of camjax/followers is a follower type: its follower.py registers an instance named
    after it, and it has the five layers of the contract."""
    from camjax import followers

    folders = sorted(p.name for p in (PACKAGE / "followers").iterdir() if p.is_dir() and not p.name.startswith("_"))
    assert list(followers.names()) == folders
    for name in folders:
        for layer in ("geometry", "problem", "follower", "report", "drawing"):
            assert (PACKAGE / "followers" / name / f"{layer}.py").is_file(), (name, layer)
        assert followers.get(name).name == name
