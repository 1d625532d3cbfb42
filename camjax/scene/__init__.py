"""Scenes: TOML file -> validated, immutable :class:`Scene`; decides which models are needed.

Every problem is reported as one :class:`SceneError` naming the field, the value and what is
allowed. Nothing is computed here: the scene only says what to compute. The sections' data types
are in :mod:`camjax.scene.spec`, the reading of [motion] in :mod:`camjax.scene.motion` and of the
other sections in :mod:`camjax.scene.sections`, typed access to a TOML table in
:mod:`camjax.scene.reader`.
"""

from __future__ import annotations

import os
import stat
import tomllib
from dataclasses import fields, replace
from importlib import resources
from pathlib import Path

from camjax.errors import MISSING, QUOTE_CHARS, SceneError, cut, quote
from camjax.scene.designed import check_train, parse_synthesis
from camjax.scene.motion import check_resolution, parse_motion, samples_needed
from camjax.scene.reader import TableReader
from camjax.scene.sections import parse_contact, parse_design, parse_dynamics, parse_guide
from camjax.scene.spec import (
    DYNAMICS_COMPUTE,
    RPM_MAX,
    SAMPLES_MAX,
    SAMPLES_PER_SEGMENT,
    ContactSpec,
    DesignSpec,
    DynamicsSpec,
    FollowerSpec,
    MotionSpec,
    Scene,
)

__all__ = [
    "BUILTIN_SCENES", "DYNAMICS_COMPUTE", "QUOTE_CHARS", "RPM_MAX",
    "SAMPLES_MAX", "SAMPLES_PER_SEGMENT", "ContactSpec", "DesignSpec", "DynamicsSpec", "FollowerSpec",
    "MotionSpec", "Scene", "SceneError", "builtin_scene_text", "cut", "decode_scene", "load_scene",
    "parse_scene", "quote", "samples_needed", "scene_from_dict", "with_design", "with_samples",
]



def _builtin_scenes() -> dict[str, str]:
    """Built-in scene name -> file: every TOML file of camjax/scenes, named by its stem (the
    embedded default scene first)."""
    files = sorted(f.name for f in resources.files("camjax.scenes").iterdir() if f.name.endswith(".toml"))
    names = {name[: -len(".toml")]: name for name in files}
    return {"default": names.pop("default"), **names}


BUILTIN_SCENES = _builtin_scenes()

SECTIONS = ("motion", "follower", "contact", "design", "guide", "dynamics", "synthesis", "manufacture",
            "export", "tolerances")


def scene_from_dict(data: dict, name: str = "scene", source: str | None = None) -> Scene:
    """Validate a parsed TOML document. Raises :class:`SceneError`.

    A scene with ``units = "in"`` at the top is read in inch units (:mod:`camjax.units`): it is
    translated once to the internal mm/MPa/N/kg spelling, and the scene keeps ``units``.
    """
    from camjax import followers
    from camjax.units import scene_error_to, scene_to_internal

    follower_table = data.get("follower") if isinstance(data, dict) else None
    ftype = follower_table.get("type") if isinstance(follower_table, dict) else None
    rocking = isinstance(ftype, str) and ftype in followers.names() and followers.get(ftype).rocking
    data, units = scene_to_internal(data, rocking, source)
    try:
        scene = _scene_from_dict(data, name, source)
    except SceneError as exc:
        raise scene_error_to(exc, units) from None
    return scene if units == "mm" else replace(scene, units=units)


