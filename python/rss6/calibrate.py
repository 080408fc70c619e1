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

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Union

import numpy as np
from numpy.typing import NDArray

from rss6 import _checks, _rss6, logs
from rss6 import thesis as _thesis
from rss6._rss6 import (
    CalibrationData,
    CalibrationResult,
    KinematicParams,
    select_configurations,
    stroke,
)
from rss6.errors import CalibrationError, InvalidInputError, LogError

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
    rng = _checks.rng(seed)
    sd = np.r_[
        np.full(48, TABLE_4_2["length"]),
        np.full(6, TABLE_4_2["eta"]),
        np.full(6, TABLE_4_2["dtheta"]),
    ]
    return np.asarray(rng.normal(0.0, sd), dtype=np.float64)


def draw_external(pose: Any, seed: int = 0) -> F64:
    """An external pose (ᴼχ_C or ᴱχ_t) perturbed with Table 4.2's sizes (0.5 mm, 0.017 rad)."""
    rng = _checks.rng(seed)
    p = _checks.pose6(pose, "pose")
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
    """Visits every configuration (row 0 = the initial configuration; θ_cmd in the drive's joint
    convention) on ``plant`` and averages the potentiometers (500 Hz) and the camera (ᶜχ_t) over
    ``dwell`` s at rest (thesis §4.5: 2 s), with rss6-exp's dwell runner (GIL released): a
    cosine-blended move over ``move_time`` s, a ``settle_time`` s wait, then the dwell; ᶜχ_t is the
    :func:`mean_pose` of the dwell's finite frames, NaN without frames. The plant should be at rest
    (e.g. just reset); the first move starts from its current readings. ``progress(done, total)`` is
    called after each configuration; if it raises (KeyboardInterrupt included) the collection stops
    and the exception reaches the caller; Ctrl-C stops it at the same points.

    With ``mcap`` (a path), the collection is also logged there as it goes by the Rust writer: every
    tick's samples and each dwell's means (what this function returns), so :func:`read_mcap` gives
    back exactly the returned data, and a killed process leaves every finished dwell readable. The
    returned data are the same with and without ``mcap``."""
    return _rss6.collect(
        plant,
        thetas,
        dwell,
        move_time=move_time,
        settle_time=settle_time,
        kappa_rate=KAPPA_RATE,
        progress=progress,
        mcap=None if mcap is None else os.fspath(mcap),
    )


def mean_pose(poses: Any) -> F64:
    """Mean of poses (N, 6) [x, y, z, α, β, γ] (m, rad): the mean position and the rotation whose
    quaternion maximises Σ (q · q_k)² (sign- and ±π-safe) — rss6-exp's ``mean_pose``, the mean the
    calibration dwells use."""
    return np.asarray(_rss6.mean_pose(np.atleast_2d(np.asarray(poses, dtype=np.float64))))


@dataclass(frozen=True)
class McapCalibration:
    """Calibration data read from an MCAP log by :func:`read_mcap`.

    ``data`` holds the usable configurations only; ``used[j]`` is the index in the log (order of
    visit, 0 = initial) of ``data``'s row j; ``dropped`` lists ``(index, reason)`` for every
    configuration left out (no camera frame, non-finite values, a dwell the log lacks because the
    collection stopped or the file was cut).
    ``kappa_samples`` and ``camera_frames`` are the counts averaged per used row. ``complete`` is
    False when the log had no end record (a truncated file, read up to its last whole chunk)."""

    data: CalibrationData
    used: list[int]
    dropped: list[tuple[int, str]]
    kappa_samples: NDArray[np.int64]
    camera_frames: NDArray[np.int64]
    complete: bool
    metadata: dict[str, str] = field(default_factory=dict)


