"""rss6.calibrate with MCAP logs: collect(..., mcap=path) writes the raw dwells, read_mcap/load_mcap
segment and average them back (issue 6, "loaded from an MCAP log")."""

import json

import numpy as np
import pytest
import rss6
from rss6 import calibrate, logs

NOMINAL = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()
KW = {"dwell": 0.4, "move_time": 0.4, "settle_time": 0.3}


def windows_of(run):
    return [tuple(w) for w in json.loads(run["metadata"]["windows"])]


def in_window(t, w):
    return (t >= w[0] - 1e-6) & (t <= w[1] + 1e-6)


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """The same robot (same seed) collected directly (compiled collector) and through an MCAP log."""
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))
    thetas = calibrate.select_configurations(NOMINAL, "rpba", seed=0, candidates=300)
    direct_plant = rss6.ModelSim(truth, DP, seed=7)
    direct = calibrate.collect(direct_plant, thetas, **KW)
    path = tmp_path_factory.mktemp("mcap") / "calib.mcap"
    calls = []
    returned = calibrate.collect(
        rss6.ModelSim(truth, DP, seed=7),
        thetas,
        mcap=path,
        progress=lambda d, t: calls.append((d, t)),
        **KW,
    )
    assert calls[-1] == (len(thetas), len(thetas))
    return thetas, direct, returned, path, direct_plant


def test_log_has_the_raw_dwell_channels(logged):
    thetas, _, _, path, _ = logged
    run = logs.read_run(path)
    assert {"kappa", "camera_pose", "theta_cmd", "metadata"} <= set(run)
    w = windows_of(run)
    assert len(w) == len(thetas)
    kt = run["kappa"][0]
    # 500 Hz potentiometer samples inside each 0.4 s dwell, nothing logged during the moves.
    assert np.allclose(np.diff(kt[in_window(kt, w[0])]), 2e-3)
    assert sum(in_window(kt, wi).sum() for wi in w) == len(kt) == 200 * len(thetas)
    np.testing.assert_array_equal(
        run["theta_cmd"][1][in_window(run["theta_cmd"][0], w[3])][0], thetas[3]
    )


