"""Results of a block sweep on disk: one JSON file per finished block, written atomically.

Layout of a sweep folder::

    DIR/manifest.json        the sweep's parameters (scenes by digest, weightings, block size, spec)
    DIR/blocks/000012.json   block 12: its records, attempts, seconds, worker
    DIR/blocks/000013.error.json   block 13 failed every attempt: the last error (retried on resume)

A block file appears only complete (write to a temporary name, then ``os.replace``), so a sweep
killed at any moment leaves finished blocks intact and no half-written one. Resuming reads the
finished block numbers and skips them; a manifest with other parameters is refused, because mixing
blocks computed with different settings would give a front that no single run produces.
"""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import asdict
from pathlib import Path

from camjax.scaleout.blocks import BlockTask, scene_digest

MANIFEST_FORMAT = "camjax-sweep-blocks/1"


class ManifestMismatch(ValueError):
    """A resume was asked for a folder written by a sweep with other parameters."""


def write_json_atomic(path: Path, data) -> None:
    """Write JSON to a temporary file beside ``path`` and rename it over ``path`` (atomic on POSIX)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as f:
            f.write(json.dumps(data, indent=1, allow_nan=False) + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def manifest_of(blocks: list[BlockTask], block_size: int) -> dict:
    """The parameters that decide a sweep's results (not how or where it runs)."""
    scenes, seen = [], set()
    for b in blocks:
        if b.scene_name not in seen:
            seen.add(b.scene_name)
            scenes.append({"name": b.scene_name, "sha256_16": scene_digest(b.scene_text)})
    weightings = []
    for b in blocks:
        if b.scene_name == blocks[0].scene_name:
            weightings.extend([a, g] for a, g in b.weightings)
    return {
        "format": MANIFEST_FORMAT,
        "scenes": scenes,
        "weightings": weightings,
        "block_size": block_size,
        "blocks": len(blocks),
        "spec": asdict(blocks[0].spec) if blocks else {},
    }


class BlockStore:
    """A sweep folder: manifest, finished blocks, errors."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.blocks_dir = self.folder / "blocks"

    def block_path(self, index: int) -> Path:
        return self.blocks_dir / f"{index:06d}.json"

    def error_path(self, index: int) -> Path:
        return self.blocks_dir / f"{index:06d}.error.json"

    def open(self, manifest: dict, resume: bool) -> None:
        """Create the folder, or (``resume``) check that it holds the same sweep.

        Without ``resume`` a folder that already holds blocks is refused rather than mixed.
        """
        path = self.folder / "manifest.json"
        if path.exists():
            old = json.loads(path.read_text())
            if not resume:
                if self.finished():
                    raise ManifestMismatch(
                        f"{self.folder} already holds {len(self.finished())} finished blocks of a sweep; "
                        "resume it (--resume) or choose another folder")
            elif old != manifest:
                keys = sorted(k for k in set(old) | set(manifest) if old.get(k) != manifest.get(k))
                raise ManifestMismatch(
                    f"{self.folder} holds a sweep with other parameters ({', '.join(keys)} differ); "
                    "resume it with the same scenes, weightings, block size and solver settings, or "
                    "choose another folder")
        write_json_atomic(path, manifest)
        self.blocks_dir.mkdir(parents=True, exist_ok=True)

    def finished(self) -> set[int]:
        """Block numbers with a complete result file."""
        if not self.blocks_dir.is_dir():
            return set()
        return {int(p.stem) for p in self.blocks_dir.glob("[0-9]*.json") if p.stem.isdigit()}

    def write_block(self, task: BlockTask, records: list[dict], attempts: int, seconds: float,
                    worker: str) -> None:
        """Store a finished block atomically and clear an earlier error of it."""
        write_json_atomic(self.block_path(task.index), {
            "block": task.index, "scene": task.scene_name, "first_weighting": task.first_weighting,
            "attempts": attempts, "seconds": seconds, "worker": worker, "records": records,
        })
        self.error_path(task.index).unlink(missing_ok=True)

    def write_error(self, task: BlockTask, error: str, attempts: int) -> None:
        write_json_atomic(self.error_path(task.index), {
            "block": task.index, "scene": task.scene_name, "attempts": attempts, "error": error,
        })

    def read_block(self, index: int) -> dict:
        return json.loads(self.block_path(index).read_text())

    def records(self) -> list[dict]:
        """Every finished block's records, in block order."""
        out = []
        for i in sorted(self.finished()):
            out.extend(self.read_block(i)["records"])
        return out
