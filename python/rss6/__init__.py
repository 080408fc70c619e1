"""rss6: calibration, identification, simulation and control of 6-RSS parallel robots (Li 2020).

Arrays are numpy float64 in SI units (m, rad, kg, s, N·m); a pose is χ = [x, y, z, α, β, γ] with
R = Rx(α)·Ry(β)·Rz(γ). Every error derives from :class:`rss6.Rss6Error` (see :mod:`rss6.errors`).

>>> import rss6
>>> kp = rss6.KinematicParams.nominal()
>>> theta = rss6.ik(kp, rss6.home_pose())
>>> bool(abs(theta).max() < 1e-12)
True

Submodules: :mod:`rss6.servo` (tracking experiments), :mod:`rss6.calibrate` (RPBA, implicit),
:mod:`rss6.logs` (MCAP), :mod:`rss6.plots` (figures), :mod:`rss6.demo` (the demo as data),
:mod:`rss6.types` (``Literal`` names, the ``Robot`` protocol), :mod:`rss6.cli` (the ``rss6`` command);
optional :mod:`rss6.can` (the CAN bridge: ``pip install rss6[can]``, imported on demand).
"""

from __future__ import annotations

import importlib
from types import ModuleType
from typing import TYPE_CHECKING

from rss6 import errors
from rss6._rss6 import (
    CalibrationData,
    CalibrationResult,
    Dsmc,
    DynamicParams,
    KalmanFilter,
    Kcsc,
    KinematicParams,
    Kjsc,
    ModelSim,
    TorqueToPosition,
    Trajectory,
    compose_poses,
    coriolis,
    dynamics_terms,
    fk,
    fk_batch,
    forward_dynamics,
    friction,
    gravity,
    home_pose,
    ik,
    ik_batch,
    inverse_dynamics,
    invert_pose,
    jacobian_ad,
    jacobian_theta,
    mass_matrix,
    regressor,
    rk4_step,
)
from rss6.errors import (
    CalibrationError,
    ControllerFaultError,
    CorruptLogError,
    IdentificationError,
    InvalidInputError,
    InvalidParameterError,
    LogError,
    NonFiniteError,
    NotConvergedError,
    OutOfBranchError,
    ParamsFileError,
    Rss6Error,
    ShapeError,
    SimulationError,
    SingularError,
    TruncatedLogError,
    UnreachableError,
)

try:  # the rapier plant (rss6-sim) is optional in builds without it
    from rss6._rss6 import Plant
except ImportError:  # pragma: no cover - depends on the build
    Plant = None  # type: ignore[assignment,misc]

if TYPE_CHECKING:
    from rss6 import calibrate, identify, logs, servo

__version__ = "0.1.0"

# calibrate, identify, logs and servo load scipy and mcap (≈ 0.8 s): they are imported when first
# used, so that `import rss6` (and with it the `rss6` command, whose Ctrl-C handling starts only once
# its module has loaded) takes a fraction of that.
_LAZY = frozenset({"calibrate", "identify", "logs", "servo"})


def __getattr__(name: str) -> ModuleType:
    if name in _LAZY:
        return importlib.import_module(f"rss6.{name}")
    raise AttributeError(f"module 'rss6' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | _LAZY)


__all__ = [
    "CalibrationData",
    "CalibrationError",
    "CalibrationResult",
    "ControllerFaultError",
    "CorruptLogError",
    "Dsmc",
    "DynamicParams",
    "IdentificationError",
    "InvalidInputError",
    "InvalidParameterError",
    "KalmanFilter",
    "Kcsc",
    "KinematicParams",
    "Kjsc",
    "LogError",
    "ModelSim",
    "NonFiniteError",
    "NotConvergedError",
    "OutOfBranchError",
    "ParamsFileError",
    "Plant",
    "Rss6Error",
    "ShapeError",
    "SimulationError",
    "SingularError",
    "TorqueToPosition",
    "Trajectory",
    "TruncatedLogError",
    "UnreachableError",
    "calibrate",
    "compose_poses",
    "coriolis",
    "dynamics_terms",
    "errors",
    "fk",
    "fk_batch",
    "forward_dynamics",
    "friction",
    "gravity",
    "home_pose",
    "identify",
    "ik",
    "ik_batch",
    "inverse_dynamics",
    "invert_pose",
    "jacobian_ad",
    "jacobian_theta",
    "logs",
    "mass_matrix",
    "regressor",
    "rk4_step",
    "servo",
]