def test_round_trip_equals_direct_collection(logged):
    thetas, direct, returned, path, _ = logged
    r = calibrate.read_mcap(path)
    assert r.complete and r.dropped == [] and r.used == list(range(len(thetas)))
    loaded = calibrate.load_mcap(path)
    assert len(loaded) == len(thetas)
    np.testing.assert_array_equal(r.kappa_samples, 200)
    np.testing.assert_array_equal(r.camera_frames, direct.camera_frames)
    np.testing.assert_allclose(loaded.theta_cmd, thetas, rtol=0, atol=0)
    # Same plant, same seed, same stepping: the κ means are the same numbers.
    np.testing.assert_allclose(loaded.kappa, direct.kappa, rtol=1e-14, atol=0)
    np.testing.assert_allclose(loaded.sensor_pose[:, :3], direct.sensor_pose[:, :3], atol=1e-12)
    # Rotations: quaternion mean here, Euler mean (unwrapped) in the compiled collector; the two
    # differ at second order in the per-frame angle spread σ.
    run = logs.read_run(path)
    ct, cv = run["camera_pose"]
    sigma = max(cv[in_window(ct, w), 3:].std(0).max() for w in windows_of(run))
    assert 0 < sigma < 1e-2
    assert np.abs(loaded.sensor_pose[:, 3:] - direct.sensor_pose[:, 3:]).max() < sigma**2
    # What collect returned is what the file gives back (JSON round trip of floats).
    np.testing.assert_allclose(loaded.sensor_pose, returned.sensor_pose, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(loaded.kappa, returned.kappa)


def test_rpba_on_loaded_data_matches_direct(logged):
    _, direct, _, path, plant = logged
    res_direct = calibrate.rpba(direct, NOMINAL)
    res_loaded = calibrate.rpba(calibrate.load_mcap(path), NOMINAL)
    assert res_loaded.rank == res_direct.rank
    assert res_loaded.unidentifiable == res_direct.unidentifiable
    assert res_loaded.cost_history[-1] < 1e-3 * res_loaded.cost_history[0]
    np.testing.assert_allclose(res_loaded.errors, res_direct.errors, rtol=0, atol=1e-6)
    np.testing.assert_allclose(
        res_loaded.target_in_effector, res_direct.target_in_effector, rtol=0, atol=1e-6
    )
    e_direct = calibrate.relative_pose_errors(res_direct, plant, n=40)["rms"]
    e_loaded = calibrate.relative_pose_errors(res_loaded, plant, n=40)["rms"]
    np.testing.assert_allclose(e_loaded, e_direct, rtol=1e-2)
    uncal = calibrate.relative_pose_errors(None, plant, n=40)["rms"]
    assert np.all(e_loaded < uncal / 10)


def rewrite(run, path, metadata=True):
    streams = {k: v for k, v in run.items() if k != "metadata"}
    logs.write_run(path, streams, run["metadata"] if metadata else None)


def test_log_without_metadata_is_segmented_by_theta_cmd(logged, tmp_path):
    _, _, _, path, _ = logged
    bare = tmp_path / "bare.mcap"
    rewrite(logs.read_run(path), bare, metadata=False)
    a, b = calibrate.read_mcap(path), calibrate.read_mcap(bare)
    assert b.used == a.used and b.dropped == [] and b.complete
    np.testing.assert_array_equal(b.data.kappa, a.data.kappa)
    # rewriting re-encodes the angles as quaternions: equal to rounding
    np.testing.assert_allclose(b.data.sensor_pose, a.data.sensor_pose, rtol=0, atol=1e-13)
    np.testing.assert_array_equal(b.data.theta_cmd, a.data.theta_cmd)


def test_nan_and_missing_frames_are_dropped_and_reported(logged, tmp_path):
    thetas, _, _, path, _ = logged
    run = logs.read_run(path)
    w = windows_of(run)
    ct, cv = run["camera_pose"]
    cv = cv.copy()
    cv[in_window(ct, w[2])] = np.nan  # every frame of configuration 2 is NaN
    cv[np.flatnonzero(in_window(ct, w[3]))[:3]] = np.nan  # a few NaN frames: still usable
    keep = ~in_window(ct, w[4])  # configuration 4: no camera frame at all
    run["camera_pose"] = (ct[keep], cv[keep])
    kt, kv = run["kappa"]
    kv = kv.copy()
    kv[np.flatnonzero(in_window(kt, w[5]))[7]] = np.nan
    run["kappa"] = (kt, kv)
    bad = tmp_path / "bad.mcap"
    rewrite(run, bad)

    clean = calibrate.read_mcap(path)
    r = calibrate.read_mcap(bad)
    assert [i for i, _ in r.dropped] == [2, 4, 5]
    reasons = dict(r.dropped)
    assert "non-finite" in reasons[2] and "camera" in reasons[2]
    assert "no camera frame" in reasons[4]
    assert "potentiometer" in reasons[5]
    assert r.used == [i for i in range(len(thetas)) if i not in (2, 4, 5)]
    assert len(r.data) == len(thetas) - 3
    assert np.all(np.isfinite(r.data.sensor_pose)) and np.all(np.isfinite(r.data.kappa))
    np.testing.assert_array_equal(r.camera_frames[r.used.index(3)], clean.camera_frames[3] - 3)
    others = [i for i in r.used if i != 3]
    rows = [r.used.index(i) for i in others]
    np.testing.assert_array_equal(r.data.kappa[rows], clean.data.kappa[others])
    np.testing.assert_allclose(
        r.data.sensor_pose[rows], clean.data.sensor_pose[others], rtol=0, atol=1e-13
    )
    np.testing.assert_allclose(
        r.data.sensor_pose[r.used.index(3)], clean.data.sensor_pose[3], atol=1e-3
    )
    # RPBA runs on what is left.
    res = calibrate.rpba(r.data, NOMINAL)
    assert res.cost_history[-1] < 1e-3 * res.cost_history[0]


def test_no_usable_configuration_is_a_calibration_error(logged, tmp_path):
    _, _, _, path, _ = logged
    run = logs.read_run(path)
    ct, cv = run["camera_pose"]
    run["camera_pose"] = (ct, np.full_like(cv, np.nan))
    bad = tmp_path / "allnan.mcap"
    rewrite(run, bad)
    with pytest.raises(rss6.CalibrationError, match="no usable configuration"):
        calibrate.load_mcap(bad)


def test_truncated_file_is_read_up_to_its_last_whole_chunk(tmp_path):
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=3))
    thetas = calibrate.select_configurations(NOMINAL, "rpba", seed=0, candidates=300)[:6]
    path = tmp_path / "long.mcap"
    # 2 s dwells: ~12k messages, several MCAP chunks.
    calibrate.collect(
        rss6.ModelSim(truth, DP, seed=3), thetas, 2.0, move_time=0.4, settle_time=0.3, mcap=path
    )
    full = calibrate.read_mcap(path)
    assert full.complete and full.used == list(range(6))
    raw = path.read_bytes()
    partial_seen = False
    for frac in (0.05, 0.3, 0.7, 0.9, 0.99):
        cut = tmp_path / f"cut{frac}.mcap"
        cut.write_bytes(raw[: int(len(raw) * frac)])
        try:
            r = calibrate.read_mcap(cut)
        except rss6.Rss6Error as e:
            assert isinstance(e, rss6.LogError | rss6.CalibrationError), e
            continue
        assert not r.complete
        assert r.used == list(range(len(r.used)))  # a prefix of the visit order
        partial_seen |= len(r.used) < 6  # (a cut in the summary section loses no data)
        assert all("truncated" in why for _, why in r.dropped)
        gone = [i for i, _ in r.dropped]
        if r.metadata:  # the dwell windows survived: every configuration not read is reported
            assert gone == list(range(len(r.used), 6))
        else:  # only the dwells seen are known; a cut one is reported
            assert gone in ([], [len(r.used)])
        np.testing.assert_array_equal(r.kappa_samples, 1000)  # no partial dwell averaged
        np.testing.assert_array_equal(r.data.kappa, full.data.kappa[r.used])
        np.testing.assert_array_equal(r.data.sensor_pose, full.data.sensor_pose[r.used])
    assert partial_seen
    with pytest.raises(rss6.LogError):
        head = tmp_path / "head.mcap"
        head.write_bytes(raw[:100])
        calibrate.read_mcap(head)


