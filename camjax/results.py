"""Result types every layer shares, low in the package so that all can use them.

- :class:`Status`: the one enumeration of a solve's outcome, each code with its message (the
  traced result carries the int32 code, ``Solution.status``; result.json its name);
- :class:`Extremes`: max and min of one curve over the cam angle and where they occur;
- :class:`MinBaseRadius`: the smallest admissible cam of a follower and the limit that binds;
- :class:`GeometryViolation`: one constraint an evaluated geometry breaks, in one sentence.

None of them depends on a follower type: each follower fills them in (:mod:`camjax.followers`).
"""

from __future__ import annotations

import enum
from typing import NamedTuple


class Status(enum.IntEnum):
    """Outcome of one solve (``Solution.status``, int32 in the traced result)."""

    CONVERGED = 0
    MAX_STEPS = 1
    INFEASIBLE = 2

    @property
    def message(self) -> str:
        """One sentence a report or a user reads."""
        return _MESSAGES[self]

    @classmethod
    def name_of(cls, code) -> str:
        """The lower-case name result.json writes for a code ("converged", ...)."""
        return cls(int(code)).name.lower()


_MESSAGES = {
    Status.CONVERGED: "the solver's stopping rule was met and the design is feasible",
    Status.MAX_STEPS: "feasible, but the step or generation budget ran out first (the GA's only stopping rule)",
    Status.INFEASIBLE: "the design violates a constraint beyond the feasibility tolerances",
}


class Extremes(NamedTuple):
    """Max and min of one curve over the cam angle and where they occur (Python floats, deg)."""

    max: float
    max_deg: float
    min: float
    min_deg: float


class MinBaseRadius(NamedTuple):
    """Smallest admissible base radius, the cam angle where it binds and the limit that binds."""

    radius_mm: float
    angle_deg: float
    binding: str  # the follower's name of the limit: "curvature", "pressure_angle", "undercut", ...
    prime_radius_mm: float | None = None  # a roller-like follower's R_b + its radius


class GeometryViolation(NamedTuple):
    """One constraint the evaluated geometry breaks: a key and one sentence with the figures."""

    constraint: str  # curvature, stress, face_width, pressure_angle, undercut, contact, ...
    message: str
