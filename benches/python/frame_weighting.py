"""CLOE with Table 4.1's per-axis weights against CLOE whitened by the frames' covariance
(``identify.cloe(noise="frames")``) on the stick–slip model twin as the robot, one 10 s random
thesis-size trajectory per seed (docs/identification.md, "Weighting by the frames' covariance").

Prints per seed and weighting: f_v1, f_v2, l_d as estimate / truth ± relative σ, the RMS and largest
|z| = |log(estimate / truth)| / σ over the 14 friction and gain quantities, the reduced χ² and the
iterations; then the residual's correlation between the camera's x and β, y and α.

    python benches/python/frame_weighting.py [--seeds 0 1 2 26] [--pot-noise] [--noise-seed-offset K]

``--pot-noise``: the twin's potentiometers are noisy and CLOE replays the estimated noise (the
study's setting); by default they are clean, so the camera is the only noise. ``--noise-seed-offset
K``: the twin's noise is drawn from seed + K while the trajectory stays that of seed (K = 1000 tells
a trajectory's effect from a noise draw's: seed 26's f_v1 tail).
"""

from __future__ import annotations

import argparse
import re

import numpy as np
import rss6
from rss6 import identify, identify_sim
from rss6.identify_report import quantities


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 26])
    ap.add_argument("--pot-noise", action="store_true")
    ap.add_argument("--noise-seed-offset", type=int, default=0)
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp_true, pid_true = identify.table_5_2_truth()
    names = identify.parameter_names()
    truth = dict(zip(names, quantities(dp_true, pid_true), strict=True))
    extra = {} if args.pot_noise else {"potentiometer_noise": 0.0}
    for seed in args.seeds:
        robot = rss6.ModelSim(
            kp, dp_true, pid=pid_true, seed=seed + args.noise_seed_offset, implicit_friction=True,
            drive_derivative_filter=identify_sim.DRIVE_DERIVATIVE_FILTER, **extra,
        )  # fmt: skip
        tr = robot.truth()
        exc = identify.random_excitation(
            kp, harmonics=5, f0=0.1, seed=seed, amplitude=(0.001, 0.005)
        )
        data = identify.collect(
            robot, exc, kp_model=kp, sensor_in_base=tr["sensor_in_base"],
            target_in_effector=tr["target_in_effector"],
        )  # fmt: skip
        guess, kw = identify_sim.cloe_settings(
            data, kp, lp=pid_true[0], pot_noise="recorded" if args.pot_noise else "none"
        )
        for label, noise in (("per axis", None), ("frames", "frames")):
            r = identify.cloe(data, kp, *guess, **{**kw, "noise": noise})
            est = dict(zip(names, quantities(r.dynamics, r.pid), strict=True))
            z = [
                np.log(est[n] / truth[n]) / r.std(n)
                for n in r.identified
                if re.fullmatch(r"f[cv]\d|l[id]", n)
            ]
            shown = ", ".join(
                f"{n} {est[n] / truth[n]:.2f} ± {r.std(n):.3f}" for n in ("fv1", "fv2", "ld")
            )
            print(
                f"seed {seed} (noise {seed + args.noise_seed_offset}) {label:8s}: {shown}; "
                f"z RMS {np.sqrt(np.mean(np.square(z))):.2f} (max {np.max(np.abs(z)):.2f}) over "
                f"{len(z)}; reduced χ² {r.reduced_chi2:.2f}; {r.iterations} iterations",
                flush=True,
            )
        c = np.corrcoef(r.residual.T)
        print(f"seed {seed}: residual correlation x–β {c[0, 4]:+.2f}, y–α {c[1, 3]:+.2f}")


if __name__ == "__main__":
    main()
