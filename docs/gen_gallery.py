"""Draw the gallery's figures: every built-in scene designed by ``camjax design``, kept small.

``python docs/gen_gallery.py`` designs every built-in scene (``camjax.scene.BUILTIN_SCENES``; a
scene that only designs its laws is drawn by ``camjax synthesize``, :func:`command`);
``python docs/gen_gallery.py --scene NAME [--scene NAME ...]`` designs only those. Each run writes
``docs/gallery/NAME-profile.png``, ``NAME-svaj.png`` and, where the scene has loads,
``NAME-loads.png`` (PNG at :data:`DPI` dpi, about 70 KB each), and ``NAME-motion.gif`` (one turn
of the mechanism, ``--animate``'s motion.gif with every :data:`GIF_STEP`-th frame kept, about 90 KB),
replacing the scene's old figures,
and ``NAME.json``: the title block the figures carry (``camjax.output.titles``), which the docs
tests hold against what the pages say of the same design, and what the run wrote (its files,
result.json's top-level keys, profile.csv's columns: ``{{ list: outputs }}`` on the CLI page). The site's build does not run this
(a scene takes seconds to a minute): it shows the committed images beside each scene's TOML
(``{{ list: gallery }}`` in docs/gallery.md, written by docs/gen_tables.py), and
``tests/test_docs.py`` fails when a built-in scene has no figures yet.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
GALLERY = ROOT / "docs" / "gallery"
sys.path.insert(0, str(ROOT))  # the checkout's camjax, as the docs build imports it
DPI = 90
FIGURES = ("profile", "svaj", "loads")
"""The figures kept, in the order the gallery shows them (``loads`` only where the scene has loads)."""
GIF_STEP = 2
"""The gallery's animation keeps every GIF_STEP-th frame of ``camjax design --animate``'s motion.gif
(each shown GIF_STEP times as long: the same turn in the same time, at half the bytes)."""


def command(scene: str) -> str:
    """The command whose figures show the scene: ``design``, or ``synthesize`` for a scene that
    designs its laws and has no [design] section (``camjax design`` would draw the laws' starting
    control values, not the designed laws; ``camjax synthesize`` draws the designed laws against
    the best built-in ones)."""
    import tomllib

    from camjax.scene import builtin_scene_text

    data = tomllib.loads(builtin_scene_text(scene))
    designs_laws = any(seg.get("design") for seg in data.get("motion", {}).get("segments", []))
    return "synthesize" if designs_laws and "design" not in data else "design"


def builtin_scenes() -> list[str]:
    """Every built-in scene's name, read from the package's registry."""
    from camjax.scene import BUILTIN_SCENES

    return list(BUILTIN_SCENES)


def figure_paths(scene: str) -> dict[str, Path]:
    """Figure name -> the gallery file it is kept in, for one scene."""
    return {name: GALLERY / f"{scene}-{name}.png" for name in FIGURES}


def thin_gif(src: Path, dest: Path, step: int = GIF_STEP) -> Path:
    """Write ``src``'s every ``step``-th frame to ``dest``, each shown ``step`` times as long (the
    same loop in the same time); the frames keep their palette."""
    from PIL import Image, ImageSequence

    with Image.open(src) as gif:
        frames = [frame.copy() for frame in ImageSequence.Iterator(gif)][::step]
        duration = gif.info.get("duration", 50) * step
    frames[0].save(dest, save_all=True, append_images=frames[1:], duration=duration, loop=0,
                   optimize=True)
    return dest


def draw(scene: str, dpi: int = DPI) -> list[Path]:
    """Run ``camjax design SCENE --dpi DPI --animate`` into a temporary folder and keep its figures
    and its animation (thinned, :func:`thin_gif`)."""
    GALLERY.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        verb = command(scene)
        cmd = [sys.executable, "-m", "camjax.cli", verb, scene, "--out", str(out), "--dpi", str(dpi),
               *(["--animate"] if verb == "design" else [])]
        run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                             env={**os.environ, "PYTHONPATH": str(ROOT)})
        if run.returncode != 0:
            raise SystemExit(f"{' '.join(cmd[1:])} failed (exit {run.returncode}):\n{run.stderr}")
        from camjax.output.titles import title_block

        result = json.loads((out / "result.json").read_text())
        meta = GALLERY / f"{scene}.json"
        profile = out / "profile.csv"
        meta.write_text(json.dumps({"scene": scene, "command": f"camjax {verb} {scene} --dpi {dpi}",
                                    "title_block": title_block(result) if verb == "design" else None,
                                    # what the command writes without --animate (the CLI page's list)
                                    "files": sorted(p.name for p in out.iterdir()
                                                    if p.is_file() and p.name != "motion.gif"),
                                    "result_keys": list(result),
                                    "profile_columns": (profile.read_text().split("\n", 1)[0].split(",")
                                                        if profile.exists() else [])},
                                   indent=1) + "\n")
        kept = [meta]
        for name, dest in figure_paths(scene).items():
            src = out / f"{name}.png"
            dest.unlink(missing_ok=True)
            if src.exists():
                shutil.copyfile(src, dest)
                kept.append(dest)
        gif = GALLERY / f"{scene}-motion.gif"
        gif.unlink(missing_ok=True)
        if (out / "motion.gif").exists():
            kept.append(thin_gif(out / "motion.gif", gif))
    return kept


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", action="append", metavar="NAME",
                        help="a built-in scene to draw (repeatable; default: every built-in scene)")
    parser.add_argument("--dpi", type=int, default=DPI, help=f"resolution of the figures (default {DPI})")
    args = parser.parse_args(argv)
    known = builtin_scenes()
    scenes = args.scene or known
    unknown = [s for s in scenes if s not in known]
    if unknown:
        parser.error(f"unknown built-in scene(s) {', '.join(unknown)}; known: {', '.join(known)}")
    for scene in scenes:
        kept = draw(scene, args.dpi)
        size = sum(p.stat().st_size for p in kept) / 1024
        print(f"{scene}: {', '.join(p.name for p in kept)} ({size:.0f} KB)", flush=True)
    total = sum(p.stat().st_size for p in GALLERY.glob("*")) / 2**20
    print(f"docs/gallery: {total:.2f} MB in all")
    return 0


if __name__ == "__main__":
    sys.exit(main())
