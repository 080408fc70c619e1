"""The bridge: six CiA 402 drives in Cyclic Synchronous Position over python-can and canopen, with
the bridge's own safety layer (one joint's fault stops all six).

:meth:`Bridge.enable` configures the drives by SDO (heartbeat times, software limits, following
error window), starts them (NMT), walks the 402 state machine to Operation Enabled with RPDO2 and
reads back, by SDO, each state and the mode of operation (canopen's ``op_mode`` setter only logs a
timeout). :meth:`Bridge.step` refuses a bad command before the bus, sends RPDO1 to every drive and a
SYNC on every channel, and returns the latest accepted positions with their ages. Every fault —
watchdog, bus error, EMCY, statusword, refused command — latches a reason, sends Quick Stop
(controlword 0x0002) to all drives, and no target is sent again until :meth:`Bridge.enable` (the
explicit restart). SYNC keeps running so the drives hold their quick-stop positions.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import can
import canopen
import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6.can.busio import BridgeNetwork, BusLog, BusWatch
from rss6.can.config import BridgeConfig
from rss6.can.load import BusLoad, bus_load, check_bus_load
from rss6.can.protocol import (
    BRIDGE_NODE_ID,
    EMCY_CODES,
    MODE_CSP,
    SW_FAULT_BIT,
    CanFaultError,
    Controlword,
    CountMap,
    DriveState,
    FrameError,
    cob,
    eds_path,
    pack_control,
    pack_target,
    split_nodes,
    state_from_statusword,
    unpack_status,
)
from rss6.errors import InvalidInputError

__all__ = ["Bridge", "BridgeConfig", "Reading"]

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Reading:
    """What one :meth:`Bridge.step` returns: ``kappa`` (bit) and ``theta`` (rad, drive convention)
    of the latest accepted TPDO1 per drive, their ``ages`` (cycles), and the latched ``fault``."""

    kappa: F64
    theta: F64
    ages: NDArray[np.int64]
    fault: str | None


class Bridge:
    """Six drives behind one bus or two (``bus_or_buses``: a python-can bus or a list, one per
    channel; node ids split in contiguous groups, e.g. 1–3 and 4–6), configured by ``config``.

    With ``config.bitrate`` set, a configuration above ``config.max_load`` is refused
    (:class:`rss6.can.load.BusLoadError`); ``loads`` holds each channel's :class:`BusLoad`.
    """

    def __init__(
        self, bus_or_buses: can.BusABC | Sequence[can.BusABC], config: BridgeConfig | None = None
    ):
        cfg = config if config is not None else BridgeConfig()
        self.config = cfg
        self.buses = [bus_or_buses] if isinstance(bus_or_buses, can.BusABC) else list(bus_or_buses)
        if len(cfg.node_ids) != 6:
            raise InvalidInputError("a 6-RSS robot needs six drives")
        self.map = cfg.count_map if cfg.count_map is not None else CountMap.nominal()
        self.groups = split_nodes(cfg.node_ids, len(self.buses))
        self.loads: list[BusLoad] = [
            bus_load(
                len(g),
                bitrate=cfg.bitrate or 1_000_000,
                sync_hz=1.0 / cfg.dt,
                tpdo_every=cfg.tpdo_every,
                heartbeat_ms=cfg.heartbeat_ms,
                bridge_heartbeat_ms=cfg.bridge_heartbeat_ms,
            )
            for g in self.groups
        ]
        if cfg.bitrate is not None:
            for load in self.loads:
                check_bus_load(load, cfg.max_load)
        default_timeout = (2 if cfg.lockstep else 5) * cfg.tpdo_every
        self.tpdo_timeout = cfg.tpdo_timeout if cfg.tpdo_timeout is not None else default_timeout
        self.hb_cycles = max(1, round(cfg.bridge_heartbeat_ms * 1e-3 / cfg.dt))
        self.hb_timeout = cfg.heartbeat_timeout * cfg.heartbeat_ms * 1e-3 / cfg.dt
        lo, hi = self.map.to_counts([cfg.limits[0]] * 6), self.map.to_counts([cfg.limits[1]] * 6)
        self.count_limits = (np.minimum(lo, hi), np.maximum(lo, hi))
        cpr = np.abs(self.map.counts_per_radian)
        self.margin_counts = cfg.position_margin * cpr
        self.jump_counts = cfg.v_max * cfg.dt * cpr
        self.noise_counts = cfg.noise_bits * self.map.counts_per_bit
        eds = cfg.eds if cfg.eds is not None else str(eds_path())
        self.networks = [BridgeNetwork(bus) for bus in self.buses]
        for net in self.networks:
            net.NOTIFIER_CYCLE = 0.05  # the notifier thread notices stop() within 50 ms, not 1 s
        self.nodes: list[canopen.RemoteNode] = []
        self.ids: list[int] = []
        self._net_of: list[canopen.Network] = []
        self._lock = threading.Lock()
        self._arrived = threading.Condition(self._lock)
        for ch, ids in enumerate(self.groups):
            net = self.networks[ch]
            for nid in ids:
                j = list(cfg.node_ids).index(nid)
                node = canopen.RemoteNode(nid, canopen.import_od(eds, nid))
                node.sdo.RESPONSE_TIMEOUT = cfg.sdo_timeout
                net.add_node(node)
                net.subscribe(cob.TPDO1 + nid, self._tpdo_handler(j))
                net.subscribe(cob.EMCY + nid, self._emcy_handler(j))
                net.subscribe(cob.HEARTBEAT + nid, self._heartbeat_handler(j))
                self.nodes.append(node)
                self.ids.append(nid)
                self._net_of.append(net)
        order = sorted(range(6), key=lambda k: list(cfg.node_ids).index(self.ids[k]))
        self.nodes = [self.nodes[k] for k in order]
        self.ids = [self.ids[k] for k in order]
        self._net_of = [self._net_of[k] for k in order]
        self.watches: list[BusWatch] = []
        self.loggers: list[BusLog] = []
        self._periodic: list[Any] = []
        self._connected = False
        self.enabled = False
        self._reset_counters()

    # --- lifecycle ------------------------------------------------------------------------------
    def _reset_counters(self) -> None:
        self.cycle = 0
        self.fault: str | None = None
        self.fault_cycle: int | None = None
        self.events: list[str] = []
        self.positions = np.zeros(6, dtype=np.int64)
        self.statuswords = np.zeros(6, dtype=np.int64)
        self.rx_cycle = np.zeros(6, dtype=np.int64)
        self.hb_cycle = np.zeros(6, dtype=np.int64)
        self.rx_seq = np.zeros(6, dtype=np.int64)
        self.accepted = 0
        self.rejected: dict[str, int] = {"dlc": 0, "range": 0, "jump": 0}
        self.lost_waits = 0
        self.refused = 0
        self.commands_sent = 0
        self.syncs_sent = 0
        self.late_cycles = 0
        self.quick_stop_cycle: int | None = None
        self.quick_stop_errors: list[str] = []
        self._last_cmd: NDArray[np.int64] | None = None

    def connect(self) -> Bridge:
        """Starts each network's notifier and adds the error-frame watch and the bus log to it."""
        if self._connected:
            return self
        for ch, net in enumerate(self.networks):
            net.connect()
            assert net.notifier is not None
            watch = BusWatch(self, ch)
            net.notifier.add_listener(watch)
            self.watches.append(watch)
            if self.config.log is not None:
                path = str(self.config.log)
                if len(self.networks) > 1:
                    stem, dot, ext = path.rpartition(".")
                    path = f"{stem}.ch{ch}.{ext}" if dot else f"{path}.ch{ch}"
                log = BusLog(path)
                net.notifier.add_listener(log)
                net.log = log
                self.loggers.append(log)
        self._connected = True
        return self

    def close(self) -> None:
        """Stops the periodic tasks, the notifiers and the bus logs (the buses stay open)."""
        for task in self._periodic:
            task.stop()
        self._periodic = []
        for net in self.networks:
            if net.notifier is not None:
                net.notifier.stop(1.0)
            net.bus = None  # the caller owns the bus
        for net in self.networks:
            net.log = None
        for log in self.loggers:
            log.stop()
        self.loggers = []
        self._connected = False

    def __enter__(self) -> Bridge:
        return self.connect()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def enable(self, timeout: float = 2.0) -> None:
        """The explicit (re)start: configures every drive, walks each to Operation Enabled in CSP
        and reads back state and mode; raises :class:`CanFaultError` naming the drive that does
        not get there. Clears a latched fault and restarts the cycle count."""
        self.connect()
        cfg = self.config
        for task in self._periodic:
            task.stop()
        self._periodic = []
        with self._lock:
            self._reset_counters()
        self.enabled = False
        consumer_ms = math.ceil(cfg.heartbeat_timeout * cfg.bridge_heartbeat_ms)
        lo, hi = self.count_limits
        window = int(np.max(np.rint(cfg.following_error * np.abs(self.map.counts_per_radian))))
        for j, node in enumerate(self.nodes):
            try:
                node.sdo[0x1017].raw = cfg.heartbeat_ms
                node.sdo[0x1016][1].raw = (BRIDGE_NODE_ID << 16) | consumer_ms
                node.sdo[0x607D][1].raw = int(lo[j])
                node.sdo[0x607D][2].raw = int(hi[j])
                node.sdo[0x6065].raw = window
            except (canopen.SdoAbortedError, canopen.SdoCommunicationError, can.CanError) as e:
                raise CanFaultError(f"drive {node.id}: configuration by SDO failed: {e}") from e
            node.nmt.send_command(0x01)  # NMT start: PDOs on, the drive's SYNC counter restarts
        self._send_heartbeat()
        try:
            self._walk_to_enabled(timeout)
        except (canopen.SdoAbortedError, canopen.SdoCommunicationError) as e:
            raise CanFaultError(f"enable: an SDO exchange with the drives failed: {e}") from e
        if not cfg.lockstep:
            self._start_periodic_heartbeat()
        self.enabled = True

    def _walk_to_enabled(self, timeout: float) -> None:
        states = self._read_states()
        for j, st in enumerate(states):
            if st is DriveState.FAULT:
                self._send_control(j, Controlword.FAULT_RESET)
                self._send_control(j, Controlword.DISABLE_VOLTAGE)
            elif st is not DriveState.SWITCH_ON_DISABLED:
                self._send_control(j, Controlword.DISABLE_VOLTAGE)
        self._wait_states(DriveState.SWITCH_ON_DISABLED, timeout)
        self._send_all(Controlword.SHUTDOWN)
        self._wait_states(DriveState.READY_TO_SWITCH_ON, timeout)
        for node in self.nodes:
            mode = int(node.sdo[0x6061].raw)
            if mode != MODE_CSP:
                self._send_all(Controlword.DISABLE_VOLTAGE)
                raise CanFaultError(
                    f"drive {node.id} reports mode of operation {mode}, not {MODE_CSP} (cyclic "
                    "synchronous position): it was not enabled"
                )
        self._send_all(Controlword.SWITCH_ON)
        self._wait_states(DriveState.SWITCHED_ON, timeout)
        self._send_all(Controlword.ENABLE_OPERATION)
        self._wait_states(DriveState.OPERATION_ENABLED, timeout)
        positions = [int(node.sdo[0x6064].raw) for node in self.nodes]  # no lock held over SDO
        with self._lock:
            self.positions[:] = positions

    def _send_control(self, j: int, cw: int) -> None:
        self._net_of[j].send_message(cob.RPDO2 + self.ids[j], pack_control(cw, MODE_CSP))

    def _send_all(self, cw: int) -> None:
        for j in range(6):
            self._send_control(j, cw)

    def _read_states(self) -> list[DriveState | None]:
        return [state_from_statusword(int(n.sdo[0x6041].raw)) for n in self.nodes]

    def _wait_states(self, target: DriveState, timeout: float) -> None:
        end = time.monotonic() + timeout
        while True:
            states = self._read_states()
            if all(s is target for s in states):
                return
            if time.monotonic() > end:
                bad = [
                    (n.id, s.name if s else "?")
                    for n, s in zip(self.nodes, states)
                    if s is not target
                ]
                raise CanFaultError(f"drives did not reach {target.name}: {bad}")
            time.sleep(0.002)

    # --- heartbeats -----------------------------------------------------------------------------
    def _heartbeat_msg(self) -> can.Message:
        return can.Message(
            arbitration_id=cob.HEARTBEAT + BRIDGE_NODE_ID, data=b"\x05", is_extended_id=False
        )

    def _send_heartbeat(self) -> None:
        for ch, net in enumerate(self.networks):
            self._send(net, cob.HEARTBEAT + BRIDGE_NODE_ID, b"\x05", f"heartbeat ch{ch}")

    def _start_periodic_heartbeat(self) -> None:
        for bus in self.buses:
            self._periodic.append(
                bus.send_periodic(self._heartbeat_msg(), self.config.bridge_heartbeat_ms * 1e-3)
            )

    # --- receive side (notifier threads) --------------------------------------------------------
    def _event(self, reason: str) -> None:
        with self._lock:
            self.events.append(reason)
            self._arrived.notify_all()

    def _tpdo_handler(self, j: int) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            with self._lock:
                self.rx_seq[j] += 1
                self._accept_tpdo(j, data)
                self._arrived.notify_all()

        return handler

    def _accept_tpdo(self, j: int, data: bytearray) -> None:
        nid = self.ids[j]
        try:
            sw, pos = unpack_status(data)
        except FrameError:
            self.rejected["dlc"] += 1
            return
        lo, hi = self.count_limits
        if pos < lo[j] - self.margin_counts[j] or pos > hi[j] + self.margin_counts[j]:
            self.rejected["range"] += 1
            return
        since = max(1, self.cycle - int(self.rx_cycle[j]))
        if abs(pos - int(self.positions[j])) > self.jump_counts[j] * since + self.noise_counts:
            self.rejected["jump"] += 1
            return
        self.accepted += 1
        self.positions[j], self.statuswords[j], self.rx_cycle[j] = pos, sw, self.cycle
        if sw & SW_FAULT_BIT:
            self.events.append(f"drive {nid}: statusword 0x{sw:04X} shows a fault")
        elif self.enabled and self.fault is None:
            st = state_from_statusword(sw)
            if st is not DriveState.OPERATION_ENABLED:
                name = st.name if st is not None else f"0x{sw:04X}"
                self.events.append(f"drive {nid}: left Operation Enabled ({name})")

    def _emcy_handler(self, j: int) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            nid = self.ids[j]
            if len(data) >= 2:
                code = int.from_bytes(bytes(data[:2]), "little")
                if code & 0xFF00 == 0:
                    return  # error reset: no new error
                name = EMCY_CODES.get(code, "drive error")
                self._event(f"EMCY 0x{code:04X} ({name}) from drive {nid}")
            else:
                self._event(f"malformed EMCY ({len(data)} bytes) from drive {nid}")

        return handler

    def _heartbeat_handler(self, j: int) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            with self._lock:
                self.hb_cycle[j] = self.cycle
            if self.enabled and len(data) >= 1 and data[0] & 0x7F == 0:
                self._event(f"drive {self.ids[j]} rebooted (boot-up message)")

        return handler

    # --- the cycle ------------------------------------------------------------------------------
    def _send(self, net: canopen.Network, can_id: int, data: bytes, what: str) -> bool:
        try:
            net.send_message(can_id, data)
            return True
        except can.CanError as e:
            self._latch(f"bus error sending {what}: {type(e).__name__}: {e}")
            return False

    def _latch(self, reason: str) -> None:
        """The first fault wins: latch it and quick-stop every drive."""
        if self.fault is not None:
            return
        self.fault, self.fault_cycle = reason, self.cycle
        self.quick_stop_cycle = self.cycle
        for j, nid in enumerate(self.ids):
            try:
                self._net_of[j].send_message(
                    cob.RPDO2 + nid, pack_control(Controlword.QUICK_STOP, MODE_CSP)
                )
            except can.CanError as e:
                self.quick_stop_errors.append(f"drive {nid}: {e}")

    def check_command(self, theta_cmd: ArrayLike, advance: int = 1) -> NDArray[np.int64]:
        """The target counts of ``theta_cmd`` (rad, drive convention), or :class:`InvalidInputError`
        for NaN/inf, INT32 overflow, a joint outside the limits or a step above v_max·dt (per cycle
        elapsed: ``advance``)."""
        th = np.asarray(theta_cmd, dtype=np.float64)
        if th.shape != (6,):
            raise InvalidInputError(f"a joint command has shape (6,), got {th.shape}")
        counts = self.map.to_counts(th)
        lo, hi = self.config.limits
        out = np.nonzero((th < lo) | (th > hi))[0]
        if out.size:
            j = int(out[0])
            raise InvalidInputError(
                f"joint {j + 1} command {th[j]:.4f} rad outside the limits [{lo:.4f}, {hi:.4f}]"
            )
        ref = self._last_cmd if self._last_cmd is not None else self.positions
        step = np.abs(counts - ref) / np.abs(self.map.counts_per_radian)
        allowed = self.config.v_max * self.config.dt * max(1, advance)
        if self._last_cmd is None:
            allowed += self.config.noise_bits * float(
                np.max(np.abs(self.map.to_theta(1) - self.map.to_theta(0)))
            )
        big = np.nonzero(step > allowed * (1 + 1e-9))[0]
        if big.size:
            j = int(big[0])
            raise InvalidInputError(
                f"joint {j + 1} command steps {step[j]:.5f} rad in one cycle, above "
                f"v_max·dt = {allowed:.5f} rad"
            )
        return counts

    def step(self, theta_cmd: ArrayLike, advance: int = 1) -> Reading:
        """One cycle: the command (refused before the bus if bad), RPDO1 ×6, SYNC per channel, the
        watchdogs. ``advance``: cycles since the previous step (a wall-clock runner passes > 1
        after a late cycle: missed cycles are counted, never caught up)."""
        if not self.enabled:
            raise CanFaultError("the bridge is not enabled: call enable() first")
        if advance < 1:
            raise InvalidInputError(f"advance must be >= 1 cycle, got {advance}")
        self.cycle += advance
        self.late_cycles += advance - 1
        cfg = self.config
        self._drain_events()  # an EMCY that arrived since the last cycle stops this cycle's command
        if self.fault is None:
            try:
                counts = self.check_command(theta_cmd, advance)
            except InvalidInputError as e:
                self.refused += 1
                self._latch(f"command refused: {e}")
        if self.fault is None:
            for j, nid in enumerate(self.ids):
                if not self._send(
                    self._net_of[j],
                    cob.RPDO1 + nid,
                    pack_target(int(counts[j])),
                    f"RPDO1 to drive {nid}",
                ):
                    break
            else:
                self.commands_sent += 1
                self._last_cmd = counts
        with self._lock:
            seq0 = self.rx_seq.copy()
        synced = [
            self._send(net, cob.SYNC, b"", f"SYNC on channel {ch}")
            for ch, net in enumerate(self.networks)
        ]
        self.syncs_sent += all(synced)
        if cfg.lockstep and self.cycle % self.hb_cycles == 0:
            self._send_heartbeat()
        # the drives count SYNCs, not cycles: a lost SYNC shifts their TPDO1 phase
        if cfg.lockstep and all(synced) and self.syncs_sent % cfg.tpdo_every == 0:
            live = (self.cycle - self.rx_cycle) <= self.tpdo_timeout
            with self._arrived:
                ok = self._arrived.wait_for(
                    lambda: bool(np.all((self.rx_seq > seq0) | ~live)), cfg.wait_timeout
                )
            self.lost_waits += 0 if ok else 1
        self._watchdogs()
        return self.reading()

    def _drain_events(self) -> None:
        with self._lock:
            events, self.events = self.events, []
        for e in events:
            self._latch(e)

    def _watchdogs(self) -> None:
        self._drain_events()
        for ch, net in enumerate(self.networks):
            exc = net.notifier.exception if net.notifier is not None else None
            if exc is not None:
                self._latch(f"receive thread of channel {ch} died: {exc}")
        for task in self._periodic:
            thread = getattr(task, "thread", None)
            if thread is not None and not thread.is_alive():
                self._latch("heartbeat sender stopped (python-can's periodic task died)")
        if not self.enabled:
            return
        for j, nid in enumerate(self.ids):
            age = self.cycle - int(self.rx_cycle[j])
            if age > self.tpdo_timeout:
                self._latch(f"TPDO1 of drive {nid} is {age} cycles old (limit {self.tpdo_timeout})")
            hb_age = self.cycle - int(self.hb_cycle[j])
            if hb_age > self.hb_timeout:
                self._latch(
                    f"heartbeat of drive {nid} lost ({hb_age} cycles, limit {self.hb_timeout:g})"
                )

    def frames_seen(self) -> int:
        """Frames the drives sent that this side has processed, all channels (a
        :class:`FaultyBus` reports what it dropped, held or added)."""
        seen = sum(w.frames for w in self.watches)
        return seen + sum(int(getattr(bus, "unseen", lambda: 0)()) for bus in self.buses)

    def wait_frames(self, count: int, timeout: float) -> bool:
        """Waits until :meth:`frames_seen` reaches ``count`` (the lockstep fence); False on
        timeout."""
        with self._arrived:
            return self._arrived.wait_for(lambda: self.frames_seen() >= count, timeout)

    def reading(self) -> Reading:
        """The latest accepted positions, their ages and the latched fault."""
        with self._lock:
            counts = self.positions.copy()
            ages = self.cycle - self.rx_cycle
        return Reading(
            self.map.to_kappa(counts),
            self.map.to_theta(counts),
            np.asarray(ages, dtype=np.int64),
            self.fault,
        )

    def stats(self) -> dict[str, Any]:
        """Counters of the run: cycles, commands sent, refused, frames accepted/rejected, lost
        waits (lockstep TPDO waits that timed out), late cycles, frames seen per channel."""
        return {
            "cycles": self.cycle,
            "commands_sent": self.commands_sent,
            "syncs_sent": self.syncs_sent,
            "refused": self.refused,
            "accepted": self.accepted,
            "rejected": dict(self.rejected),
            "lost_waits": self.lost_waits,
            "late_cycles": self.late_cycles,
            "frames": [w.frames for w in self.watches],
            "fault": self.fault,
            "fault_cycle": self.fault_cycle,
        }
