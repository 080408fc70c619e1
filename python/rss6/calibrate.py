"""Kinematic calibration from the optical CMM (thesis ch. 4): RPBA and the implicit method.

>>> import rss6, numpy as np
>>> from rss6 import calibrate
>>> truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=3))
>>> plant = rss6.ModelSim(truth, rss6.DynamicParams.nominal(), seed=3)
>>> nominal = rss6.KinematicParams.nominal()
>>> thetas = calibrate.select_configurations(nominal, "rpba", seed=0, candidates=300)
>>> data = calibrate.collect(plant, thetas, dwell=0.5)
>>> result = calibrate.rpba(data, nominal)
>>> errs = calibrate.relative_pose_errors(result, plant, n=50)
>>> bool(errs["rms"][:3].max() < 5e-5)   # below 0.05 mm in x, y, z
True
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Union

import numpy as np
from numpy.typing import NDArray

from rss6 import _rss6, logs
from rss6 import thesis as _thesis
from rss6._rss6 import (
    CalibrationData,
    CalibrationResult,
    KinematicParams,
    select_configurations,
    stroke,
)
from rss6.errors import CalibrationError, InvalidInputError, LogError, ShapeError

__all__ = [
    "TABLE_4_2",
    "THESIS_TABLES_4_3_4_4",
    "THESIS_TABLE_4_5",
    "CalibrationData",
    "CalibrationResult",
    "McapCalibration",
    "collect",
    "default_placement",
    "draw_errors",
    "draw_external",
    "implicit",
    "load_mcap",
    "mean_pose",
    "read_mcap",
    "relative_pose_errors",
    "rpba",
    "select_configurations",
    "sensor_in_base_from_reference",
    "stroke",
]

F64 = NDArray[np.float64]
Path = Union[str, "PathLike[str]"]

#: Potentiometer sampling rate during a dwell (Hz, thesis §4.5).
KAPPA_RATE = 500.0
#: Value of the MCAP metadata key ``kind`` in logs written by :func:`collect`.
MCAP_KIND = "rss6.calibrate.collect"

#: Table 4.2 error standard deviations: lengths/positions (m), η (rad/bit), Δθ (rad), external
#: position (m) and angle (rad).
TABLE_4_2 = dict(_thesis.TABLE_4_2)

#: Table 4.5 (thesis, simulation): RMS relative pose errors [x, y, z, α, β, γ] (m, rad).
THESIS_TABLE_4_5 = {k: list(v) for k, v in _thesis.TABLE_4_5.items()}
#: Tables 4.3 (implicit) and 4.4 (RPBA): (before, after) of ‖b^c − b^n‖₂ and Σ‖Φ^c − Φ^n‖₂.
THESIS_TABLES_4_3_4_4 = {
    name: {"param_error": t["param_error"], "residual": t["residual"]}
    for name, t in (("implicit", _thesis.TABLE_4_3), ("RPBA", _thesis.TABLE_4_4))
}


def default_placement() -> tuple[F64, F64]:
    """The design placement (ᴼχ_C, ᴱχ_t) of the simulated optical CMM and its target (rss6-sim's
    defaults): what a user knows nominally before calibration."""
    t = _rss6.ModelSim(KinematicParams.nominal(), _rss6.DynamicParams.nominal()).truth()
    return np.asarray(t["sensor_in_base"]), np.asarray(t["target_in_effector"])


def draw_errors(seed: int = 0) -> F64:
    """A 60-vector b of kinematic errors drawn with Table 4.2's sizes (DESIGN.md order)."""
    rng = np.random.default_rng(seed)
    sd = np.r_[
        np.full(48, TABLE_4_2["length"]),
        np.full(6, TABLE_4_2["eta"]),
        np.full(6, TABLE_4_2["dtheta"]),
    ]
    return np.asarray(rng.normal(0.0, sd), dtype=np.float64)


