"""Safe numerics: finite values and gradients, and the tiled max over angles."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax.followers.flat import problem as P
from camjax.numerics import max_over_angles, safe_divide, safe_sqrt


def test_safe_sqrt_and_divide_have_finite_gradients():
    x = jnp.asarray([-1.0, 0.0, 1e-300, 4.0])
    np.testing.assert_array_equal(jax.jit(safe_sqrt)(x), [0.0, 0.0, 1e-150, 2.0])  # one program, not op by op
    g = jax.jit(jax.vmap(jax.grad(safe_sqrt)))(x)
    assert np.all(np.isfinite(g)) and float(g[3]) == pytest.approx(0.25)
    gd = jax.jit(jax.vmap(jax.grad(lambda d: safe_divide(1.0, d))))(jnp.asarray([0.0, 2.0]))
    np.testing.assert_allclose(gd, [0.0, -0.25])


@pytest.mark.parametrize("n, tile", [(100, 8192), (20_000, 8192), (16_384, 8192), (7, 3)])
def test_max_over_angles_equals_the_plain_max_value_and_gradient(n, tile):
    rng = np.random.default_rng(n)
    c = jnp.asarray(rng.uniform(0.5, 2.0, n))
    q = jnp.asarray(rng.uniform(-3.0, 3.0, n))

    def tiled(r):
        return max_over_angles(lambda c, q: c**2 / (r + q), c, q, tile=tile)

    def plain(r):
        return jnp.max(c**2 / (r + q))

    # each side one compiled program (value and gradient together), not op by op
    tiled_value, tiled_grad = jax.jit(jax.value_and_grad(tiled))(10.0)
    plain_value, plain_grad = jax.jit(jax.value_and_grad(plain))(10.0)
    assert float(tiled_value) == float(plain_value)  # a max is exact in any order
    assert float(tiled_grad) == float(plain_grad)


@pytest.mark.slow
def test_peak_stress_on_a_long_grid_is_the_max_of_the_stress():
    prob = P.problem_from_scene(camjax.load_scene(), samples=20_000)  # > one tile, padded
    design = P.Design(jnp.asarray(28.0), jnp.asarray(20.0))
    direct = jnp.max(P.stress(prob, design))
    assert float(P.peak_stress(prob, design)) == pytest.approx(float(direct), rel=1e-15)


def test_capped_divide_saturates_with_finite_gradients():
    from camjax.numerics import capped_divide

    big = float(np.finfo(np.float64).max)
    den = jnp.asarray([2.0, -4.0, 1e-300, -1e-300, 0.0])  # normal numbers: XLA:CPU flushes subnormals
    got = jax.jit(capped_divide)(1e10, den)  # one program, not op by op
    np.testing.assert_array_equal(got, [5e9, -2.5e9, big, -big, big])
    # 1e10 / 1e-300 overflows: saturated, and the gradient must not be 0 * inf = nan
    g = jax.jit(jax.vmap(jax.grad(lambda d: capped_divide(1e10, d))))(den)
    assert np.all(np.isfinite(g)) and float(g[0]) == pytest.approx(-2.5e9)
    assert float(capped_divide(0.0, 0.0)) == big
