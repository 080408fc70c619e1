"""Dynamics bindings: shapes, identities between them, bad input."""

import numpy as np
import pytest
import rss6

KP = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()
POSE = np.array([0.005, -0.004, 0.118, 0.02, -0.015, 0.01])
VEL = np.array([0.01, -0.02, 0.005, 0.05, 0.02, -0.03])
ACC = np.array([0.1, 0.05, -0.2, 0.3, -0.1, 0.2])


def test_mass_matrix_is_symmetric_positive_definite():
    m = rss6.mass_matrix(KP, DP, POSE)
    assert m.shape == (6, 6) and m.dtype == np.float64
    np.testing.assert_allclose(m, m.T, atol=1e-12)
    assert np.linalg.eigvalsh(m).min() > 0


def test_inverse_dynamics_is_the_sum_of_its_terms():
    tau = rss6.inverse_dynamics(KP, DP, POSE, VEL, ACC)
    assert tau.shape == (6,)
    m = rss6.mass_matrix(KP, DP, POSE)
    c = rss6.coriolis(KP, DP, POSE, VEL)
    g = rss6.gravity(KP, DP, POSE)
    f = rss6.friction(KP, DP, POSE, VEL)
    j = rss6.jacobian_theta(KP, POSE)
    np.testing.assert_allclose(j.T @ tau, m @ ACC + c @ VEL + g + f, rtol=1e-9, atol=1e-9)
    terms = rss6.dynamics_terms(KP, DP, POSE, VEL)
    np.testing.assert_allclose(terms["m"], m, atol=1e-12)
    np.testing.assert_allclose(terms["j_theta"], j, atol=1e-12)


def test_forward_dynamics_inverts_inverse_dynamics():
    tau = rss6.inverse_dynamics(KP, DP, POSE, VEL, ACC)
    np.testing.assert_allclose(rss6.forward_dynamics(KP, DP, POSE, VEL, tau), ACC, atol=1e-8)


def test_regressor_times_parameters_is_the_torque():
    gamma = rss6.regressor(KP, POSE, VEL, ACC)
    assert gamma.shape == (6, 64) and gamma.dtype == np.float64
    xi = DP.to_vector() * np.random.default_rng(0).uniform(0.5, 1.5, 64)
    dp = rss6.DynamicParams.from_vector(xi)
    np.testing.assert_allclose(gamma @ xi, rss6.inverse_dynamics(KP, dp, POSE, VEL, ACC), atol=1e-9)


def test_gravity_with_a_tilted_base():
    g = rss6.gravity(KP, DP, rss6.home_pose())
    assert g[2] > 200  # 24 kg platform + legs hang on the z axis
    tilted = rss6.gravity(KP, DP, rss6.home_pose(), g=[0.0, 9.81, 0.0])
    assert abs(tilted[2]) < 1e-9 and abs(tilted[1]) > 200


def test_rk4_step_falls_under_gravity():
    p, v = rss6.rk4_step(KP, DP, rss6.home_pose(), np.zeros(6), np.zeros(6), 1e-3)
    assert p.shape == (6,) and v.shape == (6,)
    assert v[2] < 0 and p[2] < rss6.home_pose()[2]
    with pytest.raises(rss6.InvalidInputError, match="dt"):
        rss6.rk4_step(KP, DP, rss6.home_pose(), np.zeros(6), np.zeros(6), 0.0)


def test_dynamics_bad_input():
    with pytest.raises(rss6.ShapeError, match="pose_dot"):
        rss6.coriolis(KP, DP, POSE, np.zeros(3))
    with pytest.raises(rss6.NonFiniteError, match="tau_a"):
        rss6.forward_dynamics(KP, DP, POSE, VEL, [np.nan] * 6)
    with pytest.raises(rss6.UnreachableError):
        rss6.mass_matrix(KP, DP, [0, 0, 0.5, 0, 0, 0])
    with pytest.raises(rss6.ShapeError, match="g must have shape"):
        rss6.gravity(KP, DP, POSE, g=[0, 0])
