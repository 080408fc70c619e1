"""Nothing lost on a crash: runs logged by a process killed with SIGKILL part way through leave MCAP
files that read back, up to their last finished chunk, with exactly the samples that were written;
damaged files raise typed errors."""

import contextlib
import os
import signal
import struct
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import rss6
from rss6 import calibrate, logs, servo

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs SIGKILL (POSIX)")

KP = rss6.KinematicParams.nominal()
DP = rss6.DynamicParams.nominal()


def spawn(code):
    """Starts ``code`` in a fresh interpreter; the child prints one line per finished step."""
    return subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(code)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def kill_after(proc, done, timeout=120):
    """Reads the child's lines until ``done(lines)`` holds, then kills it with SIGKILL (no cleanup,
    no finally blocks, no buffers flushed). Returns the lines read."""
    lines = []
    for line in proc.stdout:
        lines.append(line.strip())
        if done(lines):
            break
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait(timeout=timeout)
    assert proc.returncode == -signal.SIGKILL, proc.stderr.read()[-2000:]
    proc.stdout.close()
    proc.stderr.close()
    return lines


def block(k, n=500):
    """Deterministic samples of block k: times k·n … (k+1)·n − 1 ms."""
    rng = np.random.default_rng(k)
    t = (k * n + np.arange(n)) * 1e-3
    pose = rss6.home_pose() + rng.normal(0, [1e-3, 1e-3, 1e-3, 0.02, 0.02, 0.02], (n, 6))
    return t, pose, rng.normal(0, 5, (n, 6))


WRITER_CHILD = """
    import sys, time
    sys.path[:0] = {path!r}
    import numpy as np
    from rss6 import logs
    from test_logs_crash import block
    with logs.RunWriter({file!r}, {{"controller": "DSMC"}}, chunk_size=64 * 1024) as w:
        for k in range(100000):
            t, pose, torque = block(k)
            w.write_streams({{"true_pose": (t, pose), "torque": (t, torque)}})
            # bytes the writer has handed to the OS so far: what the kill must not lose
            print(k, w.messages, w._synced, flush=True)
            time.sleep(0.01)
"""


def test_killed_writer_leaves_every_finished_chunk_readable(tmp_path):
    path = tmp_path / "killed.mcap"
    child = WRITER_CHILD.format(path=[os.path.dirname(__file__)], file=str(path))
    lines = kill_after(spawn(child), lambda ls: len(ls) >= 12)
    last_synced = int(lines[-1].split()[2])
    written = int(lines[-1].split()[1])
    log = logs.read_log(path)
    assert not log.complete and log.truncated and "truncated" in log.truncation
    assert log.metadata == {"controller": "DSMC"}
    # Everything handed to the OS by the last flush before the kill is read back, and at least
    # the chunks finished since.
    assert log.readable >= last_synced > 0 and log.chunks >= 3
    t, pose = log.streams["true_pose"]
    tt, torque = log.streams["torque"]
    n, m = len(t), len(tt)
    # (the child may have written a block or two more while the kill was on its way). Samples are
    # merged in time order, pose before torque at each stamp; a chunk (of 64 KiB) may end between
    # the two, so the torque stream may be one sample short, never more.
    assert 0 < n <= 40 * 500 and m in (n - 1, n) and log.messages == n + m
    assert n + m >= written - 2 * 500 * 2  # at most the last finished block's tail is missing
    blocks = [block(k) for k in range(n // 500 + 1)]
    want_t = np.concatenate([b[0] for b in blocks])[:n]
    want_pose = np.concatenate([b[1] for b in blocks])[:n]
    want_torque = np.concatenate([b[2] for b in blocks])[:m]
    # Exact: the stamps to the ns, the six-vectors bit for bit (JSON floats round-trip), the
    # positions bit for bit; angles went through a quaternion.
    np.testing.assert_array_equal(np.round(t * 1e9), np.round(want_t * 1e9))
    np.testing.assert_array_equal(tt, t[:m])
    np.testing.assert_array_equal(torque, want_torque)
    np.testing.assert_array_equal(pose[:, :3], want_pose[:, :3])
    np.testing.assert_allclose(pose[:, 3:], want_pose[:, 3:], rtol=0, atol=1e-13)
    # read_run reads it too; strict reading refuses it with a typed error saying what is there.
    np.testing.assert_array_equal(logs.read_run(path)["torque"][1], torque)
    with pytest.raises(rss6.TruncatedLogError, match="truncated MCAP log") as e:
        logs.read_log(path, strict=True)
    assert (e.value.readable, e.value.messages, e.value.chunks) == (
        log.readable,
        log.messages,
        log.chunks,
    )
    assert isinstance(e.value, rss6.LogError)


SERVO_CHILD = """
    import time
    import rss6
    from rss6 import servo
    plant = rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal(), seed=11)
    def progress(t, duration):
        print(f"{{t:.3f}}", flush=True)
        time.sleep(0.05)
    servo.track(plant, "dsmc", "exp1", duration=600.0, mcap={file!r}, progress=progress)
"""


def test_killed_servo_run_keeps_every_logged_second(tmp_path):
    path = tmp_path / "servo.mcap"
    lines = kill_after(spawn(SERVO_CHILD.format(file=str(path))), lambda ls: float(ls[-1]) >= 3.0)
    seconds = round(float(lines[-1]) + 1e-3)
    log = logs.read_log(path)
    assert not log.complete
    assert log.metadata["controller"] == "DSMC" and "status" not in log.metadata
    t, true = log.streams["true_pose"]
    # every second reported done was on disk
    assert seconds * 1000 <= len(t)
    # The same run, in this process, for as long as the log holds: the logged samples are its.
    ref = servo.track(
        rss6.ModelSim(KP, DP, seed=11), "dsmc", "exp1", duration=np.ceil(len(t) / 1000)
    )
    n = len(t)
    np.testing.assert_array_equal(np.round(t * 1e9), np.round(ref.time[:n] * 1e9))
    np.testing.assert_array_equal(true[:, :3], ref.true[:n, :3])
    np.testing.assert_allclose(true[:, 3:], ref.true[:n, 3:], rtol=0, atol=1e-13)
    np.testing.assert_array_equal(log.streams["theta_cmd"][1], ref.theta_cmd[:n])
    np.testing.assert_array_equal(log.streams["torque"][1], ref.torque[:n])
    tc, cam = log.streams["camera_pose"]
    m = len(tc)
    assert m > 25 * seconds
    np.testing.assert_array_equal(cam[:, :3], ref.measured[:m, :3])


COLLECT_CHILD = """
    import time
    import rss6
    from rss6 import calibrate
    nominal = rss6.KinematicParams.nominal()
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))
    thetas = calibrate.select_configurations(nominal, "rpba", seed=0, candidates=300)
    def progress(done, total):
        print(done, flush=True)
        time.sleep(0.2)
    calibrate.collect(
        rss6.ModelSim(truth, rss6.DynamicParams.nominal(), seed=7), thetas, 0.4,
        move_time=0.4, settle_time=0.3, mcap={file!r}, progress=progress,
    )
"""


def test_killed_calibration_collection_keeps_its_finished_dwells(tmp_path):
    path = tmp_path / "collect.mcap"
    lines = kill_after(spawn(COLLECT_CHILD.format(file=str(path))), lambda ls: int(ls[-1]) >= 4)
    done = int(lines[-1])
    r = calibrate.read_mcap(path)
    assert not r.complete
    # every dwell reported finished is in the file, each with its full 200 κ samples
    assert done <= len(r.used) and r.used == list(range(len(r.used)))
    np.testing.assert_array_equal(r.kappa_samples, 200)
    thetas = calibrate.select_configurations(KP, "rpba", seed=0, candidates=300)
    assert [i for i, _ in r.dropped] == list(range(len(r.used), len(thetas)))
    assert all("truncated" in why for _, why in r.dropped)
    # The same collection in this process: the logged dwells average to the same numbers.
    truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=7))
    ref = calibrate.collect(
        rss6.ModelSim(truth, DP, seed=7),
        thetas[: len(r.used)],
        0.4,
        move_time=0.4,
        settle_time=0.3,
        mcap=tmp_path / "ref.mcap",
    )
    np.testing.assert_array_equal(r.data.kappa, ref.kappa)
    np.testing.assert_array_equal(r.data.sensor_pose, ref.sensor_pose)
    # and bit for bit what the completed log of the same dwells gives
    done_log = calibrate.read_mcap(tmp_path / "ref.mcap")
    assert done_log.complete
    np.testing.assert_array_equal(r.data.sensor_pose, done_log.data.sensor_pose)


