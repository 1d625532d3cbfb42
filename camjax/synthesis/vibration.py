"""The follower train's response to a designed segment, as linear maps of the law's control values:
the residual vibration after the segment and the contact force during it (``residual_vibration``
and ``peak_force`` of the synthesis objective).

The model is the elastic follower train of :mod:`camjax.dynamics.plant` (the cam imposes the
follower motion theta2; the load theta3 follows through k23, damped to ground by c3:
I3 theta3'' + c3 theta3' + k23 theta3 = k23 theta2) and the contact force of
:func:`camjax.dynamics.jump.contact_force`, F = I2 theta2'' + c2 theta2' + k_s (theta2 + x0)
+ k23 (theta2 - theta3) + weight. The caller gives the train as numbers (:class:`Train`, built
from a scene's [dynamics] by :func:`camjax.dynamics.context.synthesis_train`): this model-layer
module imports nothing of the dynamics layer.

Over the segment, theta2 = L + D q(x), x = (phi - phi0) / beta in [0, 1], and the cam turns at
Omega, so x = Omega t / beta. With y = (theta3 - L) / D and the train at rest at the segment's
start (the vibration of earlier segments decayed), y solves

    y'' + 2 zeta r y' + r^2 y = r^2 q(x),  y(0) = y'(0) = 0   (' = d/dx),

with r = omega_n beta / Omega the natural frequency in radians of x (omega_n = sqrt(k23 / I3),
zeta = c3 / (2 sqrt(k23 I3))). Its state z = (y, y' / r) obeys z' = A z + b q with
A = r [[0, 1], [-1, -2 zeta]], b = (0, r), so z(x) is a linear map of q on [0, x], hence of the
control values c. It is computed exactly up to quadrature: z(a + h) = E(h) z(a) + int_0^h E(h - s)
b q(a + s) ds on subintervals that never straddle a knot (q is a polynomial there) and are short
(r h <= 1/2), the integral by Gauss-Legendre with degree + 8 points: the integrand is a polynomial
of degree k times an exponential whose Taylor terms beyond degree 2 G - 1 - k are below
(1/2)^(k+16) / (k+16)! ~ 1e-23 relative. E(h) = e^{Ah} is the closed form of a 2 x 2 exponential
(cos/sin, cosh/sinh or its series near critical damping).

**Residual vibration.** After the segment q = 1 (the next segment starts at rest in a dwell), the
tracking error e = y - 1 vibrates freely. Its amplitude is that of the undamped oscillation with
the same energy at the segment's end, A / |D| = sqrt(e(1)^2 + (y'(1) / r)^2) = |z(1) - (1, 0)|
(normalized by the lift; exact for an undamped train, and the envelope's start for a lightly
damped one). Since q(1) = c_n = 1 on every designed law (a condition), z(1) - (1, 0) = U c with
U = Z(1) - (e_n, 0): A^2 / D^2 = c^T U^T U c is a convex quadratic in c. Over a speed band it is
the mean of those over the band's speeds.

**Contact force.** F(x) = D [I2 Omega^2 / beta^2 q'' + c2 Omega / beta q' + (k_s + k23) q - k23 y]
+ k_s (L + x0) + weight, linear in c (the constant times c_n = 1), at the design speed.

The matrices are NumPy arrays: static data of a synthesis problem, built once per segment without
tracing anything (as :mod:`camjax.synthesis.basis`'s); the synthesis that uses them is the pure JAX
solve of :mod:`camjax.synthesis.solve`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from camjax.synthesis.basis import Basis, evaluation_matrix, span_points

STEP = 0.5  # largest r h (radians of the train's natural frequency) of one quadrature subinterval
EXTRA_NODES = 8  # Gauss-Legendre points beyond the degree on each subinterval
BUILTIN_GRID = 64  # subintervals per unit for a built-in law (its breaks are at multiples of 1/8)
MEASURE_PER_SPAN = 64  # points per knot span for the reported peak force


class Train(NamedTuple):
    """The follower train of a scene as numbers (SI of the follower kind: m or rad, kg or kg m^2,
    N or N m). ``speed_factors``: the speeds of the residual term, factors of the cam speed."""

    natural_frequency_rad_s: float  # omega_n of the load (sqrt(k23 / I3))
    damping_ratio: float  # zeta
    cam_speed_rad_s: float  # the design speed Omega
    speed_factors: tuple[float, ...]  # (1.0,) or a band around it
    stiffness: float  # k23
    follower_inertia: float  # I2
    follower_damping: float  # c2
    spring_rate: float | None  # k_s (None: no spring; peak_force is then undefined)
    spring_preload: float  # x0
    weight: float
    segments: dict  # designed segment index -> (level at its start, signed lift), SI


class TrainTerms(NamedTuple):
    """A designed segment's train terms as matrices on the control values (static NumPy data)."""

    residual_rows: np.ndarray  # (speeds, 2, n): z(1) - (1, 0) per speed is residual_rows @ c
    residual_gram: np.ndarray  # (n, n): mean over speeds of |z(1) - (1, 0)|^2 is c^T Q c
    force_rows: np.ndarray | None  # (points, n) F at the sampled points (N), None without a spring
    force_dense: np.ndarray | None  # (points, n) F on MEASURE_PER_SPAN points per span


