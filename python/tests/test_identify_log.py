"""An identification run read back from its MCAP log: `IdentificationData.from_mcap`."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import rss6
from rss6 import identify, logs
from rss6.discrepancy import Model, replay, run_of
from twin_case import collect

KP = rss6.KinematicParams.nominal()
GAINS = (0.45, 1.6, 0.002)
DP, PID = identify.table_5_2_truth()


def _robot() -> rss6.ModelSim:
    return rss6.ModelSim(KP, DP, pid=PID, seed=5, drive_derivative_filter=5e-3)


TRUTH = _robot().truth()
MODEL = Model(KP, DP, PID, TRUTH["sensor_in_base"], TRUTH["target_in_effector"])


def _collect(path: Path, **kw: Any) -> identify.IdentificationData:
    exc = identify.random_excitation(KP, seed=2, harmonics=3, f0=0.5)
    return collect(_robot(), exc, mcap=path, **kw)


def test_a_logged_run_reads_back_as_the_run_collect_returned(tmp_path: Path) -> None:
    """Every channel, the reference (from the logged coefficients, or refitted from the desired
    poses in a log written before they were logged) and the visual PID's gains."""
    data = _collect(tmp_path / "run.mcap", outer_gains=GAINS)
    back = identify.IdentificationData.from_mcap(tmp_path / "run.mcap")
    # The log's integer-nanosecond stamps and pose encoding round: measured ≤ 2.2e-16 s on the
    # times, ≤ 3.5e-18 on the poses; bounds 3× that. Potentiometers and commands are exact.
    for f, bound in (("t", 6.7e-16), ("tick_t", 6.7e-16), ("kappa", 0.0), ("theta_cmd", 0.0)):
        assert np.abs(getattr(back, f) - getattr(data, f)).max() <= bound, f
    for f in ("measured", "reference_pose", "true_pose"):
        assert np.abs(getattr(back, f) - getattr(data, f)).max() <= 1e-17, f
    assert np.array_equal(back.reference.coefficients, data.reference.coefficients)
    assert back.reference.f0 == data.reference.f0
    assert (back.duration, back.dt, back.fault) == (data.duration, data.dt, None)
    assert back.outer_gains == GAINS
    # A log without the coefficients and gains (as written before 2026-11-28).
    log = logs.read_log(tmp_path / "run.mcap")
    old = {k: v for k, v in log.metadata.items() if k not in ("coefficients", "outer_gains")}
    logs.write_run(tmp_path / "old.mcap", log.streams, old)
    back = identify.IdentificationData.from_mcap(tmp_path / "old.mcap")
    assert np.abs(back.reference.coefficients - data.reference.coefficients).max() < 1e-9
    assert back.outer_gains is None


def test_a_run_that_did_not_finish_is_refused_or_read_in_part(tmp_path: Path) -> None:
    """A truncated file and a run stopped by an exception are refused; with ``partial=True`` their
    recorded part is a run of its own: the whole run's first frames and ticks, a duration that
    covers them, usable by the discrepancy workflow's replay."""
    whole = _collect(tmp_path / "whole.mcap")
    raw = (tmp_path / "whole.mcap").read_bytes()
    (tmp_path / "cut.mcap").write_bytes(raw[: len(raw) // 2])
    with pytest.raises(rss6.TruncatedLogError, match=r"did not finish .* partial=True"):
        identify.IdentificationData.from_mcap(tmp_path / "cut.mcap")
    # The discrepancy workflow reads MCAP runs the same way (before: the truncated one failed as
    # an "infeasible exciting trajectory", its reference refitted on its first 0.3 s).
    with pytest.raises(rss6.TruncatedLogError, match=r"camera frames end at t ="):
        run_of(tmp_path / "cut.mcap")

    class Stop(Exception):
        pass

    calls: list[float] = []

    def stop_after_one_second(done: float, total: float) -> None:
        calls.append(done)
        if done >= 1.0:
            raise Stop

    with pytest.raises(Stop):
        _collect(tmp_path / "stopped.mcap", progress=stop_after_one_second, segment=0.5)
    with pytest.raises(rss6.InvalidInputError, match=r"status 'failed: Stop"):
        identify.IdentificationData.from_mcap(tmp_path / "stopped.mcap")
    for name in ("cut.mcap", "stopped.mcap"):
        part = identify.IdentificationData.from_mcap(tmp_path / name, partial=True)
        ticks = round(part.duration / part.dt)
        assert part.tick_t is not None and part.theta_cmd is not None
        assert 100 < ticks < round(whole.duration / whole.dt), name
        assert part.tick_t.shape[0] == ticks and part.t[-1] < part.duration
        k = part.t.shape[0]
        assert np.abs(part.measured - whole.measured[:k]).max() <= 1e-17, name
        assert np.array_equal(part.theta_cmd, np.asarray(whole.theta_cmd)[:ticks]), name
        # The discrepancy workflow replays the part as the whole run's first seconds.
        a, b = replay(MODEL, run_of(part)), replay(MODEL, run_of(whole))
        assert a.shape[0] == k and np.abs(a - b[:k]).max() < 1e-12, name
    # Older logs (no coefficients) cannot be rebuilt in part: refused with the reason.
    log = logs.read_log(tmp_path / "whole.mcap")
    old = {k: v for k, v in log.metadata.items() if k != "coefficients"}
    logs.write_run(tmp_path / "old.mcap", log.streams, {**old, "status": "failed: Stop: "})
    with pytest.raises(rss6.InvalidInputError, match="no reference coefficients"):
        identify.IdentificationData.from_mcap(tmp_path / "old.mcap", partial=True)


def test_a_logged_fault_and_bad_metadata_are_read_as_such(tmp_path: Path) -> None:
    data = _collect(tmp_path / "run.mcap")
    log = logs.read_log(tmp_path / "run.mcap")
    fault = {**log.metadata, "fault": "t = 1.250 s: pose outside the working branch"}
    logs.write_run(tmp_path / "fault.mcap", log.streams, fault)
    back = identify.IdentificationData.from_mcap(tmp_path / "fault.mcap")
    assert back.fault == (1.25, "pose outside the working branch")
    # The discrepancy workflow refuses it (before, a logged fault was not read: diagnosed as whole).
    with pytest.raises(rss6.InvalidInputError, match=r"faulted at t = 1\.250 s \(pose outside"):
        run_of(tmp_path / "fault.mcap")
    assert dataclasses.replace(back, fault=None).frames == data.frames
    bad = {**log.metadata, "coefficients": "1.0, nan"}
    logs.write_run(tmp_path / "bad.mcap", log.streams, bad)
    with pytest.raises(rss6.InvalidInputError, match="'coefficients' holds NaN"):
        identify.IdentificationData.from_mcap(tmp_path / "bad.mcap")
    with pytest.raises(rss6.InvalidInputError, match="no such MCAP file"):
        identify.IdentificationData.from_mcap(tmp_path / "none.mcap")
