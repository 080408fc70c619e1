"""Issue 13's "O_in of the stacked regressor and of the closed-loop output sensitivity ∂Y/∂A:
compare both; report cond too".

For the trajectory :func:`rss6.identify.excitation` designs (it maximises the regressor's O_in,
eq. 5.13) and ``--n`` random feasible ones of the same size (:func:`rss6.identify.random_excitation`),
prints the torque regressor's O_in and cond beside the loop's
(:func:`rss6.excitation.loop_observability`: the camera poses' noise-weighted sensitivity to CLOE's
log-parameters, l_p held, at the Table 5.2 truth with the identification drive and the stick–slip
law, or at the thesis's initial model with ``--at initial``), then Spearman's rank correlation of
the two O_in over the random trajectories and where the designed one ranks by each.

    python benches/python/excitation_observability.py [--n 20] [--seed 0] [--at truth|initial]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
import rss6
from rss6 import identify, identify_sim
from rss6.excitation import loop_observability
from scipy.stats import spearmanr


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--n", type=int, default=20, help="random feasible trajectories")
    ap.add_argument("--seed", type=int, default=0, help="the design's seed; random ones 100 + k")
    ap.add_argument("--at", choices=("truth", "initial"), default="truth")
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth() if args.at == "truth" else identify_sim.initial_model()
    t0 = time.perf_counter()
    # the design in the random trajectories' box (the default before the ninth session): a
    # comparison of shapes of one size
    designed = identify.excitation(kp, seed=args.seed, amplitude=(0.001, 0.005))
    t_design = time.perf_counter() - t0
    excs = [designed] + [identify.random_excitation(kp, seed=100 + k) for k in range(args.n)]
    rows = []
    t0 = time.perf_counter()
    for e in excs:
        o = loop_observability(
            e, kp, dp, pid, derivative_filter=identify_sim.DRIVE_DERIVATIVE_FILTER,
            implicit_friction=True,
        )  # fmt: skip
        std = o.relative_std

        def med(keep: Callable[[str], bool], std: dict[str, float] = std) -> float:
            v = [s for n, s in std.items() if keep(n)]
            return float(np.median(v)) if v else float("nan")

        rows.append(
            (
                e.observability, e.condition, o.o_in, o.condition, len(o.identifiable),
                med(lambda n: n.startswith("fc")), med(lambda n: n.startswith("fv")),
                med(lambda n: n in ("li", "ld")), med(lambda n: "." in n),
            )
        )  # fmt: skip
    t_loop = (time.perf_counter() - t0) / len(excs)
    print(
        f"model: {args.at}; designed by differential evolution in {t_design:.1f} s; "
        f"{t_loop:.2f} s per loop sensitivity\n"
        f"predicted relative σ (Cramér–Rao at Table 4.1 noise, medians over f_c, f_v, l_i and l_d, "
        f"the masses and inertias)\n"
        f"{'trajectory':>12s} {'regressor O_in':>15s} {'cond':>9s} {'loop O_in':>10s} "
        f"{'cond':>9s} {'identif.':>8s} {'σ f_c':>7s} {'σ f_v':>7s} {'σ gains':>7s} {'σ Ξ':>7s}"
    )
    for k, (ro, rc, lo, lc, n, sc, sv, sg, sm) in enumerate(rows):
        name = "designed" if k == 0 else f"random {k - 1}"
        print(
            f"{name:>12s} {ro:15.4g} {rc:9.3g} {lo:10.4g} {lc:9.3g} {n:8d} {100 * sc:6.2f}% "
            f"{100 * sv:6.2f}% {100 * sg:6.2f}% {100 * sm:6.1f}%"
        )
    r = np.array(rows)
    counts = sorted({int(n) for n in r[:, 4]})
    if len(counts) > 1:
        print(
            f"\nthe identifiable sets differ ({counts[0]}–{counts[-1]} quantities): O_in over "
            "different columns is not comparable — evaluate at a model near the robot (the truth "
            "here, or a first identification's estimate)"
        )
    rho, p = spearmanr(r[1:, 0], r[1:, 2])
    best = 1 + int(np.argmax(r[1:, 2]))
    rank_reg = int(np.sum(r[1:, 0] > r[0, 0])) + 1
    rank_loop = int(np.sum(r[1:, 2] > r[0, 2])) + 1
    print(
        f"\nSpearman ρ between the regressor's and the loop's O_in over the {args.n} random "
        f"trajectories: {rho:.2f} (p = {p:.2g})\n"
        f"the designed trajectory ranks {rank_reg} of {args.n + 1} by the regressor's O_in, "
        f"{rank_loop} of {args.n + 1} by the loop's; cond: regressor {r[0, 1]:.3g} "
        f"(random median {np.median(r[1:, 1]):.3g}), loop {r[0, 3]:.3g} "
        f"(random median {np.median(r[1:, 3]):.3g})\n"
        f"predicted σ, designed vs the best random by the loop's O_in (random {best - 1}): "
        f"f_c {100 * r[0, 5]:.2f} vs {100 * r[best, 5]:.2f} %, f_v {100 * r[0, 6]:.2f} vs "
        f"{100 * r[best, 6]:.2f} %, gains {100 * r[0, 7]:.2f} vs {100 * r[best, 7]:.2f} %, "
        f"masses and inertias {100 * r[0, 8]:.1f} vs {100 * r[best, 8]:.1f} %"
    )


if __name__ == "__main__":
    main()
