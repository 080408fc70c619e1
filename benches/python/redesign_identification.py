"""Does a trajectory chosen by what the loop sees identify better? A two-stage identification on the
rapier plant (the setting of ``rss6 identify --simulate``: Table 5.2 truth, stick–slip law at 48
solver iterations, identification drive, CLOE from the thesis's initial model through the linear
start on the recorded commands).

1. the trajectory :func:`rss6.identify.excitation` designs (the torque regressor's O_in), collected
   and identified;
2. of ``--candidates`` random feasible trajectories, the one with the largest loop O_in at stage 1's
   *estimate* (:func:`rss6.excitation.best_for_loop` — the truth is never used to choose), collected
   on the same plant and identified from the same initial model. With ``--focus fc fv li ld``
   the choice is by those quantities' predicted σ instead of O_in (``best_for_loop(focus=...)``).

Prints per stage the loop's O_in at the estimate, CLOE's iterations, reduced χ² and, for f_c, f_v,
l_i, l_d and the masses and inertias, the median reported relative σ and the median |error| against
the truth. One plant and one seed: a comparison of two trajectories, not a study.

    python benches/python/redesign_identification.py [--seed 0] [--candidates 20] [--focus fc fv li ld]
        [--amplitude 0.001 0.005]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
import rss6
from rss6 import identify, identify_sim
from rss6.excitation import best_for_loop, focus_rms, loop_observability
from rss6.identify_report import quantities


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--candidates", type=int, default=20)
    ap.add_argument("--focus", nargs="*", default=[], help="choose by these quantities' σ")
    ap.add_argument(
        "--amplitude", nargs=2, type=float, default=(0.001, 0.005), metavar=("POS", "ANG"),
        help="bounds of the free coefficients (m/s, rad/s) of the design and the candidates",
    )  # fmt: skip
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp_true, pid_true = identify.table_5_2_truth()
    t_f = identify_sim.DRIVE_DERIVATIVE_FILTER
    truth = dict(zip(identify.parameter_names(), quantities(dp_true, pid_true), strict=True))

    def run(exc: identify.Excitation) -> identify.IdentificationResult:
        data = identify_sim.collect_on_plant(exc, seed=args.seed)
        return identify_sim.estimate_from_initial(data, kp, lp=pid_true[0])

    def seen(exc: identify.Excitation, res: identify.IdentificationResult) -> float:
        o = loop_observability(
            exc, kp, res.dynamics, res.pid, derivative_filter=t_f, implicit_friction=True
        )
        return o.o_in

    def report(stage: str, exc: identify.Excitation, res: identify.IdentificationResult) -> None:
        est = dict(zip(identify.parameter_names(), quantities(res.dynamics, res.pid), strict=True))
        std = dict(zip(res.identified, res.relative_std, strict=True))
        groups: dict[str, Callable[[str], bool]] = {
            "f_c": lambda n: n.startswith("fc"),
            "f_v": lambda n: n.startswith("fv"),
            "l_i, l_d": lambda n: n in ("li", "ld"),
            "masses, inertias": lambda n: "." in n,
        }
        parts = []
        for g, keep in groups.items():
            names = [n for n in std if keep(n)]
            s = np.median([std[n] for n in names])
            e = np.median([abs(est[n] / truth[n] - 1) for n in names])
            parts.append(f"{g}: σ {100 * s:.1f} %, |error| {100 * e:.1f} %")
        print(
            f"{stage}: regressor O_in {exc.observability:.4g}, loop O_in at the estimate "
            f"{seen(exc, res):.4g}; {res.iterations} iterations ({res.converged_by}), reduced χ² "
            f"{res.reduced_chi2:.2f}, {len(res.identified)} quantities\n   " + "; ".join(parts)
        )

    t0 = time.perf_counter()
    amplitude = (float(args.amplitude[0]), float(args.amplitude[1]))
    designed = identify.excitation(kp, seed=args.seed, amplitude=amplitude)
    first = run(designed)
    report("1. designed (regressor O_in)", designed, first)
    chosen, obs = best_for_loop(
        kp, first.dynamics, first.pid, candidates=args.candidates, seed=args.seed,
        include=(designed,), derivative_filter=t_f, implicit_friction=True, focus=args.focus,
        amplitude=amplitude,
    )  # fmt: skip
    which = "the designed one" if chosen is designed else "a random one"
    by = f"RMS σ of {' '.join(args.focus)}" if args.focus else "loop O_in"
    print(f"   best for the loop at stage 1's estimate by {by}: {which}, loop O_in {obs.o_in:.4g}")
    if args.focus:
        at_first = loop_observability(
            designed, kp, first.dynamics, first.pid, derivative_filter=t_f, implicit_friction=True
        )
        print(
            f"   predicted RMS σ of the focus: designed {100 * focus_rms(at_first, args.focus):.2f} %, "
            f"chosen {100 * focus_rms(obs, args.focus):.2f} %"
        )
    if chosen is not designed:
        second = run(chosen)
        report(f"2. chosen by the {by}", chosen, second)
    print(f"({time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
