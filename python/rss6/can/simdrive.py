"""Simulated CiA 402 drives behind a CAN bus, wrapping one simulated robot (rapier plant or twin).

Each :class:`SimDrive` is a canopen ``LocalNode`` built from the shipped EDS (SDO server, NMT
slave, EMCY producer) plus what canopen does not do for a local node: the 402 state machine, the
Cyclic Synchronous Position mode, TPDO1, heartbeats counted in SYNCs, the consumer heartbeat of the
bridge (0x1016) and a following-error check (EMCY 0x8611). :class:`SimDrives` owns the robot and
the drives' networks and steps the robot by exactly one tick per SYNC with the six targets latched
before it (lockstep): a run through the bus is as deterministic as the robot itself.

Time on the drives' side is counted in SYNCs (one SYNC = one robot tick = ``dt``): the robot moves
only on SYNC, so heartbeat periods and the consumer timeout are SYNC counts too. Drives in their own
process (``rss6 can-sim``) also watch the bridge's heartbeat on the wall clock, for a bridge that
dies together with its SYNC.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from typing import Any

import can
import canopen
from numpy.typing import ArrayLike

from rss6.can.protocol import (
    BRIDGE_NODE_ID,
    DRIVE_IDS,
    MODE_CSP,
    SW_FOLLOWING_ERROR_BIT,
    CountMap,
    DriveState,
    FrameError,
    cob,
    eds_path,
    pack_status,
    split_nodes,
    unpack_control,
    unpack_target,
)
from rss6.errors import InvalidInputError

__all__ = ["SimDrive", "SimDrives"]

S = DriveState


class _DriveNode(canopen.LocalNode):
    """A LocalNode whose heartbeat the drive produces itself (in SYNCs, not with canopen's timer)."""

    def __init__(self, node_id: int, od: Any):
        super().__init__(node_id, od)
        # canopen's NmtSlave starts a wall-clock periodic heartbeat when 0x1017 is written; the
        # simulated drive counts its heartbeat in SYNCs instead, so that callback is taken out.
        self._write_callbacks.remove(self.nmt.on_write)


class _CountingNetwork(canopen.Network):
    """A canopen network that counts the frames it sent (PDOs, heartbeats, EMCY, SDO answers): the
    bridge's side waits until it has seen as many, so a lockstep cycle ends with every frame the
    drives sent in it processed."""

    def __init__(self, bus: can.BusABC):
        super().__init__(bus)
        self.sent = 0
        self._count_lock = threading.Lock()

    def send_message(self, can_id: int, data: bytes, remote: bool = False) -> None:
        super().send_message(can_id, data, remote)
        with self._count_lock:
            self.sent += 1


class SimDrive:
    """One simulated drive (node ``node_id``, joint ``joint``) of a :class:`SimDrives` group.

    Test hooks: :meth:`silence` (stop heartbeat and TPDOs), :meth:`trip` (a drive fault with EMCY).
    ``quick_stop_tick``: the SYNC count at which the drive received a Quick Stop controlword (None
    if not); ``targets_after_stop``: RPDO1 frames received after that.
    """

    def __init__(self, group: SimDrives, node_id: int, joint: int, modes: Sequence[int]):
        self.group, self.node_id, self.joint = group, node_id, joint
        self.modes = tuple(modes)
        od: Any = canopen.import_od(str(group.eds), node_id)
        self.node = _DriveNode(node_id, od)
        self.node.add_read_callback(self._on_read)  # type: ignore[no-untyped-call]
        self.node.add_write_callback(self._on_write)  # type: ignore[no-untyped-call]
        self.heartbeat_cycles = max(1, round(int(od[0x1017].default) * 1e-3 / group.dt))
        hb = int(od[0x1016][1].default)
        self.consumer_id, self.consumer_cycles = (hb >> 16) & 0x7F, (hb & 0xFFFF) * 1e-3 / group.dt
        self.window = int(od[0x6065].default)
        self.limits = (int(od[0x607D][1].default), int(od[0x607D][2].default))
        self._reset_state()

    def _reset_state(self) -> None:
        self.state = S.SWITCH_ON_DISABLED
        self.mode = 0
        self.controlword = 0
        self.error_code = 0
        self.target: int | None = None
        self.pending_target: int | None = None
        self.position = 0
        self.hold = 0
        self.following_error = False
        self.silenced_heartbeat = False
        self.silenced_tpdo = False
        self.quick_stop_tick: int | None = None
        self.targets_after_stop = 0
        self.bridge_heartbeat_tick: int | None = None
        self.bridge_heartbeat_time: float | None = None
        self.emcy_sent: list[int] = []
        self.sync_count = 0

    # --- test hooks -----------------------------------------------------------------------------
    def silence(self, heartbeat: bool = True, tpdo: bool = True) -> None:
        """Stops this drive's heartbeat and/or TPDO1 (fault injection); :meth:`SimDrives.reset`
        clears it."""
        self.silenced_heartbeat |= heartbeat
        self.silenced_tpdo |= tpdo

    def trip(self, code: int = 0x1000, emcy: bool = True) -> None:
        """A drive fault: the drive enters FAULT (statusword bit 3), holds its position and sends
        EMCY ``code`` unless ``emcy`` is False (then only the statusword shows it)."""
        self._leave_enabled()
        self.state = S.FAULT
        self.error_code = code
        if emcy:
            self.emcy_sent.append(code)
            self.group.send(self, cob.EMCY + self.node_id, self._emcy_payload(code))

    def _emcy_payload(self, code: int) -> bytes:
        return code.to_bytes(2, "little") + bytes([0x21]) + bytes(5)

    # --- object dictionary ----------------------------------------------------------------------
    def statusword(self) -> int:
        sw = self.state.statusword | 0x0200  # bit 9: remote (controlled over the bus)
        return sw | (SW_FOLLOWING_ERROR_BIT if self.following_error else 0)

    def _on_read(self, index: int, subindex: int, od: Any) -> int | None:
        live: dict[int, Callable[[], int]] = {
            0x6041: self.statusword,
            0x6061: lambda: self.mode,
            0x6064: lambda: self.position,
            0x603F: lambda: self.error_code,
            0x6040: lambda: self.controlword,
        }
        fn = live.get(index)
        return None if fn is None else int(fn())

    def _on_write(self, index: int, subindex: int, od: Any, data: bytes) -> None:
        value = od.decode_raw(data)
        if index == 0x1017:
            self.heartbeat_cycles = max(1, round(int(value) * 1e-3 / self.group.dt))
        elif index == 0x1016 and subindex == 1:
            self.consumer_id = (int(value) >> 16) & 0x7F
            self.consumer_cycles = (int(value) & 0xFFFF) * 1e-3 / self.group.dt
        elif index == 0x6065:
            self.window = int(value)
        elif index == 0x607D and subindex in (1, 2):
            lo, hi = self.limits
            self.limits = (int(value), hi) if subindex == 1 else (lo, int(value))

    # --- the 402 state machine ------------------------------------------------------------------
    def _leave_enabled(self) -> None:
        if self.state is S.OPERATION_ENABLED:
            self.hold = self.position
            self.target = self.pending_target = None

    def on_controlword(self, cw: int, mode: int) -> None:
        """RPDO2: modes of operation, then the controlword transition (CiA 402 Fig. 17)."""
        if mode in self.modes:
            self.mode = mode
        rising_reset = cw & 0x80 and not self.controlword & 0x80
        if cw & 0x86 == 0x02 and self.quick_stop_tick is None:
            self.quick_stop_tick = self.group.tick
        self.controlword = cw
        st = self.state
        disable_voltage = cw & 0x02 == 0
        quick_stop = cw & 0x06 == 0x02
        shutdown = cw & 0x87 == 0x06
        switch_on = cw & 0x8F == 0x07
        enable = cw & 0x8F == 0x0F
        new = st
        if st is S.FAULT:
            if rising_reset:
                new = S.SWITCH_ON_DISABLED
                self.error_code, self.following_error = 0, False
        elif st is S.SWITCH_ON_DISABLED:
            if shutdown:
                new = S.READY_TO_SWITCH_ON
        elif st is S.READY_TO_SWITCH_ON:
            if disable_voltage or quick_stop:
                new = S.SWITCH_ON_DISABLED
            elif switch_on:
                new = S.SWITCHED_ON
            elif enable:
                new = S.OPERATION_ENABLED
        elif st is S.SWITCHED_ON:
            if disable_voltage or quick_stop:
                new = S.SWITCH_ON_DISABLED
            elif shutdown:
                new = S.READY_TO_SWITCH_ON
            elif enable:
                new = S.OPERATION_ENABLED
        elif st is S.OPERATION_ENABLED:
            if disable_voltage:
                new = S.SWITCH_ON_DISABLED
            elif quick_stop:
                new = S.QUICK_STOP_ACTIVE
            elif shutdown:
                new = S.READY_TO_SWITCH_ON
            elif switch_on:
                new = S.SWITCHED_ON
        elif st is S.QUICK_STOP_ACTIVE and disable_voltage:
            new = S.SWITCH_ON_DISABLED  # no transition 16: leaving quick stop needs a restart
        if new is not st:
            if st is S.OPERATION_ENABLED:
                self._leave_enabled()
            if new is S.OPERATION_ENABLED:
                self.hold, self.target, self.pending_target = self.position, None, None
            self.state = new

    def on_target(self, counts: int) -> None:
        """RPDO1: a target position, applied at the next SYNC (CSP)."""
        if self.quick_stop_tick is not None:
            self.targets_after_stop += 1
        if self.state is not S.OPERATION_ENABLED:
            return
        lo, hi = self.limits
        self.pending_target = min(max(counts, lo), hi)

    def on_sync(self) -> None:
        self.sync_count += 1
        if self.state is S.OPERATION_ENABLED and self.pending_target is not None:
            self.target = self.pending_target

    def command_counts(self) -> int:
        """The position the drive's PID tracks during the coming tick (counts)."""
        if self.state is S.OPERATION_ENABLED and self.mode == MODE_CSP and self.target is not None:
            return self.target
        return self.hold

    def after_tick(self, tick: int, counts: int) -> None:
        """After the robot moved one tick: following error, bridge watchdog, TPDO1, heartbeat."""
        self.position = counts
        if (
            self.state is S.OPERATION_ENABLED
            and self.target is not None
            and abs(self.target - counts) > self.window
        ):
            self.following_error = True
            self.trip(0x8611)
        seen = self.bridge_heartbeat_tick
        if (
            seen is not None
            and self.consumer_cycles > 0
            and tick - seen > self.consumer_cycles
            and self.state is not S.FAULT
        ):
            self.bridge_heartbeat_tick = None
            self.trip(0x8130)
        operational = self.node.nmt.state == "OPERATIONAL"
        if operational and not self.silenced_tpdo and self.sync_count % self.group.tpdo_every == 0:
            self.group.send(self, cob.TPDO1 + self.node_id, pack_status(self.statusword(), counts))
        if not self.silenced_heartbeat and tick % self.heartbeat_cycles == 0:
            self.group.send(self, cob.HEARTBEAT + self.node_id, bytes([self.nmt_code()]))

    def nmt_code(self) -> int:
        return {"OPERATIONAL": 0x05, "STOPPED": 0x04}.get(self.node.nmt.state, 0x7F)


class SimDrives:
    """Six simulated drives wrapping ``plant`` (anything with ``step_joint_command``,
    ``potentiometers``, ``reset``: :class:`rss6.Plant`, :class:`rss6.ModelSim`), on ``buses`` (one
    python-can bus per channel; drives split in contiguous groups as the bridge splits them).

    ``count_map``: the drives' counts ↔ radian mapping (default: nominal). ``tpdo_every``: TPDO1
    every n-th SYNC. ``modes``: the modes of operation the drives accept (default CSP only).
    ``wall_clock_watch``: also watch the bridge's heartbeat on the wall clock (0x1016 in ms), so a
    bridge that dies with its SYNC faults the drives — for drives in their own process
    (``rss6 can-sim``); lockstep runs leave it off and count SYNCs only.
    """

    def __init__(
        self,
        plant: Any,
        buses: can.BusABC | Sequence[can.BusABC],
        *,
        node_ids: Sequence[int] = DRIVE_IDS,
        count_map: CountMap | None = None,
        tpdo_every: int = 2,
        modes: Sequence[int] = (MODE_CSP,),
        eds: str | None = None,
        wall_clock_watch: bool = False,
    ):
        self.plant = plant
        self.buses = [buses] if isinstance(buses, can.BusABC) else list(buses)
        if len(node_ids) != 6:
            raise InvalidInputError("a 6-RSS robot needs six drives")
        self.map = count_map if count_map is not None else CountMap.nominal()
        self.tpdo_every = int(tpdo_every)
        self.dt = float(plant.dt)
        self.eds = eds if eds is not None else str(eds_path())
        self.tick = 0
        self.tx_errors = 0
        self.errors: list[str] = []
        self._lock = threading.Lock()
        self._ticked = threading.Condition(self._lock)
        self.networks = [_CountingNetwork(bus) for bus in self.buses]
        for net in self.networks:
            net.NOTIFIER_CYCLE = 0.05  # the notifier thread notices stop() within 50 ms, not 1 s
        self.drives: list[SimDrive] = []
        self._net_of: dict[int, canopen.Network] = {}
        self._syncs = [0] * len(self.networks)
        for ch, ids in enumerate(split_nodes(node_ids, len(self.networks))):
            net = self.networks[ch]
            for nid in ids:
                d = SimDrive(self, nid, list(node_ids).index(nid), modes)
                net.add_node(d.node)
                self._net_of[nid] = net
                self.drives.append(d)
                net.subscribe(cob.RPDO1 + nid, self._rx(d, "target"))
                net.subscribe(cob.RPDO2 + nid, self._rx(d, "control"))
                net.subscribe(cob.HEARTBEAT + BRIDGE_NODE_ID, self._rx(d, "heartbeat"))
            net.subscribe(cob.SYNC, self._sync_handler(ch))
            net.subscribe(cob.NMT, self._nmt_handler(ids))
        self.drives.sort(key=lambda d: d.joint)
        self._started = False
        self.wall_clock_watch = wall_clock_watch
        self._watch_stop = threading.Event()
        self._watcher: threading.Thread | None = None

    # --- lifecycle ------------------------------------------------------------------------------
    def start(self) -> SimDrives:
        """Connects the networks (one Notifier each) and sends each drive's boot-up message."""
        if not self._started:
            for net in self.networks:
                net.connect()
            self._started = True
            self._publish_positions()
            for d in self.drives:
                self.send(d, cob.HEARTBEAT + d.node_id, b"\x00")
            if self.wall_clock_watch:
                self._watch_stop.clear()
                self._watcher = threading.Thread(
                    target=self._watch, name="rss6 drives: 0x1016", daemon=True
                )
                self._watcher.start()
        return self

    def _watch(self) -> None:
        """The consumer heartbeat on the wall clock: a drive whose bridge heartbeat (once seen) is
        older than its 0x1016 time faults with EMCY 0x8130."""
        while not self._watch_stop.wait(0.005):
            now = time.monotonic()
            with self._lock:
                for d in self.drives:
                    seen = d.bridge_heartbeat_time
                    limit = d.consumer_cycles * self.dt
                    if (
                        seen is not None
                        and limit > 0
                        and now - seen > limit
                        and d.state is not DriveState.FAULT
                    ):
                        d.bridge_heartbeat_time = d.bridge_heartbeat_tick = None
                        d.trip(0x8130)

    def stop(self) -> None:
        """Stops the notifiers (the buses stay open: their owner shuts them down)."""
        if self._started:
            self._watch_stop.set()
            if self._watcher is not None:
                self._watcher.join(1.0)
                self._watcher = None
            for net in self.networks:
                if net.notifier is not None:
                    net.notifier.stop(1.0)
                net.bus = None  # canopen's disconnect() would shut the caller's bus down
            self._started = False

    def __enter__(self) -> SimDrives:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def reset(self, pose: ArrayLike) -> None:
        """Resets the robot at ``pose`` and every drive to Switch On Disabled (injected faults and
        silences cleared); the clock restarts at SYNC 0."""
        with self._lock:
            self.plant.reset(pose)
            self.tick = 0
            self._syncs = [0] * len(self.networks)
            for d in self.drives:
                d._reset_state()
            self._publish_positions()
            self._ticked.notify_all()

    def _publish_positions(self) -> None:
        counts = self.map.kappa_to_counts(self.plant.potentiometers())
        for d in self.drives:
            d.position = d.hold = int(counts[d.joint])

    # --- bus traffic ----------------------------------------------------------------------------
    def send(self, drive: SimDrive, can_id: int, data: bytes) -> None:
        try:
            self._net_of[drive.node_id].send_message(can_id, data)
        except (can.CanError, RuntimeError) as e:  # a drive does not stop on a failed send
            self.tx_errors += 1
            self.errors.append(f"drive {drive.node_id}: send 0x{can_id:03X} failed: {e}")

    def _rx(self, d: SimDrive, kind: str) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            if kind == "heartbeat":
                d.bridge_heartbeat_tick = self.tick
                d.bridge_heartbeat_time = time.monotonic()
                return
            if d.node.nmt.state != "OPERATIONAL":
                return
            try:
                if kind == "target":
                    d.on_target(unpack_target(data))
                else:
                    d.on_controlword(*unpack_control(data))
            except FrameError:
                d.emcy_sent.append(0x8210)
                self.send(d, cob.EMCY + d.node_id, d._emcy_payload(0x8210))

        return handler

    def _nmt_handler(self, ids: Sequence[int]) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            # NMT start: the drives' SYNC counters (TPDO1 every n-th SYNC) restart with the run
            if len(data) == 2 and data[0] == 0x01:
                for d in self.drives:
                    if d.node_id in ids and data[1] in (0, d.node_id):
                        d.sync_count = 0

        return handler

    def _sync_handler(self, channel: int) -> Any:
        def handler(can_id: int, data: bytearray, timestamp: float) -> None:
            with self._lock:
                self._syncs[channel] += 1
                if min(self._syncs) > self.tick:
                    self._step()

        return handler

    def _step(self) -> None:
        for d in self.drives:
            d.on_sync()
        counts = [d.command_counts() for d in self.drives]
        try:
            self.plant.step_joint_command(self.map.to_theta(counts))
        except Exception as e:  # the robot failed: every drive faults
            self.errors.append(f"robot step failed: {type(e).__name__}: {e}")
            for d in self.drives:
                d.trip(0x1000)
        self.tick += 1
        actual = self.map.kappa_to_counts(self.plant.potentiometers())
        for d in self.drives:
            d.after_tick(self.tick, int(actual[d.joint]))
        self._ticked.notify_all()

    def wait_tick(self, tick: int, timeout: float = 1.0) -> bool:
        """Waits until the robot has made ``tick`` ticks since reset; False on timeout."""
        with self._ticked:
            return self._ticked.wait_for(lambda: self.tick >= tick, timeout)

    @property
    def frames_sent(self) -> int:
        """Frames the drives' side has sent since start, all channels."""
        return sum(net.sent for net in self.networks)

    def states(self) -> list[DriveState]:
        """Each drive's 402 state, joint order."""
        return [d.state for d in self.drives]
