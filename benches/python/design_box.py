"""How large may the exciting trajectory be? The design of ``rss6 identify --simulate`` (DE on the
torque regressor's O_in, 30 generations) inside two boxes of the free coefficients, each
collected on the rapier plant (Table 5.2 truth, stick–slip law at 48 solver iterations,
identification drive) and identified by CLOE from the thesis's initial model through the linear
start (l_p known): the setting of the CLI, for several seeds.

Prints per box and seed the regressor's O_in, CLOE's iterations and seconds, and for f_c, f_v and
(l_i, l_d) the RMS of the relative errors against the truth and the median reported σ; then the
medians over the seeds that converged and how many did not (CLOE's ``IdentificationError``), and per
group the ratio of each quantity's reported σ (RMS over the runs) to the spread (standard deviation)
of its estimates over the runs — issue 13's "predicted σ within ±20 % of the spread"; with 10 runs
a right σ gives a ratio anywhere in about [0.68, 1.83]. Camera and potentiometer noise differ per
seed, the plant and truth do not.

    python benches/python/design_box.py [--seeds 10] [--start 0] [--boxes 0.001,0.005 0.002,0.01]
        [--periods 1] [--noise table|frames]

``--periods N``: collect N periods of each design (the CLI collects three since the tenth session)
and identify on all. ``--hops DELTA ...``: CLOE's hops (`identify.cloe(hops=...)`).
``--pot-noise recorded|model``: the replayed potentiometer noise (`identify.cloe(pot_noise=...)`;
the CLI's is ``recorded``). ``--noise frames``: CLOE whitened by the frames' covariance
(`identify.cloe(noise="frames")`; default ``table``, Table 4.1's per-axis weights).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import rss6
from rss6 import identify, identify_sim
from rss6.identify_report import quantities

GROUPS = {
    "f_c": lambda n: n.startswith("fc"),
    "f_v": lambda n: n.startswith("fv"),
    "l_i, l_d": lambda n: n in ("li", "ld"),
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--start", type=int, default=0, help="first seed")
    ap.add_argument("--boxes", nargs="+", default=["0.001,0.005", "0.002,0.01"])
    ap.add_argument("--periods", type=int, default=1)
    ap.add_argument("--hops", type=float, nargs="*", default=[], metavar="DELTA")
    ap.add_argument("--pot-noise", choices=("recorded", "model"), default="recorded")
    ap.add_argument("--noise", choices=("table", "frames"), default="table")
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp_true, pid_true = identify.table_5_2_truth()
    names = identify.parameter_names()
    truth = dict(zip(names, quantities(dp_true, pid_true), strict=True))
    summary: dict[str, list[list[float]]] = {}
    failed: dict[str, int] = {}
    infeasible: dict[str, int] = {}
    per_q: dict[str, dict[str, list[tuple[float, float]]]] = {}
    for box in args.boxes:
        lo, hi = (float(v) for v in box.split(","))
        rows = summary.setdefault(box, [])
        for seed in range(args.start, args.start + args.seeds):
            t0 = time.perf_counter()
            try:
                exc = identify.excitation(kp, seed=seed, maxiter=30, amplitude=(lo, hi))
            except rss6.IdentificationError as err:
                infeasible[box] = infeasible.get(box, 0) + 1
                print(f"box {box} seed {seed}: no design: {str(err)[:70]}…", flush=True)
                continue
            t_design = time.perf_counter() - t0
            data = identify_sim.collect_on_plant(exc, seed=seed, periods=args.periods)
            if data.fault is not None:
                print(f"box {box} seed {seed}: the plant faulted ({data.fault})")
                continue
            t0 = time.perf_counter()
            try:
                res = identify_sim.estimate_from_initial(
                    data,
                    kp,
                    lp=pid_true[0],
                    hops=tuple(args.hops),
                    pot_noise=args.pot_noise,
                    noise=None if args.noise == "table" else args.noise,
                )
            except rss6.IdentificationError as err:
                failed[box] = failed.get(box, 0) + 1
                print(f"box {box} seed {seed}: {str(err)[:60]}…", flush=True)
                continue
            secs = time.perf_counter() - t0
            est = dict(zip(names, quantities(res.dynamics, res.pid), strict=True))
            std = dict(zip(res.identified, res.relative_std, strict=True))
            row: list[float] = [exc.observability, res.iterations, secs, t_design]
            parts = []
            for g, keep in GROUPS.items():
                sel = [n for n in names if keep(n) and n in std]
                err = float(np.sqrt(np.mean([(est[n] / truth[n] - 1) ** 2 for n in sel])))
                sig = float(np.median([std[n] for n in sel]))
                row += [err, sig]  # 4 + 2k, 5 + 2k
                parts.append(f"{g}: RMS error {100 * err:.1f} %, σ {100 * sig:.1f} %")
            for n in std:
                if any(keep(n) for keep in GROUPS.values()):
                    per_q.setdefault(box, {}).setdefault(n, []).append(
                        (est[n] / truth[n] - 1, std[n])
                    )
            ld = est["ld"] / truth["ld"] - 1
            row.append(abs(ld))
            rows.append(row)
            print(
                f"box {box} seed {seed}: design {t_design:.1f} s, O_in {exc.observability:.4f}, "
                f"{res.iterations} iterations "
                f"({res.converged_by}), {secs:.1f} s, χ² {res.reduced_chi2:.2f}"
                + (f" (hops: {' → '.join(f'{c:.2f}' for c in res.hops)})" if res.hops else "")
                + "; "
                + "; ".join(parts)
                + f"; l_d {100 * ld:+.1f} %",
                flush=True,
            )
    print("\nmedians over the seeds")
    for box in args.boxes:
        rows = summary.get(box, [])
        counts = (
            f"{len(rows)} converged, {failed.get(box, 0)} not, "
            f"{infeasible.get(box, 0)} without a feasible design"
        )
        if not rows:
            print(f"box {box} ({counts})")
            continue
        m = np.median(np.array(rows), axis=0)
        print(
            f"box {box} ({counts}): design {m[3]:.1f} s, O_in {m[0]:.4f}, {m[1]:.0f} iterations, "
            f"{m[2]:.1f} s; "
            + "; ".join(
                f"{g}: RMS error {100 * m[4 + 2 * k]:.1f} %, σ {100 * m[5 + 2 * k]:.1f} %"
                for k, g in enumerate(GROUPS)
            )
            + f"; |l_d error| {100 * m[10]:.1f} % (worst {100 * max(r[10] for r in rows):.1f} %)"
        )
        # The "predicted σ within ±20 % of the spread": RMS of the reported relative σ
        # over the runs against the standard deviation of the relative estimates.
        parts = []
        for g, keep in GROUPS.items():
            ratios = [
                float(
                    np.sqrt(np.mean(np.square([sg for _, sg in v])))
                    / np.std([e for e, _ in v], ddof=1)
                )
                for n, v in per_q.get(box, {}).items()
                if keep(n) and len(v) >= 3
            ]
            if ratios:
                inside = sum(0.8 <= r <= 1.2 for r in ratios)
                parts.append(
                    f"{g} {min(ratios):.2f}–{max(ratios):.2f} ({inside}/{len(ratios)} within ±20 %)"
                )
        print("   σ / spread over the runs: " + "; ".join(parts))


if __name__ == "__main__":
    main()
