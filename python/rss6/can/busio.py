"""Bus-level helpers of the bridge: a canopen network that logs what it sends, and a thread-safe bus
log (python-can's ``Logger``) holding both directions, and the listener that counts frames and turns
error frames into bridge faults."""

from __future__ import annotations

import threading
import time
from typing import TYPE_CHECKING

import can
import canopen

if TYPE_CHECKING:
    from rss6.can.bridge import Bridge

__all__ = ["BridgeNetwork", "BusLog", "BusWatch"]


class BusLog(can.Listener):
    """python-can's ``Logger`` for one channel, fed the received frames by the notifier and the
    sent ones by :class:`BridgeNetwork` (a bus does not receive its own frames), under a lock."""

    def __init__(self, path: str):
        self.logger = can.Logger(path)
        self._lock = threading.Lock()

    def on_message_received(self, msg: can.Message) -> None:
        with self._lock:
            self.logger.on_message_received(msg)

    def stop(self) -> None:
        with self._lock:
            self.logger.stop()


class BridgeNetwork(canopen.Network):
    """A canopen network that also logs what it sends (the bus log holds both directions)."""

    def __init__(self, bus: can.BusABC):
        super().__init__(bus)
        self.log: BusLog | None = None

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        super().send_message(can_id, data, remote)
        if self.log is not None:
            self.log.on_message_received(
                can.Message(
                    timestamp=time.time(),
                    arbitration_id=can_id,
                    data=bytes(data),
                    is_extended_id=can_id > 0x7FF,
                    is_remote_frame=remote,
                    is_rx=False,
                )
            )


class BusWatch(can.Listener):
    """On a network's notifier: counts frames and turns error frames into bridge faults."""

    def __init__(self, bridge: Bridge, channel: int):
        self.bridge, self.channel = bridge, channel
        self.frames = 0

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame:
            self.bridge._event(f"error frame on channel {self.channel}")
        with self.bridge._arrived:  # after canopen's handlers: the frame is fully processed
            self.frames += 1
            self.bridge._arrived.notify_all()

    def on_error(self, exc: Exception) -> None:
        self.bridge._event(f"receive error on channel {self.channel}: {exc}")