def _exp_parts(r: float, zeta: float, tau: np.ndarray):
    """e^{-zeta r tau}, C = cosh(delta tau), S = sinh(delta tau) / delta, delta^2 = r^2 (zeta^2 - 1)
    (cos and sin / omega_d below critical damping; a series where |delta tau| is tiny)."""
    d2 = r * r * (zeta * zeta - 1.0)
    tau = np.asarray(tau, dtype=np.float64)
    small = abs(d2) * float(np.max(tau, initial=0.0)) ** 2 < 1e-6
    if small:
        u = d2 * tau * tau
        c = 1.0 + u / 2.0 + u * u / 24.0
        s = tau * (1.0 + u / 6.0 + u * u / 120.0)
    elif d2 < 0.0:
        w = np.sqrt(-d2)
        c, s = np.cos(w * tau), np.sin(w * tau) / w
    else:
        d = np.sqrt(d2)
        c, s = np.cosh(d * tau), np.sinh(d * tau) / d
    return np.exp(-zeta * r * tau), c, s


def _transition(r: float, zeta: float, tau: np.ndarray) -> np.ndarray:
    """e^{A tau}, (..., 2, 2): e^{-zeta r tau} [C I + S (A + zeta r I)], A + zeta r I = r [[zeta, 1],
    [-1, -zeta]]."""
    g, c, s = _exp_parts(r, zeta, tau)
    out = np.empty((*np.shape(tau), 2, 2))
    out[..., 0, 0] = g * (c + s * r * zeta)
    out[..., 0, 1] = g * s * r
    out[..., 1, 0] = -g * s * r
    out[..., 1, 1] = g * (c - s * r * zeta)
    return out


def _input_response(r: float, zeta: float, tau: np.ndarray) -> np.ndarray:
    """e^{A tau} b, (..., 2), b = (0, r)."""
    e = _transition(r, zeta, tau)
    return r * e[..., :, 1]


