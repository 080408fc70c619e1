"""rss6.calibrate: selection, collection on a simulated robot, RPBA, implicit, bad input."""

import numpy as np
import pytest
import rss6
from rss6 import calibrate

NOMINAL = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()


def camera_sigma(sim):
    """Per-frame standard deviation (6,) of the simulated CMM's ᶜχ_t at rest (m, rad)."""
    frames = []
    for _ in range(3000):
        sim.step_joint_command(np.zeros(6))
        z = sim.camera()
        if z is not None:
            frames.append(z)
    return np.array(frames[10:]).std(0)


@pytest.fixture(scope="module")
def setup():
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))
    plant = rss6.ModelSim(truth, DP, seed=7)
    lo, hi = calibrate.stroke(NOMINAL)
    thetas = calibrate.select_configurations(
        NOMINAL, "rpba", seed=0, candidates=300, stroke=(lo, hi)
    )
    data = calibrate.collect(plant, thetas, dwell=0.4, move_time=0.4, settle_time=0.3)
    return plant, thetas, data, (lo, hi)


def test_stroke_and_selection(setup):
    _, thetas, _, (lo, hi) = setup
    assert lo < 0 < hi
    assert thetas.ndim == 2 and thetas.shape[1] == 6 and thetas.dtype == np.float64
    np.testing.assert_allclose(thetas[0], np.zeros(6))  # configuration 0 = initial
    assert np.all(thetas >= lo - 1e-12) and np.all(thetas <= hi + 1e-12)


def test_collect_averages_every_configuration(setup):
    _, thetas, data, _ = setup
    assert len(data) == len(thetas)
    assert data.kappa.shape == (len(thetas), 6) and data.sensor_pose.shape == (len(thetas), 6)
    assert np.all(data.camera_frames >= 10)
    np.testing.assert_allclose(data.theta_cmd, thetas)


def test_rpba_recovers_the_robot(setup):
    plant, _, data, s = setup
    res = calibrate.rpba(data, NOMINAL)
    assert res.method == "rpba" and res.parameter_count == 66
    assert res.cost_history[-1] < 1e-3 * res.cost_history[0]
    assert res.target_in_effector.shape == (6,) and res.sensor_in_base is None
    assert isinstance(res.unidentifiable, list) and res.rank < 66  # gauge directions exist
    before = calibrate.relative_pose_errors(None, plant, n=60, stroke=s)["rms"]
    after = calibrate.relative_pose_errors(res, plant, n=60, stroke=s)["rms"]
    assert np.all(after < before / 10), (before, after)
    # ᴼχ_C from configuration 0 (in the calibrated model's frame, which may differ from the true base
    # frame by a gauge transform): camera poses converted with it agree with the calibrated FK at
    # every configuration.
    est = calibrate.sensor_in_base_from_reference(data, res)
    inv_t = rss6.invert_pose(res.target_in_effector)
    kp = res.params
    res_ = np.array(
        [
            rss6.compose_poses(rss6.compose_poses(est, z), inv_t)
            - rss6.fk(kp, kp.theta_from_reading(kappa))
            for kappa, z in zip(data.kappa, data.sensor_pose)
        ]
    )
    rms = np.sqrt((res_**2).mean(0))
    # within the noise of a dwell mean: the simulated CMM's per-frame σ (measured at rest) / √frames
    bound = (
        2.5 * camera_sigma(rss6.ModelSim(NOMINAL, DP, seed=8)) / np.sqrt(data.camera_frames.min())
    )
    # (norms over the three axes: the sensor-frame noise is anisotropic and rotates into the base frame)
    assert np.linalg.norm(rms[:3]) < np.linalg.norm(bound[:3]), (rms, bound)
    assert np.linalg.norm(rms[3:]) < np.linalg.norm(bound[3:]), (rms, bound)


def test_an_exception_in_the_rpba_progress_callback_reaches_the_caller(setup):
    _, _, data, _ = setup
    calls: list[int] = []

    def stop(iteration: int, cost: float) -> None:
        calls.append(iteration)
        if iteration >= 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        calibrate.rpba(data, NOMINAL, progress=stop)
    assert calls[-1] == 2  # no callback after the one that raised


def test_implicit_runs_from_a_rough_sensor_pose(setup):
    plant, _, data, _ = setup
    guess = calibrate.draw_external(plant.truth()["sensor_in_base"], seed=1)
    res = calibrate.implicit(data, NOMINAL, guess)
    assert res.method == "implicit" and res.parameter_count == 72
    assert res.sensor_in_base is not None and res.sensor_in_base.shape == (6,)
    assert res.cost_history[-1] < res.cost_history[0]


def test_too_few_configurations_names_the_count(setup):
    _, _, data, _ = setup
    few = rss6.CalibrationData.from_arrays(data.kappa[:4], data.sensor_pose[:4])
    with pytest.raises(rss6.CalibrationError, match="too few usable configurations") as info:
        calibrate.rpba(few, NOMINAL)
    assert info.value.needed > 4


def test_missing_frames_are_dropped_and_reported(setup):
    _, _, data, _ = setup
    sp = data.sensor_pose.copy()
    sp[5] = np.nan
    d2 = rss6.CalibrationData.from_arrays(data.kappa, sp)
    res = calibrate.rpba(d2, NOMINAL)
    assert [i for i, _ in res.dropped] == [5]
    assert "frame" in res.dropped[0][1]
    assert 5 not in res.used


