"""The CiA 402 layout the bridge and the simulated drives share: COB-IDs, objects, frame codecs, the
drive state machine's words and the counts ↔ radian mapping.

Every drive runs Cyclic Synchronous Position (mode 8):

=========  ==========  =====  ========================================================  ==========
COB-ID     direction   bytes  content                                                   when
=========  ==========  =====  ========================================================  ==========
0x080      bridge →    0      SYNC                                                      1 kHz
0x200+id   bridge →    4      RPDO1: target position 0x607A (INT32, counts)             every SYNC
0x300+id   bridge →    3      RPDO2: controlword 0x6040 (UINT16) + mode 0x6060 (INT8)   on change
0x180+id   → bridge    6      TPDO1: statusword 0x6041 (UINT16) + position 0x6064       2nd SYNC
0x080+id   → bridge    8      EMCY: error code, error register, 5 vendor bytes          on fault
0x700+id   both        1      heartbeat (NMT state); the bridge's id is 0x7F            0x1017
=========  ==========  =====  ========================================================  ==========

>>> from rss6.can.protocol import CountMap, pack_status, unpack_status
>>> m = CountMap.nominal()
>>> int(m.to_counts([0.1, 0, 0, 0, 0, 0])[0]), round(float(m.counts_per_radian[0]), 1)
(33377, 333772.1)
>>> unpack_status(pack_status(0x0027, -1234))
(39, -1234)
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6.errors import InvalidInputError, Rss6Error

__all__ = [
    "BRIDGE_NODE_ID",
    "DRIVE_IDS",
    "EMCY_CODES",
    "MODE_CSP",
    "CanFaultError",
    "Controlword",
    "CountMap",
    "DriveState",
    "FrameError",
    "cob",
    "eds_path",
    "pack_control",
    "pack_status",
    "pack_target",
    "role_filters",
    "split_nodes",
    "state_from_statusword",
    "unpack_control",
    "unpack_status",
    "unpack_target",
]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Node ids of the six drives (leg i ↔ node i).
DRIVE_IDS: tuple[int, ...] = (1, 2, 3, 4, 5, 6)
#: The bridge's own node id: its heartbeat is 0x77F and the drives' 0x1016 watches it.
BRIDGE_NODE_ID = 0x7F
#: Modes of operation 0x6060: Cyclic Synchronous Position.
MODE_CSP = 8
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1

#: EMCY error codes the simulated drives send and the bridge names in its fault reasons.
EMCY_CODES: dict[int, str] = {
    0x8611: "following error",
    0x8130: "heartbeat of the bridge lost",
    0x8210: "PDO length error",
    0x8612: "position limit",
    0x1000: "generic error",
}


class cob:
    """COB-IDs of the predefined connection set (CiA 301)."""

    NMT = 0x000
    SYNC = 0x080
    EMCY = 0x080
    TPDO1 = 0x180
    RPDO1 = 0x200
    RPDO2 = 0x300
    SDO_TX = 0x580
    SDO_RX = 0x600
    HEARTBEAT = 0x700


class Controlword(enum.IntEnum):
    """Controlword 0x6040 commands (CiA 402 §6.3)."""

    DISABLE_VOLTAGE = 0x0000
    QUICK_STOP = 0x0002
    SHUTDOWN = 0x0006
    SWITCH_ON = 0x0007
    ENABLE_OPERATION = 0x000F
    FAULT_RESET = 0x0080


class DriveState(enum.Enum):
    """States of the CiA 402 drive state machine, with the statusword bits that show them."""

    NOT_READY_TO_SWITCH_ON = 0x0000
    SWITCH_ON_DISABLED = 0x0040
    READY_TO_SWITCH_ON = 0x0021
    SWITCHED_ON = 0x0023
    OPERATION_ENABLED = 0x0027
    QUICK_STOP_ACTIVE = 0x0007
    FAULT_REACTION_ACTIVE = 0x000F
    FAULT = 0x0008

    @property
    def statusword(self) -> int:
        """The statusword of this state (bit 5 "quick stop" is active low, bit 4 voltage on)."""
        sw = int(self.value)
        if self in (
            DriveState.READY_TO_SWITCH_ON,
            DriveState.SWITCHED_ON,
            DriveState.OPERATION_ENABLED,
        ):
            sw |= 0x0010
        return sw


_SW_MASKS: tuple[tuple[int, DriveState], ...] = tuple(
    (0x6F if s.value & 0x20 or s is DriveState.QUICK_STOP_ACTIVE else 0x4F, s) for s in DriveState
)
SW_FAULT_BIT = 0x0008
SW_FOLLOWING_ERROR_BIT = 0x2000


def state_from_statusword(sw: int) -> DriveState | None:
    """The 402 state a statusword shows, or None if the bits match no state."""
    for mask, state in _SW_MASKS:
        if sw & mask == state.value:
            return state
    return None


class FrameError(Rss6Error, ValueError):
    """A CAN frame has the wrong length for its object (the DLC check)."""


class CanFaultError(Rss6Error):
    """The bridge latched a fault (the message names it); restart only by an explicit reset."""


_TARGET = struct.Struct("<i")
_CONTROL = struct.Struct("<Hb")
_STATUS = struct.Struct("<Hi")


def pack_target(counts: int) -> bytes:
    """RPDO1 payload: target position 0x607A (INT32 counts)."""
    return _TARGET.pack(counts)


def unpack_target(data: bytes | bytearray) -> int:
    """Decodes RPDO1; raises :class:`FrameError` unless the frame has exactly 4 bytes."""
    if len(data) != _TARGET.size:
        raise FrameError(f"RPDO1 needs {_TARGET.size} bytes, got {len(data)}")
    return int(_TARGET.unpack(bytes(data))[0])


def pack_control(controlword: int, mode: int = MODE_CSP) -> bytes:
    """RPDO2 payload: controlword 0x6040 (UINT16) + modes of operation 0x6060 (INT8)."""
    return _CONTROL.pack(controlword, mode)


def unpack_control(data: bytes | bytearray) -> tuple[int, int]:
    """Decodes RPDO2 → (controlword, mode); :class:`FrameError` unless it has 3 bytes."""
    if len(data) != _CONTROL.size:
        raise FrameError(f"RPDO2 needs {_CONTROL.size} bytes, got {len(data)}")
    cw, mode = _CONTROL.unpack(bytes(data))
    return int(cw), int(mode)


def pack_status(statusword: int, position: int) -> bytes:
    """TPDO1 payload: statusword 0x6041 (UINT16) + position actual 0x6064 (INT32 counts)."""
    return _STATUS.pack(statusword, position)


def unpack_status(data: bytes | bytearray) -> tuple[int, int]:
    """Decodes TPDO1 → (statusword, counts); :class:`FrameError` unless it has 6 bytes."""
    if len(data) != _STATUS.size:
        raise FrameError(f"TPDO1 needs {_STATUS.size} bytes, got {len(data)}")
    sw, pos = _STATUS.unpack(bytes(data))
    return int(sw), int(pos)


def split_nodes(node_ids: Sequence[int], channels: int) -> list[tuple[int, ...]]:
    """Drives per channel: contiguous groups, the first channels taking one more if uneven
    (six drives on two channels: nodes 1–3 and 4–6)."""
    if channels < 1 or channels > len(node_ids):
        raise InvalidInputError(f"channels must be 1..{len(node_ids)}, got {channels}")
    k, r = divmod(len(node_ids), channels)
    out, i = [], 0
    for c in range(channels):
        n = k + (1 if c < r else 0)
        out.append(tuple(node_ids[i : i + n]))
        i += n
    return out


def role_filters(role: str, node_ids: Sequence[int] = DRIVE_IDS) -> list[dict[str, int]]:
    """python-can ``can_filters`` for one side of the bus: what the ``"drives"`` or the
    ``"bridge"`` must receive. On ``udp_multicast`` a sender receives its own frames, so each side
    filters them out (an echoed RPDO would look like a periodic map to canopen)."""
    if role == "drives":
        ids = [cob.NMT, cob.SYNC, cob.HEARTBEAT + BRIDGE_NODE_ID]
        for n in node_ids:
            ids += [cob.RPDO1 + n, cob.RPDO2 + n, cob.SDO_RX + n]
    elif role == "bridge":
        ids = []
        for n in node_ids:
            ids += [cob.TPDO1 + n, cob.EMCY + n, cob.HEARTBEAT + n, cob.SDO_TX + n]
    else:
        raise InvalidInputError(f"role must be 'drives' or 'bridge', got {role!r}")
    return [{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in ids]


def eds_path() -> Path:
    """The EDS of the simulated drive, shipped with rss6 (python/rss6/can/rss6_drive.eds)."""
    return Path(__file__).with_name("rss6_drive.eds")


@dataclass(frozen=True)
class CountMap:
    """Drive counts ↔ joint angles through the potentiometer convention (eq. 4.2).

    A drive counts its potentiometer in ``counts_per_bit`` counts per bit: counts = κ·s, so with
    the drive's nominal convention θ = η·κ + Δθ, counts = s·(θ − Δθ)/η and one count is η/s rad
    (π/4096/256 ≈ 3.0 µrad for the nominal η). Commands θ_cmd (drive convention, rad) become the
    target counts round(s·(θ_cmd − Δθ)/η); a drive's position actual gives κ = counts/s (bit).
    """

    eta: tuple[float, ...]
    dtheta: tuple[float, ...]
    counts_per_bit: int = 256
    _eta: F64 = field(init=False, repr=False, compare=False)
    _dtheta: F64 = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        eta = np.asarray(self.eta, dtype=np.float64)
        dth = np.asarray(self.dtheta, dtype=np.float64)
        if eta.shape != (6,) or dth.shape != (6,):
            raise InvalidInputError("CountMap needs six η and six Δθ")
        if not (np.all(np.isfinite(eta)) and np.all(np.isfinite(dth)) and np.all(eta != 0)):
            raise InvalidInputError("CountMap: η must be finite and non-zero, Δθ finite")
        if self.counts_per_bit < 1:
            raise InvalidInputError("counts_per_bit must be >= 1")
        object.__setattr__(self, "_eta", eta)
        object.__setattr__(self, "_dtheta", dth)

    @classmethod
    def from_params(cls, kp: Any, counts_per_bit: int = 256) -> CountMap:
        """The map of a :class:`rss6.KinematicParams` (its η and Δθ: the drive's convention)."""
        d = kp.to_dict()
        return cls(tuple(map(float, d["eta"])), tuple(map(float, d["dtheta"])), counts_per_bit)

    @classmethod
    def nominal(cls, counts_per_bit: int = 256) -> CountMap:
        """The nominal robot's map (η = π/4096 rad/bit, Δθ = 0)."""
        from rss6 import _rss6

        return cls.from_params(_rss6.KinematicParams.nominal(), counts_per_bit)

    @property
    def counts_per_radian(self) -> F64:
        """s/η for each joint (counts/rad)."""
        return self.counts_per_bit / self._eta

    def to_counts(self, theta: ArrayLike) -> I64:
        """Joint angles (rad, drive convention) → target counts. Raises on NaN/inf or INT32 overflow."""
        th = np.asarray(theta, dtype=np.float64)
        if not np.all(np.isfinite(th)):
            raise InvalidInputError("joint command contains NaN or infinity")
        c = np.rint((th - self._dtheta) / self._eta * self.counts_per_bit)
        if np.any(c < INT32_MIN) or np.any(c > INT32_MAX):
            raise InvalidInputError("joint command overflows the INT32 target position")
        return c.astype(np.int64)

    def to_theta(self, counts: ArrayLike) -> F64:
        """Counts → joint angles (rad, drive convention)."""
        c = np.asarray(counts, dtype=np.float64)
        return np.asarray(self._eta * (c / self.counts_per_bit) + self._dtheta, dtype=np.float64)

    def to_kappa(self, counts: ArrayLike) -> F64:
        """Counts → potentiometer readings κ (bit)."""
        return np.asarray(np.asarray(counts, dtype=np.float64) / self.counts_per_bit)

    def kappa_to_counts(self, kappa: ArrayLike) -> I64:
        """Potentiometer readings κ (bit) → counts (what a drive reports as 0x6064)."""
        c = np.rint(np.asarray(kappa, dtype=np.float64) * self.counts_per_bit)
        return np.asarray(np.clip(c, INT32_MIN, INT32_MAX).astype(np.int64))

    def quantise(self, theta: ArrayLike) -> F64:
        """θ as a drive receives it: to counts and back (what the simulated drive commands)."""
        return self.to_theta(self.to_counts(theta))
