"""The cases `next_best_fit.patch` was measured on (docs/discrepancy.md, "The plant's solver
iterations"): payload and tilt at 2× and 5× with the out-of-library cases and pairs on the plant
(48 solver iterations, implicit law), or at 1×, 2×, 5× with 10 no-effect runs on the twin.

    python benches/experiments/next_best_fit_cases.py plant|twin
"""

import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

from rss6.discrepancy.benchmark import benchmark_case, cases


def one():
    os.environ["RAYON_NUM_THREADS"] = "1"


def main():
    robot = sys.argv[1]
    if robot == "twin":
        specs = cases(
            effects=["payload", "base_tilt"], magnitudes=(1.0, 2.0, 5.0), n_null=10, robot="twin"
        )
    else:
        specs = cases(
            effects=["payload", "base_tilt"],
            magnitudes=(2.0, 5.0),
            n_null=0,
            robot="plant",
            friction_law="implicit",
        )
    t0 = time.time()
    with ProcessPoolExecutor(2, initializer=one) as pool:
        for spec, rec in zip(specs, pool.map(benchmark_case, specs)):
            print(
                f"{time.time() - t0:6.0f}s {spec['spec_id']}: {rec['verdict']} | {rec.get('notes', '')[:300]}",
                flush=True,
            )


if __name__ == "__main__":
    main()
