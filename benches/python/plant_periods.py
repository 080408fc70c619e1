"""Does the model follow the rapier plant over several periods of an exciting trajectory? The
design of ``rss6 identify --simulate`` (seed 0) run for N periods on the plant with the Table 5.2
truth, the identification drive and the stick–slip law, noise-free (no camera or potentiometer
noise), then replayed on the model with the same truth and the run's recorded commands. Prints the
pose residual RMS per axis in units of Table 4.1's camera noise, per period and per W-second
window. Since the tenth session an exciting trajectory repeats with its period; before, a run of
N periods held the start at rest after the first (docs/identification.md, "Runs of several
periods").

    python benches/python/plant_periods.py [--periods 3] [--window 2] [--solver-iterations 48]
"""

from __future__ import annotations

import argparse

import numpy as np
import rss6
from rss6 import identify
from rss6.discrepancy.benchmark import CAMERA_SIGMA
from rss6.identify_sim import DRIVE_DERIVATIVE_FILTER, IMPLICIT_PLANT_ITERATIONS


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--periods", type=int, default=3)
    ap.add_argument("--window", type=float, default=2.0, help="s")
    ap.add_argument("--solver-iterations", type=int, default=IMPLICIT_PLANT_ITERATIONS)
    a = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    exc = identify.excitation(kp, seed=0, maxiter=30)
    robot = rss6.Plant(
        kp, dp, pid=pid, seed=0, drive_derivative_filter=DRIVE_DERIVATIVE_FILTER,
        implicit_friction=True, solver_iterations=a.solver_iterations,
        potentiometer_noise=0.0, pixel_noise=0.0,
    )  # fmt: skip
    tr = robot.truth()
    d = identify.collect(
        robot, exc, kp_model=kp, sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"], periods=a.periods,
    )  # fmt: skip
    chi = identify.simulate(
        kp, dp, pid, d.reference, times=d.t, dt=d.dt, commands=d.frame_commands(),
        derivative_filter=DRIVE_DERIVATIVE_FILTER, implicit_friction=True,
    )  # fmt: skip
    e = (d.measured - chi) / CAMERA_SIGMA

    def rms(m: np.ndarray) -> str:
        return " ".join(f"{v:5.2f}" for v in np.sqrt(np.mean(e[m] ** 2, axis=0)))

    print(
        f"{a.periods} periods of {exc.duration:.0f} s, noise-free plant vs model (x y z α β γ, σ)"
    )
    for k in range(a.periods):
        m = (d.t >= k * exc.duration) & (d.t < (k + 1) * exc.duration)
        print(f"  period {k + 1}: {rms(m)}")
    worst = 0.0
    for s in np.arange(0.0, d.duration, a.window):
        m = (d.t >= s) & (d.t < s + a.window)
        if m.any():
            worst = max(worst, float(np.sqrt(np.mean(e[m] ** 2, axis=0)).max()))
    print(f"  worst axis over {a.window:g} s windows: {worst:.2f}")


if __name__ == "__main__":
    main()
