"""Scaling of the Dask studies (issue 16): the same 16-task calibration study (rapier plant, 0.5 s
dwells) on a LocalCluster of 1 and of 2 process workers — the ratio of wall times in one run — and
the per-task overhead of Dask against a plain loop over the same task function (a task that does
nothing).

    python benches/python/dask_scaling.py [--tasks 16] [--dwell 0.5]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from rss6 import studies
from rss6.studies.engine import probe_task, run_study


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--tasks", type=int, default=16)
    ap.add_argument("--dwell", type=float, default=0.5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        wall = {}
        for w in (1, 2):
            t0 = time.perf_counter()
            df = studies.calibration_study(
                args.tasks,
                out=Path(d) / f"cal{w}.csv",
                workers=w,
                plant=True,
                dwell=args.dwell,
                candidates=400,
                progress=False,
            )
            wall[w] = time.perf_counter() - t0
            ok = int((df["status"] == "ok").sum())
            print(
                f"{args.tasks} calibration tasks (rapier plant), {w} worker(s): "
                f"{wall[w]:.1f} s ({ok} ok)",
                flush=True,
            )
        print(f"speed-up 2 workers / 1 worker: {wall[1] / wall[2]:.2f}×")
        n = 200
        specs = [{"spec_id": f"p{k}"} for k in range(n)]
        t0 = time.perf_counter()
        for s in specs:
            probe_task(s)
        loop = (time.perf_counter() - t0) / n
        from dask.distributed import Client, LocalCluster

        with (
            LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
            ) as cluster,
            Client(cluster) as client,
        ):
            t0 = time.perf_counter()
            run_study(
                probe_task,
                specs,
                out=Path(d) / "probe.csv",
                fields=[],
                client=client,
                progress=False,
            )
            dask = (time.perf_counter() - t0) / n
        print(
            f"per-task cost of an empty task: plain loop {1e6 * loop:.1f} µs, Dask (2 workers, "
            f"CSV record flushed per task) {1e3 * dask:.2f} ms"
        )


if __name__ == "__main__":
    main()
