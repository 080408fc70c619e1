"""Kinematics bindings: shapes, dtypes, round trips, bad input, parameter files."""

import numpy as np
import pytest
import rss6
from scipy.spatial.transform import Rotation

KP = rss6.KinematicParams.nominal()
POSE = np.array([0.01, -0.005, 0.12, 0.02, -0.01, 0.03])


def random_poses(n, seed=0):
    rng = np.random.default_rng(seed)
    half = np.array([0.015, 0.015, 0.015, 0.04, 0.04, 0.04])
    return rss6.home_pose() + rng.uniform(-1, 1, (n, 6)) * half


def test_home_pose_maps_to_zero_angles():
    home = rss6.home_pose()
    assert home.shape == (6,) and home.dtype == np.float64
    np.testing.assert_allclose(home, [0, 0, 0.115, 0, 0, 0])
    assert np.abs(rss6.ik(KP, home)).max() < 1e-12


def test_ik_fk_round_trip_and_dtypes():
    theta = rss6.ik(KP, POSE)
    assert theta.shape == (6,) and theta.dtype == np.float64
    pose = rss6.fk(KP, theta)
    assert pose.shape == (6,) and pose.dtype == np.float64
    np.testing.assert_allclose(pose, POSE, atol=1e-11)
    # the "normal" method of Fig. 3.2 agrees
    np.testing.assert_allclose(rss6.fk(KP, theta, method="theta_newton"), POSE, atol=1e-10)


def test_lists_and_ints_are_accepted():
    theta = rss6.ik(KP, [0, 0, 0.115, 0, 0, 0])
    assert theta.dtype == np.float64


def test_batches_match_single_calls():
    poses = random_poses(25)
    thetas = rss6.ik_batch(KP, poses)
    assert thetas.shape == (25, 6) and thetas.dtype == np.float64
    for p, t in zip(poses, thetas):
        np.testing.assert_allclose(t, rss6.ik(KP, p), atol=1e-14)
    back = rss6.fk_batch(KP, thetas)
    assert back.shape == (25, 6)
    np.testing.assert_allclose(back, poses, atol=1e-10)


def test_fk_batch_warm_starts_from_the_previous_solution():
    # A slowly varying path: warm-started solves need few iterations, so a tight bound still works,
    # while a cold start at home with the same bound does not converge for the far end of the path.
    end = rss6.home_pose() + np.array([0.02, 0.02, 0.02, 0.05, 0.05, 0.05])
    path = np.linspace(rss6.home_pose(), end, 60)
    thetas = rss6.ik_batch(KP, path)
    poses = rss6.fk_batch(KP, thetas, max_iterations=3)
    np.testing.assert_allclose(poses, path, atol=1e-10)
    with pytest.raises(rss6.NotConvergedError):
        rss6.fk(KP, thetas[-1], max_iterations=3)


def test_wrong_shape_raises_shape_error_naming_the_argument():
    with pytest.raises(rss6.ShapeError, match=r"pose must have shape \(6,\), got \(5,\)"):
        rss6.ik(KP, np.zeros(5))
    with pytest.raises(rss6.ShapeError, match=r"poses must have shape \(N, 6\)"):
        rss6.ik_batch(KP, np.zeros((3, 5)))
    with pytest.raises(ValueError):  # ShapeError is a ValueError too
        rss6.fk(KP, np.zeros((6, 1)))


def test_nan_raises_non_finite_error_with_the_index():
    bad = POSE.copy()
    bad[3] = np.nan
    with pytest.raises(rss6.NonFiniteError, match=r"pose contains NaN or infinity at index \[3\]"):
        rss6.ik(KP, bad)
    thetas = np.zeros((4, 6))
    thetas[2, 1] = np.inf
    with pytest.raises(rss6.NonFiniteError, match=r"\[2, 1\]"):
        rss6.fk_batch(KP, thetas)


def test_unreachable_pose_raises_unreachable_error():
    with pytest.raises(rss6.UnreachableError) as info:
        rss6.ik(KP, [0, 0, 0.5, 0, 0, 0])
    e = info.value
    assert isinstance(e, ValueError) and isinstance(e, rss6.Rss6Error)
    assert 1 <= e.leg <= 6 and e.excess > 0
    assert "unreachable" in str(e) and f"leg {e.leg}" in str(e)


