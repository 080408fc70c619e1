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


def test_quaternion_convention_matches_the_core_rotation():
    pose = np.array([0.0, 0.0, 0.0, 0.3, -0.2, 0.5])
    x, y, z, w = logs.euler_to_quaternion(pose)[0]
    first_column = [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w)]
    np.testing.assert_allclose(
        rss6.compose_poses(pose, [1, 0, 0, 0, 0, 0])[:3], first_column, atol=1e-14
    )
    np.testing.assert_allclose(logs.quaternion_to_euler([[x, y, z, w]])[0], pose[3:], atol=1e-14)


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
