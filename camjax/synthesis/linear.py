"""A program's kinematics as an affine function of its designed laws' free coordinates.

A designed segment moves by s = s0 + D q(x), x = (theta - theta0) / beta, D its signed lift in
the program's units (mm, or rad for a rocking follower) and q = sum_i c_i N_i,k the B-spline of
its normalized control values c = A^+ b + N z (:mod:`camjax.synthesis.problem`: the conditions
met by construction, z free). Its derivatives per radian of cam angle are D q^(r)(x) / beta^r.
Every one is linear in c, hence affine in z; so on the sample grid

    kinematics(z) = kinematics(z0) + J (z - z0),

J built once in NumPy from the basis' evaluation matrices (:func:`camjax.synthesis.basis.evaluation_matrix`,
which agree with the program's de Boor evaluation to rounding), z0 the coordinates of the law the
program moves by now. The samples of a segment are those :func:`camjax.program.motion_at` gives it
(a sample on a joint belongs to the segment that starts there), so the affine map reproduces the
program's own arrays; tests/test_codesign.py checks it against a program built from c(z).

The squared-derivative objective terms (``l2_accel``, ``l2_jerk``) are quadratics in z here.
Designed segments are read by duck typing (``index``, ``kind``, ``conditions``, ``values``,
``basis()``), so this model-layer module imports nothing of the scene layer.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from camjax.synthesis.basis import evaluation_matrix, gram_matrix
from camjax.synthesis.problem import L2_OBJECTIVES, build_problem, kept_values


class LinearSegment(NamedTuple):
    """One designed segment's part of the affine map (NumPy)."""

    index: int  # in the program
    cp: np.ndarray  # (n,) particular control values, A^+ b
    null: np.ndarray  # (n, m) orthonormal null-space basis
    offset: int  # its coordinates are z[offset: offset + m]
    knots: np.ndarray  # full clamped knot vector


class LinearKinematics(NamedTuple):
    """kinematics(z) = kin0 + J (z - z0) on the grid (NumPy, static data of a co-design)."""

    segments: tuple[LinearSegment, ...]
    jacobian: np.ndarray  # (4, samples, free): rows s, s', s'', s''' (program units per rad^r)
    z0: np.ndarray  # (free,) coordinates of the laws the program moves by now

    @property
    def free(self) -> int:
        return self.jacobian.shape[-1]

    def control(self, z) -> list[np.ndarray]:
        """Each designed segment's normalized control values c = cp + N z (NumPy)."""
        z = np.asarray(z, dtype=np.float64)
        return [s.cp + s.null @ z[s.offset: s.offset + s.null.shape[1]] for s in self.segments]

    def coordinates(self, controls) -> np.ndarray:
        """The z of given normalized control values (their projection onto the conditions' set)."""
        z = np.zeros(self.free)
        for s, c in zip(self.segments, controls, strict=True):
            z[s.offset: s.offset + s.null.shape[1]] = s.null.T @ (np.asarray(c, dtype=np.float64) - s.cp)
        return z


def segment_samples(program, index: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The sample indices on the grid of ``samples`` angles that belong to segment ``index`` and
    their local coordinates x (the selection rule of :func:`camjax.program.motion_at`)."""
    theta = np.arange(samples, dtype=np.float64) * (360.0 / samples)
    lo, width = program.start_deg[index], program.angles_deg[index]
    inside = (theta >= lo) & (theta < lo + width)
    if index == len(program.angles_deg) - 1:
        inside = theta >= lo
    rows = np.nonzero(inside)[0]
    return rows, np.clip((theta[rows] - lo) / width, 0.0, 1.0)


def linear_kinematics(program, designed, samples: int, z0_controls) -> LinearKinematics:
    """The affine map of the designed segments ``designed`` of ``program`` on ``samples`` angles;
    ``z0_controls``: the normalized control values each segment's law in ``program`` has now."""
    lifts = np.asarray(program.lifts, dtype=np.float64)
    parts, blocks, z0, offset = [], [], [], 0
    for ds, c0 in zip(designed, z0_controls, strict=True):
        basis = ds.basis()
        problem = build_problem(basis, ds.conditions, ())
        cp = problem.A_pinv @ kept_values(problem, np.asarray(ds.values, dtype=np.float64))
        null = problem.null
        i = ds.index
        signed = lifts[i] if program.kinds[i] == "rise" else -lifts[i]
        beta = math.radians(program.angles_deg[i])
        rows, x = segment_samples(program, i, samples)
        block = np.zeros((4, samples, null.shape[1]))
        for r in range(4):
            block[r, rows] = signed / beta**r * (evaluation_matrix(basis, x, r) @ null)
        blocks.append(block)
        parts.append(LinearSegment(i, cp, null, offset, basis.knots))
        z0.append(null.T @ (np.asarray(c0, dtype=np.float64) - cp))
        offset += null.shape[1]
    jac = np.concatenate(blocks, axis=-1) if blocks else np.zeros((4, samples, 0))
    return LinearKinematics(tuple(parts), jac, np.concatenate(z0) if z0 else np.zeros(0))


def law_quadratics(lin: LinearKinematics, designed, weights: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """The weighted squared-derivative terms of ``weights`` ({l2 name: weight}) summed over the
    designed segments as 0.5 z^T P z + q^T z + const (normalized units, as ``camjax synthesize``)."""
    m = lin.free
    P, q, const = np.zeros((m, m)), np.zeros(m), 0.0
    for seg, ds in zip(lin.segments, designed, strict=True):
        basis = ds.basis()
        sl = slice(seg.offset, seg.offset + seg.null.shape[1])
        for name, w in weights.items():
            Q = gram_matrix(basis, L2_OBJECTIVES[name])
            NQ = seg.null.T @ Q
            P[sl, sl] += 2.0 * w * NQ @ seg.null
            q[sl] += 2.0 * w * NQ @ seg.cp
            const += w * float(seg.cp @ Q @ seg.cp)
    return P, q, const
