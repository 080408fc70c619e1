"""Speed of the whole discrepancy workflow (issue 14: ≤ 60 s on a 30 s run with every candidate).

Twin as the robot, a 30 s run (three periods of a 10 s excitation) and a held-out run of another
excitation; every one of the 19 candidates screened. Prints seconds without an effect and with a
hidden camera latency (one fit round, the held-out checks, a second screening round).

    python benches/python/discrepancy_speed.py [--workers 2] [--commands recorded|simulated]
        [--hold-nominal] [--pot-noise recorded]

``--pot-noise recorded`` replays each run's estimated potentiometer noise (``run_of``; the
estimate is inside the timed part).
"""

from __future__ import annotations

import argparse
import time

import rss6
from rss6 import discrepancy, identify
from rss6.discrepancy.model import run_of


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--commands", default="recorded", choices=("recorded", "simulated"))
    ap.add_argument(
        "--hold-nominal", action="store_true", help="no nominal refit (the model taken as exact)"
    )
    ap.add_argument("--pot-noise", default="none", choices=("none", "recorded"))
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    for hidden in (None, {"camera_latency": {"latency": 0.01}}):
        runs = []
        for seed, exc_seed in ((1, 1), (2, 2)):
            robot = rss6.ModelSim(
                kp,
                dp,
                pid=pid,
                seed=seed,
                drive_derivative_filter=5e-3,
                friction_smoothing=1.0,
                effects=hidden,
            )
            tr = robot.truth()
            runs.append(
                identify.collect(
                    robot,
                    identify.random_excitation(kp, seed=exc_seed),
                    kp_model=kp,
                    sensor_in_base=tr["sensor_in_base"],
                    target_in_effector=tr["target_in_effector"],
                    periods=3,
                )
            )
        model = discrepancy.Model(
            kp,
            dp,
            pid,
            tr["sensor_in_base"],
            tr["target_in_effector"],
            derivative_filter=5e-3,
            friction_smoothing=1.0,
        )
        t0 = time.perf_counter()
        fit, val = (run_of(r, commands=args.commands, pot_noise=args.pot_noise) for r in runs)
        rep = discrepancy.diagnose(
            fit,
            model,
            validation=val,
            workers=args.workers,
            commands=args.commands,
            nominal=None if args.hold_nominal else discrepancy.NOMINAL_SPREAD,
        )
        dt = time.perf_counter() - t0
        print(
            f"30 s run ({args.commands} commands, potentiometer noise {args.pot_noise}), "
            f"{len(discrepancy.effects.candidates())} "
            f"candidates, hidden {hidden}: "
            f"{dt:.1f} s -> {rep.verdict}"
        )


if __name__ == "__main__":
    main()