def test_bad_files_are_log_errors(tmp_path):
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"not an mcap file at all" * 100)
    with pytest.raises(rss6.LogError):
        calibrate.load_mcap(garbage)
    with pytest.raises(rss6.LogError):
        calibrate.load_mcap(tmp_path / "missing.mcap")
    other = tmp_path / "servo.mcap"
    logs.write_run(other, {"true_pose": (np.arange(3) * 1e-3, np.zeros((3, 6)))})
    with pytest.raises(rss6.LogError, match="calibration"):
        calibrate.load_mcap(other)
    assert issubclass(rss6.LogError, rss6.Rss6Error)


def test_collect_with_mcap_rejects_bad_input(tmp_path):
    sim = rss6.ModelSim(NOMINAL, DP, seed=0)
    with pytest.raises(rss6.ShapeError):
        calibrate.collect(sim, np.zeros((3, 5)), mcap=tmp_path / "x.mcap")
    with pytest.raises(rss6.InvalidInputError):
        calibrate.collect(sim, np.zeros((2, 6)), dwell=0.0, mcap=tmp_path / "x.mcap")
    with pytest.raises(rss6.InvalidInputError):
        calibrate.collect(sim, np.full((2, 6), np.nan), mcap=tmp_path / "x.mcap")
    assert not (tmp_path / "x.mcap").exists()


class FailingPlant:
    """A plant whose simulation fails after ``fail_after`` ticks."""

    def __init__(self, sim, fail_after):
        self.sim, self.left = sim, fail_after
        self.dt = sim.dt

    @property
    def time(self):
        return self.sim.time

    def step_joint_command(self, cmd):
        self.left -= 1
        if self.left < 0:
            raise rss6.SimulationError("simulated fault")
        self.sim.step_joint_command(cmd)

    def potentiometers(self):
        return self.sim.potentiometers()

    def camera(self):
        return self.sim.camera()


def test_failed_collection_keeps_the_finished_dwells(logged, tmp_path):
    thetas, _, returned, _, _ = logged
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))
    plant = FailingPlant(rss6.ModelSim(truth, DP, seed=7), fail_after=3 * 1100 + 900)
    path = tmp_path / "failed.mcap"
    with pytest.raises(rss6.SimulationError):
        calibrate.collect(plant, thetas[:6], mcap=path, **KW)
    r = calibrate.read_mcap(path)
    assert r.complete and r.used == [0, 1, 2]
    assert [i for i, _ in r.dropped] == [3, 4, 5]
    assert all("stopped" in why for _, why in r.dropped)
    np.testing.assert_array_equal(r.data.kappa, returned.kappa[:3])


def quat(pose):
    q = logs.euler_to_quaternion(pose)[0]
    return q if q[3] >= 0 else -q


def test_mean_pose_is_safe_near_pi():
    rng = np.random.default_rng(0)
    center = np.array([0.01, -0.02, 0.3, 0.2, -0.1, np.pi - 1e-4])
    poses = np.tile(center, (200, 1))
    poses[:, 3:] += rng.normal(0.0, 2e-3, (200, 3))
    poses[:, 5] = (poses[:, 5] + np.pi) % (2 * np.pi) - np.pi  # γ wraps to −π for about half
    assert (poses[:, 5] < 0).sum() > 20 and (poses[:, 5] > 0).sum() > 20
    m = calibrate.mean_pose(poses)
    np.testing.assert_allclose(m[:3], poses[:, :3].mean(0))
    # The naive mean of γ lands near 0 (a half-turn away); the rotation mean stays at ~π.
    assert abs(poses[:, 5].mean()) < 2.0
    assert np.abs(quat(m) - quat(center)).max() < 5e-4
    with pytest.raises(rss6.ShapeError):
        calibrate.mean_pose(np.zeros((0, 6)))
