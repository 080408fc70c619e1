# Type stubs of the compiled module rss6._rss6 (checked by `python -m mypy.stubtest rss6._rss6`).

from collections.abc import Callable
from os import PathLike
from typing import Any, Literal, final

import numpy as np
from numpy.typing import ArrayLike, NDArray
from typing_extensions import Self, TypeAlias

__all__ = [
    "SETTLE_STEPS",
    "CalibrationData",
    "CalibrationResult",
    "Dsmc",
    "DynamicParams",
    "ExcitationProblem",
    "KalmanFilter",
    "Kcsc",
    "KinematicParams",
    "Kjsc",
    "LogWriter",
    "ModelSim",
    "Plant",
    "TorqueToPosition",
    "Trajectory",
    "calibration_study",
    "cloe_identify",
    "cloe_parameter_names",
    "cloe_psi",
    "collect",
    "compose_poses",
    "coriolis",
    "dynamics_terms",
    "excitation_at",
    "fk",
    "fk_batch",
    "forward_dynamics",
    "friction",
    "gravity",
    "home_pose",
    "identification_run",
    "ik",
    "ik_batch",
    "implicit",
    "inverse_dynamics",
    "invert_pose",
    "jacobian_ad",
    "jacobian_theta",
    "loop_observability",
    "mass_matrix",
    "mean_pose",
    "read_log",
    "regressor",
    "relative_pose_errors_raw",
    "rk4_step",
    "rpba",
    "run_servo",
    "select_configurations",
    "simulate_identification",
    "stroke",
    "table_5_2_truth_params",
    "thesis_tables",
]

SETTLE_STEPS: int

_F64: TypeAlias = NDArray[np.float64]
_Path: TypeAlias = str | PathLike[str]
_FkMethod: TypeAlias = Literal["quasi_stewart", "theta_newton"]

@final
class KinematicParams:
    def __new__(
        cls,
        base_joints: ArrayLike,
        platform_joints: ArrayLike,
        wrench_lengths: ArrayLike,
        link_lengths: ArrayLike,
        theta0: ArrayLike,
        eta: ArrayLike,
        dtheta: ArrayLike,
    ) -> KinematicParams: ...
    @staticmethod
    def nominal() -> KinematicParams: ...
    @staticmethod
    def perturbed(b: ArrayLike) -> KinematicParams: ...
    def with_errors(self, b: ArrayLike) -> KinematicParams: ...
    def errors_from(self, reference: KinematicParams) -> _F64: ...
    def validate(self) -> None: ...
    def theta_from_reading(self, kappa: ArrayLike) -> _F64: ...
    def reading_from_theta(self, theta: ArrayLike) -> _F64: ...
    @property
    def base_joints(self) -> _F64: ...
    @property
    def platform_joints(self) -> _F64: ...
    @property
    def wrench_lengths(self) -> _F64: ...
    @property
    def link_lengths(self) -> _F64: ...
    @property
    def theta0(self) -> _F64: ...
    @property
    def eta(self) -> _F64: ...
    @property
    def dtheta(self) -> _F64: ...
    def to_dict(self) -> dict[str, _F64]: ...
    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> KinematicParams: ...
    def to_toml(self, path: _Path) -> None: ...
    @classmethod
    def load(cls, path: _Path) -> KinematicParams: ...
    def __eq__(self, value: object, /) -> bool: ...

@final
class DynamicParams:
    @staticmethod
    def nominal() -> DynamicParams: ...
    @staticmethod
    def from_vector(x: ArrayLike) -> DynamicParams: ...
    def to_vector(self) -> _F64: ...
    def validate(self) -> None: ...
    @property
    def coulomb(self) -> _F64: ...
    @property
    def viscous(self) -> _F64: ...
    def to_dict(self) -> dict[str, Any]: ...
    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> DynamicParams: ...
    def to_toml(self, path: _Path) -> None: ...
    @classmethod
    def load(cls, path: _Path) -> DynamicParams: ...
    def __eq__(self, value: object, /) -> bool: ...

def home_pose() -> _F64: ...
def ik(kp: KinematicParams, pose: ArrayLike) -> _F64: ...
def ik_batch(kp: KinematicParams, poses: ArrayLike) -> _F64: ...
def fk(
    kp: KinematicParams,
    theta: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    max_iterations: int = 30,
    tol: float = 1e-13,
    method: _FkMethod = "quasi_stewart",
) -> _F64: ...
def fk_batch(
    kp: KinematicParams,
    thetas: ArrayLike,
    guess: ArrayLike | None = None,
    *,
    max_iterations: int = 30,
    tol: float = 1e-13,
    method: _FkMethod = "quasi_stewart",
) -> _F64: ...
def jacobian_theta(kp: KinematicParams, pose: ArrayLike) -> _F64: ...
def jacobian_ad(kp: KinematicParams, pose: ArrayLike) -> _F64: ...

