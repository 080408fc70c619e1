"""Names the workflows accept, as ``Literal`` types, and the :class:`Robot` protocol of a plant.

>>> import rss6
>>> from rss6.types import CONTROLLERS, Robot
>>> CONTROLLERS
('kjsc', 'kcsc', 'dsmc')
>>> isinstance(rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal()), Robot)
True
"""

from __future__ import annotations

from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "CONTROLLERS",
    "TRAJECTORIES",
    "TUNINGS",
    "ControllerName",
    "PlantKind",
    "Robot",
    "TrajectoryName",
    "TuningName",
]

#: A servo controller: Kalman-filtered joint-space (eq. 6.42), Cartesian-space (eq. 6.40) or the
#: dynamic sliding-mode controller (eq. 6.25 + converter).
ControllerName = Literal["kjsc", "kcsc", "dsmc"]
#: A servo tuning: "tuned" (the default: rss6's presets ``ServoConfig::tuned`` + ``DsmcGains::tuned``,
#: used to reproduce Tables 6.1/6.2 — the thesis prints no DSMC gains) or rss6's low-noise DSMC servo
#: (DSMC only).
TuningName = Literal["tuned", "low_noise"]
#: A named reference: Experiment 1 (sinusoid) or Experiment 2 (Fourier series) of thesis §6.5.
TrajectoryName = Literal["exp1", "exp2"]

#: Which simulated robot a workflow builds: the rapier plant, the analytic-model twin, or the rapier
#: plant if this build has it.
PlantKind = Literal["auto", "rapier", "model"]

#: Every controller name, in the order the thesis's tables list them.
CONTROLLERS: tuple[ControllerName, ...] = ("kjsc", "kcsc", "dsmc")
#: Every tuning name.
TUNINGS: tuple[TuningName, ...] = ("tuned", "low_noise")
#: Every trajectory name.
TRAJECTORIES: tuple[TrajectoryName, ...] = ("exp1", "exp2")


@runtime_checkable
class Robot(Protocol):
    """What the workflows use of a robot: :class:`rss6.Plant` (rapier), :class:`rss6.ModelSim`
    (analytic twin) and, later, the CAN bridge to the real robot.

    Poses are χ = [x, y, z, α, β, γ] (m, rad) of the end effector in the base frame; joint vectors
    are six angles (rad) or torques (N·m). The simulation-only members (``truth``, ``true_pose``)
    give what only a simulation knows; a real robot raises on them.
    """

    @property
    def time(self) -> float:
        """Time since the last :meth:`reset` (s)."""
        ...

    @property
    def dt(self) -> float:
        """Length of one :meth:`step_joint_command` tick (s)."""
        ...

    def reset(self, pose: ArrayLike) -> None:
        """Puts the robot at rest at ``pose`` and the clock at 0."""
        ...

    def step_joint_command(self, theta_cmd: ArrayLike) -> None:
        """Sends one joint position command (rad, the drives' convention) and advances one tick."""
        ...

    def camera(self) -> NDArray[np.float64] | None:
        """The camera's target pose ᶜχ_t if a frame was exposed during the last tick, else None."""
        ...

    def potentiometers(self) -> NDArray[np.float64]:
        """The six potentiometer readings κ (bit)."""
        ...

    def torque(self) -> NDArray[np.float64]:
        """The six drive torques of the last tick (N·m)."""
        ...

    def true_pose(self) -> NDArray[np.float64]:
        """The true end-effector pose χ_E (simulation only)."""
        ...

    def truth(self) -> dict[str, Any]:
        """The true kinematics, dynamics, drive PID, camera placement and effects (simulation only)."""
        ...
