"""rss6: calibration, identification, simulation and control of 6-RSS parallel robots (Li 2020).

Arrays are numpy float64 in SI units (m, rad, kg, s, N·m); a pose is χ = [x, y, z, α, β, γ] with
R = Rx(α)·Ry(β)·Rz(γ). Every error derives from :class:`rss6.Rss6Error` (see :mod:`rss6.errors`).

>>> import rss6
>>> kp = rss6.KinematicParams.nominal()
>>> theta = rss6.ik(kp, rss6.home_pose())
>>> bool(abs(theta).max() < 1e-12)
True
"""

from __future__ import annotations

from rss6 import errors
from rss6._rss6 import (
    DynamicParams,
    KinematicParams,
    fk,
    fk_batch,
    home_pose,
    ik,
    ik_batch,
    jacobian_ad,
    jacobian_theta,
)
from rss6.errors import (
    CalibrationError,
    ControllerFaultError,
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
    UnreachableError,
)

__version__ = "0.1.0"

__all__ = [
    "errors",
    "KinematicParams",
    "DynamicParams",
    "home_pose",
    "ik",
    "ik_batch",
    "fk",
    "fk_batch",
    "jacobian_theta",
    "jacobian_ad",
    "Rss6Error",
    "InvalidInputError",
    "ShapeError",
    "NonFiniteError",
    "InvalidParameterError",
    "UnreachableError",
    "OutOfBranchError",
    "NotConvergedError",
    "SingularError",
    "ControllerFaultError",
    "SimulationError",
    "CalibrationError",
    "LogError",
    "ParamsFileError",
]
