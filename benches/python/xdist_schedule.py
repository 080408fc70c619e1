"""When a pytest-xdist worksteal run on k workers would end, in file order and in the order
``python/tests/conftest.py`` deals the tests, from the durations of one measured run; optionally
writes ``python/tests/durations.json`` (the tests of at least 5 s) from that run.

    python3 -m pytest python/tests -q -n auto --dist worksteal --durations=0 > durations.log
    python benches/python/xdist_schedule.py durations.log [--workers 2] [--write]

The model of worksteal (pytest-xdist 3.8): each worker gets an equal count of consecutive tests;
a worker with fewer than 2 queued (its running test included) takes the last half of the longest
queue, keeping 2 there. Tests run for their measured call + setup + teardown time, whatever runs
beside them. Forty-first session, the slow machine's run before the order: 1023 s in file order,
981 s dealt (that run took 1032 s; CI 95 and 96 then took 941 and 867 s dealt).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python" / "tests"))
from conftest import DURATIONS, SLOW_S  # noqa: E402  (the order's own file and threshold)

MIN_PENDING = 2  # xdist's worksteal


def measured(log: Path) -> dict[str, float]:
    """Seconds per test id (call + setup + teardown) from a ``--durations=0`` report."""
    out: dict[str, float] = {}
    pat = re.compile(r"([\d.]+)s (?:call|setup|teardown)\s+(python/tests/\S.*)$")
    for line in log.read_text().splitlines():
        m = pat.match(line)
        if m:
            out[m.group(2)] = out.get(m.group(2), 0.0) + float(m.group(1))
    return out


def collection(workers: int | None) -> list[str]:
    """The test ids in the order pytest collects them (as an xdist worker of ``workers``)."""
    env = dict(os.environ)
    env.pop("PYTEST_XDIST_WORKER_COUNT", None)
    if workers is not None:
        env["PYTEST_XDIST_WORKER_COUNT"] = str(workers)
    cmd = [sys.executable, "-m", "pytest", "python/tests", "--collect-only", "-q"]
    out = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    return [line for line in out.stdout.splitlines() if "::" in line]


def worksteal_end(durations: list[float], k: int) -> float:
    """When the last of ``durations`` (in collection order) ends on ``k`` worksteal workers."""
    n = len(durations)
    queues = [list(range(w * (n // k), (w + 1) * (n // k) if w < k - 1 else n)) for w in range(k)]
    end = [durations[q[0]] if q else None for q in queues]
    clock = 0.0
    while any(e is not None for e in end):
        w = min((w for w in range(k) if end[w] is not None), key=lambda w: end[w] or 0.0)
        clock = end[w] or 0.0
        queues[w].pop(0)
        for v in range(k):
            if len(queues[v]) < MIN_PENDING:
                src = max(range(k), key=lambda u: len(queues[u]))
                num = min(len(queues[src]) // 2, max(0, len(queues[src]) - MIN_PENDING))
                if num > 0 and src != v:
                    queues[v].extend(queues[src][-num:])
                    del queues[src][-num:]
        for v in range(k):
            if (v == w or end[v] is None) and queues[v]:
                end[v] = clock + durations[queues[v][0]]
            elif not queues[v]:
                end[v] = None
    return clock


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("log", type=Path, help="output of a pytest --durations=0 run")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--write", action="store_true", help="write python/tests/durations.json")
    args = ap.parse_args()
    took = measured(args.log)
    if not took:
        sys.exit(f"{args.log}: no durations (run pytest with --durations=0)")
    total = sum(took.values())
    if args.write:
        slow = {t: round(s, 1) for t, s in sorted(took.items(), key=lambda x: -x[1]) if s >= SLOW_S}
        DURATIONS.write_text(json.dumps(slow, indent=1) + "\n")
        print(f"wrote {len(slow)} tests of >= {SLOW_S:g} s to {DURATIONS.relative_to(ROOT)}")
    print(
        f"{len(took)} tests measured, {total:.0f} s in all ({total / args.workers:.0f} s per worker)"
    )
    for name, order in (("file order", collection(None)), ("dealt", collection(args.workers))):
        end = worksteal_end([took.get(t, 0.0) for t in order], args.workers)
        print(f"{name}: ends at {end:.0f} s")


if __name__ == "__main__":
    main()
