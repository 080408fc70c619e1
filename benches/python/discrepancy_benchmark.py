"""Hidden-effect benchmark of the discrepancy workflow (issue 14): every case of
:func:`rss6.discrepancy.benchmark.cases` on a process pool, records to a CSV as they finish, and the
summary (per hidden effect × magnitude: named right, ambiguous, unexplained; no-effect false
positives). For the same study on Dask: ``rss6 study discrepancy``.

    python benches/python/discrepancy_benchmark.py [--robot twin|plant] [--null 100] [--workers 2]
        [--seeds 0] [--friction table|none] [--friction-law tanh|implicit]
        [--commands recorded|simulated] [--solver-iterations 100] [--hold-nominal]
        [--model-error] [--no-bias-refresh] [--effects backlash ... | none]
        [--out out/discrepancy_benchmark.csv]
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from rss6.discrepancy.benchmark import benchmark_case, cases, summary


def _one_thread() -> None:
    os.environ["RAYON_NUM_THREADS"] = "1"


def _effect_key(effect: object) -> str | None:
    """A spec's effect as ``--effects`` names it: a pair joined by "+"."""
    return "+".join(effect) if isinstance(effect, list) else effect  # type: ignore[return-value]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--robot", default="twin", choices=("twin", "plant"))
    ap.add_argument("--null", type=int, default=100)
    ap.add_argument("--friction", default="table", choices=("table", "none"))
    ap.add_argument(
        "--friction-law",
        default=None,
        choices=("tanh", "implicit"),
        help="default: implicit on the plant, tanh on the twin",
    )
    ap.add_argument("--commands", default="recorded", choices=("recorded", "simulated"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--magnitudes", type=float, nargs="+", default=[1.0, 2.0, 5.0])
    ap.add_argument(
        "--solver-iterations",
        type=int,
        default=None,
        help="the plant's solver iterations with the implicit law (default 100; ids tagged -itN)",
    )
    ap.add_argument(
        "--hold-nominal",
        action="store_true",
        help="hold the model's friction and gains (default: refitted inside NOMINAL_SPREAD)",
    )
    ap.add_argument(
        "--model-error",
        action="store_true",
        help="the model's friction and gains drawn from the nominal refit's prior around the\n"
        "truth (default: the model is the truth)",
    )
    ap.add_argument(
        "--bias-refresh",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="refit each candidate against the loop's bias at its values (diagnose(bias_refresh=),\n"
        "the default; --no-bias-refresh takes the bias of the model as given)",
    )
    ap.add_argument(
        "--pot-noise",
        default="none",
        choices=("none", "recorded"),
        help="replay the robot's estimated potentiometer noise in the model's drive (run_of)",
    )
    ap.add_argument(
        "--effects",
        nargs="+",
        default=None,
        help="run only the cases hiding these effects (a spec's 'effect', e.g. backlash; a pair\n"
        "joined by '+', e.g. camera_latency+base_tilt; 'none' for the no-effect runs)",
    )
    ap.add_argument("--out", default="out/discrepancy_benchmark.csv")
    args = ap.parse_args()
    specs = cases(
        magnitudes=args.magnitudes,
        seeds=args.seeds,
        n_null=args.null,
        robot=args.robot,
        friction=args.friction,
        friction_law=args.friction_law,
        commands=args.commands,
        solver_iterations=args.solver_iterations,
        hold_nominal=args.hold_nominal,
        model_error=args.model_error,
        bias_refresh=args.bias_refresh,
        pot_noise=args.pot_noise,
    )
    if args.effects is not None:
        wanted = [None if e == "none" else e for e in args.effects]
        specs = [s for s in specs if _effect_key(s.get("effect")) in wanted]
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    done = set()
    if out.exists():
        with out.open() as f:
            done = {r["spec_id"] for r in csv.DictReader(f)}
    todo = [s for s in specs if s["spec_id"] not in done]
    print(f"{len(specs)} cases, {len(done)} already in {out}, {len(todo)} to run", flush=True)
    t0 = time.perf_counter()
    # One thread per worker process: the Rust side would otherwise also use every core for
    # each process (CLOE's stages ahead and its speculative trials; docs/identification.md).
    with ProcessPoolExecutor(args.workers, initializer=_one_thread) as pool:
        futs = [pool.submit(benchmark_case, s) for s in todo]
        for k, fut in enumerate(as_completed(futs), 1):
            try:
                rec = fut.result()
            except Exception as e:  # a case that fails is reported, the rest go on
                print(f"case failed: {type(e).__name__}: {e}", flush=True)
                continue
            new = not out.exists()
            if not new:
                with out.open() as f:
                    fields = next(csv.reader(f))
                rec = {k: rec.get(k, "") for k in fields}
            with out.open("a", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(rec))
                if new:
                    w.writeheader()
                w.writerow(rec)
            print(
                f"[{k}/{len(todo)} {time.perf_counter() - t0:6.0f}s] {rec['hidden']} "
                f"×{rec['magnitude']} (reached {float(rec.get('reached') or 0):.2f}) -> {rec['verdict']}",
                flush=True,
            )
    summarise(out)
    return 0


def summarise(path: Path) -> None:
    """Prints :func:`rss6.discrepancy.benchmark.summary` of the CSV."""
    with path.open() as f:
        print(summary(list(csv.DictReader(f))))


if __name__ == "__main__":
    sys.exit(main())
