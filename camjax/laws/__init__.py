"""Normalized motion laws p(x), x in [0, 1], p(0) = 0, p(1) = 1 (SPEC section 1).

A :class:`Law` evaluates p, p', p'', p''' (derivatives with respect to x) in closed form over
any array of x at once. Laws are immutable, hashable and compared by identity, so a program can
carry them as static structure through ``jax.jit``; factories are cached so that the same
exponent list or coefficient table gives the same object (and the same compiled code).

Scaling to a rise of lift h over cam angle beta (radians):
s = h p(theta/beta), s' = h p'/beta, s'' = h p''/beta**2, s''' = h p'''/beta**3.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from camjax.laws.base import Law as Law
from camjax.laws.base import LawValues as LawValues
from camjax.laws.polynomial import PolynomialLaw as PolynomialLaw
from camjax.laws.polynomial import bernstein_law as bernstein_law
from camjax.laws.polynomial import boundary_condition_number as boundary_condition_number
from camjax.laws.polynomial import polynomial_coefficients as polynomial_coefficients
from camjax.laws.polynomial import polynomial_law as polynomial_law

PI = math.pi


# ------------------------------------------------------------------------------- uniform


def _uniform(x):
    # constant velocity, the textbook's first law: p'' and p''' vanish inside, so the whole
    # change of velocity happens at the ends (a shock against a dwell)
    z = jnp.zeros_like(x)
    return LawValues(x, jnp.ones_like(x), z, z)


# ---------------------------------------------------------------------------- trigonometric


def _harmonic(x):
    return LawValues(
        0.5 * (1.0 - jnp.cos(PI * x)),
        0.5 * PI * jnp.sin(PI * x),
        0.5 * PI**2 * jnp.cos(PI * x),
        -0.5 * PI**3 * jnp.sin(PI * x),
    )


def _cycloidal(x):
    w = 2.0 * PI
    return LawValues(
        x - jnp.sin(w * x) / w,
        1.0 - jnp.cos(w * x),
        w * jnp.sin(w * x),
        w**2 * jnp.cos(w * x),
    )


def _double_harmonic(x):
    c1, c2 = jnp.cos(PI * x), jnp.cos(2 * PI * x)
    s1, s2 = jnp.sin(PI * x), jnp.sin(2 * PI * x)
    return LawValues(
        0.5 * ((1.0 - c1) - 0.25 * (1.0 - c2)),
        0.5 * (PI * s1 - 0.5 * PI * s2),
        0.5 * PI**2 * (c1 - c2),
        0.5 * PI**3 * (-s1 + 2.0 * s2),
    )


def _double_cycloidal(x):
    w = 2.0 * PI
    k = 4.0 / 3.0
    return LawValues(
        k * ((x - jnp.sin(w * x) / w) - 0.25 * (x - jnp.sin(2 * w * x) / (2 * w))),
        k * ((1.0 - jnp.cos(w * x)) - 0.25 * (1.0 - jnp.cos(2 * w * x))),
        k * (w * jnp.sin(w * x) - 0.5 * w * jnp.sin(2 * w * x)),
        k * (w**2 * jnp.cos(w * x) - w**2 * jnp.cos(2 * w * x)),
    )


# --------------------------------------------------- piecewise-sine acceleration (mod. trap/sine)


def _piecewise_sine_law(name: str, pieces: Sequence[tuple[float, float, float, float, float]], desc):
    """Law whose acceleration is A*(c0 + c1*sin(w*(x - x0) + phi)) on [x0, x1] for each piece.

    ``pieces`` = (x0, c0, c1, w, phi). Velocity and displacement are integrated exactly piece by
    piece (continuity at each break), and A is chosen so that p(1) = 1.
    """
    starts = [p[0] for p in pieces] + [1.0]

    def integrate(v0, s0, c0, c1, w, phi, u):
        v = v0 + c0 * u + c1 * (math.cos(phi) - math.cos(w * u + phi)) / w
        s = s0 + v0 * u + c0 * u * u / 2 + c1 * (
            u * math.cos(phi) / w - (math.sin(w * u + phi) - math.sin(phi)) / w**2
        )
        return v, s

    v0s, s0s = [], []
    v, s = 0.0, 0.0
    for (x0, c0, c1, w, phi), x1 in zip(pieces, starts[1:], strict=True):
        v0s.append(v)
        s0s.append(s)
        v, s = integrate(v, s, c0, c1, w, phi, x1 - x0)
    amp = 1.0 / s  # p(1) = 1

    def evaluate(x):
        out = [jnp.zeros_like(x) for _ in range(4)]
        for i, (x0, c0, c1, w, phi) in enumerate(pieces):
            inside = (x >= x0) & (x < starts[i + 1]) if i < len(pieces) - 1 else x >= x0
            u = x - x0
            sw = jnp.sin(w * u + phi)
            cw = jnp.cos(w * u + phi)
            vals = (
                amp * (s0s[i] + v0s[i] * u + c0 * u * u / 2
                       + c1 * (u * math.cos(phi) / w - (sw - math.sin(phi)) / w**2)),
                amp * (v0s[i] + c0 * u + c1 * (math.cos(phi) - cw) / w),
                amp * (c0 + c1 * sw),
                amp * c1 * w * cw,
            )
            out = [jnp.where(inside, val, o) for val, o in zip(vals, out, strict=True)]
        return LawValues(*out)

    return Law(name, evaluate, desc)


_W4 = 4.0 * PI
_MOD_TRAP = _piecewise_sine_law(
    "modified_trapezoid",
    [
        (0.0, 0.0, 1.0, _W4, 0.0),  # sine blend up to +A
        (1 / 8, 1.0, 0.0, 1.0, 0.0),  # constant +A
        (3 / 8, 0.0, 1.0, _W4, PI / 2),  # +A -> -A through a half sine
        (5 / 8, -1.0, 0.0, 1.0, 0.0),  # constant -A
        (7 / 8, 0.0, 1.0, _W4, -PI / 2),  # -A -> 0
    ],
    "modified trapezoid: cycloidal blends on [0,1/8], [3/8,5/8], [7/8,1], constant between",
)
_MOD_SINE = _piecewise_sine_law(
    "modified_sine",
    [
        (0.0, 0.0, 1.0, _W4, 0.0),  # quarter sine of period 1/2 up to +A
        (1 / 8, 0.0, 1.0, _W4 / 3, PI / 2),  # +A -> -A over [1/8, 7/8], period 3/2
        (7 / 8, 0.0, 1.0, _W4, -PI / 2),  # -A -> 0
    ],
    "modified sine: quarter-period sine ends, long sine in the middle",
)


# -------------------------------------------------------------------------------- stepped

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(32)


def stepped_law(half_acceleration: Callable[[jax.Array], jax.Array], name: str = "stepped") -> Law:
    """Stepped law from a half-acceleration a_A(x) on [0, 1/2], zero at both ends (SPEC 1).

    p_A = c * integral_0^x (x - t) a_A(t) dt with c chosen so that p_A(1/2) = 1/2; the second half
    by symmetry, p(x) = 1 - p_A(1 - x). The integrals use 32-point Gauss-Legendre quadrature
    (exact for polynomial a_A up to degree 61); the jerk is ``jax.grad`` of a_A.

    ``half_acceleration`` must be a pure JAX function of a scalar. The returned law is built
    once per call: keep and reuse it so jitted programs are not recompiled.
    """
    nodes = jnp.asarray((_GL_NODES + 1.0) / 2.0)  # on [0, 1]
    weights = jnp.asarray(_GL_WEIGHTS / 2.0)
    d_accel = jnp.vectorize(jax.grad(half_acceleration))
    accel = jnp.vectorize(half_acceleration)

    def raw(x):  # unscaled p_A, p_A' for x in [0, 1/2]
        t = x[..., None] * nodes
        a = accel(t)
        vel = x * jnp.sum(weights * a, axis=-1)
        disp = x * jnp.sum(weights * (x[..., None] - t) * a, axis=-1)
        return disp, vel

    scale = 0.5 / float(raw(jnp.asarray(0.5))[0])
    if not math.isfinite(scale):
        raise ValueError(f"stepped law '{name}': the half acceleration integrates to zero lift")

    def evaluate(x):
        first = x <= 0.5
        xa = jnp.where(first, x, 1.0 - x)
        disp, vel = raw(xa)
        a, j = accel(xa), d_accel(xa)
        return LawValues(
            jnp.where(first, scale * disp, 1.0 - scale * disp),
            scale * vel,
            jnp.where(first, scale * a, -scale * a),
            scale * j,
        )

    return Law(name, evaluate, f"stepped law from half acceleration {name}")


# -------------------------------------------------------------------------------- Fourier


@dataclass(frozen=True)
class FourierSeries:
    """Limited Fourier series over the whole cycle: s(t) = h0 + sum_i h_i cos(i t + phi_i).

    Attributes:
      h0: mean level (units of the motion: mm, or rad for an oscillating follower).
      harmonics: tuple of (i, h_i, phi_i) with i >= 1, phi in radians.
    """

    h0: float
    harmonics: tuple[tuple[int, float, float], ...]

    def evaluate(self, theta: jax.Array) -> LawValues:
        """s, ds/dtheta, d2s/dtheta2, d3s/dtheta3 at cam angles ``theta`` (rad)."""
        theta = jnp.asarray(theta)
        out = [jnp.full_like(theta, self.h0)] + [jnp.zeros_like(theta) for _ in range(3)]
        for i, h, phi in self.harmonics:
            arg = i * theta + phi
            c, s = h * jnp.cos(arg), h * jnp.sin(arg)
            out[0] = out[0] + c
            out[1] = out[1] - i * s
            out[2] = out[2] - i**2 * c
            out[3] = out[3] + i**3 * s
        return LawValues(*out)

    @classmethod
    def from_mapping(cls, coefficients: Mapping[str, float], phases: Mapping[str, float] | None = None):
        """From ``{"h0": .., "h1": .., "h3": ..}`` and optional ``{"phi1": ..}`` (rad)."""
        phases = dict(phases or {})
        h0 = float(coefficients.get("h0", 0.0))
        harmonics = []
        for key, value in coefficients.items():
            if key == "h0":
                continue
            if not (key.startswith("h") and key[1:].isdigit() and int(key[1:]) >= 1):
                raise ValueError(f"coefficients: key '{key}' must be h0, h1, h2, ...")
            i = int(key[1:])
            harmonics.append((i, float(value), float(phases.pop(f"phi{i}", 0.0))))
        if phases:
            raise ValueError(f"phases: {sorted(phases)} have no matching amplitude h<i>")
        return cls(h0, tuple(sorted(harmonics)))


# Nominal cam of the dynamic-compensation thesis (oscillating follower, amplitudes in rad).
THESIS_NOMINAL = FourierSeries(
    0.2417,
    ((1, 0.2667, 0.0), (3, -0.0254, 0.0), (5, 0.0004257, 0.0), (7, -0.00004702, 0.0),
     (9, 0.00001073, 0.0)),
)
FOURIER_PRESETS: dict[str, FourierSeries] = {"thesis_nominal": THESIS_NOMINAL}


@functools.cache
def fourier_law(series: FourierSeries) -> Law:
    """The rising half of a limited Fourier series, normalized to a rise law.

    p(x) = (S(pi (1 + x)) - S(pi)) / (S(2 pi) - S(pi)): the series from its value at pi to its
    value at 2 pi. For a cosine series with odd harmonics and zero phases (the thesis' nominal
    cam), a rise of 180 deg followed by a return of 180 deg reproduces the series exactly.
    """
    lo = series.evaluate(jnp.asarray(PI))
    hi = series.evaluate(jnp.asarray(2 * PI))
    span = float(hi.p - lo.p)
    if abs(span) < 1e-300 or not math.isfinite(span):
        raise ValueError("coefficients: the series takes the same value at 180 and 360 deg")

    def evaluate(x):
        v = series.evaluate(PI * (1.0 + x))
        return LawValues((v.p - lo.p) / span, PI * v.dp / span, PI**2 * v.d2p / span,
                         PI**3 * v.d3p / span)

    return Law("fourier", evaluate, f"limited Fourier series, {len(series.harmonics)} harmonics")


# ------------------------------------------------------------------------------- registry

LAWS: dict[str, Law] = {
    "uniform": Law("uniform", _uniform, "uniform (constant velocity) x", end_velocity=1.0),
    "harmonic": Law("harmonic", _harmonic, "simple harmonic 1/2 (1 - cos pi x)"),
    "cycloidal": Law("cycloidal", _cycloidal, "cycloidal x - sin(2 pi x)/(2 pi)"),
    "double_harmonic": Law("double_harmonic", _double_harmonic,
                           "double harmonic 1/2[(1 - cos pi x) - 1/4 (1 - cos 2 pi x)]"),
    "double_cycloidal": Law("double_cycloidal", _double_cycloidal, "double cycloidal"),
    "modified_trapezoid": _MOD_TRAP,
    "modified_sine": _MOD_SINE,
}
for _exps in [(3, 4), (4, 5), (3, 4, 5), (4, 5, 6), (3, 4, 5, 6), (4, 5, 6, 7)]:
    LAWS[polynomial_law(_exps).name] = polynomial_law(_exps)


def get_law(name: str) -> Law:
    """The registered law called ``name``; ValueError naming the allowed names otherwise."""
    try:
        return LAWS[name]
    except KeyError:
        raise ValueError(f"unknown law '{name}'; allowed: {', '.join(LAWS)}") from None


class LawSummary(NamedTuple):
    """Peaks of a normalized law on a dense grid and its FLCD status against dwells."""

    name: str
    peak_velocity: float  # max |p'|
    peak_accel_pos: float  # max p''
    peak_accel_neg: float  # min p'' (negative)
    peak_jerk: float  # max |p'''| (finite part; see end_jerk for the end values)
    end_accel: tuple[float, float]  # p''(0), p''(1)
    end_jerk: tuple[float, float]  # p'''(0), p'''(1)
    flcd_against_dwells: bool  # p', p'' vanish at both ends
    perturbation_against_dwells: bool  # p''' does not vanish at an end
    end_velocity: tuple[float, float] = (0.0, 0.0)  # p'(0), p'(1)


PEAK_CANDIDATES = 4  # grid maxima refined per quantity (a tie of two peaks needs both)
ZOOM_POINTS = 33  # points of each refining window (its spacing shrinks 16-fold per stage)
ZOOM_STAGES = 3


def _figures(law: Law, x):
    """The ten figures of :class:`LawSummary` as one array: the peaks max |p'|, max p'', min p'',
    max |p'''| and the end values p', p'', p''' at x = 0 and 1.

    Each peak starts from the grid ``x``: its :data:`PEAK_CANDIDATES` largest samples are refined
    :data:`ZOOM_STAGES` times by a window of :data:`ZOOM_POINTS` points spanning the neighbouring
    spacing on either side, centred on the best point of the last window. The result is the
    largest value seen anywhere, so it is never below the grid's. On a grid of 2001 points the
    final spacing is 1.2e-7: a smooth peak is found to ~1e-14 times its curvature, a peak at a jump
    of a piecewise law (the modified laws' jerk) to 1.2e-7 times the slope beside it.
    """
    grid = law(x)
    quantities = (lambda v: jnp.abs(v.dp), lambda v: v.d2p, lambda v: -v.d2p, lambda v: jnp.abs(v.d3p))
    best = jnp.stack([jnp.max(q(grid)) for q in quantities])
    centres = jnp.stack([x[jax.lax.top_k(q(grid), PEAK_CANDIDATES)[1]] for q in quantities])  # (4, k)
    offsets = jnp.linspace(-1.0, 1.0, ZOOM_POINTS)
    rows = jnp.arange(PEAK_CANDIDATES)

    def zoom(_, carry):  # one law call in the loop body: a small program for a table of laws
        best, centres, half = carry
        points = jnp.clip(centres[..., None] + half * offsets, x[0], x[-1])  # (4, k, zoom)
        v = law(points)
        values = jnp.stack([q(LawValues(*(c[i] for c in v))) for i, q in enumerate(quantities)])
        centres = jnp.stack([points[i, rows, jnp.argmax(values[i], axis=1)] for i in range(4)])
        return jnp.maximum(best, jnp.max(values, axis=(1, 2))), centres, 2.0 * half / (ZOOM_POINTS - 1)

    half = (x[-1] - x[0]) / (x.shape[0] - 1)
    best, _, _ = jax.lax.fori_loop(0, ZOOM_STAGES, zoom, (best, centres, half))
    # the grid's first and last points are the ends x = 0 and 1
    return jnp.stack([best[0], best[1], -best[2], best[3], grid.dp[0], grid.dp[-1], grid.d2p[0],
                      grid.d2p[-1], grid.d3p[0], grid.d3p[-1]])


def _figures_of(laws: tuple, x):
    """:func:`_figures` of every law, (L, 10): mapped over the law's index (``lax.switch`` picks
    its closed form), so the refinement is traced once for the whole table."""
    def law_at(index, points):
        return jax.lax.switch(index, laws, points)

    return jax.vmap(lambda i: _figures(functools.partial(law_at, i), x))(jnp.arange(len(laws)))


def summarize(law: Law, samples: int = 2001, tol: float = 1e-9) -> LawSummary:
    """Peaks of ``law`` refined from a grid of ``samples`` points on [0, 1] (see :func:`_figures`)."""
    return summarize_all([law], samples, tol)[0]


def summarize_all(laws: Sequence[Law], samples: int = 2001, tol: float = 1e-9) -> list[LawSummary]:
    """:func:`summarize` of every law of ``laws``, in one compiled program.

    Evaluated op by op, each law's peaks cost a dispatch (and a compile or a cache read) per
    operation; here every law's figures are one ``jax.jit`` program: one trace and one compile
    (or compilation-cache read) for the whole table. (A saved program,
    :func:`camjax.runtime.program_cache`, loads slower than this small program traces.) Not itself
    traceable (it returns Python numbers).
    """
    laws = tuple(laws)
    x = jnp.linspace(0.0, 1.0, samples)
    table = np.asarray(jax.jit(_figures_of, static_argnums=0)(laws, x))
    out = []
    for law, row in zip(laws, table, strict=True):
        e_v, e_a, e_j = row[4:6], row[6:8], row[8:10]
        out.append(LawSummary(
            law.name, float(row[0]), float(row[1]), float(row[2]), float(row[3]),
            (float(e_a[0]), float(e_a[1])), (float(e_j[0]), float(e_j[1])),
            bool(np.all(np.abs(e_v) < tol) and np.all(np.abs(e_a) < tol)),
            bool(np.any(np.abs(e_j) >= tol)),
            (float(e_v[0]), float(e_v[1])),
        ))
    return out