def _scene_from_dict(data: dict, name: str, source: str | None) -> Scene:
    """:func:`scene_from_dict` of a scene in the internal units."""
    from camjax import followers

    top = TableReader(data, "", source)
    top.check_keys((*SECTIONS, "units"))
    if "motion" not in data:
        raise SceneError("motion", MISSING, "section [motion] is required", source=source)
    if "follower" not in data:
        raise SceneError("follower", MISSING, "section [follower] is required", source=source)
    ftype = data["follower"].get("type") if isinstance(data["follower"], dict) else None
    follower = followers.get(ftype) if isinstance(ftype, str) and ftype in followers.names() else None
    motion = parse_motion(top.sub("motion"), oscillating=follower is not None and follower.rocking)
    table = top.sub("follower")
    if follower is None:
        table.choice("type", followers.names())  # required, one of the registered types: raises
    spec = follower.parse(table)
    contact = parse_contact(top.sub("contact")) if "contact" in data else None
    if contact is not None and not follower.takes_contact:
        raise SceneError("contact", MISSING, f"contact stress is not defined for a {follower.title} "
                         "follower (a point contact of zero radius: the Hertz stress is unbounded); remove "
                         "the [contact] section", source=source)
    if contact is not None and spec.train is None:
        raise SceneError("contact", MISSING,
                         "contact stress needs the follower force: give follower.mass_kg and/or "
                         "follower.spring_N_per_m", source=source)
    if "design" in data and contact is None and follower.design_needs_contact:
        raise SceneError("design", MISSING, "the objective needs the contact stress: add a "
                         "[contact] section", source=source)
    design = (parse_design(top.sub("design"), follower, spec, contact is not None) if "design" in data
              else None)
    guide = parse_guide(top.sub("guide")) if "guide" in data else None
    if guide is not None and (spec.train is None or not follower.takes_guide):
        kinds = " or ".join(f.title for f in followers.all_followers() if f.takes_guide)
        raise SceneError("guide", MISSING, f"guide reactions need a {kinds} follower with loads "
                         "(follower.mass_kg and/or spring_N_per_m)", source=source)
    dynamics = (parse_dynamics(top.sub("dynamics"), motion, spec, follower.rocking) if "dynamics" in data
                else None)
    synthesis = (parse_synthesis(top.sub("synthesis"), motion.designed, follower.rocking)
                 if "synthesis" in data else None)
    check_train(synthesis, dynamics, source)
    manufacture = export = None
    if "manufacture" in data or "export" in data:  # how the cam is cut; a drive's cam table
        from camjax.scene.manufacture import parse_export, parse_manufacture

        if "manufacture" in data:
            width = None if contact is None else contact.cam_width_mm
            manufacture = parse_manufacture(top.sub("manufacture"), width)
        if "export" in data:
            export = parse_export(top.sub("export"), follower.rocking)
    scene = Scene(name, motion, spec, contact, design, guide, dynamics, synthesis, manufacture, export)
    if "tolerances" in data:  # camjax.robust: what camjax robust samples (other commands ignore it)
        from camjax.robust.tolerances import parse_tolerances

        scene = replace(scene, tolerances=parse_tolerances(top.sub("tolerances"), scene))
    if design is not None and design.robust is not None:  # camjax.robust.design: drawn from [tolerances]
        _check_robust(scene, source)
    return scene


def _check_robust(scene: Scene, source: str | None) -> None:
    """A robust [design] samples the scene's [tolerances], of a scene whose laws are given."""
    robust = scene.design.robust
    tol = scene.tolerances
    if tol is None or not (tol.values or tol.profile):
        raise SceneError("design.robust", {"probability": robust.probability, "samples": robust.samples},
                         "a robust design keeps its limits over samples of the scene's tolerances: add a "
                         "[tolerances] section", "e.g. [tolerances] rpm = { sd_percent = 2 }", source)
    if scene.motion.designed:
        raise SceneError("design.robust", {"probability": robust.probability, "samples": robust.samples},
                         "a robust design of designed laws (design = true in [motion]) is not supported",
                         "laws given in [motion], or no robust key", source)


def with_design(scene: Scene, **overrides) -> Scene:
    """The scene with some [design] keys replaced, checked by the same rules as a scene file.

    Raises :class:`SceneError` naming ``design.<key>`` (and nothing is changed) when a value is
    not allowed, e.g. ``alpha = gamma = 0``.
    """
    from camjax import followers

    if scene.design is None:
        raise SceneError("design", MISSING, "the scene has no [design] section to override")
    d = scene.design
    table = {name: list(bounds) for name, bounds in d.variables}
    table.update({f.name: getattr(d, f.name) for f in fields(DesignSpec)
                  if f.name not in ("variables", "robust")})
    if d.robust is not None:
        table["robust"] = {f.name: getattr(d.robust, f.name) for f in fields(d.robust)}
    table = {k: v for k, v in table.items() if v is not None}
    design = parse_design(TableReader({**table, **overrides}, "design", None), followers.of(scene),
                          scene.follower, scene.contact is not None)
    return replace(scene, design=design)


