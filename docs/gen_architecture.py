"""Draw docs/architecture.png: camjax's layers, their modules and the imports between them.

``python docs/gen_architecture.py [OUT.png]`` reads the package's own imports (what each module
imports when it is imported, as ``tests/test_structure.py`` reads them) and draws one box per layer
with its modules and lines of code, the follower folders side by side, and an arrow wherever a
layer imports another. Nothing is drawn by hand: a new module or import shows up on the next run.
"""

from __future__ import annotations

import ast
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "camjax"

# the layers, from the bottom of the picture to the top: (name, what decides that a module is in it).
# A follower folder holds a module of three layers (its geometry and problem; its follower.py, the
# plug-in that runs a design; its report and drawing), so the folders appear in three rows.
OUTPUT_PARTS = ("report", "drawing", "_translating_report", "_translating_drawing", "_rocking_report",
                "_rocking_drawing")
RUN_PARTS = ("follower", "_translating", "_rocking")


def _follower_part(name: str) -> str | None:
    """"model", "run" or "output" for a module of camjax.followers (None for another module)."""
    if not name.startswith("camjax.followers"):
        return None
    leaf = name.rsplit(".", 1)[-1]
    if leaf in OUTPUT_PARTS:
        return "output"
    if leaf in RUN_PARTS:
        return "run"
    return "model"


LAYERS = [
    ("models, registries, runtime", lambda n: n in ("camjax.followers", "camjax.followers._contract",
                                                    "camjax.runtime", "camjax.solvers.registry")
     or n.startswith(("camjax.errors", "camjax.results", "camjax.numerics", "camjax.extrema", "camjax.laws",
                      "camjax.program", "camjax.contact", "camjax.loads"))),
    ("scene", lambda n: n.startswith("camjax.scene")),
    ("evaluate", lambda n: n == "camjax.evaluate"),
    ("followers: geometry and design problems",
     lambda n: _follower_part(n) == "model" or n == "camjax.family"),
    ("solvers", lambda n: n.startswith("camjax.solvers") and n != "camjax.solvers.registry"),
    ("followers: the plug-ins that run a design", lambda n: _follower_part(n) == "run"),
    ("dynamics", lambda n: n.startswith("camjax.dynamics")),
    ("pipeline", lambda n: n == "camjax.pipeline"),
    ("output (and the followers' report and drawing)", lambda n: n.startswith("camjax.output")
     or _follower_part(n) == "output"),
    ("scale-out", lambda n: n.startswith("camjax.scaleout")),
    ("cli", lambda n: n.startswith("camjax.cli")),
]


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path) -> set[str]:
    """camjax modules a file imports at its top level (not inside functions, not for annotations)."""
    names = set()
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            continue
        for sub in ast.walk(node) if isinstance(node, (ast.If, ast.Try)) else [node]:
            if isinstance(sub, ast.Import):
                names.update(a.name for a in sub.names)
            elif isinstance(sub, ast.ImportFrom) and sub.module and sub.level == 0:
                names.update({sub.module, *(f"{sub.module}.{a.name}" for a in sub.names)})
    return {n for n in names if n.startswith("camjax.")}


def layer_of(name: str) -> str | None:
    for layer, member in LAYERS:
        if member(name):
            return layer
    return None


def main(out: str = str(ROOT / "docs" / "architecture.png")) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    modules = {module_name(p): p for p in PACKAGE.rglob("*.py") if module_name(p) != "camjax"}
    lines = {name: len(p.read_text().splitlines()) for name, p in modules.items()}
    edges = set()
    for name, path in modules.items():
        a = layer_of(name)
        for target in imports(path):
            b = layer_of(target) if target in modules else None
            if a and b and a != b:
                edges.add((a, b))
    order = [name for name, _ in LAYERS]
    fig = Figure(figsize=(11.0, 9.0), layout="constrained")
    ax = fig.subplots()
    ax.set_xlim(0, 100)
    ax.set_ylim(0, 10.5 * len(order))
    ax.set_axis_off()
    centre = {}
    for k, layer in enumerate(order):
        y = 10.5 * k + 1
        members = sorted(n for n in modules if layer_of(n) == layer)
        text = ", ".join(n.replace("camjax.", "").replace("followers.", "f.") for n in members)
        size = sum(lines[n] for n in members)
        ax.add_patch(FancyBboxPatch((18, y), 80, 8, boxstyle="round,pad=0.3",
                                    fc="#e8eef7" if k % 2 else "#f4f4f4", ec="0.4"))
        ax.text(19, y + 6.8, f"{layer}  ({len(members)} modules, {size} lines)", fontsize=9, weight="bold",
                va="top")
        ax.text(19, y + 4.6, textwrap.fill(text, 150, replace_whitespace=False), fontsize=6.5, va="top",
                family="monospace")
        centre[layer] = y + 4
    for a, b in sorted(edges):
        ya, yb = centre[a], centre[b]
        x = 3 + 14 * (order.index(a) % 5) / 5 + (0.6 if ya > yb else 0.0)
        xb = x + 1.5 * (order.index(b) % 3)
        ax.add_patch(FancyArrowPatch((xb, ya), (xb, yb), arrowstyle="-|>", mutation_scale=8,
                                     color="C3" if ya < yb else "0.35", linewidth=0.7,
                                     connectionstyle="arc3,rad=0.25"))
    up = [f"{a} -> {b}" for a, b in sorted(edges) if order.index(a) < order.index(b)]
    fig.suptitle("camjax layers (f. = camjax.followers): an arrow for each layer a module imports "
                 "(grey: downwards; red: upwards" + (": " + ", ".join(up) if up else ", none") + ")",
                 fontsize=9)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}: {len(modules)} modules, {len(edges)} layer imports, {len(up)} upwards")


if __name__ == "__main__":
    main(*sys.argv[1:])
