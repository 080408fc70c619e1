"""Fault injection: a python-can bus wrapper that drops, delays, duplicates or corrupts frames,
raises on send, or injects error frames. canopen accepts any ``can.BusABC``, so a
:class:`FaultyBus` goes wherever a bus goes (``canopen.Network(FaultyBus(bus))``, ``Bridge``).

Faults are armed with a count and an optional COB-ID and act on the next matching frames, so a test
says exactly which frames suffer:

>>> import can
>>> from rss6.can import FaultyBus
>>> a = can.Bus(interface="virtual", channel="faulty-doc")
>>> b = FaultyBus(can.Bus(interface="virtual", channel="faulty-doc"))
>>> b.drop(count=1, can_id=0x181)
>>> for i in (1, 2):
...     a.send(can.Message(arbitration_id=0x181, data=[i], is_extended_id=False))
>>> b.recv(0.5).data[0], b.counts["dropped"]
(2, 1)
>>> a.shutdown(); b.shutdown()
"""

from __future__ import annotations

import threading
from collections import deque
from dataclasses import dataclass
from typing import Any, Literal

import can

__all__ = ["FaultyBus"]

Corruption = Literal["dlc", "flip", "value"]


@dataclass
class _Rule:
    kind: str
    count: int
    can_id: int | None
    arg: Any = None

    def matches(self, msg: can.Message) -> bool:
        return self.count > 0 and (self.can_id is None or msg.arbitration_id == self.can_id)


class FaultyBus(can.BusABC):
    """Wraps ``bus`` (which it shuts down with itself). Received frames pass through the armed
    receive faults; sends through the armed send faults. ``counts`` says what was done."""

    def __init__(self, bus: can.BusABC, **kwargs: Any):
        self.inner = bus
        self._rules: list[_Rule] = []
        self._held: deque[tuple[int, can.Message]] = deque()
        self._ready: deque[can.Message] = deque()
        self._lock = threading.Lock()
        self.counts: dict[str, int] = {
            "dropped": 0,
            "delayed": 0,
            "duplicated": 0,
            "corrupted": 0,
            "send_failures": 0,
            "send_dropped": 0,
            "error_frames": 0,
            "received": 0,
        }
        super().__init__(channel=getattr(bus, "channel_info", "faulty"), **kwargs)
        self.channel_info = f"faulty({getattr(bus, 'channel_info', '?')})"

    # --- arming ---------------------------------------------------------------------------------
    def _arm(self, kind: str, count: int, can_id: int | None, arg: Any = None) -> None:
        with self._lock:
            self._rules.append(_Rule(kind, count, can_id, arg))

    def drop(self, count: int = 1, can_id: int | None = None) -> None:
        """Drops the next ``count`` received frames (with ``can_id``, if given)."""
        self._arm("drop", count, can_id)

    def delay(self, count: int = 1, can_id: int | None = None, frames: int = 1) -> None:
        """Holds each of the next ``count`` matching frames until ``frames`` later frames have been
        received (a delay measured in bus traffic, so lockstep runs stay deterministic)."""
        self._arm("delay", count, can_id, frames)

    def duplicate(self, count: int = 1, can_id: int | None = None) -> None:
        """Delivers each of the next ``count`` matching frames twice."""
        self._arm("duplicate", count, can_id)

    def corrupt(
        self,
        count: int = 1,
        can_id: int | None = None,
        how: Corruption = "dlc",
        value: bytes | None = None,
    ) -> None:
        """Corrupts the next ``count`` matching received frames: ``"dlc"`` drops the last data byte,
        ``"flip"`` flips the top bit of the last byte, ``"value"`` replaces the data by ``value``."""
        self._arm("corrupt", count, can_id, (how, value))

    def fail_sends(self, count: int = 1, can_id: int | None = None) -> None:
        """The next ``count`` matching sends raise ``can.CanOperationError``."""
        self._arm("fail_send", count, can_id)

    def drop_sends(self, count: int = 1, can_id: int | None = None) -> None:
        """The next ``count`` matching sends silently vanish."""
        self._arm("drop_send", count, can_id)

    def error_frame(self, count: int = 1) -> None:
        """The next ``count`` receives also deliver an error frame."""
        self._arm("error_frame", count, None)

    def _take(self, kind: str, msg: can.Message) -> _Rule | None:
        for r in self._rules:
            if r.kind == kind and r.matches(msg):
                r.count -= 1
                return r
        return None

    # --- BusABC ---------------------------------------------------------------------------------
    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        with self._lock:
            if self._take("fail_send", msg) is not None:
                self.counts["send_failures"] += 1
                raise can.CanOperationError(f"injected send failure (0x{msg.arbitration_id:03X})")
            if self._take("drop_send", msg) is not None:
                self.counts["send_dropped"] += 1
                return
        self.inner.send(msg, timeout)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        with self._lock:
            if self._ready:
                return self._ready.popleft(), True
        msg = self.inner.recv(timeout)
        if msg is None:
            return None, True
        with self._lock:
            self.counts["received"] += 1
            released = [m for k, m in self._held if k <= 1]
            self._held = deque((k - 1, m) for k, m in self._held if k > 1)
            out: list[can.Message] = []
            if self._take("error_frame", msg) is not None:
                self.counts["error_frames"] += 1
                out.append(can.Message(is_error_frame=True, timestamp=msg.timestamp))
            if self._take("drop", msg) is not None:
                self.counts["dropped"] += 1
            elif (r := self._take("delay", msg)) is not None:
                self.counts["delayed"] += 1
                self._held.append((int(r.arg), msg))
            else:
                if (r := self._take("corrupt", msg)) is not None:
                    self.counts["corrupted"] += 1
                    msg = _corrupted(msg, *r.arg)
                out.append(msg)
                if self._take("duplicate", msg) is not None:
                    self.counts["duplicated"] += 1
                    out.append(_copy(msg))
            out.extend(released)
            if not out:
                return None, True
            self._ready.extend(out[1:])
            return out[0], True

    def unseen(self) -> int:
        """Frames read from the wrapped bus that listeners will not see (dropped, held) minus the
        frames it added (duplicates, error frames): delivered = read − unseen."""
        with self._lock:
            extra = self.counts["duplicated"] + self.counts["error_frames"]
            return self.counts["dropped"] + len(self._held) - extra

    def shutdown(self) -> None:
        super().shutdown()
        self.inner.shutdown()


def _copy(msg: can.Message) -> can.Message:
    return can.Message(
        arbitration_id=msg.arbitration_id,
        data=bytes(msg.data),
        is_extended_id=msg.is_extended_id,
        timestamp=msg.timestamp,
        channel=msg.channel,
    )


def _corrupted(msg: can.Message, how: str, value: bytes | None) -> can.Message:
    data = bytearray(msg.data)
    if how == "dlc":
        data = data[:-1]
    elif how == "flip" and data:
        data[-1] ^= 0x80
    elif how == "value":
        data = bytearray(value or b"")
    out = _copy(msg)
    out.data, out.dlc = data, len(data)
    return out