_Triple: TypeAlias = tuple[_F64, _F64, _F64]

# --- dynamics ---------------------------------------------------------------------------------
def mass_matrix(kp: KinematicParams, dp: DynamicParams, pose: ArrayLike) -> _F64: ...
def coriolis(
    kp: KinematicParams, dp: DynamicParams, pose: ArrayLike, pose_dot: ArrayLike
) -> _F64: ...
def gravity(
    kp: KinematicParams, dp: DynamicParams, pose: ArrayLike, *, g: ArrayLike | None = None
) -> _F64: ...
def friction(
    kp: KinematicParams, dp: DynamicParams, pose: ArrayLike, pose_dot: ArrayLike
) -> _F64: ...
def inverse_dynamics(
    kp: KinematicParams,
    dp: DynamicParams,
    pose: ArrayLike,
    pose_dot: ArrayLike,
    pose_ddot: ArrayLike,
    *,
    g: ArrayLike | None = None,
) -> _F64: ...
def forward_dynamics(
    kp: KinematicParams,
    dp: DynamicParams,
    pose: ArrayLike,
    pose_dot: ArrayLike,
    tau_a: ArrayLike,
    *,
    g: ArrayLike | None = None,
) -> _F64: ...
def regressor(
    kp: KinematicParams,
    pose: ArrayLike,
    pose_dot: ArrayLike,
    pose_ddot: ArrayLike,
    *,
    g: ArrayLike | None = None,
) -> _F64: ...
def dynamics_terms(
    kp: KinematicParams, dp: DynamicParams, pose: ArrayLike, pose_dot: ArrayLike
) -> dict[str, _F64]: ...
def rk4_step(
    kp: KinematicParams,
    dp: DynamicParams,
    pose: ArrayLike,
    pose_dot: ArrayLike,
    tau_a: ArrayLike,
    dt: float,
    *,
    g: ArrayLike | None = None,
) -> tuple[_F64, _F64]: ...
def compose_poses(a: ArrayLike, b: ArrayLike) -> _F64: ...
def invert_pose(a: ArrayLike) -> _F64: ...

# --- control ----------------------------------------------------------------------------------
@final
class Trajectory:
    @staticmethod
    def experiment1() -> Trajectory: ...
    @staticmethod
    def experiment2() -> Trajectory: ...
    @staticmethod
    def sinusoid(
        center: ArrayLike, amplitude: ArrayLike, phase: ArrayLike, omega: float
    ) -> Trajectory: ...
    @staticmethod
    def fourier(s: ArrayLike, c: ArrayLike, offset: ArrayLike, omega0: float) -> Trajectory: ...
    def sample(self, t: float) -> _Triple: ...
    def sample_many(self, times: ArrayLike) -> _Triple: ...
    @property
    def name(self) -> str: ...

@final
class KalmanFilter:
    def __new__(
        cls,
        initial_pose: ArrayLike,
        *,
        r: ArrayLike | None = None,
        q_jerk: ArrayLike | None = None,
        q_vel: ArrayLike | None = None,
        nominal_dt: float = 0.033,
        steady_state: bool = False,
    ) -> KalmanFilter: ...
    def step(self, dt: float, measurement: ArrayLike | None = None) -> _Triple: ...
    def estimate(self) -> _Triple: ...
    def reset(self, pose: ArrayLike) -> None: ...
    def pose_variance(self) -> _F64: ...

@final
class Dsmc:
    def __new__(
        cls,
        kp_model: KinematicParams,
        dp_model: DynamicParams,
        *,
        lambda_: ArrayLike | None = None,
        kp: ArrayLike | None = None,
        ki: ArrayLike | None = None,
        kr: ArrayLike | None = None,
        epsilon: ArrayLike | None = None,
        integral_limit: ArrayLike | None = None,
    ) -> Dsmc: ...
    def step(
        self, reference: tuple[ArrayLike, ...], estimate: tuple[ArrayLike, ...], dt: float
    ) -> dict[str, Any]: ...
    @property
    def fault(self) -> str | None: ...
    def integral(self) -> _F64: ...
    def reset(self) -> None: ...

