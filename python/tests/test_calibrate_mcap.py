"""rss6.calibrate with MCAP logs: collect(..., mcap=path) logs the collection with the Rust writer
(every tick and each dwell's means), read_mcap/load_mcap read the means back (issue 6, "loaded from
an MCAP log"; issue 11: one data path, the same numbers with and without a log)."""

import numpy as np
import pytest
import rss6
from rss6 import _rss6, calibrate, logs

NOMINAL = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()
KW = {"dwell": 0.4, "move_time": 0.4, "settle_time": 0.3}


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """The same robot (same seed) collected without and with an MCAP log."""
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
    assert calls == [(k + 1, len(thetas)) for k in range(len(thetas))]
    return thetas, direct, returned, path, direct_plant


def test_collect_returns_the_same_data_with_and_without_mcap(logged):
    # Regression (issue 11): with mcap= the plant used to be stepped from Python and the rotations
    # averaged differently, so the same plant and seed gave a different sensor_pose.
    _, direct, returned, _, _ = logged
    np.testing.assert_array_equal(returned.kappa, direct.kappa)
    np.testing.assert_array_equal(returned.sensor_pose, direct.sensor_pose)
    np.testing.assert_array_equal(returned.theta_cmd, direct.theta_cmd)
    np.testing.assert_array_equal(returned.camera_frames, direct.camera_frames)


def in_window(t, w):
    return (t >= w[0] - 1e-6) & (t <= w[1] + 1e-6)


def test_log_holds_every_tick_and_the_dwell_means(logged):
    thetas, _, returned, path, _ = logged
    log = logs.read_log(path, strict=True)
    md = log.metadata
    assert md["kind"] == calibrate.MCAP_KIND and md["status"] == "finished"
    assert (int(md["configurations"]), float(md["dwell"]), float(md["kappa_rate"])) == (
        len(thetas),
        0.4,
        500.0,
    )
    assert {"kappa", "theta_cmd", "sensor_pose", "true_pose", "theta", "torque"} <= set(log.streams)
    per_config = round((0.4 + 0.3 + 0.4) / 1e-3)
    assert len(log.streams["kappa"][0]) == per_config * len(thetas)
    assert [d["index"] for d in log.dwells] == list(range(len(thetas)))
    kt, kv = log.streams["kappa"]
    st, sv = log.streams["sensor_pose"]
    for d, kappa, pose in zip(log.dwells, returned.kappa, returned.sensor_pose):
        # the logged means are the returned ones, bit for bit
        np.testing.assert_array_equal(d["kappa"], kappa)
        np.testing.assert_array_equal(d["sensor_pose"], pose)
        # and they are the means of the logged ticks: κ every 2 ms of the window (the reading
        # after each sampled tick), ᶜχ_t over every frame of the window (rss6's one pose mean)
        a, b = d["window"]
        assert b - a == pytest.approx(0.399)
        after = in_window(kt, (a + 1e-3, b))
        np.testing.assert_allclose(kv[after][::2].mean(0), kappa, rtol=0, atol=1e-9)
        frames = sv[in_window(st, (a, b))]
        assert len(frames) == d["camera_frames"]
        np.testing.assert_allclose(calibrate.mean_pose(frames), pose, rtol=0, atol=1e-12)


def test_round_trip_equals_direct_collection(logged):
    thetas, direct, returned, path, _ = logged
    r = calibrate.read_mcap(path)
    assert r.complete and r.dropped == [] and r.used == list(range(len(thetas)))
    np.testing.assert_array_equal(r.kappa_samples, 200)
    np.testing.assert_array_equal(r.camera_frames, direct.camera_frames)
    loaded = calibrate.load_mcap(path)
    assert len(loaded) == len(thetas)
    for name in ("theta_cmd", "kappa", "sensor_pose", "camera_frames", "sensor_pose_cov"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(returned, name), err_msg=name)
    np.testing.assert_array_equal(loaded.theta_cmd, thetas)


def test_rpba_on_loaded_data_matches_direct(logged):
    _, direct, _, path, plant = logged
    res_direct = calibrate.rpba(direct, NOMINAL)
    res_loaded = calibrate.rpba(calibrate.load_mcap(path), NOMINAL)
    assert res_loaded.rank == res_direct.rank
    assert res_loaded.unidentifiable == res_direct.unidentifiable
    assert res_loaded.cost_history[-1] < 1e-3 * res_loaded.cost_history[0]
    # the same data: the same calibration
    np.testing.assert_array_equal(res_loaded.errors, res_direct.errors)
    np.testing.assert_array_equal(res_loaded.target_in_effector, res_direct.target_in_effector)
    # and weighted by the dwells' own camera covariance, which the log keeps too
    np.testing.assert_array_equal(
        calibrate.rpba(calibrate.load_mcap(path), NOMINAL, noise="dwells").errors,
        calibrate.rpba(direct, NOMINAL, noise="dwells").errors,
    )
    e_loaded = calibrate.relative_pose_errors(res_loaded, plant, n=40)["rms"]
    uncal = calibrate.relative_pose_errors(None, plant, n=40)["rms"]
    assert np.all(e_loaded < uncal / 10)


