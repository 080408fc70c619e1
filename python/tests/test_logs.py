"""MCAP logs: round trip, Foxglove schemas, truncated files, bad input."""

import json

import numpy as np
import pytest
import rss6
from rss6 import logs


def streams(n=200):
    rng = np.random.default_rng(0)
    t = np.arange(n) * 1e-3
    poses = rss6.home_pose() + rng.normal(0, [1e-3, 1e-3, 1e-3, 0.02, 0.02, 0.02], (n, 6))
    return {"true_pose": (t, poses), "torque": (t, rng.normal(0, 5, (n, 6)))}


def test_round_trip(tmp_path):
    s = streams()
    p = tmp_path / "r.mcap"
    logs.write_run(p, s, metadata={"controller": "DSMC"})
    back = logs.read_run(p)
    for k, (t, v) in s.items():
        np.testing.assert_allclose(back[k][0], t, atol=1e-9)
        np.testing.assert_allclose(back[k][1], v, atol=1e-12)
    assert back["metadata"] == {"controller": "DSMC"}


def test_poses_are_foxglove_frame_transforms(tmp_path):
    from mcap.reader import make_reader

    p = tmp_path / "r.mcap"
    logs.write_run(p, streams(5))
    with open(p, "rb") as f:
        reader = make_reader(f)
        seen = {}
        for schema, channel, message in reader.iter_messages():
            seen[channel.topic] = (
                schema.name,
                schema.encoding,
                channel.message_encoding,
                json.loads(message.data),
            )
    name, enc, menc, msg = seen["/rss6/true_pose"]
    assert (name, enc, menc) == ("foxglove.FrameTransform", "jsonschema", "json")
    assert msg["parent_frame_id"] == "base" and set(msg["rotation"]) == {"x", "y", "z", "w"}
    assert seen["/rss6/torque"][0] == "rss6.JointVector"


def test_stream_names_are_the_rust_ones(tmp_path):
    t = np.arange(2) * 1e-3
    p = tmp_path / "s.mcap"
    names = [*logs.POSE_TOPICS, *logs.VECTOR_TOPICS]
    assert "sensor_pose" in names and "kappa" in names
    logs.write_run(p, {n: (t, np.tile(rss6.home_pose(), (2, 1))) for n in names})
    assert set(logs.read_log(p).streams) == set(names)


def test_frame_transforms_hold_the_quaternion_of_rx_ry_rz(tmp_path):
    # R = Rx(α)·Ry(β)·Rz(γ) is scipy's intrinsic "XYZ"; the Rust writer stores its quaternion.
    from mcap.reader import make_reader
    from scipy.spatial.transform import Rotation

    poses = streams(7)["true_pose"][1]
    p = tmp_path / "q.mcap"
    logs.write_run(p, {"true_pose": (np.arange(7) * 1e-3, poses)})
    with open(p, "rb") as f:
        msgs = [json.loads(m.data) for _, _, m in make_reader(f).iter_messages()]
    q = np.array([[m["rotation"][k] for k in "xyzw"] for m in msgs])
    want = Rotation.from_euler("XYZ", poses[:, 3:]).as_quat()
    np.testing.assert_allclose(q * np.sign(q[:, 3:]), want * np.sign(want[:, 3:]), atol=1e-14)
    np.testing.assert_allclose(
        Rotation.from_euler("XYZ", poses[0, 3:]).as_matrix()[:, 0],
        rss6.compose_poses(poses[0] * [0, 0, 0, 1, 1, 1], [1, 0, 0, 0, 0, 0])[:3],
        atol=1e-14,
    )


def test_truncated_file_is_readable_up_to_its_last_chunk(tmp_path):
    n = 20000
    s = streams(n)
    p = tmp_path / "full.mcap"
    logs.write_run(p, s)
    data = p.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) * 2 // 3])  # a run killed mid-way: no summary, no footer
    back = logs.read_run(cut)
    t, v = back["true_pose"]
    assert 0 < len(t) < n
    np.testing.assert_allclose(v, s["true_pose"][1][: len(t)], atol=1e-12)


def test_bad_streams_raise_log_error(tmp_path):
    t = np.arange(3.0)
    with pytest.raises(rss6.LogError, match="unknown stream"):
        logs.write_run(tmp_path / "a.mcap", {"bogus": (t, np.zeros((3, 6)))})
    with pytest.raises(rss6.LogError, match=r"\(N, 6\)"):
        logs.write_run(tmp_path / "a.mcap", {"torque": (t, np.zeros((3, 5)))})
    with pytest.raises(rss6.LogError, match="cannot read"):
        logs.read_run(tmp_path / "missing.mcap")


def test_run_writer_appends_samples_and_metadata_as_it_goes(tmp_path):
    s = streams(300)
    p = tmp_path / "w.mcap"
    t, tau = s["torque"]
    with logs.RunWriter(p, {"controller": "KCSC", "trajectory": "exp1"}, flush_interval=0) as w:
        w.write_streams({"true_pose": (s["true_pose"][0][:100], s["true_pose"][1][:100])})
        w.write("torque", t[0], tau[0])  # one sample
        w.write("torque", t[1:], tau[1:])
        w.write("true_pose", s["true_pose"][0][100:], s["true_pose"][1][100:])
        w.add_metadata({"status": "finished"})
        on_disk = logs.read_log(p)  # readable while the writer is still open
        assert not on_disk.complete and len(on_disk.streams["torque"][0]) == 300
        assert on_disk.chunks >= 3  # flush_interval=0: every write finished its chunk
    assert w.closed and w.messages == 600
    back = logs.read_log(p, strict=True)
    assert back.complete and back.messages == 600 and back.truncation == ""
    np.testing.assert_array_equal(back.streams["torque"][1], tau)
    np.testing.assert_allclose(back.streams["true_pose"][1], s["true_pose"][1], atol=1e-12)
    assert back.metadata == {"controller": "KCSC", "trajectory": "exp1", "status": "finished"}
    assert [name for name, _ in back.records] == ["rss6", "rss6"]
    with pytest.raises(rss6.LogError, match="already closed"):
        w.write("torque", t, tau)


def test_run_writer_finishes_the_file_when_the_run_raises(tmp_path):
    p = tmp_path / "failed.mcap"
    t, tau = streams(50)["torque"]
    with pytest.raises(ZeroDivisionError), logs.RunWriter(p) as w:
        w.write("torque", t, tau)
        _ = 1 / 0
    back = logs.read_log(p, strict=True)
    assert back.complete and back.metadata == {
        "status": "failed: ZeroDivisionError: division by zero"
    }
    np.testing.assert_array_equal(back.streams["torque"][1], tau)
    with pytest.raises(rss6.LogError, match="cannot write"):
        logs.RunWriter(tmp_path / "no" / "such" / "dir.mcap")
    with pytest.raises(rss6.LogError, match="non-decreasing"), logs.RunWriter(p) as w:
        w.write("torque", t[::-1], tau)