def test_calibration_data_bad_input():
    with pytest.raises(rss6.ShapeError):
        rss6.CalibrationData.from_arrays(np.zeros((3, 6)), np.zeros((2, 6)))
    with pytest.raises(rss6.NonFiniteError):
        rss6.CalibrationData.from_arrays(np.full((3, 6), np.nan), np.zeros((3, 6)))
    with pytest.raises(rss6.InvalidInputError, match="method"):
        calibrate.select_configurations(NOMINAL, "magic")
    # Seeds and poses that used to give numpy's "expected non-negative integer", PyO3's
    # OverflowError, or (a NaN pose) a NaN external pose returned as if drawn.
    with pytest.raises(rss6.InvalidInputError, match="seed must be an integer"):
        calibrate.select_configurations(NOMINAL, "rpba", -1)
    with pytest.raises(rss6.InvalidInputError, match=r"candidates must be an integer >= 0"):
        calibrate.select_configurations(NOMINAL, candidates=-5)
    with pytest.raises(rss6.InvalidInputError, match=r"seed must be in \[0, 2\*\*32 - 1\], got -1"):
        calibrate.draw_errors(-1)
    with pytest.raises(rss6.InvalidInputError, match=r"seed must be an int, got 0\.5"):
        calibrate.draw_external(rss6.home_pose(), 0.5)
    with pytest.raises(rss6.NonFiniteError, match="pose contains NaN"):
        calibrate.draw_external([np.nan] * 6)
    with pytest.raises(rss6.ShapeError, match=r"pose must have shape \(6,\)"):
        calibrate.draw_external(np.zeros(5))


def test_the_dwells_record_the_cameras_covariance_and_calibration_can_weigh_by_it(setup):
    plant, _, data, _ = setup
    cov = data.sensor_pose_cov
    assert cov.shape == (len(data), 6, 6)
    np.testing.assert_array_equal(cov, np.swapaxes(cov, 1, 2))
    assert np.all(np.linalg.eigvalsh(cov) > 0)
    # the stereo head's pose noise in its own frame: β and γ move together (measured +0.82 pooled
    # over 20 robots' dwells; this robot's 0.4 s dwells +0.84)
    w = (data.camera_frames - 1).astype(float)
    # pooled frame by frame in the order the library sums them, so "dwells" and the matrix passed
    # by hand below are the same bits (another summation order moves the fit by ~1e-11)
    pooled = np.zeros((6, 6))
    for wi, ci in zip(w, cov):
        pooled = pooled + ci * wi
    pooled = pooled / w.sum()
    sd = np.sqrt(np.diag(pooled))
    assert pooled[4, 5] / (sd[4] * sd[5]) > 0.5
    table = calibrate.rpba(data, NOMINAL)
    dwells = calibrate.rpba(data, NOMINAL, noise="dwells")
    given = calibrate.rpba(data, NOMINAL, noise=pooled)
    # "dwells" is the pooled covariance passed by hand
    np.testing.assert_allclose(given.errors, dwells.errors, rtol=0, atol=1e-12)
    assert dwells.fit_statistic != table.fit_statistic
    guess = calibrate.draw_external(plant.truth()["sensor_in_base"], seed=1)
    assert calibrate.implicit(data, NOMINAL, guess, noise="dwells").fit_statistic > 0


def test_weighing_by_the_dwells_needs_their_covariance_and_a_valid_one(setup):
    _, _, data, _ = setup
    bare = rss6.CalibrationData.from_arrays(data.kappa, data.sensor_pose)
    assert np.all(np.isnan(bare.sensor_pose_cov))
    with pytest.raises(rss6.InvalidInputError, match=r"Table 4\.1"):
        calibrate.rpba(bare, NOMINAL, noise="dwells")
    with pytest.raises(rss6.InvalidInputError, match="noise must be"):
        calibrate.rpba(data, NOMINAL, noise="frames")
    with pytest.raises(rss6.InvalidInputError, match="positive definite"):
        calibrate.rpba(data, NOMINAL, noise=-np.eye(6))
    with pytest.raises(rss6.ShapeError):
        calibrate.rpba(data, NOMINAL, noise=np.eye(5))
    # from arrays: a (m, 6, 6) covariance round-trips; an asymmetric block is refused
    again = rss6.CalibrationData.from_arrays(
        data.kappa, data.sensor_pose, sensor_pose_cov=data.sensor_pose_cov
    )
    np.testing.assert_array_equal(again.sensor_pose_cov, data.sensor_pose_cov)
    bad = data.sensor_pose_cov.copy()
    bad[0, 0, 1] += 1e-12
    with pytest.raises(rss6.InvalidInputError, match="symmetric"):
        rss6.CalibrationData.from_arrays(data.kappa, data.sensor_pose, sensor_pose_cov=bad)
    # asymmetry at rounding level (what np.cov or R C Rᵀ leave) is accepted and averaged away
    rounded = data.sensor_pose_cov.copy()
    rounded[0, 0, 1] *= 1 + 4e-15
    kept = rss6.CalibrationData.from_arrays(
        data.kappa, data.sensor_pose, sensor_pose_cov=rounded
    ).sensor_pose_cov
    np.testing.assert_array_equal(kept, np.swapaxes(kept, 1, 2))
    np.testing.assert_allclose(kept, data.sensor_pose_cov, rtol=4e-15, atol=0)
    skew = data.sensor_pose_cov[0].copy()
    skew[4, 5] *= 1 + 1e-13
    exact = calibrate.rpba(data, NOMINAL, noise=(skew + skew.T) / 2)
    np.testing.assert_array_equal(calibrate.rpba(data, NOMINAL, noise=skew).errors, exact.errors)
    skew[4, 5] *= 1 + 1e-9
    with pytest.raises(rss6.InvalidInputError, match="symmetric"):
        calibrate.rpba(data, NOMINAL, noise=skew)
