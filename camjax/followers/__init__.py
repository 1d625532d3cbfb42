"""Follower types as plug-ins: one folder per type, one contract they all fill in.

A follower type is a folder of this package, named after the scene's ``follower.type``, whose
``follower.py`` holds ``FOLLOWER``, an instance of a :class:`camjax.followers._contract.Follower`
subclass. The folder is the registration: :func:`names` lists the folders (without importing them)
and :func:`get` imports a follower when it is first asked for. Everything outside the folders
reaches a follower through :func:`get` (or :func:`of` a scene) and the contract, never by
comparing its name.

This module imports neither JAX nor NumPy: the drawing processes and the scale-out workers read the
names, and :func:`drawing` imports a follower's drawing module alone (matplotlib, no JAX).
"""

from __future__ import annotations

import importlib
import pkgutil
from pathlib import Path
from types import ModuleType

_HERE = Path(__file__).resolve().parent
_LOADED: dict = {}


def names() -> tuple[str, ...]:
    """Every registered follower type (the folders of this package), sorted."""
    return tuple(sorted(m.name for m in pkgutil.iter_modules([str(_HERE)])
                        if m.ispkg and not m.name.startswith("_")))


def get(name: str):
    """The follower of type ``name`` (a :class:`camjax.followers._contract.Follower`).

    Raises ``KeyError`` naming the registered types for an unknown one (the scene turns that into a
    :class:`camjax.errors.SceneError` naming ``follower.type``).
    """
    follower = _LOADED.get(name)
    if follower is None:
        if name not in names():
            raise KeyError(f"follower.type {name!r} is not registered (registered: {', '.join(names())})")
        follower = importlib.import_module(f"camjax.followers.{name}.follower").FOLLOWER
        if follower.name != name:
            raise TypeError(f"camjax/followers/{name}/follower.py registers {follower.name!r}, not {name!r}")
        _LOADED[name] = follower
    return follower


def of(scene):
    """The follower of a scene (its ``follower.type``)."""
    return get(scene.follower.type)


def all_followers() -> tuple:
    """Every registered follower, in the order of :func:`names`."""
    return tuple(get(name) for name in names())


def drawing(name: str) -> ModuleType:
    """The drawing module of follower type ``name`` (figures, profile table, animation) without
    importing the follower itself (no JAX): what a drawing process needs."""
    if name not in names():
        raise KeyError(f"follower.type {name!r} is not registered (registered: {', '.join(names())})")
    return importlib.import_module(f"camjax.followers.{name}.drawing")