def _split(edges: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    """``edges`` with subinterval k split into ``pieces[k]`` equal parts: the points of
    ``np.linspace(edges[k], edges[k + 1], pieces[k] + 1)`` for every k, each edge once, computed
    as linspace computes them (``a + j * ((b - a) / p)``, the last point ``b`` itself) for all
    subintervals at once (a co-design splits ~10^5 of them)."""
    last = np.cumsum(pieces) - 1  # each subinterval's last new point
    first = np.repeat(np.arange(len(pieces)), pieces)  # the subinterval of each new point
    j = np.arange(1, len(first) + 1, dtype=np.float64) - np.repeat(last + 1 - pieces, pieces)
    step = (edges[1:] - edges[:-1]) / pieces
    inner = j * step[first] + edges[:-1][first]
    inner[last] = edges[1:]  # each subinterval's last point: its end, exactly
    return np.concatenate([edges[:1], inner])


def state_maps(r: float, zeta: float, edges: np.ndarray, values_at, degree: int) -> np.ndarray:
    """The state z = (y, y'/r) at every point of ``edges`` (sorted, edges[0] = 0, from rest there)
    as linear maps of the input's coefficients: (len(edges), 2, m), where ``values_at(x)`` gives
    q at points x as (len(x), m) (a basis matrix, or a built-in law's values as one column).
    The edges must include every break of q (a knot); subintervals longer than STEP / r are split.
    """
    edges = np.asarray(edges, dtype=np.float64)
    rate = r * max(1.0, 2.0 * zeta)
    pieces = np.maximum(1, np.ceil(np.diff(edges) * rate / STEP).astype(int))
    fine = _split(edges, pieces)
    keep = np.searchsorted(fine, edges)  # each edge's index on the fine grid
    nodes, weights = np.polynomial.legendre.leggauss(degree + EXTRA_NODES)
    a, h = fine[:-1], np.diff(fine)
    # node positions: x = a + h (1 + t) / 2; the kernel e^{A (h - s)} b at s = x - a
    s = 0.5 * h[:, None] * (1.0 + nodes[None, :])
    x = a[:, None] + s
    kernel = _input_response(r, zeta, h[:, None] - s)  # (P, G, 2)
    q = values_at(x.ravel())
    q = q.reshape(*x.shape, -1)  # (P, G, m)
    forced = np.einsum("pg,pgi,pgm->pim", 0.5 * h[:, None] * weights[None, :], kernel, q)
    trans = _transition(r, zeta, h)  # (P, 2, 2)
    z = np.zeros((len(fine), 2, q.shape[-1]))
    for p in range(len(h)):
        z[p + 1] = trans[p] @ z[p] + forced[p]
    return z[keep]


def ratio(train: Train, angle_deg: float, factor: float = 1.0) -> float:
    """r = omega_n beta / Omega at the speed factor x Omega (beta in rad)."""
    return train.natural_frequency_rad_s * np.deg2rad(angle_deg) / (train.cam_speed_rad_s * factor)


def _basis_values(basis: Basis):
    return lambda x: evaluation_matrix(basis, x, 0)


def train_terms(basis: Basis, train: Train, segment, per_span: int) -> TrainTerms:
    """The residual and force matrices of a designed segment (``segment``: its index, angle_deg;
    its level and lift in ``train.segments``) on ``basis``; ``per_span`` + 1 force samples per
    knot span for the synthesis (as the sampled peaks), 65 for the reported peak."""
    rows, gram = residual_maps(basis, train, segment)
    force = dense = None
    if train.spring_rate is not None and basis.degree >= 2:
        force = force_matrix(basis, train, segment, span_points(basis, per_span))
        dense = force_matrix(basis, train, segment, span_points(basis, MEASURE_PER_SPAN))
    return TrainTerms(rows, gram, force, dense)


def residual_maps(basis: Basis, train: Train, segment) -> tuple[np.ndarray, np.ndarray]:
    """(rows, Q) of the residual vibration on ``basis`` (``segment``: its angle_deg): rows
    (speeds, 2, n) with z(1) - (1, 0) = rows[s] @ c at each speed factor, and Q (n, n) the mean
    over the speeds of rows^T rows (symmetrized), so residual_vibration^2 = c^T Q c."""
    values = _basis_values(basis)
    end_row = evaluation_matrix(basis, np.asarray([1.0]), 0)[0]  # q(1) = c_n
    rows = []
    for f in train.speed_factors:
        z1 = state_maps(ratio(train, segment.angle_deg, f), train.damping_ratio, basis.breaks, values,
                        basis.degree)[-1]
        rows.append(np.stack([z1[0] - end_row, z1[1]]))
    rows = np.asarray(rows)
    gram = np.einsum("sin,sim->nm", rows, rows) / len(rows)
    return rows, 0.5 * (gram + gram.T)


def force_matrix(basis: Basis, train: Train, segment, points: np.ndarray) -> np.ndarray:
    """(len(points), n): the contact force F(x) at ``points`` (N or N m) as rows on c, at the
    design speed (``points`` sorted, including 0 and 1)."""
    edges = np.union1d(points, basis.breaks)
    z = state_maps(ratio(train, segment.angle_deg), train.damping_ratio, edges, _basis_values(basis),
                   basis.degree)
    y = z[np.searchsorted(edges, points), 0]  # (points, n)
    q, v, a = (evaluation_matrix(basis, points, k) for k in (0, 1, 2))
    end_row = evaluation_matrix(basis, np.asarray([1.0]), 0)[0]  # q(1) = 1 carries the constant
    return contact_force(train, segment, q, v, a, y, end_row[None, :])


def contact_force(train: Train, segment, q, v, a, y, one=1.0):
    """F = D [I2 Omega^2 / beta^2 q'' + c2 Omega / beta q' + (k_s + k23) q - k23 y] + (k_s (L + x0)
    + weight) ``one``, from the normalized q, q', q'', y (values or rows on c; ``one``: 1, or the
    row of q(1) to keep the force linear in c)."""
    beta = float(np.deg2rad(segment.angle_deg))
    level, lift = train.segments[segment.index]
    w = train.cam_speed_rad_s
    ks, k23 = float(train.spring_rate), train.stiffness
    const = ks * (level + train.spring_preload) + train.weight
    return (lift * (train.follower_inertia * w**2 / beta**2 * a + train.follower_damping * w / beta * v
                    + (ks + k23) * q - k23 * y) + const * one)


# ------------------------------------------------------------------ a built-in law's figures


def builtin_train_measures(q_of, train: Train, segment) -> dict:
    """``residual_vibration`` (RMS over the speed factors of A / |D|), its values per speed and, with
    a spring, ``peak_force`` (N) of a law given as ``q_of(x) -> (q, q', q'')`` (NumPy), on a grid of
    BUILTIN_GRID subintervals per unit (the built-in laws' breaks are multiples of 1/8)."""
    # one grid fine enough for the slowest speed (largest r), so the law is evaluated once
    r_max = max(ratio(train, segment.angle_deg, f) for f in train.speed_factors)
    per = int(np.ceil(r_max * max(1.0, 2.0 * train.damping_ratio) / STEP / BUILTIN_GRID))
    grid = np.linspace(0.0, 1.0, BUILTIN_GRID * max(1, per) + 1)
    cache: dict = {}

    def values(x):
        key = x.tobytes()
        if key not in cache:
            cache[key] = np.asarray(q_of(x)[0])[:, None]
        return cache[key]

    amps = []
    for f in train.speed_factors:
        z1 = state_maps(ratio(train, segment.angle_deg, f), train.damping_ratio, grid, values, 9)[-1, :, 0]
        amps.append(float(np.hypot(z1[0] - 1.0, z1[1])))
    out = residual_figures(np.asarray(amps))
    if train.spring_rate is not None:
        pts = np.linspace(0.0, 1.0, 4097)
        z = state_maps(ratio(train, segment.angle_deg), train.damping_ratio, pts, values, 9)
        q, v, a = (np.asarray(t) for t in q_of(pts)[:3])
        out["peak_force"] = float(np.max(np.abs(contact_force(train, segment, q, v, a, z[:, 0, 0]))))
    return out


def residual_figures(amplitudes: np.ndarray) -> dict:
    """The reported residual figures from the amplitudes per speed factor (normalized by the lift)."""
    a = np.asarray(amplitudes, dtype=np.float64)
    return {"residual_vibration": float(np.sqrt(np.mean(a**2))),
            "residual_vibration_by_speed": [float(v) for v in a]}
