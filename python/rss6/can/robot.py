"""The bridge seen as a robot (the :class:`rss6.types.Robot` protocol), and simulated drives on a
virtual bus behind it: :func:`simulated_robot`.

>>> import rss6, rss6.can
>>> plant = rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal(), seed=1)
>>> with rss6.can.simulated_robot(plant, channel="doc-robot") as robot:
...     robot.reset(rss6.home_pose())
...     for _ in range(10):
...         robot.step_joint_command([0.0] * 6)
...     print(round(robot.time, 3), robot.fault)
0.01 None
"""

from __future__ import annotations

import contextlib
import itertools
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import can
import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6.can.bridge import Bridge, BridgeConfig, Reading
from rss6.can.protocol import CountMap
from rss6.can.simdrive import SimDrive, SimDrives
from rss6.errors import InvalidInputError, Rss6Error

__all__ = ["CanRobot", "simulated_robot"]

F64 = NDArray[np.float64]
_channels = itertools.count()


class CanRobot:
    """A robot behind a :class:`Bridge`: joint commands (rad, drive convention) go out as RPDO1 +
    SYNC, potentiometer readings (bit) come back from TPDO1, the camera from its own source.

    ``camera``: a callable returning ᶜχ_t or None each tick (the optical CMM is not on the bus).
    ``sim``: the :class:`SimDrives` behind the bus when the drives are simulated in this process —
    then :meth:`reset` resets the simulated robot, each step waits for its tick, and ``truth``,
    ``true_pose``, ``torque`` come from it. Without ``sim`` (real drives) ``reset`` re-enables the
    drives where they stand, ``torque`` is NaN (not on the bus) and the simulation-only members raise.
    """

    def __init__(
        self,
        bridge: Bridge,
        *,
        camera: Callable[[], Any] | None = None,
        sim: SimDrives | None = None,
        tick_timeout: float = 2.0,
    ):
        self.bridge = bridge
        self.sim = sim
        self._camera = camera
        self.tick_timeout = tick_timeout
        self.fence_timeout = 0.1
        self.fence_timeouts = 0
        self._frames_offset = 0
        self.last: Reading | None = None

    # --- the Robot protocol ---------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Time since the last :meth:`reset` (s): cycles × dt."""
        return self.bridge.cycle * self.bridge.config.dt

    @property
    def dt(self) -> float:
        """The SYNC period (s)."""
        return self.bridge.config.dt

    @property
    def fault(self) -> str | None:
        """None, or the latched fault reason."""
        return self.bridge.fault

    @property
    def drives(self) -> list[SimDrive]:
        """The simulated drives (joint order); real drives have no such handle."""
        if self.sim is None:
            raise Rss6Error("the drives are not simulated in this process")
        return self.sim.drives

    def reset(self, pose: ArrayLike) -> None:
        """The explicit restart: a simulated robot is put at rest at ``pose``; then every drive is
        walked to Operation Enabled again and the fault cleared, the clock at 0."""
        if self.sim is not None:
            self.sim.reset(pose)
        self.bridge.enable()
        self.last = self.bridge.reading()
        if self.sim is not None:
            self.bridge.wait_frames(self.sim.frames_sent - self._frames_offset, 0.2)
            self._frames_offset = self.sim.frames_sent - self.bridge.frames_seen()

    def step_joint_command(self, theta_cmd: ArrayLike) -> None:
        """One cycle (see :meth:`Bridge.step`); after a fault, commands are dropped and the drives
        hold their quick-stop positions while time goes on."""
        self._fence()  # anything the drives sent since (e.g. an injected EMCY) is seen first
        self.last = self.bridge.step(theta_cmd)
        if self.sim is not None:
            want = self.bridge.syncs_sent
            if not self.sim.wait_tick(want, self.tick_timeout):
                self.bridge._latch(
                    f"the simulated drives missed a SYNC (tick {self.sim.tick} of {want})"
                )
            self._fence()

    def _fence(self) -> None:
        """Lockstep fence: every frame the simulated drives sent (EMCY, heartbeats, TPDO1) has
        been processed by the bridge, so fault reactions are as deterministic as the data."""
        if self.sim is not None and self.bridge.config.lockstep:
            self.fence_timeouts += not self.bridge.wait_frames(
                self.sim.frames_sent - self._frames_offset, self.fence_timeout
            )

    def step_joint_commands(self, commands: ArrayLike) -> dict[str, Any]:
        """N cycles, one command row each (N, 6) rad; returns what a caller would collect tick by
        tick, with the plant's keys: ``time`` (N,) s, ``true_pose`` and ``true_theta`` (N, 6;
        simulated drives only, else NaN), ``kappa`` (N, 6) bit, ``torque`` (N, 6) N·m,
        ``camera_time`` (M,) s and ``camera`` (M, 6) ᶜχ_t frames; and the bridge's ``ages``
        (N, 6) cycles and the ``fault`` at the end (None or the latched reason)."""
        c = np.asarray(commands, dtype=np.float64)
        if c.ndim != 2 or c.shape[1] != 6:
            raise InvalidInputError(f"commands must have shape (N, 6), got {c.shape}")
        n = len(c)
        out = {k: np.full((n, 6), np.nan) for k in ("true_pose", "true_theta", "kappa", "torque")}
        ages = np.zeros((n, 6), dtype=np.int64)
        t = np.empty(n)
        cam_t: list[float] = []
        cams: list[F64] = []
        for k in range(n):
            self.step_joint_command(c[k])
            t[k] = self.time
            out["kappa"][k] = self.potentiometers()
            out["torque"][k] = self.torque()
            ages[k] = self.ages()
            cam = self.camera()
            if cam is not None:
                cam_t.append(t[k])
                cams.append(cam)
            if self.sim is not None:
                out["true_pose"][k] = self.true_pose()
                out["true_theta"][k] = self.true_theta()
        return {
            "time": t,
            **out,
            "camera_time": np.asarray(cam_t, dtype=np.float64),
            "camera": np.asarray(cams, dtype=np.float64).reshape(-1, 6),
            "ages": ages,
            "fault": self.fault,
        }

    def camera(self) -> F64 | None:
        """ᶜχ_t from the camera source if it exposed a frame during the last tick, else None."""
        if self._camera is None:
            return None
        cam = self._camera()
        return None if cam is None else np.asarray(cam, dtype=np.float64)

    def potentiometers(self) -> F64:
        """κ (bit) of the latest accepted TPDO1 of each drive (quantised to the drive's counts)."""
        r = self.last if self.last is not None else self.bridge.reading()
        return r.kappa

    def ages(self) -> NDArray[np.int64]:
        """Cycles since each drive's latest accepted TPDO1."""
        r = self.last if self.last is not None else self.bridge.reading()
        return r.ages

    def torque(self) -> F64:
        """Drive torques (N·m): the simulated robot's; NaN for real drives (not in the PDOs)."""
        if self.sim is not None:
            return np.asarray(self.sim.plant.torque(), dtype=np.float64)
        return np.full(6, np.nan)

    def true_pose(self) -> F64:
        """The true end-effector pose (simulated drives only)."""
        return np.asarray(self._simulated().plant.true_pose(), dtype=np.float64)

    def true_theta(self) -> F64:
        """The true joint angles (simulated drives only)."""
        return np.asarray(self._simulated().plant.true_theta(), dtype=np.float64)

    def truth(self) -> dict[str, Any]:
        """The simulated robot's truth (simulated drives only)."""
        return dict(self._simulated().plant.truth())

    def _simulated(self) -> SimDrives:
        if self.sim is None:
            raise Rss6Error("a real robot has no simulation truth")
        return self.sim

    def close(self) -> None:
        """Stops the bridge (and the simulated drives)."""
        self.bridge.close()
        if self.sim is not None:
            self.sim.stop()


