"""A wall-clock runner for real drives: one cycle per period (1 kHz), late cycles counted, missed
cycles skipped — never caught up with a burst of commands — and the cycle statistics it reports.

CI never asserts wall-clock figures: ``scripts/can_timing.py`` prints them. On this project's shared
2-core CI machine a Python 1 kHz loop gives a median period of 1.0 ms, a p99 of ≈ 2.7 ms and ≈ 3 %
late cycles; real hardware wants a quiet core (``taskset``/``chrt``) or a compiled loop.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rss6.errors import InvalidInputError

__all__ = ["CycleStats", "run_wall_clock"]


@dataclass(frozen=True)
class CycleStats:
    """Cycle statistics of a wall-clock run: ``cycles`` run, ``skipped`` (missed, not caught up),
    ``late`` (started more than half a period after their deadline), start-to-start ``median``,
    ``p99`` and ``max`` periods (s)."""

    period: float
    cycles: int
    skipped: int
    late: int
    median: float
    p99: float
    max: float

    def __str__(self) -> str:
        return (
            f"{self.cycles} cycles at {1 / self.period:.0f} Hz: median {1e3 * self.median:.3f} ms, "
            f"p99 {1e3 * self.p99:.3f} ms, max {1e3 * self.max:.3f} ms, late {self.late} "
            f"({100 * self.late / max(self.cycles, 1):.1f} %), skipped {self.skipped}"
        )


def run_wall_clock(
    step: Callable[[int, int], object],
    duration: float,
    period: float = 1e-3,
    *,
    spin: float = 2e-4,
) -> CycleStats:
    """Calls ``step(cycle, advance)`` once per ``period`` for ``duration`` seconds of wall clock.
    ``advance`` is 1, or 1 + the number of whole periods missed before this cycle (those cycles are
    skipped and counted, the schedule moves on: ``Bridge.step(theta, advance)`` fits). The last
    ``spin`` seconds before a deadline are busy-waited for a tighter start."""
    if not (period > 0 and duration > 0):
        raise InvalidInputError("period and duration must be > 0")
    n = round(duration / period)
    starts: list[float] = []
    skipped = late = 0
    t0 = time.perf_counter()
    k = 0
    while k < n:
        deadline = t0 + k * period
        now = time.perf_counter()
        if now < deadline - spin:
            time.sleep(deadline - spin - now)
        while (now := time.perf_counter()) < deadline:
            pass
        behind = int((now - deadline) / period)
        if behind:
            skipped += behind
            k += behind
            deadline += behind * period
        if now - deadline > 0.5 * period:
            late += 1
        step(k, 1 + behind)
        starts.append(now)
        k += 1
    d = np.diff(np.asarray(starts)) if len(starts) > 1 else np.zeros(1)
    return CycleStats(
        period,
        len(starts),
        skipped,
        late,
        float(np.median(d)),
        float(np.percentile(d, 99)),
        float(np.max(d)),
    )
