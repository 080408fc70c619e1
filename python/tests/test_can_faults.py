"""rss6.can safety: each fault injected on a virtual bus in lockstep, and the reaction asserted —
quick stop on all six drives within 3 cycles (3 heartbeat periods for a lost heartbeat), the reason
latched, no target sent afterwards, corrupted frames never reaching the controller."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
import rss6

can = pytest.importorskip("can")
pytest.importorskip("canopen")

import rss6.can as rcan  # noqa: E402
from rss6.can import protocol as P  # noqa: E402

HB = 10  # heartbeat period (cycles) of the default configuration


def _plant() -> rss6.ModelSim:
    return rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal(), seed=5)


def _cmd(k: int) -> np.ndarray:
    return 0.05 * np.sin(2 * np.pi * 1.0 * k * 1e-3) * np.ones(6)


def _run(
    robot: rcan.CanRobot, n: int, start: int = 0, cmd: Callable[[int], Any] = _cmd
) -> list[np.ndarray]:
    out = []
    for k in range(start, start + n):
        robot.step_joint_command(cmd(k))
        out.append(robot.potentiometers().copy())
    return out


def _assert_stopped(robot: rcan.CanRobot, injected: int, within: int, match: str) -> None:
    """Fault latched with ``match``; every drive in Quick Stop within ``within`` cycles of
    ``injected``; no RPDO1 reached a drive after it left Operation Enabled."""
    assert robot.fault is not None and match in robot.fault, robot.fault
    b = robot.bridge
    assert b.fault_cycle is not None and b.fault_cycle - injected <= within
    for d in robot.drives:
        assert d.state in (rcan.DriveState.QUICK_STOP_ACTIVE, rcan.DriveState.FAULT), d.state
        assert d.quick_stop_tick is not None and d.quick_stop_tick - injected <= within
        assert d.targets_after_stop == 0
    sent = b.commands_sent
    _run(robot, 20, start=b.cycle)
    assert b.commands_sent == sent  # nothing commanded after the fault
    assert all(d.targets_after_stop == 0 for d in robot.drives)


def test_silent_drive_stops_all_six() -> None:
    with rcan.simulated_robot(_plant()) as robot:
        _run(robot, 50)
        robot.drives[2].silence()
        _run(robot, 3 * HB, start=50)
        _assert_stopped(robot, 50, 3 * HB, "TPDO1 of drive 3")
        assert robot.bridge.fault_cycle is not None and robot.bridge.fault_cycle - 50 <= 5


def test_lost_heartbeat_stops_all_six_within_three_periods() -> None:
    with rcan.simulated_robot(_plant()) as robot:
        _run(robot, 50)
        robot.drives[4].silence(heartbeat=True, tpdo=False)
        _run(robot, 4 * HB, start=50)
        _assert_stopped(robot, 50, 3 * HB, "heartbeat of drive 5 lost")


@pytest.mark.parametrize(("emcy", "match"), [(True, "EMCY 0x8611"), (False, "statusword")])
def test_drive_fault_stops_all_six(emcy: bool, match: str) -> None:
    with rcan.simulated_robot(_plant()) as robot:
        _run(robot, 41)
        robot.drives[0].trip(0x8611, emcy=emcy)
        _run(robot, 5, start=41)
        _assert_stopped(robot, 41, 3, match)


def test_fault_reactions_are_deterministic() -> None:
    """Lockstep covers the fault path too: the same injection gives the same cycles every run."""
    runs = []
    for _ in range(2):
        with rcan.simulated_robot(_plant()) as robot:
            _run(robot, 41)
            robot.drives[0].trip(0x8611)
            _run(robot, 10, start=41)
            runs.append(
                (
                    robot.bridge.fault_cycle,
                    [d.quick_stop_tick for d in robot.drives],
                    robot.fence_timeouts,
                )
            )
    # latched at the start of cycle 42: the quick stop reaches the drives before SYNC 42 (tick 41)
    assert runs[0] == runs[1] == (42, [41] * 6, 0)


def test_real_following_error_sends_emcy() -> None:
    with rcan.simulated_robot(_plant()) as robot:
        robot.bridge.nodes[3].sdo[0x6065].raw = 1  # a one-count window: any lag trips the drive
        _run(robot, 30)
        assert robot.fault is not None and "EMCY 0x8611 (following error) from drive 4" in (
            robot.fault
        )
        assert robot.drives[3].state is rcan.DriveState.FAULT
        _assert_stopped(robot, robot.drives[3].quick_stop_tick or 0, 30, "0x8611")


def test_bridge_heartbeat_lost_drives_fault_themselves() -> None:
    faulty: list[rcan.FaultyBus] = []

    def wrap(bus: can.BusABC) -> can.BusABC:
        faulty.append(rcan.FaultyBus(bus))
        return faulty[-1]

    with rcan.simulated_robot(_plant(), bridge_bus=wrap) as robot:
        _run(robot, 40)
        faulty[0].drop_sends(count=10_000, can_id=0x700 + P.BRIDGE_NODE_ID)
        _run(robot, 4 * HB, start=40)
        assert robot.fault is not None and "0x8130" in robot.fault
        assert robot.bridge.fault_cycle is not None and robot.bridge.fault_cycle - 40 <= 3 * HB + 3


@pytest.mark.parametrize(
    ("inject", "match"),
    [
        (lambda fb: fb.fail_sends(can_id=0x203), "bus error sending RPDO1 to drive 3"),
        (lambda fb: fb.fail_sends(can_id=0x080), "bus error sending SYNC"),
        (lambda fb: fb.error_frame(), "error frame on channel 0"),
        (lambda fb: fb.drop(count=3, can_id=0x186), "TPDO1 of drive 6"),
    ],
)
def test_bus_faults_stop_all_six(inject: Callable[[rcan.FaultyBus], None], match: str) -> None:
    faulty: list[rcan.FaultyBus] = []

    def wrap(bus: can.BusABC) -> can.BusABC:
        faulty.append(rcan.FaultyBus(bus))
        return faulty[-1]

    with rcan.simulated_robot(_plant(), bridge_bus=wrap) as robot:
        _run(robot, 30)
        inject(faulty[0])
        _run(robot, 10, start=30)
        _assert_stopped(robot, 30, 8 if "TPDO1" in match else 3, match)


def test_single_losses_duplicates_and_delays_are_tolerated() -> None:
    faulty: list[rcan.FaultyBus] = []

    def wrap(bus: can.BusABC) -> can.BusABC:
        faulty.append(rcan.FaultyBus(bus))
        return faulty[-1]

    with rcan.simulated_robot(_plant(), bridge_bus=wrap) as robot:
        fb = faulty[0]
        _run(robot, 20)
        fb.drop(count=1, can_id=0x182)
        _run(robot, 10, start=20)
        fb.duplicate(count=2, can_id=0x183)
        fb.delay(count=1, can_id=0x184, frames=3)
        _run(robot, 20, start=30)
        assert robot.fault is None
        assert fb.counts["dropped"] == 1 and fb.counts["duplicated"] == 2
        assert robot.bridge.stats()["lost_waits"] >= 1  # the dropped frame was waited for


@pytest.mark.parametrize(
    ("how", "value", "kind"),
    [
        ("dlc", None, "dlc"),
        ("value", P.pack_status(0x0237, 2**30), "range"),
        ("value", P.pack_status(0x0237, 60_000), "jump"),
    ],
)
def test_corrupted_frames_never_reach_the_controller(
    how: str, value: bytes | None, kind: str
) -> None:
    faulty: list[rcan.FaultyBus] = []

    def wrap(bus: can.BusABC) -> can.BusABC:
        faulty.append(rcan.FaultyBus(bus))
        return faulty[-1]

    with rcan.simulated_robot(_plant(), bridge_bus=wrap) as robot:
        before = _run(robot, 20)
        faulty[0].corrupt(count=1, can_id=0x181, how=how, value=value)  # type: ignore[arg-type]
        after = _run(robot, 20, start=20)
        assert robot.fault is None
        assert robot.bridge.rejected[kind] == 1 and faulty[0].counts["corrupted"] == 1
    kappa = np.array(before + after)[:, 0]
    corrupt_kappa = P.unpack_status(value)[1] / 256 if value else None
    assert corrupt_kappa is None or not np.any(kappa == corrupt_kappa)
    assert np.max(np.abs(np.diff(kappa))) < 20  # bits: no jump reached the readings


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        (lambda c: np.where(np.arange(6) == 1, np.nan, c), "NaN"),
        (lambda c: np.where(np.arange(6) == 2, np.inf, c), "NaN or infinity"),
        (lambda c: np.where(np.arange(6) == 3, 2.0, c), "joint 4 command 2.0000 rad outside"),
        (lambda c: c + np.where(np.arange(6) == 4, 0.2, 0.0), "joint 5 command steps"),
        (lambda c: np.where(np.arange(6) == 0, 1e9, c), "INT32"),
    ],
)
def test_bad_commands_are_refused_before_the_bus(
    bad: Callable[[np.ndarray], np.ndarray], match: str
) -> None:
    with rcan.simulated_robot(_plant()) as robot:
        _run(robot, 30)
        robot.step_joint_command(bad(_cmd(30)))
        assert robot.bridge.refused == 1
        _assert_stopped(robot, 31, 1, "command refused")
        assert robot.fault is not None and match in robot.fault


def test_restart_only_by_an_explicit_reset() -> None:
    with rcan.simulated_robot(_plant()) as robot:
        _run(robot, 20)
        robot.drives[1].trip(0x1000)
        _run(robot, 10, start=20)
        reason = robot.fault
        assert reason is not None and "0x1000" in reason
        _run(robot, 10, start=30)
        assert robot.fault == reason  # latched: the first reason stays
        robot.reset(rss6.home_pose())
        assert robot.fault is None and robot.time == 0.0
        assert all(d.state is rcan.DriveState.OPERATION_ENABLED for d in robot.drives)
        _run(robot, 20)
        assert robot.fault is None and robot.bridge.commands_sent == 20


# python-can's sender thread dies with the injected exception: that death is what is tested
@pytest.mark.filterwarnings("ignore::pytest.PytestUnhandledThreadExceptionWarning")
def test_dead_periodic_heartbeat_task_is_a_fault() -> None:
    """Wall-clock mode: python-can's threaded periodic sender dies on its first send error; the
    bridge's supervision notices it at the next cycle (no timing asserted)."""
    buses = [can.Bus(interface="virtual", channel="rss6-periodic") for _ in range(2)]
    fb = rcan.FaultyBus(buses[1])
    plant = _plant()
    plant.reset(rss6.home_pose())
    sim = rcan.SimDrives(plant, buses[0]).start()
    bridge = rcan.Bridge(fb, rcan.BridgeConfig(lockstep=False, heartbeat_timeout=1000.0))
    try:
        bridge.enable()
        fb.fail_sends(count=1, can_id=0x77F)
        end = time.monotonic() + 5.0
        while bridge.fault is None and time.monotonic() < end:
            bridge.step(np.zeros(6))
            time.sleep(0.002)
        assert bridge.fault is not None and "periodic task died" in bridge.fault, bridge.fault
    finally:
        bridge.close()
        sim.stop()
        fb.shutdown()
        buses[0].shutdown()