def draw_external(pose: Any, seed: int = 0) -> F64:
    """An external pose (ᴼχ_C or ᴱχ_t) perturbed with Table 4.2's sizes (0.5 mm, 0.017 rad)."""
    rng = np.random.default_rng(seed)
    p = np.asarray(pose, dtype=np.float64)
    sd = np.r_[np.full(3, TABLE_4_2["ext_position"]), np.full(3, TABLE_4_2["ext_angle"])]
    return np.asarray(p + rng.normal(0.0, sd), dtype=np.float64)


def collect(
    plant: Any,
    thetas: Any,
    dwell: float = 2.0,
    *,
    move_time: float = 1.0,
    settle_time: float = 0.5,
    progress: Callable[[int, int], Any] | None = None,
    mcap: Path | None = None,
) -> CalibrationData:
    """Visits every configuration (row 0 = the initial configuration) on ``plant`` and averages the
    potentiometers (500 Hz) and the camera (ᶜχ_t) over ``dwell`` s at rest (thesis §4.5: 2 s). The
    plant should be at rest (e.g. just reset); the first move starts from its current readings.
    ``progress(done, total)`` is called after each configuration.

    With ``mcap`` (a path), the raw dwell data are also written to an MCAP log (see
    :func:`read_mcap`): the plant is then stepped from Python with the same procedure as the compiled
    collector (cosine-blended move over ``move_time``, ``settle_time`` wait, then ``dwell``), and the
    returned means are computed like :func:`read_mcap` computes them (quaternion mean of the
    rotations); a configuration without camera frames gets a NaN sensor pose, as from the compiled
    collector. Without ``mcap`` the compiled collector runs (GIL released)."""
    if mcap is None:
        return _rss6.collect(
            plant, thetas, dwell, move_time=move_time, settle_time=settle_time, progress=progress
        )
    th = _rows6(thetas, "thetas")
    if len(th) == 0:
        raise InvalidInputError("thetas must contain at least one configuration")
    if not np.all(np.isfinite(th)):
        raise InvalidInputError("thetas must be finite")
    if not (np.isfinite(dwell) and dwell > 0):
        raise InvalidInputError(f"dwell must be > 0 s, got {dwell}")
    if not (np.isfinite(move_time) and move_time > 0 and np.isfinite(settle_time)):
        raise InvalidInputError("move_time must be > 0 and settle_time >= 0")
    if settle_time < 0:
        raise InvalidInputError("move_time must be > 0 and settle_time >= 0")
    raw: dict[str, tuple[list[float], list[F64]]] = {
        "kappa": ([], []),
        "camera_pose": ([], []),
        "theta_cmd": ([], []),
    }
    windows: list[list[float]] = []
    metadata = {
        "kind": MCAP_KIND,
        "configurations": str(len(th)),
        "dwell": repr(float(dwell)),
        "move_time": repr(float(move_time)),
        "settle_time": repr(float(settle_time)),
        "kappa_rate": repr(KAPPA_RATE),
        "windows": "[]",
    }
    written = dict.fromkeys(raw, 0)
    # The log is written as the collection goes: after each dwell, its samples (one chunk, flushed)
    # and then the windows so far, so a killed process leaves every finished dwell readable. If the
    # collection fails, the writer records the error and finishes the file with the finished dwells.
    with logs.RunWriter(mcap, metadata) as writer:

        def on_dwell() -> None:
            new = {
                name: (
                    np.asarray(t[written[name] :], dtype=np.float64),
                    np.asarray(v[written[name] :], dtype=np.float64).reshape(-1, 6),
                )
                for name, (t, v) in raw.items()
            }
            written.update({name: len(t) for name, (t, _) in raw.items()})
            writer.write_streams(new)
            writer.add_metadata({"windows": json.dumps(windows)})

        _step_dwells(plant, th, dwell, move_time, settle_time, progress, raw, windows, on_dwell)
        writer.add_metadata({"status": "finished"})
    return _average_dwells(
        _series(raw), windows, complete=True, drop=False, kappa_rate=KAPPA_RATE
    ).data