@final
class Kcsc:
    def __new__(
        cls,
        kp_model: KinematicParams,
        *,
        bias: ArrayLike | None = None,
        kp: ArrayLike | None = None,
        ki: ArrayLike | None = None,
        kd: ArrayLike | None = None,
    ) -> Kcsc: ...
    def step(
        self, reference: tuple[ArrayLike, ...], estimate: tuple[ArrayLike, ...], dt: float
    ) -> _F64: ...
    @property
    def fault(self) -> str | None: ...
    def reset(self) -> None: ...

@final
class Kjsc:
    def __new__(
        cls,
        kp_model: KinematicParams,
        *,
        bias: ArrayLike | None = None,
        kp: float | None = None,
        ki: float | None = None,
        kd: float | None = None,
    ) -> Kjsc: ...
    def step(self, reference: tuple[ArrayLike, ...], theta: ArrayLike, dt: float) -> _F64: ...
    @property
    def fault(self) -> str | None: ...
    def reset(self) -> None: ...

@final
class TorqueToPosition:
    def __new__(
        cls,
        *,
        pid: tuple[float, float, float] = ...,
        dt: float = 1e-3,
        torque_limit: float = 30.0,
        stroke: tuple[float, float] | None = None,
        max_rate: float = 3.0,
        initial_command: ArrayLike | None = None,
    ) -> TorqueToPosition: ...
    def step(self, tau_a: ArrayLike, theta: ArrayLike) -> dict[str, Any]: ...
    def reset(self) -> None: ...