def write_dwells(path, dwells, configurations):
    """A calibration log written by hand: metadata, then the given dwells (index, sensor_pose)."""
    w = _rss6.LogWriter(str(path))
    w.add_metadata({"kind": calibrate.MCAP_KIND, "configurations": str(configurations)})
    rng = np.random.default_rng(1)
    for index, pose in dwells:
        w.write_dwell(
            index,
            (index * 2.0, index * 2.0 + 0.399),
            rng.normal(0, 0.1, 6),
            rng.normal(0, 100, 6),
            pose,
            200,
            0 if pose is None else 12,
        )
    w.finish("finished")


def test_defective_and_missing_dwells_are_dropped_and_reported(tmp_path):
    pose = rss6.home_pose()
    path = tmp_path / "defects.mcap"
    write_dwells(path, [(0, pose), (1, pose), (2, None), (4, pose)], configurations=6)
    r = calibrate.read_mcap(path)
    assert r.used == [0, 1, 4] and len(r.data) == 3 and r.complete
    reasons = dict(r.dropped)
    assert sorted(reasons) == [2, 3, 5]
    assert "no camera frame" in reasons[2]
    assert "not finished" in reasons[3] and "truncated" not in reasons[3]
    np.testing.assert_array_equal(r.camera_frames, 12)
    np.testing.assert_array_equal(r.data.camera_frames, 12)


def test_no_usable_configuration_is_a_calibration_error(tmp_path):
    path = tmp_path / "none.mcap"
    write_dwells(path, [(0, None), (1, None)], configurations=2)
    with pytest.raises(rss6.CalibrationError, match="no usable configuration"):
        calibrate.load_mcap(path)


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


def test_failed_collection_keeps_the_finished_dwells(logged, tmp_path):
    thetas, _, returned, _, _ = logged
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))

    def progress(done, total):
        if done == 3:
            raise RuntimeError("operator abort")

    path = tmp_path / "failed.mcap"
    with pytest.raises(RuntimeError, match="operator abort"):
        calibrate.collect(
            rss6.ModelSim(truth, DP, seed=7), thetas[:6], mcap=path, progress=progress, **KW
        )
    log = logs.read_log(path, strict=True)
    assert log.metadata["status"] == "failed: RuntimeError: operator abort"
    r = calibrate.read_mcap(path)
    assert r.complete and r.used == [0, 1, 2]
    assert [i for i, _ in r.dropped] == [3, 4, 5]
    assert all("stopped" in why for _, why in r.dropped)
    np.testing.assert_array_equal(r.data.kappa, returned.kappa[:3])


@pytest.mark.parametrize("mcap", [False, True])
def test_keyboard_interrupt_in_progress_stops_the_collection(tmp_path, mcap):
    calls = []

    def progress(done, total):
        calls.append(done)
        raise KeyboardInterrupt

    thetas = np.zeros((4, 6))
    path = tmp_path / "ki.mcap" if mcap else None
    with pytest.raises(KeyboardInterrupt):
        calibrate.collect(rss6.ModelSim(NOMINAL, DP), thetas, mcap=path, progress=progress, **KW)
    assert calls == [1]
    if mcap:
        assert (
            logs.read_log(path, strict=True)
            .metadata["status"]
            .startswith("failed: KeyboardInterrupt")
        )


def quat(pose):
    from scipy.spatial.transform import Rotation

    q = Rotation.from_euler("XYZ", pose[3:]).as_quat()
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


def test_collection_log_is_readable_by_the_mcap_package(logged):
    import json

    from mcap.reader import make_reader

    thetas, _, returned, path, _ = logged
    topics, dwells = set(), []
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages():
            topics.add((channel.topic, schema.name))
            if channel.topic == "/rss6/dwell":
                dwells.append(json.loads(message.data))
    assert ("/rss6/dwell", "rss6.Dwell") in topics
    assert ("/rss6/sensor_pose", "foxglove.FrameTransform") in topics
    assert ("/rss6/kappa", "rss6.JointVector") in topics
    assert [d["index"] for d in dwells] == list(range(len(thetas)))
    np.testing.assert_array_equal([d["kappa"] for d in dwells], returned.kappa)
