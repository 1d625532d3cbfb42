"""Cam laws as limited Fourier series over one revolution (SPEC 6).

f(phi) = a0 + sum_n a_n cos(n phi) + b_n sin(n phi), phi the cam angle in rad, f in motion
units (m or rad). A motion program becomes one through the FFT of its samples
(:func:`harmonics_from_samples`): exactly for a band-limited law such as the thesis' nominal cam,
by truncation otherwise.
"""

from __future__ import annotations

import math
from functools import partial
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

TWO_PI = 2.0 * math.pi


class CamHarmonics(NamedTuple):
    """Limited Fourier law over one cam revolution, phi in rad.

    f(phi) = a_0 + sum_{n=1..H} (a_n cos(n phi) + b_n sin(n phi)), in motion units (m or rad).
    """

    cos: jax.Array  # (H+1,) a_0 .. a_H; a_0 is the mean
    sin: jax.Array  # (H+1,) b_0 .. b_H; b_0 multiplies sin(0) = 0 and is kept at 0


class CamValues(NamedTuple):
    """A cam law and its derivatives with respect to cam angle, each with the shape of phi."""

    f: jax.Array  # follower position (m or rad)
    df: jax.Array  # df/dphi, per rad
    d2f: jax.Array  # d2f/dphi2, per rad^2


def complex_harmonics(cam: CamHarmonics) -> jax.Array:
    """Z_n = a_n - i b_n, so that f = Re sum_n Z_n exp(i n phi)."""
    return cam.cos - 1j * cam.sin


def from_complex(z: jax.Array) -> CamHarmonics:
    """The inverse of :func:`complex_harmonics`."""
    return CamHarmonics(jnp.real(z), -jnp.imag(z))


@partial(jax.jit, static_argnames="n_harmonics")
def harmonics_from_samples(values: jax.Array, n_harmonics: int) -> CamHarmonics:
    """The first ``n_harmonics`` harmonics of a law sampled at phi_k = 2 pi k / N, k = 0..N-1.

    Exact for a law band-limited below N/2 harmonics (the thesis' nominal cam has 9); otherwise
    the truncated (and slightly aliased) series. ``n_harmonics`` must be < N/2 (static).
    """
    n = values.shape[-1]
    if not 1 <= n_harmonics < n / 2:
        raise ValueError(f"n_harmonics: {n_harmonics} must be in [1, N/2) with N = {n} samples")
    z = jnp.fft.rfft(values)[: n_harmonics + 1] / n
    z = z.at[1:].multiply(2.0)
    return CamHarmonics(jnp.real(z), -jnp.imag(z).at[0].set(0.0))


def pad_harmonics(cam: CamHarmonics, n_harmonics: int) -> CamHarmonics:
    """Zero-pad (or truncate) to ``n_harmonics`` harmonics (static)."""
    h = cam.cos.shape[-1] - 1
    if n_harmonics <= h:
        return CamHarmonics(cam.cos[: n_harmonics + 1], cam.sin[: n_harmonics + 1])
    pad = jnp.zeros(n_harmonics - h, dtype=cam.cos.dtype)
    return CamHarmonics(jnp.concatenate([cam.cos, pad]), jnp.concatenate([cam.sin, pad]))


def trim_harmonics(cam: CamHarmonics, rtol: float = 1e-13) -> CamHarmonics:
    """Drop trailing harmonics below ``rtol`` times the largest (not traceable: sets a shape)."""
    mag = np.hypot(np.asarray(cam.cos), np.asarray(cam.sin))
    keep = np.nonzero(mag[1:] > rtol * max(mag[1:].max(initial=0.0), 1e-300))[0]
    return pad_harmonics(cam, int(keep[-1]) + 1 if keep.size else 1)


@jax.jit
def evaluate_cam(cam: CamHarmonics, phi: jax.Array) -> CamValues:
    """f, df/dphi, d2f/dphi2 at cam angles ``phi`` (rad, any shape)."""
    phi = jnp.asarray(phi)
    n = jnp.arange(cam.cos.shape[-1], dtype=phi.dtype)
    arg = phi[..., None] * n
    c, s = jnp.cos(arg), jnp.sin(arg)
    f = c @ cam.cos + s @ cam.sin
    df = (c * n) @ cam.sin - (s * n) @ cam.cos
    d2f = -(c * n**2) @ cam.cos - (s * n**2) @ cam.sin
    return CamValues(f, df, d2f)


def cam_grid(samples: int, dtype=None) -> jax.Array:
    """phi_k = 2 pi k / N, k = 0..N-1 (rad)."""
    return jnp.arange(samples, dtype=dtype or jnp.result_type(float)) * (TWO_PI / samples)


@jax.jit
def mean_square(cam: CamHarmonics) -> jax.Array:
    """Mean over the cycle of f(phi)^2 by Parseval: a_0^2 + (1/2) sum_{n>=1} (a_n^2 + b_n^2)."""
    return cam.cos[0] ** 2 + 0.5 * jnp.sum(cam.cos[1:] ** 2 + cam.sin[1:] ** 2)


@jax.jit
def max_abs(cam: CamHarmonics, phi: jax.Array) -> jax.Array:
    """max over the grid ``phi`` of |f(phi)| (the sampled maximum; a grid of N >> 2H is tight)."""
    return jnp.max(jnp.abs(evaluate_cam(cam, phi).f))


@partial(jax.jit, static_argnames="n_harmonics")
def fit_harmonics(phi: jax.Array, values: jax.Array, n_harmonics: int) -> CamHarmonics:
    """Least-squares limited Fourier law through scattered samples (phi (K,) rad, values (K,))."""
    n = jnp.arange(n_harmonics + 1, dtype=phi.dtype)
    arg = phi[:, None] * n
    basis = jnp.concatenate([jnp.cos(arg), jnp.sin(arg[:, 1:])], axis=1)
    coef, *_ = jnp.linalg.lstsq(basis, values)
    return CamHarmonics(coef[: n_harmonics + 1],
                        jnp.concatenate([jnp.zeros(1, coef.dtype), coef[n_harmonics + 1:]]))
