"""The follower contract: everything camjax knows of a follower type, behind one interface.

A follower type is a folder ``camjax/followers/<name>/`` (the name is the scene's
``follower.type``) with one module per layer, each importing only what its layer may:

- ``geometry.py``: the pitch and contact geometry in closed form (pure JAX, one design, any grid);
- ``problem.py``: the design problem the solvers run (the family protocol of
  :mod:`camjax.solvers.base`);
- ``follower.py``: ``FOLLOWER``, an instance of a :class:`Follower` subclass: its [follower] and
  [design] keys and the design run (the smallest cam, the solved design, the curves);
- ``report.py``: ``report(scene, run) -> dict``, its result.json;
- ``drawing.py``: its figures, profile table and animation (NumPy and matplotlib only: it runs in
  the drawing processes, which never import JAX).

Everything outside a folder reaches a follower through this contract and the registry
(:mod:`camjax.followers`), never by its name. Two families share most of the work:
:class:`camjax.followers._translating.TranslatingFollower` (a follower sliding along its axis,
lifts in mm) and :class:`camjax.followers._rocking.RockingFollower` (an arm swinging about a
pivot, lifts in deg); a new follower subclasses one and fills in its hooks, and
``tests/test_followers.py`` runs every registered follower through the same checks.
"""

from __future__ import annotations

import abc
import importlib
from types import ModuleType
from typing import TYPE_CHECKING, Any, ClassVar

if TYPE_CHECKING:
    from camjax.scene.reader import TableReader
    from camjax.scene.spec import FollowerSpec


