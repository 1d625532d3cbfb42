"""What every rocking (oscillating) follower shares: the layout, the arm's relative turning rate,
and the scan-and-bisect search of the sizing functions.

Layout (follower frame, fixed; mm). The cam centre O is the origin and the pivot A = (d, 0) lies
on +X at the pivot distance d. The arm angle psi is measured at the pivot from the line of
centres A -> O; the arm's unit vector is u(psi) = (-cos psi, sin psi), so the arm points at the
cam centre for psi = 0 and swings up (+Y) as psi grows. The motion program gives psi = psi0 + s
with s in rad (``lift_deg`` in the scene), psi0 its value at s = 0.

Kinematic inversion. The cam frame turns with the cam as in :mod:`camjax.followers._pitch`: a
follower-frame point x appears at P = R(-sigma theta) x in cam coordinates (sigma = +1 ccw, -1
cw; :func:`camjax.followers._pitch.to_cam_frame`). The same physical layout serves both rotations;
the rotation enters every closed form only through Q = 1 + sigma s', the rate at which the arm
turns relative to the cam (per rad of cam angle). The followers' own closed forms are in
:mod:`camjax.followers.oscillating_roller.geometry` and :mod:`camjax.followers.oscillating_flat.geometry`.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from camjax.followers._pitch import DEFAULT_ROTATION, rotation_sign
from camjax.program import Kinematics

# Arm start angles scanned by the sizing functions before the bisection (see first_admissible).
SIZING_SCAN = 2048
SIZING_BISECTIONS = 80
SIZING_BATCH_VALUES = 1 << 22  # arm angles x samples evaluated at once by the scan (~32 MB of float64)




def relative_rate(kin: Kinematics, rotation: str = DEFAULT_ROTATION) -> jax.Array:
    """Q = 1 + sigma s' (rad/rad): the arm's turning rate relative to the cam, per rad of cam angle.

    In the cam frame the follower frame turns at +sigma per rad of cam angle (P = R(-sigma theta)
    x), so an arm at psi(theta) = psi0 + s turns at s' + sigma relative to the cam, sigma Q.
    """
    return 1.0 + rotation_sign(rotation) * kin.ds


def arm_angle(psi0, kin: Kinematics) -> jax.Array:
    """psi = psi0 + s (rad) at every sample."""
    return psi0 + kin.s



def first_admissible(bad, lo, hi, samples: int, scan: int = SIZING_SCAN,
                      bisections: int = SIZING_BISECTIONS):
    """Smallest x in (lo, hi) with bad(x) False: a scan of ``scan`` points, then a bisection.

    The scan finds the first admissible grid point x_k; bisecting [x_{k-1}, x_k] moves to the
    boundary (80 halvings: below float64 resolution for brackets < 1e5). Returns (x, found);
    x = hi where nothing on the scan is admissible. ``bad`` maps one x (shape ()) to a bool over
    the whole grid of ``samples`` angles; the scan evaluates it in batches of ~SIZING_BATCH_VALUES
    / samples points, so memory stays bounded on dense grids. jit/vmap-safe; not differentiable
    (a search), nor meant to be.
    """
    xs = lo + (hi - lo) * (jnp.arange(1, scan + 1) / (scan + 1))
    ok = ~jax.lax.map(bad, xs, batch_size=max(1, min(scan, SIZING_BATCH_VALUES // max(samples, 1))))
    found = jnp.any(ok)
    k = jnp.argmax(ok)
    a = jnp.where(k > 0, xs[jnp.maximum(k - 1, 0)], lo)
    b = xs[k]

    def halve(_, bracket):
        a, b = bracket
        m = 0.5 * (a + b)
        is_bad = bad(m)
        return jnp.where(is_bad, m, a), jnp.where(is_bad, b, m)

    a, b = jax.lax.fori_loop(0, bisections, halve, (a, b))
    return jnp.where(found, b, hi), found


