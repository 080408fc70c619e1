"""Controller bindings: trajectories, Kalman filter, DSMC, KCSC, KJSC, converter; faults."""

import numpy as np
import pytest
import rss6

KP = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()


@pytest.mark.parametrize("traj", [rss6.Trajectory.experiment1(), rss6.Trajectory.experiment2()])
def test_trajectory_derivatives_are_analytic(traj):
    t, h = 1.3, 1e-5
    p, v, a = traj.sample(t)
    assert p.shape == v.shape == a.shape == (6,)
    pm, vm, _ = traj.sample(t - h)
    pp, vp, _ = traj.sample(t + h)
    np.testing.assert_allclose(v, (pp - pm) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(a, (vp - vm) / (2 * h), atol=1e-6)
    ps, _vs, _as = traj.sample_many(np.linspace(0, 2, 11))
    assert ps.shape == (11, 6)
    np.testing.assert_allclose(ps[0], traj.sample(0.0)[0])


def test_experiment_trajectories_start_with_a_step_and_stay_reachable():
    p1 = rss6.Trajectory.experiment1().sample(0.0)[0]
    assert p1[1] == pytest.approx(0.008) and p1[2] == pytest.approx(0.120)  # y, z step (docs)
    p2 = rss6.Trajectory.experiment2().sample(0.0)[0]
    assert np.all(np.abs(p2 - rss6.home_pose()) > 0)  # a step in every dimension
    times = np.linspace(0, 42, 400)
    for traj in (rss6.Trajectory.experiment1(), rss6.Trajectory.experiment2()):
        rss6.ik_batch(KP, traj.sample_many(times)[0])  # raises if any pose is unreachable


def test_custom_trajectories_and_their_errors():
    s = rss6.Trajectory.sinusoid(rss6.home_pose(), np.full(6, 1e-3), np.zeros(6), 2.0)
    _p, v, _ = s.sample(0.0)
    np.testing.assert_allclose(v, np.full(6, 2e-3))
    f = rss6.Trajectory.fourier(np.full((6, 3), 1e-3), np.zeros((6, 3)), rss6.home_pose(), 0.2)
    assert f.name == "fourier"
    with pytest.raises(rss6.ShapeError, match="same shape"):
        rss6.Trajectory.fourier(np.zeros((6, 3)), np.zeros((6, 2)), rss6.home_pose(), 0.2)
    with pytest.raises(rss6.ShapeError, match=r"\(6, n\)"):
        rss6.Trajectory.fourier(np.zeros((6, 11)), np.zeros((6, 11)), rss6.home_pose(), 0.2)


def test_kalman_filter_lowers_pose_noise():
    rng = np.random.default_rng(0)
    traj = rss6.Trajectory.experiment1()
    kf = rss6.KalmanFilter(traj.sample(0.0)[0])
    sd = np.r_[np.full(3, 0.0096e-3), np.full(3, np.radians(0.0261))]
    raw, est = [], []
    for k in range(1, 600):
        truth = traj.sample(k * 0.033)[0]
        z = truth + rng.normal(0, sd)
        p, v, a = kf.step(0.033, z)
        if k > 100:
            raw.append(z - truth)
            est.append(p - truth)
    assert p.shape == v.shape == a.shape == (6,)
    assert np.sqrt(np.mean(np.square(est))) < np.sqrt(np.mean(np.square(raw)))
    # predict-only on a missing frame
    p2, _, _ = kf.step(0.033, None)
    assert np.all(np.isfinite(p2))
    assert kf.pose_variance().shape == (6,)


def test_kalman_bad_input():
    with pytest.raises(rss6.InvalidInputError, match="time step"):
        rss6.KalmanFilter(rss6.home_pose()).step(0.0, rss6.home_pose())
    with pytest.raises(rss6.NonFiniteError):
        rss6.KalmanFilter(rss6.home_pose()).step(0.033, [np.nan] * 6)
    with pytest.raises(rss6.InvalidParameterError, match="measurement variance"):
        rss6.KalmanFilter(rss6.home_pose(), r=np.zeros(6))


def test_dsmc_step_outputs_and_fault_latch():
    d = rss6.Dsmc(KP, DP)
    ref = rss6.Trajectory.experiment1().sample(0.0)
    est = (rss6.home_pose(), np.zeros(6), np.zeros(6))
    out = d.step(ref, est, 0.033)
    assert set(out) == {"tau_a", "sliding", "generalized", "tau_model", "in_boundary_layer"}
    assert out["tau_a"].shape == (6,) and out["tau_a"].dtype == np.float64
    assert d.fault is None
    # An estimate the model cannot evaluate (unreachable pose) latches a fault with a readable reason.
    with pytest.raises(rss6.ControllerFaultError) as info:
        d.step(ref, (np.array([0, 0, 0.5, 0, 0, 0.0]), np.zeros(6)), 0.033)
    assert "model evaluation failed" in info.value.reason
    assert d.fault is not None
    with pytest.raises(rss6.ControllerFaultError):
        d.step(ref, est, 0.033)  # stays faulted
    d.reset()
    assert d.fault is None
    d.step(ref, est, 0.033)


def test_controllers_reject_malformed_references():
    d = rss6.Dsmc(KP, DP)
    with pytest.raises(rss6.InvalidInputError, match="reference must be a tuple"):
        d.step(np.zeros(6), (rss6.home_pose(), np.zeros(6)), 0.033)
    with pytest.raises(rss6.ShapeError, match=r"reference\[1\]"):
        d.step((rss6.home_pose(), np.zeros(5)), (rss6.home_pose(), np.zeros(6)), 0.033)
    with pytest.raises(rss6.InvalidParameterError):
        rss6.Dsmc(KP, DP, epsilon=np.zeros(6))


def test_kcsc_command_is_eq_6_40():
    # θ_d = J_θ(χ_m)·(k_p e + k_d ė + k_i Σ e dt), e = χ_d − χ_m, with the thesis's gains (§5.5):
    # k_p = 0.3, k_d = 0.001 s, k_i = 2.4 1/s, and θ_bias = 0.
    dt = 0.033
    pose = rss6.home_pose() + np.array([0.001, -0.002, 0.003, 0.01, -0.02, 0.015])
    e = np.array([0.002, -0.001, 0.0005, 0.004, 0.003, -0.002])
    e_dot = np.array([0.01, 0.02, -0.01, 0.05, -0.04, 0.03])
    est = (pose, np.zeros(6), np.zeros(6))
    ref = (pose + e, e_dot, np.zeros(6))
    j = rss6.jacobian_theta(KP, pose)
    k = rss6.Kcsc(KP)
    np.testing.assert_allclose(
        k.step(ref, est, dt), j @ (0.3 * e + 0.001 * e_dot + 2.4 * e * dt), rtol=1e-12, atol=1e-15
    )
    # the integral accumulates; a bias shifts the command
    np.testing.assert_allclose(
        k.step(ref, est, dt),
        j @ (0.3 * e + 0.001 * e_dot + 2.4 * 2 * e * dt),
        rtol=1e-12,
        atol=1e-15,
    )
    bias = np.full(6, 0.1)
    np.testing.assert_allclose(
        rss6.Kcsc(KP, bias=bias).step(ref, est, dt),
        bias + j @ (0.3 * e + 0.001 * e_dot + 2.4 * e * dt),
        rtol=1e-12,
        atol=1e-15,
    )
    assert k.fault is None


def test_kjsc_command_is_eq_6_42():
    # θ_d = k_p e + k_d ė + k_i Σ e dt with e = IK(χ_d) − θ, ė = J_θ(χ_d) χ̇_d − θ̇ (θ̇ by differences of
    # the potentiometer angles, 0 on the first step); thesis gains k_p = 0.3, k_d = 0.001, k_i = 2.4.
    dt = 0.033
    pose_d = rss6.home_pose() + np.array([0.002, 0.001, -0.001, 0.01, 0.0, -0.01])
    pose_d_dot = np.array([0.01, 0.0, 0.02, 0.0, 0.03, 0.0])
    ref = (pose_d, pose_d_dot, np.zeros(6))
    theta_r = rss6.ik(KP, pose_d)
    theta_r_dot = rss6.jacobian_theta(KP, pose_d) @ pose_d_dot
    k = rss6.Kjsc(KP)
    th0 = np.zeros(6)
    e0 = theta_r - th0
    np.testing.assert_allclose(
        k.step(ref, th0, dt), 0.3 * e0 + 0.001 * theta_r_dot + 2.4 * e0 * dt, rtol=1e-12, atol=1e-15
    )
    th1 = np.full(6, 0.002)
    e1 = theta_r - th1
    np.testing.assert_allclose(
        k.step(ref, th1, dt),
        0.3 * e1 + 0.001 * (theta_r_dot - (th1 - th0) / dt) + 2.4 * (e0 + e1) * dt,
        rtol=1e-12,
        atol=1e-15,
    )
    assert k.fault is None


def test_torque_to_position_inverts_the_drive_pid():
    c = rss6.TorqueToPosition()
    out = c.step(np.full(6, 1.0), np.zeros(6))
    np.testing.assert_allclose(out["tau_expected"], np.full(6, 1.0), rtol=1e-9)
    assert not out["stroke_limited"]
    big = c.step(np.full(6, 1e6), np.zeros(6))
    assert big["rate_limited"] or big["stroke_limited"]
    assert np.all(np.abs(big["theta_cmd"]) <= np.radians(57.1) + 1e-12)
    with pytest.raises(rss6.NonFiniteError, match="theta"):
        c.step(np.ones(6), [np.nan] * 6)