def test_batch_error_names_the_row():
    poses = random_poses(5)
    poses[3, 2] = 0.5
    with pytest.raises(rss6.UnreachableError, match="poses row 3"):
        rss6.ik_batch(KP, poses)


def test_non_converging_fk_raises_not_converged_error():
    theta = rss6.ik(KP, POSE)
    with pytest.raises(rss6.NotConvergedError) as info:
        rss6.fk(KP, theta, max_iterations=1)
    assert info.value.iterations == 1
    assert info.value.residual > 0
    assert "did not converge in 1 iterations" in str(info.value)


def test_bad_fk_options():
    with pytest.raises(rss6.InvalidInputError, match="method must be"):
        rss6.fk(KP, np.zeros(6), method="bogus")
    with pytest.raises(rss6.InvalidInputError, match="tol"):
        rss6.fk(KP, np.zeros(6), tol=float("nan"))


def test_jacobian_theta_matches_finite_differences():
    j = rss6.jacobian_theta(KP, POSE)
    assert j.shape == (6, 6) and j.dtype == np.float64
    h = 1e-7
    fd = np.empty((6, 6))
    for k in range(6):
        d = np.zeros(6)
        d[k] = h
        fd[:, k] = (rss6.ik(KP, POSE + d) - rss6.ik(KP, POSE - d)) / (2 * h)
    np.testing.assert_allclose(j, fd, atol=1e-6)
    assert rss6.jacobian_ad(KP, POSE).shape == (6, 6)


def test_pose_compose_and_invert():
    a = np.array([0.1, -0.2, 0.3, 0.2, -0.1, 0.4])
    ident = rss6.compose_poses(a, rss6.invert_pose(a))
    np.testing.assert_allclose(ident, np.zeros(6), atol=1e-14)


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def rotation_of(pose):
    """R of a pose, read from the bindings: composing with a pure translation e_i gives p + R e_i."""
    p = np.asarray(pose, dtype=float)
    return np.column_stack(
        [rss6.compose_poses(p, np.r_[np.eye(3)[i], 0, 0, 0])[:3] - p[:3] for i in range(3)]
    )


@pytest.mark.parametrize("seed", range(5))
def test_pose_rotation_is_rx_ry_rz_and_scipy_intrinsic_xyz(seed):
    rng = np.random.default_rng(seed)
    a = np.r_[rng.uniform(-0.2, 0.2, 3), rng.uniform(-1.2, 1.2, 3)]
    b = np.r_[rng.uniform(-0.2, 0.2, 3), rng.uniform(-1.2, 1.2, 3)]
    r_a = rotation_of(a)
    # R = Rx(α)·Ry(β)·Rz(γ), built by hand from cos/sin …
    np.testing.assert_allclose(r_a, rx(a[3]) @ ry(a[4]) @ rz(a[5]), atol=1e-14)
    # … which is scipy's intrinsic "XYZ" (extrinsic "xyz" is the reverse product Rz·Ry·Rx)
    np.testing.assert_allclose(r_a, Rotation.from_euler("XYZ", a[3:]).as_matrix(), atol=1e-14)
    assert not np.allclose(r_a, Rotation.from_euler("xyz", a[3:]).as_matrix(), atol=1e-3)
    # compose: p = p_a + R_a p_b, R = R_a R_b, angles back by scipy's intrinsic XYZ
    c = rss6.compose_poses(a, b)
    np.testing.assert_allclose(c[:3], a[:3] + r_a @ b[:3], atol=1e-14)
    r_c = Rotation.from_euler("XYZ", a[3:]) * Rotation.from_euler("XYZ", b[3:])
    np.testing.assert_allclose(rotation_of(c), r_c.as_matrix(), atol=1e-14)
    np.testing.assert_allclose(c[3:], r_c.as_euler("XYZ"), atol=1e-12)


def test_perturbed_params_and_error_vector_round_trip():
    b = np.random.default_rng(1).normal(0, 1e-3, 60)
    kp = rss6.KinematicParams.perturbed(b)
    np.testing.assert_allclose(kp.errors_from(KP), b, atol=1e-15)
    assert kp != KP and rss6.KinematicParams.nominal() == KP
    assert kp.base_joints.shape == (6, 3) and kp.eta.shape == (6,)
    with pytest.raises(rss6.ShapeError, match=r"b must have shape \(60,\)"):
        rss6.KinematicParams.perturbed(np.zeros(59))