def with_samples(scene: Scene, samples: int) -> Scene:
    """The scene on a grid of ``samples`` cam angles, checked by the same rules as ``motion.samples``.

    Raises :class:`SceneError` naming ``motion.samples`` when the grid is out of range or too
    coarse for the shortest segment.
    """
    r = TableReader({"samples": samples}, "motion", None)
    motion = replace(scene.motion, samples=r.number("samples", low=1, high=SAMPLES_MAX, integer=True))
    check_resolution(motion, r)
    return replace(scene, motion=motion)


def parse_scene(text: str, name: str = "scene", source: str | None = None) -> Scene:
    """Parse and validate TOML text."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("toml", MISSING, f"not valid TOML ({exc})", source=source) from None
    except RecursionError:
        raise SceneError("toml", MISSING, "nested too deeply to read", "tables and arrays nested a "
                         "few levels", source=source) from None
    return scene_from_dict(data, name, source)


def builtin_scene_text(name: str) -> str:
    """TOML text of a built-in scene."""
    if name not in BUILTIN_SCENES:
        raise SceneError("scene", name, "unknown built-in scene", ", ".join(BUILTIN_SCENES))
    return resources.files("camjax.scenes").joinpath(BUILTIN_SCENES[name]).read_text()


def load_scene(path_or_name: str | Path | None = None) -> Scene:
    """Load a scene file, or a built-in scene by name (None -> the embedded default scene)."""
    if path_or_name is None:
        path_or_name = "default"
    p = Path(path_or_name)
    if str(path_or_name) in BUILTIN_SCENES and not p.is_file():
        return parse_scene(builtin_scene_text(str(path_or_name)), str(path_or_name),
                           f"<built-in {path_or_name}>")
    _check_scene_path(p, str(path_or_name))
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise SceneError("scene", str(path_or_name), f"cannot be read ({exc.strerror})") from None
    return parse_scene(decode_scene(raw, str(p)), p.stem, str(p))


_NOT_REGULAR = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
                (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _check_scene_path(p: Path, given: str) -> None:
    """A scene path must name a regular file (through any links); else :class:`SceneError` saying
    what it names instead. Nothing is opened: reading a FIFO would wait for a writer, /dev/zero
    would never end."""
    allowed = f"a TOML file or one of {', '.join(BUILTIN_SCENES)}"
    try:
        mode = p.stat().st_mode  # follows links
    except (FileNotFoundError, NotADirectoryError):
        if p.is_symlink():
            raise SceneError("scene", given, f"is a link whose target is missing "
                             f"({quote(os.readlink(p))})", allowed) from None
        raise SceneError("scene", given, "no such file or built-in scene", allowed) from None
    except (OSError, ValueError) as exc:  # a name too long, a NUL character, a loop of links
        raise SceneError("scene", given, f"cannot be used as a path "
                         f"({getattr(exc, 'strerror', None) or exc})") from None
    if stat.S_ISDIR(mode):
        raise SceneError("scene", given, "is a folder, not a scene file", allowed)
    if not stat.S_ISREG(mode):
        kind = next((name for test, name in _NOT_REGULAR if test(mode)), "a special file")
        raise SceneError("scene", given, f"is not a regular file: it is {kind}", allowed)


def decode_scene(raw: bytes, source: str) -> str:
    """A scene file's bytes as text: UTF-8 (TOML's encoding), with a BOM tolerated.

    Raises :class:`SceneError` for UTF-16/32 (says so), binary data or other encodings.
    """
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError("scene", MISSING, "is UTF-16 or UTF-32 text; TOML files are UTF-8",
                         "save the file as UTF-8", source)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError("scene", MISSING, f"is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                         f"{exc.start}); TOML files are UTF-8", "a UTF-8 text file", source) from None
    if "\x00" in text:
        i = text.index("\x00")
        raise SceneError("scene", MISSING, f"holds a NUL character at offset {i}: a binary file, "
                         "not a TOML scene", "a UTF-8 text file", source)
    return text
