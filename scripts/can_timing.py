#!/usr/bin/env python3
"""Prints the cycle statistics of the CAN bridge in wall-clock mode (never asserted anywhere).

Six simulated drives (model twin) on a python-can virtual bus, the bridge at 1 kHz of wall clock
(not lockstep: it uses the latest TPDO1 and its age), a small sinusoid commanded for --seconds.
Usage: python scripts/can_timing.py [--seconds 3]
"""

from __future__ import annotations

import argparse

import can
import numpy as np
import rss6
import rss6.can as rc
from rss6.can.realtime import run_wall_clock


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=3.0)
    args = ap.parse_args()
    plant = rss6.ModelSim(rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal(), seed=0)
    plant.reset(rss6.home_pose())
    drives_bus = can.Bus(interface="virtual", channel="rss6-timing")
    bridge_bus = can.Bus(interface="virtual", channel="rss6-timing")
    sim = rc.SimDrives(plant, drives_bus).start()
    bridge = rc.Bridge(bridge_bus, rc.BridgeConfig(lockstep=False))
    ages: list[int] = []
    try:
        bridge.enable()

        def step(k: int, advance: int) -> None:
            theta = 0.05 * np.sin(2 * np.pi * 0.5 * k * 1e-3) * np.ones(6)
            r = bridge.step(theta, advance)
            ages.append(int(r.ages.max()))

        stats = run_wall_clock(step, args.seconds)
    finally:
        bridge.close()
        sim.stop()
        drives_bus.shutdown()
        bridge_bus.shutdown()
    print(stats)
    a = np.asarray(ages)
    print(
        f"TPDO1 age (cycles): median {np.median(a):.0f}, p99 {np.percentile(a, 99):.0f}, "
        f"max {a.max()}"
    )
    print(f"bridge: {bridge.stats()}")
    print(f"drives: {sim.tick} robot ticks, send errors {sim.tx_errors}")


if __name__ == "__main__":
    main()