@contextlib.contextmanager
def simulated_robot(
    plant: Any,
    *,
    interface: str = "virtual",
    channel: str | Sequence[str] | None = None,
    channels: int = 1,
    config: BridgeConfig | None = None,
    bridge_bus: Callable[[can.BusABC], can.BusABC] | None = None,
    drive_bus: Callable[[can.BusABC], can.BusABC] | None = None,
    modes: Sequence[int] = (8,),
) -> Iterator[CanRobot]:
    """``plant`` (:class:`rss6.Plant` or :class:`rss6.ModelSim`) behind six :class:`SimDrive` on
    ``channels`` buses of ``interface`` in this process, seen through a :class:`Bridge` as a
    :class:`CanRobot`; the camera is the plant's own. The robot is reset at home and enabled (one
    ``plant.reset``: a reset does not reseed the plant's noise, so a run to compare with resets its
    plant as often).

    ``channel``: the bus channel name (or one per channel; default: fresh unique names).
    ``bridge_bus``/``drive_bus``: wrap the bridge's or the drives' bus (e.g. ``FaultyBus``).
    ``config``: the bridge's configuration (its ``count_map`` is the drives' too).
    """
    from rss6 import _rss6

    if channel is None:
        names = [f"rss6-can-{next(_channels)}" for _ in range(channels)]
    elif isinstance(channel, str):
        names = [channel] if channels == 1 else [f"{channel}-{c}" for c in range(channels)]
    else:
        names = list(channel)
    if len(names) != channels:
        raise Rss6Error(f"{channels} channels need {channels} channel names, got {names}")
    cfg = config if config is not None else BridgeConfig(dt=float(plant.dt))
    if abs(cfg.dt - float(plant.dt)) > 1e-12:
        raise InvalidInputError(
            f"the SYNC period dt = {cfg.dt} s must equal the plant's tick {plant.dt} s (lockstep)"
        )
    cmap = cfg.count_map if cfg.count_map is not None else CountMap.nominal()
    buses: list[can.BusABC] = []
    robot: CanRobot | None = None
    try:
        d_buses, b_buses = [], []
        for name in names:
            d = can.Bus(interface=interface, channel=name)
            buses.append(d)
            b = can.Bus(interface=interface, channel=name)
            buses.append(b)
            d_buses.append(drive_bus(d) if drive_bus is not None else d)
            b_buses.append(bridge_bus(b) if bridge_bus is not None else b)
        buses = d_buses + b_buses
        sim = SimDrives(
            plant, d_buses, count_map=cmap, tpdo_every=cfg.tpdo_every, modes=modes
        ).start()
        bridge = Bridge(b_buses, cfg)
        robot = CanRobot(bridge, camera=plant.camera, sim=sim)
        robot.reset(_rss6.home_pose())
        yield robot
    finally:
        if robot is not None:
            robot.close()
        for bus in buses:
            bus.shutdown()
