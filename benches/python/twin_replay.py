"""Seconds per 10 s replay of the model twin in the discrepancy workflow (its unit of work): the
no-effect twin case of the benchmark (stick–slip law, 5× magnitude, seed 0), its fitting run
replayed with the recorded commands by ``rss6.discrepancy.model.simulate``. Run on an idle machine.

    python benches/python/twin_replay.py [--repeats 30] [--friction-law implicit|tanh]

``tanh``: the twin cases' default law (f_c tanh(θ̇/ε) at every RK4 stage).

Fortieth session, slow machine: 0.151 s (0.210 s before ``rk4_step_implicit_friction``).
"""

from __future__ import annotations

import argparse
import time

from rss6.discrepancy import benchmark
from rss6.discrepancy import model as m


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--friction-law", choices=("implicit", "tanh"), default="implicit")
    args = ap.parse_args()
    spec = {
        "robot": "twin",
        "friction_law": args.friction_law,
        "magnitude": 5.0,
        "seed": 0,
        "effect": None,
    }
    case = benchmark.hidden_case(spec)
    run = m.run_of(case.fit, commands="recorded")
    t0 = time.perf_counter()
    for _ in range(args.repeats):
        m.simulate(case.model, run)
    per = (time.perf_counter() - t0) / args.repeats
    tick_us = per / run.duration * 1e3
    print(
        f"{args.friction_law}: {run.duration:.1f} s replay: {per:.3f} s ({tick_us:.1f} µs per tick)"
    )


if __name__ == "__main__":
    main()