class Follower(abc.ABC):
    """One follower type. A subclass sets the class attributes and fills in the abstract methods;
    ``FOLLOWER = TheFollower()`` in the folder's ``follower.py`` is what the registry loads.
    Instances hold no state: every method is a function of its arguments.
    """

    name: ClassVar[str]  # the scene's follower.type: the folder's name
    title: ClassVar[str]  # words for figures and messages, e.g. "roller"
    rocking: ClassVar[bool]  # an arm swinging about a pivot (lifts in deg, loads about it)
    keys: ClassVar[tuple[str, ...]]  # the [follower] table's keys besides ``type``
    variables: ClassVar[tuple[str, ...]]  # design variables (mm), in result.json's order
    # [design] variables that only some of its scenes have (a conjugate pair's yoke span or second
    # arm angle): :meth:`design_bounds` returns them, after :attr:`variables`, only where they apply
    optional_variables: ClassVar[tuple[str, ...]] = ()
    example_scene: ClassVar[str]  # a built-in scene with a [design] that shows it (docs, tests/test_followers.py)
    design_needs_contact: ClassVar[bool] = False  # a [design] needs [contact] (its objective is the stress)
    takes_contact: ClassVar[bool] = True  # a [contact] section (Hertz stress) is defined for it
    takes_guide: ClassVar[bool] = False  # a [guide] section (stem reactions, SPEC 4) applies to it
    # the closures it runs with ([follower] closure, camjax.scene.spec.CLOSURES): "spring" for every
    # type; "groove" and "conjugate" (positive drive) where its closure keys and geometry exist
    closures: ClassVar[tuple[str, ...]] = ("spring",)

    # ----------------------------------------------------------------------------- scene

    @abc.abstractmethod
    def parse(self, r: TableReader) -> FollowerSpec:
        """The [follower] table read and checked (SceneError naming the key)."""

    @abc.abstractmethod
    def design_bounds(self, r: TableReader, follower: FollowerSpec) -> dict[str, tuple[float, float]]:
        """The [design] table's design variables as (low, high) bounds, mm (a fixed one as (v, v)),
        in the order of :attr:`variables`, then those of :attr:`optional_variables` the scene has; a
        box in which no design closes is a SceneError."""

    def design_numbers(self, follower: FollowerSpec) -> dict[str, float]:
        """The [follower]'s dimensions a design varies (its :attr:`variables` that are fields of the
        spec, the base radius not), by name: the drawing's programs take them as data, so one
        compiled program serves every design of a scene's follower."""
        from dataclasses import fields

        own = {f.name for f in fields(follower)}
        return {k: getattr(follower, k) for k in self.variables if k != "base_radius_mm" and k in own}

    def without_design_numbers(self, follower: FollowerSpec) -> tuple[FollowerSpec, dict[str, float]]:
        """(the spec with its :meth:`design_numbers` set to 0, those numbers): the first keys a
        drawing program (static, hashable), the second are its data, put back in the traced spec
        with ``dataclasses.replace``."""
        from dataclasses import replace

        numbers = self.design_numbers(follower)
        return replace(follower, **dict.fromkeys(numbers, 0.0)), numbers

    def check_keys(self, r: TableReader) -> None:
        """Refuse a [follower] key of another follower type (naming the types it belongs to) or of
        none, then any key this type does not take."""
        from camjax import followers
        from camjax.scene.spec import CLOSURES

        own = {"type", "closure", *self.keys}
        if "closure" in r.table:
            value = r.table["closure"]
            if value not in CLOSURES:
                raise r.error("closure", value, "is not allowed", ", ".join(self.closures))
            if value not in self.closures:
                owners = [f.name for f in followers.all_followers() if value in f.closures]
                raise r.error("closure", value, f"a {self.title} follower cannot run in a {value} closure "
                              f"(only type = {' or '.join(map(repr, owners))})", ", ".join(self.closures))
        for key in r.table:
            if key in own:
                continue
            owners = [f.name for f in followers.all_followers() if key in f.keys]
            if owners:
                raise r.error(key, r.table[key], f"only for type = {' or '.join(map(repr, owners))}, not "
                              f"type = {self.name!r}", ", ".join(self.keys))
        r.check_keys(("type", "closure", *self.keys))

    # ---------------------------------------------------------------------------- design

    def problem_module(self) -> ModuleType:
        """The folder's design problem (``problem.py``: the solvers' family protocol)."""
        return self.module("problem")

    @abc.abstractmethod
    def run(self, scene, arrays=None, *, base_radius_mm: float | None = None, dtype=None):
        """Every model the scene declares at its design: the smallest admissible cam, the solved
        [design] (if any), the radius the cam is drawn at (``base_radius_mm`` overrides it), the
        curves there and the constraints they break. The run's ``curves`` are what the drawing
        module draws; :meth:`report` formats the whole run."""

    # ---------------------------------------------------------------------------- output

    def report(self, scene, run) -> dict[str, Any]:
        """result.json of a run (the folder's ``report.py``)."""
        return self.module("report").report(scene, run)

    def drawing(self) -> ModuleType:
        """The folder's ``drawing.py`` (NumPy and matplotlib only, no JAX): ``figure_builders(curves)``,
        ``profile_table(curves)``, ``mechanism(curves, title, violation)`` (the animation's
        :class:`camjax.output.animation.Mechanism`), ``follower_points(m, s)`` and
        ``artists(ax, m, poses, r_max)`` (its pose and artists in the animation)
        and ``CONTACT_SHAPE`` ("face" or "circle": what touches the
        cam, which the riding check of tests/test_followers.py rides on the exported outline)."""
        return self.module("drawing")

    @abc.abstractmethod
    def summary(self, design: dict[str, Any]) -> str:
        """The sizes of a solved design (result.json's ``design`` block) in one line, for the
        command line, e.g. ``R_f = 5.0000 mm, offset 1.0000 mm, R_p = 30.0000 mm``."""

    def drawn_summary(self, data: dict[str, Any]) -> str:
        """What the command line adds after "files drawn at R_b = ..." from result.json ``data``
        (e.g. ``, L = 19.0986 mm``); default nothing."""
        return ""

    def title_dimensions(self, data: dict[str, Any]) -> list[str]:
        """The words the figures' title block gives the follower's own dimensions, the ones the cam
        was drawn with, from result.json ``data`` (e.g. ``["R_f = 8 mm, e = 0 mm"]``; the base radius
        and a face width are in the shared line, :func:`camjax.output.titles.title_block`); default
        none. Text only: the title is worded where the design ran, before its figures are drawn."""
        return []

    # ---------------------------------------------------------------------------- folder

    def module(self, layer: str) -> ModuleType:
        """The folder's module of one layer: ``geometry``, ``problem``, ``report`` or ``drawing``."""
        return importlib.import_module(f"camjax.followers.{self.name}.{layer}")