# --- simulation -------------------------------------------------------------------------------
class _SimBase:
    def __new__(
        cls,
        kp: KinematicParams,
        dp: DynamicParams,
        *,
        pid: tuple[float, float, float] = ...,
        effects: dict[str, dict[str, float]] | list[tuple[str, dict[str, float]]] | None = None,
        seed: int = 0,
        dt: float = 1e-3,
        sensor_in_base: ArrayLike | None = None,
        target_in_effector: ArrayLike | None = None,
        torque_limit: float = 30.0,
        camera_latency: float = 0.0,
        solver_iterations: int | None = None,
        potentiometer_noise: float | None = None,
        pixel_noise: float | None = None,
        drive_derivative_filter: float = 0.0,
        friction_smoothing: float = 0.0,
        implicit_friction: bool = False,
        velocity_projection: bool = False,
    ) -> Self: ...
    def reset(self, pose: ArrayLike) -> None: ...
    def step_joint_command(self, theta_cmd: ArrayLike) -> None: ...
    def step_joint_commands(self, commands: ArrayLike) -> dict[str, _F64]: ...
    def true_pose(self) -> _F64: ...
    def true_theta(self) -> _F64: ...
    def loop_closure_error(self) -> float: ...
    def solver_gap(self) -> float: ...
    def inexact_friction_steps(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def dt(self) -> float: ...
    def camera(self) -> _F64 | None: ...
    def potentiometers(self) -> _F64: ...
    def torque(self) -> _F64: ...
    def truth(self) -> dict[str, Any]: ...

@final
class Plant(_SimBase): ...

@final
class ModelSim(_SimBase): ...

def run_servo(
    plant: Plant | ModelSim,
    controller: str,
    trajectory: Trajectory | tuple[ArrayLike, ArrayLike, ArrayLike],
    duration: float,
    kp_model: KinematicParams,
    dp_model: DynamicParams,
    *,
    sensor_in_base: ArrayLike | None = None,
    target_in_effector: ArrayLike | None = None,
    pid: tuple[float, float, float] | None = None,
    torque_limit: float | None = None,
    steady_state_kalman: bool | None = None,
    kalman_r: ArrayLike | None = None,
    kalman_q_jerk: ArrayLike | None = None,
    camera_latency: float | None = None,
    on_segment: Callable[[dict[str, Any]], object] | None = None,
    segment: float = 1.0,
    tuning: str = "tuned",
    mcap: _Path | None = None,
    trajectory_name: str | None = None,
) -> dict[str, Any]: ...

# --- logs -------------------------------------------------------------------------------------
@final
class LogWriter:
    def __new__(
        cls, path: _Path, *, chunk_size: int | None = None, t0: float = 0.0
    ) -> LogWriter: ...
    def write(self, name: str, t: ArrayLike, values: ArrayLike) -> None: ...
    def write_streams(self, streams: dict[str, tuple[ArrayLike, ArrayLike]]) -> None: ...
    def write_dwell(
        self,
        index: int,
        window: tuple[float, float],
        theta_cmd: ArrayLike,
        kappa: ArrayLike,
        sensor_pose: ArrayLike | None,
        kappa_samples: int,
        camera_frames: int,
    ) -> None: ...
    def add_metadata(self, pairs: dict[str, str], name: str = "rss6") -> None: ...
    def flush(self, sync: bool = False) -> None: ...
    def finish(self, status: str | None = None) -> None: ...
    @property
    def messages(self) -> int: ...
    @property
    def finished(self) -> bool: ...
    @property
    def path(self) -> str: ...

def read_log(path: _Path) -> dict[str, Any]: ...
def mean_pose(poses: ArrayLike) -> _F64: ...

# --- calibration ------------------------------------------------------------------------------
@final
class CalibrationData:
    @staticmethod
    def from_arrays(
        kappa: ArrayLike,
        sensor_pose: ArrayLike,
        theta_cmd: ArrayLike | None = None,
        *,
        kappa_samples: list[int] | ArrayLike | None = None,
        camera_frames: list[int] | ArrayLike | None = None,
        sensor_pose_cov: ArrayLike | None = None,
    ) -> CalibrationData: ...
    def __len__(self) -> int: ...
    @property
    def kappa(self) -> _F64: ...
    @property
    def sensor_pose(self) -> _F64: ...
    @property
    def theta_cmd(self) -> _F64: ...
    @property
    def sensor_pose_cov(self) -> _F64: ...
    @property
    def camera_frames(self) -> _F64: ...

@final
class CalibrationResult:
    @property
    def method(self) -> str: ...
    @property
    def params(self) -> KinematicParams: ...
    @property
    def errors(self) -> _F64: ...
    @property
    def target_in_effector(self) -> _F64: ...
    @property
    def sensor_in_base(self) -> _F64 | None: ...
    @property
    def cost_history(self) -> _F64: ...
    @property
    def rank(self) -> int: ...
    @property
    def parameter_count(self) -> int: ...
    @property
    def unidentifiable(self) -> list[str]: ...
    @property
    def gauge_directions(self) -> list[str]: ...
    @property
    def singular_values(self) -> _F64: ...
    @property
    def iterations(self) -> int: ...
    @property
    def dropped(self) -> list[tuple[int, str]]: ...
    @property
    def used(self) -> list[int]: ...
    @property
    def rejected(self) -> list[tuple[int, float]]: ...
    @property
    def normalized_residuals(self) -> list[tuple[int, float]]: ...
    @property
    def fit_statistic(self) -> float: ...
    @property
    def degrees_of_freedom(self) -> int: ...
    @property
    def convergence(self) -> str: ...

def stroke(kp: KinematicParams) -> tuple[float, float]: ...
def select_configurations(
    kp: KinematicParams,
    method: str = "rpba",
    seed: int = 0,
    *,
    start: int = 13,
    candidates: int = 5000,
    stroke: tuple[float, float] | None = None,
) -> _F64: ...
def collect(
    plant: Plant | ModelSim,
    thetas: ArrayLike,
    dwell: float = 2.0,
    *,
    move_time: float = 1.0,
    settle_time: float = 0.5,
    kappa_rate: float = 500.0,
    progress: Callable[[int, int], Any] | None = None,
    mcap: _Path | None = None,
) -> CalibrationData: ...
def rpba(
    data: CalibrationData,
    kp: KinematicParams,
    *,
    max_iterations: int = 60,
    target_guess: ArrayLike | None = None,
    progress: Callable[[int, float], Any] | None = None,
    noise: str | ArrayLike | None = None,
) -> CalibrationResult: ...
def implicit(
    data: CalibrationData,
    kp: KinematicParams,
    sensor_pose_guess: ArrayLike,
    *,
    max_iterations: int = 60,
    target_guess: ArrayLike | None = None,
    noise: str | ArrayLike | None = None,
) -> CalibrationResult: ...
def relative_pose_errors_raw(
    params: KinematicParams,
    target_in_effector: ArrayLike,
    true_kp: KinematicParams,
    true_sensor_in_base: ArrayLike,
    true_target_in_effector: ArrayLike,
    *,
    n: int = 100,
    seed: int = 0,
    stroke: tuple[float, float] | None = None,
) -> dict[str, Any]: ...
def calibration_study(
    rpba_thetas: ArrayLike,
    implicit_thetas: ArrayLike,
    *,
    robots: int = 20,
    seed: int = 0,
    dwell: float = 2.0,
    test_configurations: int = 100,
    stroke: tuple[float, float] | None = None,
    plant: bool = False,
    noise: str | ArrayLike | None = None,
) -> list[dict[str, Any]]: ...

@final
class ExcitationProblem:
    def __new__(
        cls,
        kp: KinematicParams,
        *,
        harmonics: int = 5,
        f0: float = 0.1,
        start: ArrayLike | None = None,
        stroke: tuple[float, float] | None = None,
        stroke_margin: float = 0.15,
        max_joint_rate: float = 1.5,
        samples: int = 200,
        rank_threshold: float = 1e-8,
    ) -> ExcitationProblem: ...
    @property
    def dimension(self) -> int: ...
    @property
    def columns(self) -> list[int]: ...
    @property
    def start(self) -> _F64: ...
    def objectives(self, population: ArrayLike) -> _F64: ...
    def coefficients(self, free: ArrayLike) -> _F64: ...
    def check(self, coefficients: ArrayLike) -> tuple[str, float, float] | None: ...
    def observability(self, coefficients: ArrayLike) -> tuple[float, float]: ...

def excitation_at(f0: float, coefficients: ArrayLike, t: float) -> tuple[_F64, _F64, _F64]: ...
def identification_run(
    robot: Any,
    f0: float,
    coefficients: ArrayLike,
    duration: float,
    kp_model: KinematicParams,
    sensor_in_base: ArrayLike,
    target_in_effector: ArrayLike,
    *,
    segment: float = 1.0,
    progress: Callable[[float, float], Any] | None = None,
    mcap: _Path | None = None,
    commands: ArrayLike | None = None,
    outer_gains: tuple[float, float, float] | None = None,
) -> dict[str, Any]: ...
def simulate_identification(
    kp: KinematicParams,
    dp: DynamicParams,
    pid: tuple[float, float, float],
    f0: float,
    coefficients: ArrayLike,
    *,
    start: ArrayLike,
    duration: float,
    torque_limit: float = 30.0,
    camera_latency: float = 0.0,
    dt: float = 1e-3,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    commands: ArrayLike | None = None,
    gravity: ArrayLike | None = None,
    load: tuple[float, ArrayLike, ArrayLike] | None = None,
    offset_drift: ArrayLike | None = None,
    outer_gains: tuple[float, float, float] | None = None,
    pot_dither: ArrayLike | None = None,
) -> tuple[_F64, _F64, int, _F64]: ...
def cloe_identify(
    t: ArrayLike,
    measured: ArrayLike,
    f0: float,
    coefficients: ArrayLike,
    kp: KinematicParams,
    dp_guess: DynamicParams,
    pid_guess: tuple[float, float, float],
    *,
    start: ArrayLike,
    duration: float,
    parameters: list[str] | None = None,
    hold: list[str] | None = None,
    max_iterations: int = 20,
    torque_limit: float = 30.0,
    camera_latency: float = 0.0,
    dt: float = 1e-3,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    commands: ArrayLike | None = None,
    noise: tuple[float, float] | None = None,
    per_tick_jacobians: bool = False,
    tol_cost: float = 1e-6,
    tol_step: float = 1e-5,
    identifiability_threshold: float = 1e-3,
    poor_std: float = 0.1,
    prior_log_std: float = 1.0,
    progress: Callable[[int, float], Any] | None = None,
    gravity: ArrayLike | None = None,
    load: tuple[float, ArrayLike, ArrayLike] | None = None,
    offset_drift: ArrayLike | None = None,
    outer_gains: tuple[float, float, float] | None = None,
    pot_dither: ArrayLike | None = None,
    settle_steps: int = ...,
    initial: tuple[DynamicParams, tuple[float, float, float]] | None = None,
    noise_covariance: ArrayLike | None = None,
) -> dict[str, Any]: ...
def cloe_parameter_names() -> list[str]: ...
def table_5_2_truth_params() -> tuple[DynamicParams, tuple[float, float, float]]: ...
def cloe_psi(
    dp: DynamicParams, pid: tuple[float, float, float], psi: list[float] | None = None
) -> tuple[_F64, DynamicParams, tuple[float, float, float]]: ...
def loop_observability(
    kp: KinematicParams,
    dp: DynamicParams,
    pid: tuple[float, float, float],
    f0: float,
    coefficients: ArrayLike,
    *,
    start: ArrayLike,
    duration: float,
    torque_limit: float = 30.0,
    dt: float = 1e-3,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    noise: tuple[float, float] | None = None,
    hold: list[str] | None = None,
    identifiability_threshold: float = 1e-3,
) -> tuple[float, float, list[str], int, list[float]]: ...
def thesis_tables() -> dict[str, dict[str, Any]]: ...
