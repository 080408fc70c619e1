"""``rss6 can-sim``: six simulated drives on a bus, for a user's own tools (or a bridge in another
process). Each SYNC steps the simulated robot by one tick; Ctrl-C, SIGTERM or ``--seconds`` stops.

Example, two processes over UDP multicast inside a network namespace (no CAN hardware)::

    unshare -rn sh -c 'ip link set lo up; ip route add 224.0.0.0/4 dev lo;
                       rss6 can-sim --interface udp_multicast --channel 239.74.163.2 & ...'
"""

from __future__ import annotations

import argparse
import signal
import threading
import time
from collections.abc import Sequence
from typing import Any

import can

from rss6._argtypes import count, nonnegative, seed
from rss6.can.protocol import DRIVE_IDS, role_filters, split_nodes

__all__ = ["add_arguments", "make_bus", "run"]


def make_bus(
    interface: str, channel: str, role: str, node_ids: Sequence[int] = DRIVE_IDS
) -> can.BusABC:
    """A python-can bus for one side (``"drives"`` or ``"bridge"``) with that side's
    ``can_filters`` (needed on ``udp_multicast``, where senders receive their own frames)."""
    kwargs: dict[str, Any] = {"can_filters": role_filters(role, node_ids)}
    if interface == "udp_multicast":
        kwargs["fd"] = False  # classic CAN frames
    return can.Bus(interface=interface, channel=channel, **kwargs)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--interface",
        default="virtual",
        help="python-can interface: virtual, udp_multicast, socketcan, … (default virtual)",
    )
    p.add_argument(
        "--channel",
        action="append",
        required=True,
        help="bus channel (repeat for two channels: drives 1-3 on the first, 4-6 on the "
        "second), e.g. vcan0 or the IPv4 group 239.74.163.2",
    )
    p.add_argument(
        "--plant",
        choices=("model", "rapier"),
        default="model",
        help="the simulated robot: analytic-model twin (default) or rapier plant",
    )
    p.add_argument("--seed", type=seed, default=0, help="noise seed (default 0)")
    p.add_argument(
        "--tpdo-every", type=count(1), default=2, help="TPDO1 every n-th SYNC (default 2)"
    )
    p.add_argument(
        "--seconds",
        type=nonnegative,
        default=0.0,
        help="stop after this many seconds of wall clock (default: run until Ctrl-C)",
    )
    p.add_argument("--log", help="also write the drives' side of the bus to this .asc/.log file")


def run(args: argparse.Namespace) -> int:
    import rss6
    from rss6.can.simdrive import SimDrives

    kp, dp = rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal()
    if args.plant == "rapier":
        if rss6.Plant is None:
            raise rss6.Rss6Error("this build of rss6 has no rapier plant: use --plant model")
        plant: Any = rss6.Plant(kp, dp, seed=args.seed)
    else:
        plant = rss6.ModelSim(kp, dp, seed=args.seed)
    plant.reset(rss6.home_pose())
    groups = split_nodes(DRIVE_IDS, len(args.channel))
    buses = [make_bus(args.interface, ch, "drives", ids) for ch, ids in zip(args.channel, groups)]
    loggers: list[Any] = []
    sim = SimDrives(plant, buses, tpdo_every=args.tpdo_every, wall_clock_watch=True)
    try:
        sim.start()
        if args.log:
            for k, net in enumerate(sim.networks):
                path = args.log if len(sim.networks) == 1 else f"{args.log}.ch{k}"
                logger = can.Logger(path)
                assert net.notifier is not None
                net.notifier.add_listener(logger)
                loggers.append(logger)
        print(
            f"rss6 can-sim: drives {', '.join(map(str, DRIVE_IDS))} on {args.interface} "
            f"{', '.join(args.channel)} ({args.plant}); Ctrl-C stops",
            flush=True,
        )
        end = time.monotonic() + args.seconds if args.seconds > 0 else float("inf")
        stop = threading.Event()
        # SIGTERM stops it as Ctrl-C does (a background job of a script ignores SIGINT)
        signal.signal(signal.SIGTERM, lambda signum, frame: stop.set())
        try:
            while time.monotonic() < end and not stop.is_set():
                stop.wait(min(0.1, max(0.0, end - time.monotonic())))
        except KeyboardInterrupt:
            pass
        print(
            f"rss6 can-sim: {sim.tick} ticks, states "
            f"{[s.name for s in sim.states()]}, send errors {sim.tx_errors}",
            flush=True,
        )
        for e in sim.errors[:10]:
            print(f"  {e}")
    finally:
        sim.stop()
        for logger in loggers:
            logger.stop()
        for bus in buses:
            bus.shutdown()
    return 0