def read_mcap(path: Path) -> McapCalibration:
    """Reads a calibration log written by ``collect(..., mcap=path)``: the means of every finished
    dwell, as the collector computed them (its ``dwell`` messages, with their index and window), read
    by the Rust reader (:func:`rss6.logs.read_log`).

    A truncated file (no MCAP footer, e.g. the collecting process was killed; ``.complete`` False) is
    read up to its last whole chunk: it holds every dwell finished before the cut. Configurations the
    log lacks (the metadata's ``configurations`` against the dwells present) and those with a defect
    (no camera frame, non-finite values) are left out and listed in ``.dropped`` as
    ``(index, reason)``. Raises :class:`rss6.LogError` for an unreadable file or one without
    calibration data (:class:`rss6.CorruptLogError` if it is not MCAP or damaged) and
    :class:`rss6.CalibrationError` if no configuration is usable."""
    log = logs.read_log(path)
    md = log.metadata if any(name == "rss6" for name, _ in log.records) else None
    count = None
    if md is not None:
        if md.get("kind") != MCAP_KIND:
            raise LogError(
                f"{path}: not a calibration log written by collect() (metadata kind "
                f"{md.get('kind')!r}, expected {MCAP_KIND!r})"
            )
        try:
            count = int(md["configurations"])
        except (KeyError, ValueError) as e:
            raise LogError(f"{path}: bad calibration metadata: {e}") from e
    elif not log.dwells:
        raise LogError(f"{path}: no calibration data (empty, corrupt or not written by collect())")
    cut = "" if log.complete else " (the file is truncated)"
    dwells = sorted(log.dwells, key=lambda d: int(d["index"]))
    seen = {int(d["index"]) for d in dwells}
    dropped = [(int(d["index"]), str(d["defect"])) for d in dwells if d["defect"] is not None]
    rows = [d for d in dwells if d["defect"] is None]
    total = count if count is not None else max(seen, default=-1) + 1
    dropped += [
        (k, "not finished: the collection stopped before the end of its dwell" + cut)
        for k in range(total)
        if k not in seen
    ]
    if not rows:
        reasons = "; ".join(f"{k}: {r}" for k, r in sorted(dropped))
        raise CalibrationError(f"no usable configuration in the log ({reasons})")
    kappa_samples = np.array([d["kappa_samples"] for d in rows], dtype=np.int64)
    camera_frames = np.array([d["camera_frames"] for d in rows], dtype=np.int64)
    data = CalibrationData.from_arrays(
        np.array([d["kappa"] for d in rows]),
        np.array([d["sensor_pose"] for d in rows]),
        np.array([d["theta_cmd"] for d in rows]),
        kappa_samples=kappa_samples.tolist(),
        camera_frames=camera_frames.tolist(),
        sensor_pose_cov=np.array(
            [
                np.full((6, 6), np.nan)
                if d.get("sensor_pose_cov") is None
                else d["sensor_pose_cov"]
                for d in rows
            ]
        ),
    )
    return McapCalibration(
        data=data,
        used=[int(d["index"]) for d in rows],
        dropped=sorted(dropped),
        kappa_samples=kappa_samples,
        camera_frames=camera_frames,
        complete=log.complete,
        metadata=dict(md or {}),
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
    noise: Any = "table",
) -> CalibrationResult:
    """RPBA (eq. 4.16–4.21): 60 kinematic + 6 external (ᴱχ_t) parameters from ``data``, starting at
    ``kp`` and ``target_guess`` (default: the design target of :func:`default_placement`).
    Levenberg–Marquardt with analytic Jacobians; ``progress(iteration, cost)`` per iteration.

    ``noise``: the camera's noise the residuals are whitened by — ``"table"`` (Table 4.1,
    independent components), ``"dwells"`` (the covariance of one frame pooled from the dwells' own
    scatter, ``data.sensor_pose_cov``: the stereo head's correlated components as measured; raises
    :class:`rss6.InvalidInputError` if no dwell recorded it) or a (6, 6) covariance of one frame's
    ᶜχ_t (m², m·rad, rad²)."""
    guess = default_placement()[1] if target_guess is None else target_guess
    return _rss6.rpba(
        data,
        kp,
        max_iterations=max_iterations,
        target_guess=guess,
        progress=progress,
        noise=noise,
    )


def implicit(
    data: CalibrationData,
    kp: KinematicParams,
    sensor_pose_guess: Any,
    *,
    target_guess: Any = None,
    max_iterations: int = 60,
    noise: Any = "table",
) -> CalibrationResult:
    """Implicit calibration (eq. 4.10–4.15): 60 kinematic + 12 external parameters (ᴼχ_C, ᴱχ_t) from
    ``data``, starting at ``kp``, the rough sensor pose ``sensor_pose_guess`` and ``target_guess``
    (default: the design target of :func:`default_placement`). ``noise`` as in :func:`rpba`."""
    guess = default_placement()[1] if target_guess is None else target_guess
    return _rss6.implicit(
        data,
        kp,
        sensor_pose_guess,
        max_iterations=max_iterations,
        target_guess=guess,
        noise=noise,
    )