def test_drives_in_their_own_process_fault_when_the_bridge_dies() -> None:
    """``wall_clock_watch`` (what ``rss6 can-sim`` uses): once the bridge's heartbeat and SYNC stop,
    each drive's 0x1016 (25 ms) expires on the wall clock and it faults with EMCY 0x8130."""
    buses = [can.Bus(interface="virtual", channel="rss6-dead-bridge") for _ in range(2)]
    plant = _plant()
    plant.reset(rss6.home_pose())
    sim = rcan.SimDrives(plant, buses[0], wall_clock_watch=True).start()
    bridge = rcan.Bridge(buses[1])
    try:
        bridge.enable()
        for k in range(20):
            bridge.step(_cmd(k))
        bridge.close()  # the bridge is gone: no heartbeat, no SYNC
        end = time.monotonic() + 5.0
        while time.monotonic() < end and not all(
            d.state is rcan.DriveState.FAULT for d in sim.drives
        ):
            time.sleep(0.01)
        assert all(d.state is rcan.DriveState.FAULT for d in sim.drives)
        assert all(0x8130 in d.emcy_sent for d in sim.drives)
    finally:
        bridge.close()
        sim.stop()
        for bus in buses:
            bus.shutdown()


def test_a_drive_that_cannot_send_is_stopped_with_the_others() -> None:
    """Faults on the drives' side of the bus (a FaultyBus there): drive 3's TPDO1 sends fail."""
    faulty: list[rcan.FaultyBus] = []

    def wrap(bus: can.BusABC) -> can.BusABC:
        faulty.append(rcan.FaultyBus(bus))
        return faulty[-1]

    with rcan.simulated_robot(_plant(), drive_bus=wrap) as robot:
        _run(robot, 30)
        faulty[0].fail_sends(count=1000, can_id=0x183)
        _run(robot, 10, start=30)
        assert robot.sim is not None and robot.sim.tx_errors >= 2
        assert robot.fence_timeouts == 0
        _assert_stopped(robot, 30, 8, "TPDO1 of drive 3")
