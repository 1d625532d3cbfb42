"""The law type every law module builds: :class:`Law` and the values it returns."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import jax
import jax.numpy as jnp


class LawValues(NamedTuple):
    """A normalized law and its derivatives, each with the shape of x."""

    p: jax.Array  # displacement, 0..1
    dp: jax.Array  # dp/dx
    d2p: jax.Array  # d2p/dx2
    d3p: jax.Array  # d3p/dx3


@dataclass(frozen=True, eq=False)
class Law:
    """A normalized rise law.

    Attributes:
      name: registry name, or a generated description for parametric laws.
      evaluate: x -> LawValues, pure JAX, elementwise over any shape of x in [0, 1].
      description: one line for tables and reports.
      end_velocity: p' at both ends; 0 for every rest-to-rest law, 1 for the uniform law (whose
        joints against dwells are therefore velocity jumps, "shock" in the FLCD classes).
    """

    name: str
    evaluate: Callable[[jax.Array], LawValues] = field(repr=False)
    description: str = ""
    end_velocity: float = 0.0

    def __call__(self, x: jax.Array) -> LawValues:
        return self.evaluate(jnp.asarray(x))
