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
    designed = identify.excitation(kp, seed=args.seed)
    t_design = time.perf_counter() - t0
    excs = [designed] + [identify.random_excitation(kp, seed=100 + k) for k in range(args.n)]
    rows = []
    t0 = time.perf_counter()
    for e in excs:
        o = loop_observability(
            e, kp, dp, pid, derivative_filter=identify_sim.DRIVE_DERIVATIVE_FILTER,
            implicit_friction=True,
        )  # fmt: skip
        rows.append((e.observability, e.condition, o.o_in, o.condition, len(o.identifiable)))
    t_loop = (time.perf_counter() - t0) / len(excs)
    print(
        f"model: {args.at}; designed by differential evolution in {t_design:.1f} s; "
        f"{t_loop:.2f} s per loop sensitivity\n"
        f"{'trajectory':>12s} {'regressor O_in':>15s} {'cond':>9s} {'loop O_in':>10s} "
        f"{'cond':>9s} {'identifiable':>12s}"
    )
    for k, (ro, rc, lo, lc, n) in enumerate(rows):
        name = "designed" if k == 0 else f"random {k - 1}"
        print(f"{name:>12s} {ro:15.4g} {rc:9.3g} {lo:10.4g} {lc:9.3g} {n:12d}")
    r = np.array(rows)
    rho, p = spearmanr(r[1:, 0], r[1:, 2])
    rank_reg = int(np.sum(r[1:, 0] > r[0, 0])) + 1
    rank_loop = int(np.sum(r[1:, 2] > r[0, 2])) + 1
    print(
        f"\nSpearman ρ between the regressor's and the loop's O_in over the {args.n} random "
        f"trajectories: {rho:.2f} (p = {p:.2g})\n"
        f"the designed trajectory ranks {rank_reg} of {args.n + 1} by the regressor's O_in, "
        f"{rank_loop} of {args.n + 1} by the loop's; cond: regressor {r[0, 1]:.3g} "
        f"(random median {np.median(r[1:, 1]):.3g}), loop {r[0, 3]:.3g} "
        f"(random median {np.median(r[1:, 3]):.3g})"
    )


if __name__ == "__main__":
    main()
