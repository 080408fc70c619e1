"""The CAN bridge's configuration (:class:`BridgeConfig`), checked where it is made."""

from __future__ import annotations

import math
from dataclasses import dataclass
from os import PathLike

from rss6.can.load import MAX_LOAD
from rss6.can.protocol import DRIVE_IDS, CountMap
from rss6.errors import InvalidInputError

__all__ = ["BridgeConfig"]


@dataclass
class BridgeConfig:
    """What the bridge needs to know about the drives and the bus. Angles in the drive's convention.

    ``dt``: SYNC period (s). ``tpdo_every``: TPDO1 every n-th SYNC. ``heartbeat_ms``: the drives'
    producer heartbeat (written to 0x1017); ``bridge_heartbeat_ms``: the bridge's own; a heartbeat
    older than ``heartbeat_timeout`` periods is a fault on either side (0x1016 on the drives).
    ``tpdo_timeout``: cycles without an accepted TPDO1 before a fault (default 2·tpdo_every in
    lockstep: one lost TPDO is tolerated; 5·tpdo_every on the wall clock, where TPDOs arrive a cycle
    or two after their SYNC and a late cycle ages them too). ``v_max`` (rad/s): larger command steps are refused, larger position jumps
    rejected. ``limits`` (rad): the software position limits (0x607D); commands outside are refused,
    positions beyond ``position_margin`` outside them rejected. ``following_error`` (rad, 0x6065).
    ``bitrate``: the bus bitrate; when given, a configuration above ``max_load`` (worst-case
    stuffed) is refused. ``lockstep``: wait for each cycle's TPDOs (simulated drives; real drives:
    False). ``log``: a bus log (``.asc``/``.log``/``.blf``) written through python-can's ``Logger``.
    """

    node_ids: tuple[int, ...] = DRIVE_IDS
    count_map: CountMap | None = None
    dt: float = 1e-3
    tpdo_every: int = 2
    heartbeat_ms: int = 10
    bridge_heartbeat_ms: int = 10
    heartbeat_timeout: float = 2.5
    tpdo_timeout: int | None = None
    v_max: float = 10.0
    limits: tuple[float, float] = (-math.pi / 2, math.pi / 2)
    position_margin: float = 0.05
    noise_bits: float = 4.0
    following_error: float = 0.1
    bitrate: int | None = None
    max_load: float = MAX_LOAD
    lockstep: bool = True
    wait_timeout: float = 0.25
    sdo_timeout: float = 1.0
    log: str | PathLike[str] | None = None
    eds: str | None = None

    def __post_init__(self) -> None:
        # A NaN or negative limit would switch a safety check off without a word (every
        # comparison with NaN is False): refused here, naming the field.
        ids = tuple(self.node_ids)
        if len(set(ids)) != len(ids) or not all(1 <= int(i) == i <= 127 for i in ids):
            raise InvalidInputError(f"node_ids must be distinct CANopen ids in 1..127, got {ids}")
        for name, least in (("tpdo_every", 1), ("heartbeat_ms", 1), ("bridge_heartbeat_ms", 1)):
            v = getattr(self, name)
            if not isinstance(v, int) or v < least:
                raise InvalidInputError(f"{name} must be an int >= {least}, got {v!r}")
        for name in ("tpdo_timeout", "bitrate"):
            v = getattr(self, name)
            if v is not None and (not isinstance(v, int) or v < 1):
                raise InvalidInputError(f"{name} must be None or an int >= 1, got {v!r}")
        positive = ("dt", "heartbeat_timeout", "v_max", "following_error", "wait_timeout")
        for name in (*positive, "sdo_timeout", "position_margin", "noise_bits", "max_load"):
            v = float(getattr(self, name))
            strict = name in positive or name == "sdo_timeout"
            if not math.isfinite(v) or v < 0 or (strict and v == 0):
                raise InvalidInputError(
                    f"{name} must be finite and {'>' if strict else '>='} 0, got {v}"
                )
        lo, hi = (float(x) for x in self.limits)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise InvalidInputError(f"limits must be finite with lower < upper, got {self.limits}")
        if self.max_load > 1:
            raise InvalidInputError(f"max_load is a fraction of the bus, <= 1; got {self.max_load}")
