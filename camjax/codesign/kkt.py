"""The inner optimum's multipliers (NumPy): which constraints hold the co-design's inner geometry
where it is, and how hard, for the envelope gradient of :mod:`camjax.codesign.problem`.

At the inner optimum d* the multipliers lambda >= 0 of the active constraints satisfy
stationarity, grad f + sum lambda_i grad g_i - mu_lo + mu_hi = 0; they are its nonnegative
least-squares solution (:func:`nnls`) over every angle's active row and the active bounds.
"""

from __future__ import annotations

import jax
import numpy as np

ACTIVE_RTOL = 1e-7  # a constraint is active within this fraction of the problem's size norm


def multipliers(values, jac, design, lower, upper, size_norm) -> np.ndarray:
    """Multipliers lambda >= 0 of the constraints (every angle's) at ``design``: the nonnegative
    least-squares solution of stationarity grad f + sum lambda_i grad g_i - mu_lo + mu_hi = 0 over
    the active constraints (g_i within :data:`ACTIVE_RTOL` of the size norm of 0) and the active
    bounds (:func:`nnls`). Every angle's constraint is its own column, so a constraint whose
    maximum is reached at two angles at once (a kink of the maximum: e.g. a roller's pressure
    angle on the rise and on the return, balanced by the offset) gets a multiplier at each.
    Inactive constraints get 0; the box's multipliers are dropped (the box does not depend on z)."""
    grads = np.stack([np.asarray(leaf, dtype=np.float64) for leaf in jax.tree.leaves(jac)], axis=-1)
    g = np.asarray(values[1:], dtype=np.float64)
    tol = ACTIVE_RTOL * float(size_norm)
    active = np.nonzero(g > -tol)[0]
    d = np.asarray([float(v) for v in jax.tree.leaves(design)])
    lo = np.asarray([float(v) for v in jax.tree.leaves(lower)])
    hi = np.asarray([float(v) for v in jax.tree.leaves(upper)])
    eye = np.eye(d.size)
    cols = [grads[1 + i] for i in active]
    cols += [-eye[i] for i in range(d.size) if d[i] - lo[i] <= tol]
    cols += [eye[i] for i in range(d.size) if hi[i] - d[i] <= tol]
    lam = np.zeros(g.size)
    if cols:
        sol = nnls(np.stack(cols, axis=1), -grads[0])
        lam[active] = sol[:active.size]
    return lam


def nnls(A: np.ndarray, b: np.ndarray, iterations: int = 200) -> np.ndarray:
    """min ||A x - b|| subject to x >= 0, by Lawson and Hanson's active-set method (NumPy; the
    problems here have a few rows and a few dozen columns)."""
    m, n = A.shape
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    tol = 1e-12 * max(1.0, float(np.abs(A).max(initial=0.0)) * float(np.abs(b).max(initial=0.0)))
    for _ in range(iterations):
        w = A.T @ (b - A @ x)
        if passive.all() or np.max(np.where(passive, -np.inf, w)) <= tol:
            break
        passive[int(np.argmax(np.where(passive, -np.inf, w)))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(A[:, passive], b, rcond=None)[0]
            if np.all(z[passive] > 0.0):
                x = z
                break
            neg = passive & (z <= 0.0)
            alpha = np.min(x[neg] / (x[neg] - z[neg]))
            x = x + alpha * (z - x)
            passive &= x > tol
    return x
