"""Visual servoing on a simulated robot (thesis §6.5): Experiments 1 and 2 with DSMC, KCSC and KJSC.

The closed loop (Kalman filter + controller at the camera rate, converter and command guard at 1 kHz,
the plant's drive PID) and its optional MCAP log run entirely in Rust (rss6-exp's servo runner, through
:func:`rss6._rss6.run_servo`); this module names the pieces, tabulates Python reference functions and
computes the Table 6.1/6.2 statistics.

>>> import rss6
>>> plant = rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal(), seed=1)
>>> res = rss6.servo.track(plant, controller="dsmc", trajectory="exp1", duration=2.0)
>>> res.rmse.shape, bool(res.rmse[0] < 5e-3)
((6,), True)
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Union

import numpy as np
from numpy.typing import NDArray

from rss6 import _rss6
from rss6 import thesis as _thesis
from rss6.errors import InvalidInputError, NonFiniteError, Rss6Error, ShapeError
from rss6.logs import write_run

__all__ = [
    "AXES",
    "THESIS_TABLES",
    "TrackingResult",
    "filter_statistics",
    "named_trajectory",
    "track",
]

F64 = NDArray[np.float64]
TrajectoryLike = Union[str, "_rss6.Trajectory", Callable[[float], Any]]

#: Axis names of a pose χ.
AXES = ("x", "y", "z", "alpha", "beta", "gamma")

#: Thesis Tables 6.1 (Experiment 1) and 6.2 (Experiment 2): {"exp1"|"exp2": {"rmse"|"mae":
#: {"KJSC"|"KCSC"|"DSMC": [x, y, z (mm), α, β, γ (1e-3 rad)]}}}.
THESIS_TABLES: dict[str, dict[str, dict[str, list[float]]]] = {
    "exp1": _thesis.TABLE_6_1,
    "exp2": _thesis.TABLE_6_2,
}


def named_trajectory(name: str) -> _rss6.Trajectory:
    """The reference of Experiment 1 ("exp1", sinusoid with an initial step, 0.5 rad/s) or
    Experiment 2 ("exp2", finite Fourier series, n = 5, ω0 = 0.15 rad/s)."""
    if name == "exp1":
        return _rss6.Trajectory.experiment1()
    if name == "exp2":
        return _rss6.Trajectory.experiment2()
    raise InvalidInputError(
        f"trajectory must be 'exp1', 'exp2', an rss6.Trajectory or a callable, got {name!r}"
    )


@dataclass
class TrackingResult:
    """One closed-loop run. Arrays are float64; poses are [x, y, z, α, β, γ] (m, rad).

    Per plant tick (1 kHz): ``time`` (N,), ``desired`` (N, 6), ``true`` (N, 6) true pose (both at
    the start of the tick), ``theta_cmd`` (N, 6) the joint commands sent to the drive, in the drive's
    joint convention (nominal η, Δθ; KJSC's model-convention commands converted), ``torque`` (N, 6)
    drive torques.
    Per camera frame: ``frame_time`` (M,), ``frame_desired``, ``measured`` (camera pose in the base
    frame), ``frame_true``, ``estimate`` (Kalman χ_m), ``estimate_dot``, ``sliding`` (DSMC's F).
    ``rmse``/``mae`` (6,) compare desired and measured poses at the frames, as the thesis's Tables
    6.1/6.2 do (the C-Track measured the pose); ``rmse_true``/``mae_true`` use the true pose.
    """

    controller: str
    trajectory: str
    time: F64
    desired: F64
    true: F64
    theta_cmd: F64
    torque: F64
    frame_time: F64
    frame_desired: F64
    measured: F64
    frame_true: F64
    estimate: F64
    estimate_dot: F64
    sliding: F64
    fault: tuple[float, str] | None = None
    log_path: str | None = None
    rmse: F64 = field(init=False)
    mae: F64 = field(init=False)
    rmse_true: F64 = field(init=False)
    mae_true: F64 = field(init=False)

    def __post_init__(self) -> None:
        e = self.frame_desired - self.measured
        et = self.frame_desired - self.frame_true
        if len(e) == 0:
            nan = np.full(6, np.nan)
            self.rmse, self.mae, self.rmse_true, self.mae_true = nan, nan, nan.copy(), nan.copy()
            return
        self.rmse = np.sqrt(np.mean(e**2, axis=0))
        self.mae = np.mean(np.abs(e), axis=0)
        self.rmse_true = np.sqrt(np.mean(et**2, axis=0))
        self.mae_true = np.mean(np.abs(et), axis=0)

    @property
    def errors(self) -> F64:
        """Tracking errors χ_d − χ_measured at the camera frames (M, 6)."""
        return self.frame_desired - self.measured

    def table(self) -> dict[str, list[float]]:
        """RMSE and MAE in the thesis's table units: mm for x, y, z and 1e-3 rad for α, β, γ."""
        return {"rmse": (self.rmse * 1e3).tolist(), "mae": (self.mae * 1e3).tolist()}

    def write_mcap(self, path: str | PathLike[str]) -> None:
        """Writes the run to an MCAP file (see :mod:`rss6.logs`)."""
        write_run(
            path,
            {
                "true_pose": (self.time, self.true),
                "desired_pose": (self.time, self.desired),
                "camera_pose": (self.frame_time, self.measured),
                "estimate_pose": (self.frame_time, self.estimate),
                "theta_cmd": (self.time, self.theta_cmd),
                "torque": (self.time, self.torque),
            },
            metadata={"controller": self.controller, "trajectory": self.trajectory},
        )
        self.log_path = str(path)


def filter_statistics(result: TrackingResult, after: float = 2.0) -> tuple[F64, F64]:
    """How well the servo's Kalman filter did in a simulated run (the true pose is known).

    Returns ``(noise_ratio, rate_ratio)``, each (6,) per pose axis: the standard deviation of
    (estimate − true pose) over that of (camera pose − true pose) at the camera frames (< 1: the filter
    lowers the pose noise; the mean is removed so that a constant offset of the camera pose, e.g. from
    estimated external parameters, does not count as noise), and the RMS of (χ̇ estimate − true χ̇)
    over the RMS of the true χ̇ at the frames after ``after`` seconds (the initial step excluded; true
    χ̇ by central differences of the 1 kHz true pose).
    """
    if len(result.frame_time) < 3 or not np.any(result.frame_time > after):
        raise InvalidInputError(f"need camera frames after {after} s to compare rates")
    rate = np.gradient(result.true, result.time, axis=0)
    idx = np.clip(np.searchsorted(result.time, result.frame_time - 1e-9), 0, len(result.time) - 1)
    true_rate = rate[idx]
    late = result.frame_time > after

    def rms(a: F64) -> F64:
        return np.asarray(np.sqrt((a**2).mean(0)), dtype=np.float64)

    est, cam = result.estimate - result.frame_true, result.measured - result.frame_true
    noise = rms(est - est.mean(0)) / rms(cam - cam.mean(0))
    vel = rms((result.estimate_dot - true_rate)[late]) / rms(true_rate[late])
    return noise, vel


def _tabulate(fn: Callable[[float], Any], dt: float, duration: float) -> tuple[F64, F64, F64]:
    n = round(duration / dt) + 1
    p, v, a = np.empty((n, 6)), np.empty((n, 6)), np.empty((n, 6))
    for k in range(n):
        out = fn(k * dt)
        if not (isinstance(out, tuple) and len(out) == 3):
            raise InvalidInputError("a trajectory callable must return (pose, pose_dot, pose_ddot)")
        for arr, val, name in (
            (p, out[0], "pose"),
            (v, out[1], "pose_dot"),
            (a, out[2], "pose_ddot"),
        ):
            x = np.asarray(val, dtype=np.float64)
            if x.shape != (6,):
                raise ShapeError(
                    f"trajectory {name} at t = {k * dt:.3f} s must have shape (6,), got {x.shape}"
                )
            if not np.all(np.isfinite(x)):
                raise NonFiniteError(
                    f"trajectory {name} at t = {k * dt:.3f} s contains NaN or infinity"
                )
            arr[k] = x
    return p, v, a


def _check_reach(traj: Any, kp: _rss6.KinematicParams, duration: float) -> None:
    """Raises :class:`rss6.UnreachableError` (or the IK's other error) naming the first time, on a
    100 Hz sampling, at which the desired pose is out of the controller model's reach. Without it
    the task-space controllers (DSMC, KCSC) ran on with the robot pressed against its limit and
    returned a "finished" run; KJSC faulted."""
    ts = np.arange(0.0, duration + 1e-9, 0.01)
    poses = traj[0][:: max(1, round(0.01 / traj[3]))] if isinstance(traj, tuple) else None
    if poses is None:
        poses = np.asarray(traj.sample_many(ts)[0])
    for k, pose in enumerate(poses):
        try:
            _rss6.ik(kp, pose)
        except Rss6Error as e:
            # The same error, its attributes (e.g. the leg) kept, saying when.
            e.args = (f"the trajectory's pose at t = {k * 0.01:.2f} s is out of reach: {e}",)
            raise


def track(
    plant: Any,
    controller: str = "dsmc",
    trajectory: TrajectoryLike = "exp1",
    kp_model: _rss6.KinematicParams | None = None,
    dp_model: _rss6.DynamicParams | None = None,
    duration: float = 20.0,
    *,
    sensor_in_base: Any = None,
    target_in_effector: Any = None,
    pid: tuple[float, float, float] | None = None,
    reset: bool = True,
    mcap: str | PathLike[str] | None = None,
    progress: Callable[[float, float], Any] | None = None,
    tuning: str = "tuned",
) -> TrackingResult:
    """Runs one servo experiment on ``plant`` (:class:`rss6.Plant` or :class:`rss6.ModelSim`).

    ``controller``: "dsmc" (eq. 6.25 + converter), "kcsc" (eq. 6.40) or "kjsc" (eq. 6.42).
    ``trajectory``: "exp1", "exp2", an :class:`rss6.Trajectory`, or a callable ``t -> (χ_d, χ̇_d,
    χ̈_d)`` (tabulated every plant tick). ``kp_model``/``dp_model``: the controller's model (default
    nominal kinematics and Table 5.1 dynamics; pass calibrated kinematics). ``sensor_in_base`` (ᴼχ_C)
    and ``target_in_effector`` (ᴱχ_t) turn camera frames into end-effector poses (default: the plant's
    truth, i.e. a perfectly known camera placement). ``reset`` puts the plant at home first (thesis
    §6.5.1). ``mcap``: log the run there as it goes (the Rust writer, :mod:`rss6.logs`) — every
    simulated second the new samples are flushed to the OS (before ``progress`` is called), so a run
    killed mid-way leaves a log readable up to its last whole second (:func:`rss6.logs.read_log`);
    metadata: controller, tuning, trajectory, duration, then ``status`` ("finished", or "failed: …"
    if the run raised) and ``fault``. ``progress(t, duration)`` (s) is called every simulated second;
    if it raises (KeyboardInterrupt included) the run stops and the exception reaches the caller, and
    Ctrl-C stops a run at the same points.
    ``tuning``: "tuned" (the default: the thesis's Kalman filter, rss6's tuned DSMC gains — the
    thesis gives none in SI for this robot — and the thesis's KCSC/KJSC gains) or "low_noise"
    (DSMC only: rss6-ctrl's ``ServoConfig::low_noise`` + ``DsmcGains::low_noise`` — hold compensation
    between frames, potentiometer rates in the filter, a smoother filter; its estimate tracks all six
    pose rates, see docs/control.md).
    """
    if not (np.isfinite(duration) and duration > 0):
        raise InvalidInputError(f"duration must be finite and > 0 s, got {duration}")
    kp = kp_model if kp_model is not None else _rss6.KinematicParams.nominal()
    dp = dp_model if dp_model is not None else _rss6.DynamicParams.nominal()
    if reset:
        plant.reset(_rss6.home_pose())
    if isinstance(trajectory, str):
        traj: Any = named_trajectory(trajectory)
        name = trajectory
    elif isinstance(trajectory, _rss6.Trajectory):
        traj, name = trajectory, trajectory.name
    elif callable(trajectory):
        traj, name = (
            _tabulate(trajectory, float(plant.dt), duration),
            getattr(trajectory, "__name__", "callable"),
        )
    else:
        raise InvalidInputError(
            "trajectory must be 'exp1', 'exp2', an rss6.Trajectory or a callable"
        )
    _check_reach((*traj, float(plant.dt)) if isinstance(traj, tuple) else traj, kp, duration)

    def on_segment(seg: dict[str, Any]) -> None:
        if progress is not None and len(seg["t"]):
            progress(float(seg["t"][-1]), float(duration))

    d = _rss6.run_servo(
        plant,
        controller,
        traj,
        duration,
        kp,
        dp,
        sensor_in_base=sensor_in_base,
        target_in_effector=target_in_effector,
        pid=pid,
        on_segment=on_segment if progress is not None else None,
        tuning=tuning,
        mcap=None if mcap is None else os.fspath(mcap),
        trajectory_name=name,
    )
    res = TrackingResult(
        controller=str(d["controller"]),
        trajectory=name,
        time=d["t"],
        desired=d["desired"],
        true=d["true"],
        theta_cmd=d["theta_cmd"],
        torque=d["torque"],
        frame_time=d["frame_t"],
        frame_desired=d["frame_desired"],
        measured=d["measured"],
        frame_true=d["frame_true"],
        estimate=d["estimate"],
        estimate_dot=d["estimate_dot"],
        sliding=d["sliding"],
        fault=d["fault"],
    )
    if mcap is not None:
        res.log_path = str(mcap)
    return res
