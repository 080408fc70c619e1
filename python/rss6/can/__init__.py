"""rss6.can: the CAN bridge to the real robot's six CiA 402 drives, simulated drives behind a bus,
fault injection, bus-load arithmetic and a wall-clock runner (needs ``pip install rss6[can]``:
python-can and canopen). See docs/can.md.

* :class:`Bridge` / :class:`BridgeConfig` — drives to Operation Enabled, ``step`` (RPDO1 + SYNC),
  watchdogs and fault reactions (quick stop on all six, a latched reason).
* :class:`CanRobot` — the bridge as a :class:`rss6.types.Robot`; :func:`simulated_robot` — a plant
  behind :class:`SimDrives` on a virtual bus, in lockstep.
* :class:`SimDrive` / :class:`SimDrives` — simulated drives (canopen ``LocalNode`` + the shipped EDS).
* :class:`FaultyBus` — drops, delays, duplicates, corrupts, fails sends, injects error frames.
* :mod:`rss6.can.load` — bus load; :mod:`rss6.can.protocol` — COB-IDs, codecs, :class:`CountMap`;
  :mod:`rss6.can.realtime` — the 1 kHz wall-clock runner and its cycle statistics.
"""

from __future__ import annotations

from rss6.can.bridge import Bridge, BridgeConfig, Reading
from rss6.can.faulty import FaultyBus
from rss6.can.load import MAX_LOAD, BusLoad, BusLoadError, bus_load, check_bus_load
from rss6.can.protocol import (
    CanFaultError,
    Controlword,
    CountMap,
    DriveState,
    FrameError,
    eds_path,
)
from rss6.can.robot import CanRobot, simulated_robot
from rss6.can.simdrive import SimDrive, SimDrives

__all__ = [
    "MAX_LOAD",
    "Bridge",
    "BridgeConfig",
    "BusLoad",
    "BusLoadError",
    "CanFaultError",
    "CanRobot",
    "Controlword",
    "CountMap",
    "DriveState",
    "FaultyBus",
    "FrameError",
    "Reading",
    "SimDrive",
    "SimDrives",
    "bus_load",
    "check_bus_load",
    "eds_path",
    "simulated_robot",
]