def test_reading_conversion_is_eq_4_2():
    kappa = np.arange(6.0) * 100
    theta = KP.theta_from_reading(kappa)
    np.testing.assert_allclose(theta, KP.eta * kappa + KP.dtheta)
    np.testing.assert_allclose(KP.reading_from_theta(theta), kappa)


def test_reading_conversion_takes_one_reading_per_row():
    kappa = np.random.default_rng(3).normal(0, 300, (50, 6))
    theta = KP.theta_from_reading(kappa)
    assert theta.shape == (50, 6)
    # row by row, bit for bit, and back
    assert np.array_equal(theta, np.array([KP.theta_from_reading(k) for k in kappa]))
    assert np.array_equal(
        KP.reading_from_theta(theta), np.array([KP.reading_from_theta(t) for t in theta])
    )
    assert KP.theta_from_reading(np.zeros((0, 6))).shape == (0, 6)
    with pytest.raises(rss6.ShapeError, match=r"kappa must have shape \(6,\) or \(N, 6\)"):
        KP.theta_from_reading(np.zeros((4, 5)))
    with pytest.raises(rss6.NonFiniteError, match=r"index \[1, 2\]"):
        KP.theta_from_reading(np.where(np.arange(12).reshape(2, 6) == 8, np.nan, 0.0))


def test_kinematic_dict_round_trip():
    kp = rss6.KinematicParams.perturbed(np.random.default_rng(2).normal(0, 1e-3, 60))
    d = kp.to_dict()
    assert set(d) == {
        "base_joints",
        "platform_joints",
        "wrench_lengths",
        "link_lengths",
        "theta0",
        "eta",
        "dtheta",
    }
    assert d["base_joints"].shape == (6, 3)
    assert rss6.KinematicParams.from_dict(d) == kp
    # lists work as well
    assert rss6.KinematicParams.from_dict({k: v.tolist() for k, v in d.items()}) == kp


def test_kinematic_dict_errors():
    d = KP.to_dict()
    del d["eta"]
    with pytest.raises(rss6.InvalidInputError, match="missing key 'eta'"):
        rss6.KinematicParams.from_dict(d)
    d = KP.to_dict()
    d["extra"] = 1
    with pytest.raises(rss6.InvalidInputError, match="unknown key 'extra'"):
        rss6.KinematicParams.from_dict(d)
    d = KP.to_dict()
    d["link_lengths"] = -d["link_lengths"]
    with pytest.raises(rss6.InvalidParameterError, match="link length"):
        rss6.KinematicParams.from_dict(d)


def test_toml_round_trip(tmp_path):
    kp = rss6.KinematicParams.perturbed(np.random.default_rng(3).normal(0, 1e-3, 60))
    path = tmp_path / "kp.toml"
    kp.to_toml(path)
    text = path.read_text()
    for key in (
        "base_joints",
        "platform_joints",
        "wrench_lengths",
        "link_lengths",
        "theta0",
        "eta",
        "dtheta",
    ):
        assert key in text
    assert rss6.KinematicParams.load(path) == kp
    dp = rss6.DynamicParams.from_vector(rss6.DynamicParams.nominal().to_vector() * 1.1)
    dp.to_toml(tmp_path / "dp.toml")
    assert rss6.DynamicParams.load(tmp_path / "dp.toml") == dp


def test_bad_toml_raises_params_file_error(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("base_joints = 3\n")
    with pytest.raises(rss6.ParamsFileError, match=r"bad\.toml"):
        rss6.KinematicParams.load(p)
    with pytest.raises(rss6.ParamsFileError, match=r"missing\.toml: No such file"):
        rss6.KinematicParams.load(tmp_path / "missing.toml")


def test_dynamic_params_vector_and_dict():
    dp = rss6.DynamicParams.nominal()
    x = dp.to_vector()
    assert x.shape == (64,) and x[0] == 24.0  # Table 5.1 platform mass
    assert rss6.DynamicParams.from_vector(x) == dp
    d = dp.to_dict()
    assert d["wrenches"]["inertia"].shape == (6, 3)
    assert rss6.DynamicParams.from_dict(d) == dp
    d["platform"]["mass"] = -1.0
    with pytest.raises(rss6.InvalidParameterError, match="mass"):
        rss6.DynamicParams.from_dict(d)
