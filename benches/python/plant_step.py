"""Ticks per second of the rapier plant driven from Python with ``Plant.step_joint_commands`` (one
call for N ticks, GIL released) against the same loop in Rust (``benches/examples/plant_loop.rs``),
and their ratio (issue 11: >= 95 %).

    python benches/python/plant_step.py [ticks] [rounds]

Same plant (nominal robot, PID (400, 2000, 4), seed 0, from home), same commands, fresh plant per
round; the Rust and Python rounds alternate (so both see the same machine load) and the best round of
each is compared.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import rss6


def commands(ticks: int, dt: float) -> np.ndarray:
    """Legs alternating ±0.15 rad sinusoids at 0.5 Hz (as plant_loop.rs)."""
    s = 0.15 * np.sin(np.pi * np.arange(ticks) * dt)
    return np.stack([s if i % 2 == 0 else -s for i in range(6)], axis=1)


def python_rate(ticks: int) -> float:
    """Ticks/s of one round driven from Python."""
    kp, dp = rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal()
    plant = rss6.Plant(kp, dp, pid=(400.0, 2000.0, 4.0), seed=0)
    plant.reset(rss6.home_pose())
    cmds = commands(ticks, plant.dt)
    start = time.perf_counter()
    out = plant.step_joint_commands(cmds)
    rate = ticks / (time.perf_counter() - start)
    assert out["time"].shape == (ticks,)
    return rate


def rust_rate(ticks: int, rounds: int = 1) -> float:
    """Best ticks/s of ``rounds`` rounds of the Rust loop (timed inside the example)."""
    root = Path(__file__).resolve().parents[2]
    run = subprocess.run(
        [
            *("cargo", "run", "--release", "-q", "-p", "rss6-benches", "--example", "plant_loop"),
            *("--", str(ticks), str(rounds)),
        ],
        cwd=root,
        capture_output=True,
        text=True,
        check=True,
    )
    m = re.search(r"best (\d+) ticks/s", run.stdout)
    if m is None:
        raise RuntimeError(f"unexpected output of plant_loop: {run.stdout!r} {run.stderr!r}")
    return float(m.group(1))


def main() -> None:
    ticks = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    rust_rate(100)  # build the example first
    rust, py = [], []
    for _ in range(rounds):
        rust.append(rust_rate(ticks))
        py.append(python_rate(ticks))
    print(f"{ticks} ticks of rss6.Plant, best of {rounds} alternating rounds")
    print(f"rust loop (plant_loop example):  {max(rust):8.0f} ticks/s")
    print(f"python step_joint_commands:      {max(py):8.0f} ticks/s")
    print(f"ratio python / rust:             {max(py) / max(rust):8.1%}  (target >= 95 %)")


if __name__ == "__main__":
    main()
