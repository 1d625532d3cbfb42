"""Kinetostatic loads, guide reactions and Hertz contact stress."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import camjax
from camjax import contact, loads
from camjax.followers.flat import geometry as flat_geo
from camjax.numerics import RHO_FLOOR_MM


def test_reference_force_and_torque(default_arrays, reference_1deg):
    f = np.asarray(default_arrays.force_N)
    # SPEC 5: peak cam force 68.45 N at 344 deg (within 0.05 N)
    assert f.max() == pytest.approx(68.45, abs=0.05)
    assert int(np.argmax(f)) == 344
    # independent recomputation from the closed-form cycloid (tests/reference.py)
    np.testing.assert_allclose(f, reference_1deg.force_N, rtol=1e-12)
    w = 8 * math.pi
    t = np.asarray(default_arrays.torque_Nm)
    np.testing.assert_allclose(t, f * np.asarray(default_arrays.motion.velocity) / w, rtol=1e-12)


def test_loss_of_contact_at_high_speed(default_scene):
    # at 240 rpm the spring keeps contact; the inertia term grows with w^2 and wins eventually
    arrays = camjax.scene_arrays(default_scene)
    assert float(loads.contact_margin(arrays.force_N)) > 0
    train = default_scene.follower.train
    motion = camjax.program.time_kinematics(arrays.kin, 2000 * 2 * math.pi / 60)
    assert float(loads.contact_margin(loads.kinetostatic_force(train, motion))) < 0


def test_guide_reactions_satisfy_equilibrium():
    # the corrected solution must satisfy the thesis' equilibrium equations (2.27), (2.29), (2.30)
    g = loads.Guide(length_mm=40.0, cam_friction=0.1, guide_friction=0.15, overhang_ratio=0.5)
    a = jnp.linspace(-15, 15, 31)
    P = 60.0
    r = loads.guide_reactions(g, P, a)
    b, mu0, mu, xi = 40.0, 0.1, 0.15, 0.5
    np.testing.assert_allclose(r.cam_force, (r.reaction_1 - r.reaction_2) / mu0, rtol=1e-10)
    np.testing.assert_allclose(r.cam_force, P + mu * (r.reaction_1 + r.reaction_2), rtol=1e-10)
    np.testing.assert_allclose(a * r.cam_force, xi * b * r.reaction_1 - b * (1 + xi) * r.reaction_2,
                               atol=1e-9)
    # jamming (Gamma -> 0) sits exactly at a = -jamming_limit
    lim = loads.jamming_limit_mm(g)
    gam = loads.guide_reactions(g, P, jnp.asarray(-lim)).gamma
    assert float(gam) == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.asarray(r.gamma)[np.asarray(a) > -lim] > 0)


def test_hertz_stress_closed_form():
    cam, fol = contact.Material(2.1e5, 0.3), contact.Material(1.15e5, 0.26)
    k = (1 - 0.09) / 2.1e5 + (1 - 0.26**2) / 1.15e5
    sigma = contact.hertz_line_stress(50.0, 12.0, 10.0, cam, fol)
    assert float(sigma) == pytest.approx(0.564 * math.sqrt(5.0 / (12.0 * k)), rel=1e-14)
    # sigma ~ rho^-1/2 down to rho = 1e-12 mm, finite
    small = contact.hertz_line_stress(50.0, 1e-12, 10.0, cam, fol)
    assert float(small) == pytest.approx(0.564 * math.sqrt(5.0 / (1e-12 * k)), rel=1e-12)
    # no contact force -> no stress; rho <= 0 -> finite saturated value
    assert float(contact.hertz_line_stress(-5.0, 12.0, 10.0, cam, fol)) == 0.0
    sat = contact.hertz_line_stress(50.0, -3.0, 10.0, cam, fol)
    assert float(sat) == pytest.approx(0.564 * math.sqrt(5.0 / (RHO_FLOOR_MM * k)), rel=1e-12)


@pytest.mark.slow
def test_gradients_finite_for_any_base_radius_lift_speed_spring(default_scene):
    """d(max stress)/d(R_b, lift, rpm, k) is finite everywhere, far below the feasible R_b too."""
    sc = default_scene
    prog = sc.motion.program
    c = sc.contact

    def peak_stress(params):
        rb, lift, rpm, k = params
        p = camjax.MotionProgram(prog.kinds, prog.angles_deg, prog.laws, prog.lifts.at[1].set(lift).at[3].set(lift))
        kin = camjax.program.evaluate(p, 360)
        w = rpm * 2 * jnp.pi / 60
        motion = camjax.program.time_kinematics(kin, w)
        train = sc.follower.train._replace(spring_N_per_m=k)
        f = loads.kinetostatic_force(train, motion)
        rho = flat_geo.flat_radius_of_curvature(rb, kin)
        sigma = contact.hertz_line_stress(f, rho, c.cam_width_mm, c.cam, c.follower)
        torque = loads.cam_torque(f, kin.ds)
        return jnp.max(sigma) + jnp.max(torque)

    grad = jax.jit(jax.grad(peak_stress))
    for rb in [1e-3, 1.0, 10.0, 24.0, 24.2, 40.0, 400.0]:
        for rpm in [0.0, 240.0, 20_000.0]:
            g = grad(jnp.asarray([rb, 5.0, rpm, 3004.0]))
            assert np.all(np.isfinite(np.asarray(g))), (rb, rpm, g)
    # and where the design is feasible, the gradient in R_b agrees with central differences
    x = jnp.asarray([30.0, 5.0, 240.0, 3004.0])
    e = jnp.asarray([1e-5, 0, 0, 0])
    fd = (peak_stress(x + e) - peak_stress(x - e)) / 2e-5
    assert float(grad(x)[0]) == pytest.approx(float(fd), rel=1e-6)


def test_force_parts_of_the_reference_case_add_up(default_scene, default_arrays):
    from reference import (
        CAM_SPEED_RAD_S,
        DAMPING_NS_PER_M,
        GRAVITY_M_S2,
        MASS_KG,
        PRELOAD_MM,
        SPRING_N_PER_M,
        reference_motion,
    )

    from camjax import followers

    curves = followers.of(default_scene).curves(default_scene, default_arrays, 30.0)
    parts = curves.force_parts_N
    assert list(parts) == ["inertia", "damping", "spring", "gravity"]
    # each term from the closed-form cycloids (NumPy), SI; 1e-9 N: float64 rounding of ~60 N
    s, ds, d2s = reference_motion(curves.theta_deg)
    w = CAM_SPEED_RAD_S
    np.testing.assert_allclose(parts["inertia"], MASS_KG * d2s * w**2 * 1e-3, atol=1e-9)
    np.testing.assert_allclose(parts["damping"], DAMPING_NS_PER_M * ds * w * 1e-3, atol=1e-9)
    np.testing.assert_allclose(parts["spring"], SPRING_N_PER_M * (s + PRELOAD_MM) * 1e-3, atol=1e-9)
    np.testing.assert_allclose(parts["gravity"], MASS_KG * GRAVITY_M_S2, atol=1e-12)
    np.testing.assert_allclose(sum(parts.values()), curves.force_N, atol=1e-9)