def test_damaged_files_raise_typed_errors(tmp_path):
    t, pose, torque = block(0, 6000)
    good = tmp_path / "good.mcap"
    with logs.RunWriter(good, chunk_size=16 * 1024) as w:
        w.write_streams({"true_pose": (t, pose), "torque": (t, torque)})
    full = logs.read_log(good, strict=True)
    assert full.complete and full.chunks > 10 and full.truncation == ""
    raw = good.read_bytes()

    def put(name, data):
        p = tmp_path / name
        p.write_bytes(data)
        return p

    with pytest.raises(rss6.CorruptLogError, match="bad magic"):
        logs.read_log(put("garbage.mcap", b"not an mcap file at all" * 100))
    # A flipped byte inside a chunk's data (its CRC or decompression fails), or in a message index
    # (the data-section CRC fails); in the truncated file, the chunk CRC still catches it.
    records, pos = [], 8
    while pos < len(raw) - 8:
        (length,) = struct.unpack_from("<Q", raw, pos + 1)
        records.append((raw[pos], pos, length))
        pos += 9 + length
    chunk = [r for r in records if r[0] == 0x06][3]
    index = [r for r in records if r[0] == 0x07][3]
    for (_, at, length), cut in ((chunk, None), (index, None), (chunk, chunk[1] + 9 + chunk[2])):
        bad = bytearray(raw[:cut])
        bad[at + 9 + length // 2] ^= 0xFF
        with pytest.raises(rss6.CorruptLogError, match="not a readable MCAP log") as e:
            logs.read_log(put("flipped.mcap", bytes(bad)))
        assert 0 < e.value.offset <= len(raw)
    mid = bytearray(raw)
    mid[len(raw) // 2] ^= 0xFF
    with pytest.raises(rss6.TruncatedLogError, match="empty"):
        logs.read_log(put("empty.mcap", b""))
    with pytest.raises(rss6.TruncatedLogError, match="before its header"):
        logs.read_log(put("magic.mcap", raw[:12]))
    cut = put("cut.mcap", raw[: len(raw) // 3])
    part = logs.read_log(cut)
    assert not part.complete and 0 < len(part.streams["torque"][0]) < 6000
    np.testing.assert_array_equal(
        part.streams["torque"][1], torque[: len(part.streams["torque"][0])]
    )
    with pytest.raises(rss6.TruncatedLogError):
        logs.read_run(cut, strict=True)
    # every one of them is a LogError (an Rss6Error), never a raw mcap/struct/zstd exception
    for name, data in (("a", raw[:5]), ("b", raw[:9]), ("c", raw[:100]), ("d", bytes(mid))):
        with contextlib.suppress(rss6.LogError):
            logs.read_log(put(name + ".mcap", data))