def _series(raw: Mapping[str, tuple[list[float], list[F64]]]) -> dict[str, tuple[F64, F64]]:
    return {
        name: (np.asarray(t, dtype=np.float64), np.asarray(v, dtype=np.float64).reshape(-1, 6))
        for name, (t, v) in raw.items()
    }


def _rows6(x: Any, name: str) -> F64:
    a = np.asarray(x, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 6:
        raise ShapeError(f"{name} must have shape (m, 6), got {a.shape}")
    return a


def _step_dwells(
    plant: Any,
    thetas: F64,
    dwell: float,
    move_time: float,
    settle_time: float,
    progress: Callable[[int, int], Any] | None,
    raw: dict[str, tuple[list[float], list[F64]]],
    windows: list[list[float]],
    on_dwell: Callable[[], Any] | None = None,
) -> None:
    """Steps ``plant`` through the configurations as rss6-ident's ``Stepped`` source does, appending
    the raw dwell samples to ``raw`` (kappa, camera_pose, theta_cmd: times, values) and, once a dwell
    is finished, its window [t0, t1] to ``windows`` (s, plant times of its first and last tick), then
    calling ``on_dwell()``."""
    dt = float(plant.dt)

    def ticks(t: float) -> int:
        return max(round(t / dt), 0)

    every = max(round(1.0 / (KAPPA_RATE * dt)), 1)
    last = np.asarray(KinematicParams.nominal().theta_from_reading(plant.potentiometers()))
    kt, kv = raw["kappa"]
    ct, cv = raw["camera_pose"]
    tt, tv = raw["theta_cmd"]
    n_move = max(ticks(move_time), 1)
    for l, cmd in enumerate(thetas):
        for k in range(1, n_move + 1):
            s = 0.5 - 0.5 * np.cos(np.pi * k / n_move)
            plant.step_joint_command(last + (cmd - last) * s)
        last = cmd
        for _ in range(ticks(settle_time)):
            plant.step_joint_command(cmd)
        start = None
        for k in range(max(ticks(dwell), 1)):
            plant.step_joint_command(cmd)
            t = float(plant.time)
            start = t if start is None else start
            if k % every == 0:
                kt.append(t)
                kv.append(np.asarray(plant.potentiometers(), dtype=np.float64))
                tt.append(t)
                tv.append(cmd)
            z = plant.camera()
            if z is not None:
                ct.append(t)
                cv.append(np.asarray(z, dtype=np.float64))
        windows.append([float(start if start is not None else plant.time), float(plant.time)])
        if on_dwell is not None:
            on_dwell()
        if progress is not None:
            progress(l + 1, len(thetas))


def mean_pose(poses: Any) -> F64:
    """Mean of poses (N, 6) [x, y, z, α, β, γ] (m, rad): the mean position and the rotation mean
    of the quaternions (eigenvector of Σ q qᵀ with the largest eigenvalue; sign- and ±π-safe)."""
    p = np.atleast_2d(np.asarray(poses, dtype=np.float64))
    if p.ndim != 2 or p.shape[1] != 6 or len(p) == 0:
        raise ShapeError(f"poses must have shape (N >= 1, 6), got {p.shape}")
    q = logs.euler_to_quaternion(p)
    _, vecs = np.linalg.eigh(q.T @ q)
    qm = vecs[:, -1]
    return np.r_[p[:, :3].mean(axis=0), logs.quaternion_to_euler(qm[None, :])[0]]


@dataclass(frozen=True)
class McapCalibration:
    """Calibration data read from an MCAP log by :func:`read_mcap`.

    ``data`` holds the usable configurations only; ``used[j]`` is the index in the log (order of
    visit, 0 = initial) of ``data``'s row j; ``dropped`` lists ``(index, reason)`` for every
    configuration left out (missing or non-finite frames, a dwell cut short by truncation).
    ``kappa_samples`` and ``camera_frames`` are the counts averaged per used row. ``complete`` is
    False when the log had no end record (a truncated file, read up to its last whole chunk)."""

    data: CalibrationData
    used: list[int]
    dropped: list[tuple[int, str]]
    kappa_samples: NDArray[np.int64]
    camera_frames: NDArray[np.int64]
    complete: bool
    metadata: dict[str, str] = field(default_factory=dict)


def _segments(theta_t: F64, theta_v: F64) -> list[list[float]]:
    """Dwell windows from the theta_cmd stream alone (a log without metadata): a new configuration
    starts where θ_cmd changes or the samples have a gap longer than 10 sample intervals."""
    if len(theta_t) == 0:
        return []
    step = float(np.median(np.diff(theta_t))) if len(theta_t) > 1 else 0.0
    cuts = [0]
    for k in range(1, len(theta_t)):
        if np.any(theta_v[k] != theta_v[k - 1]) or theta_t[k] - theta_t[k - 1] > 10 * step:
            cuts.append(k)
    cuts.append(len(theta_t))
    return [[float(theta_t[a]), float(theta_t[b - 1] + step)] for a, b in zip(cuts, cuts[1:])]


def _average_dwells(
    streams: Mapping[str, Any],
    windows: list[list[float]] | None,
    *,
    complete: bool,
    drop: bool,
    kappa_rate: float | None = None,
    configurations: int | None = None,
    metadata: dict[str, str] | None = None,
) -> McapCalibration:
    """Averages κ and ᶜχ_t over each dwell window (metadata windows, or segments of θ_cmd). With
    ``kappa_rate`` (metadata), a dwell with fewer κ samples than its window holds is cut short;
    without it, only a last dwell shorter than the median of the others is."""
    for name in ("kappa", "theta_cmd"):
        if name not in streams:
            raise LogError(f"no /rss6/{name} channel: not a calibration log written by collect()")
    kt, kv = (np.asarray(a, dtype=np.float64) for a in streams["kappa"])
    tt, tv = (np.asarray(a, dtype=np.float64) for a in streams["theta_cmd"])
    ct, cv = (
        (np.asarray(a, dtype=np.float64) for a in streams["camera_pose"])
        if "camera_pose" in streams
        else (np.zeros(0), np.zeros((0, 6)))
    )
    if windows is None:
        windows = _segments(tt, tv)
    if not windows:
        raise LogError("the log holds no calibration dwell (empty or cut before the first one)")
    cut = "" if complete else " (the file is truncated)"
    tol = 1e-6  # s; stamps are rounded to ns
    rows: list[tuple[int, F64, F64, F64, int, int]] = []
    dropped: list[tuple[int, str]] = []
    for l, (a, b) in enumerate(windows):
        kin = (kt >= a - tol) & (kt <= b + tol)
        tin = (tt >= a - tol) & (tt <= b + tol)
        cin = (ct >= a - tol) & (ct <= b + tol)
        theta = tv[tin][0] if np.any(tin) else np.full(6, np.nan)
        ks, cs = kv[kin], cv[cin]
        finite = cs[np.all(np.isfinite(cs), axis=1)]
        expected = int(np.floor((b - a) * kappa_rate + 1e-6)) + 1 if kappa_rate else 0
        reason = None
        if len(ks) == 0:
            reason = "no potentiometer sample during the dwell" + cut
        elif len(ks) < expected:
            reason = f"dwell cut short: {len(ks)} of {expected} potentiometer samples" + cut
        elif not np.all(np.isfinite(ks)):
            reason = "non-finite potentiometer reading"
        elif len(cs) == 0:
            reason = "no camera frame during the dwell"
        elif len(finite) == 0:
            reason = f"all {len(cs)} camera frames non-finite"
        pose = mean_pose(finite) if len(finite) else np.full(6, np.nan)
        kappa = ks.mean(axis=0) if len(ks) else np.full(6, np.nan)
        if reason is not None:
            dropped.append((l, reason))
            if drop:
                continue
        rows.append((l, kappa, pose, theta, len(ks), len(finite)))
    for l in range(len(windows), configurations or 0):
        dropped.append(
            (l, "not finished: the collection stopped before the end of its dwell" + cut)
        )
    if (
        drop
        and not complete
        and not kappa_rate
        and len(rows) > 1
        and rows[-1][0] == len(windows) - 1
    ):
        # The last dwell of a truncated log may be cut short: keep it only if it is as long as
        # the others.
        n, typical = rows[-1][4], int(np.median([r[4] for r in rows[:-1]]))
        if n < typical:
            why = f"dwell cut short: {n} of ~{typical} potentiometer samples" + cut
            dropped.append((rows[-1][0], why))
            rows.pop()
    if not rows:
        reasons = "; ".join(f"{l}: {r}" for l, r in dropped)
        raise CalibrationError(f"no usable configuration in the log ({reasons})")
    data = CalibrationData.from_arrays(
        np.array([r[1] for r in rows]),
        np.array([r[2] for r in rows]),
        np.array([r[3] for r in rows]),
    )
    return McapCalibration(
        data=data,
        used=[r[0] for r in rows],
        dropped=sorted(dropped),
        kappa_samples=np.array([r[4] for r in rows], dtype=np.int64),
        camera_frames=np.array([r[5] for r in rows], dtype=np.int64),
        complete=complete,
        metadata=dict(metadata or {}),
    )


def read_mcap(path: Path) -> McapCalibration:
    """Reads a calibration log written by ``collect(..., mcap=path)`` (or any
    :func:`rss6.logs.write_run` log with ``kappa``, ``theta_cmd`` and ``camera_pose`` streams holding
    only dwell samples), splits it into configurations and averages κ and ᶜχ_t per dwell (mean
    position, quaternion mean of the rotations: :func:`mean_pose`).

    Configurations are split by the metadata's dwell windows, or, in a log without metadata, where
    θ_cmd changes or its samples pause. A truncated file (no MCAP footer, e.g. the collecting process
    was killed; ``.complete`` False) is read up to its last whole chunk, as :func:`rss6.logs.read_log`
    does: a log written by :func:`collect` then holds every dwell finished before the cut, with its
    window. Configurations with missing
    or non-finite frames, or whose dwell the truncation cut short, are dropped and listed in
    ``.dropped`` as ``(index, reason)``. Raises :class:`rss6.LogError` for an unreadable file or one
    without calibration data (:class:`rss6.CorruptLogError` if it is not MCAP or damaged) and
    :class:`rss6.CalibrationError` if no configuration is usable."""
    log = logs.read_log(path)
    complete = log.complete
    run = log.streams
    md = log.metadata if any(name == "rss6" for name, _ in log.records) else None
    windows = None
    rate = None
    count = None
    if md is not None:
        if md.get("kind") != MCAP_KIND:
            raise LogError(
                f"{path}: not a calibration log written by collect() (metadata kind "
                f"{md.get('kind')!r}, expected {MCAP_KIND!r})"
            )
        try:
            windows = [[float(a), float(b)] for a, b in json.loads(md.get("windows", "[]"))]
            rate = float(md["kappa_rate"])
            count = int(md["configurations"])
        except (KeyError, TypeError, ValueError) as e:
            raise LogError(f"{path}: bad calibration metadata: {e}") from e
    if "kappa" not in run and "theta_cmd" not in run:
        raise LogError(f"{path}: no calibration data (empty, corrupt or not written by collect())")
    return _average_dwells(
        run,
        windows,
        complete=complete,
        drop=True,
        kappa_rate=rate,
        configurations=count,
        metadata=md,
    )


def load_mcap(path: Path) -> CalibrationData:
    """The usable configurations of the calibration log at ``path`` (see :func:`read_mcap`, which
    also reports the dropped ones)."""
    return read_mcap(path).data


def _truth_of(plant_or_truth: Any) -> dict[str, Any]:
    if isinstance(plant_or_truth, dict):
        t = plant_or_truth
    elif hasattr(plant_or_truth, "truth"):
        t = plant_or_truth.truth()
    else:
        raise InvalidInputError("plant_or_truth must be a plant (with .truth()) or a truth dict")
    for k in ("kinematics", "sensor_in_base", "target_in_effector"):
        if k not in t:
            raise InvalidInputError(f"truth dict is missing '{k}'")
    return t


def relative_pose_errors(
    result: CalibrationResult | KinematicParams | None,
    plant_or_truth: Any,
    n: int = 100,
    seed: int = 0,
    *,
    target_in_effector: Any = None,
    stroke: tuple[float, float] | None = None,
) -> dict[str, Any]:
    """RMS relative pose errors of Table 4.5 (procedure steps 1–4) over ``n`` random test
    configurations: ``result`` is a :class:`CalibrationResult`, or kinematic parameters (with
    ``target_in_effector``, default the design target of :func:`default_placement`) — ``None`` means
    the uncalibrated nominal model.
    Returns ``{"rms": (6,), "errors": (n', 6), "skipped": int}`` (m, rad)."""
    t = _truth_of(plant_or_truth)
    if isinstance(result, CalibrationResult):
        params, target = result.params, result.target_in_effector
    else:
        params = result if result is not None else KinematicParams.nominal()
        target = default_placement()[1] if target_in_effector is None else target_in_effector
    return _rss6.relative_pose_errors_raw(
        params,
        target,
        t["kinematics"],
        t["sensor_in_base"],
        t["target_in_effector"],
        n=n,
        seed=seed,
        stroke=stroke,
    )


def sensor_in_base_from_reference(data: CalibrationData, result: CalibrationResult) -> F64:
    """ᴼχ_C estimated from configuration 0 with the calibrated model (RPBA does not estimate it):
    ᴼχ_C = χ_E⁰ ∘ ᴱχ_t ∘ (ᶜχ_t⁰)⁻¹ with χ_E⁰ the calibrated FK of the mean readings κ⁰."""
    if result.sensor_in_base is not None:
        return np.asarray(result.sensor_in_base)
    kp = result.params
    z0 = data.sensor_pose[0]
    if not np.all(np.isfinite(z0)):
        raise InvalidInputError("configuration 0 has no camera frames")
    pose0 = _rss6.fk(kp, kp.theta_from_reading(data.kappa[0]), _rss6.home_pose())
    return _rss6.compose_poses(
        _rss6.compose_poses(pose0, result.target_in_effector), _rss6.invert_pose(z0)
    )


def rpba(
    data: CalibrationData,
    kp: KinematicParams,
    *,
    target_guess: Any = None,
    max_iterations: int = 60,
    progress: Callable[[int, float], Any] | None = None,
) -> CalibrationResult:
    """RPBA (eq. 4.16–4.21): 60 kinematic + 6 external (ᴱχ_t) parameters from ``data``, starting at
    ``kp`` and ``target_guess`` (default: the design target of :func:`default_placement`).
    Levenberg–Marquardt with analytic Jacobians; ``progress(iteration, cost)`` per iteration."""
    guess = default_placement()[1] if target_guess is None else target_guess
    return _rss6.rpba(
        data, kp, max_iterations=max_iterations, target_guess=guess, progress=progress
    )


def implicit(
    data: CalibrationData,
    kp: KinematicParams,
    sensor_pose_guess: Any,
    *,
    target_guess: Any = None,
    max_iterations: int = 60,
) -> CalibrationResult:
    """Implicit calibration (eq. 4.10–4.15): 60 kinematic + 12 external parameters (ᴼχ_C, ᴱχ_t) from
    ``data``, starting at ``kp``, the rough sensor pose ``sensor_pose_guess`` and ``target_guess``
    (default: the design target of :func:`default_placement`)."""
    guess = default_placement()[1] if target_guess is None else target_guess
    return _rss6.implicit(
        data, kp, sensor_pose_guess, max_iterations=max_iterations, target_guess=guess
    )
