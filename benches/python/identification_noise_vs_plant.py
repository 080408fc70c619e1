"""Is the plant's identification error the plant's numerics or the noise? The seed's designed
trajectory (`identify.excitation(kp, seed=S, maxiter=30)`, as `rss6 identify --simulate`), three
periods collected on a robot with Table 5.2's truth, then CLOE from the thesis's initial model as the
CLI runs it (`identify_sim.estimate_from_initial`, l_p held). Prints the errors of the gains, the
Coulomb frictions and f_v4 with their predicted σ, for each robot:

    python benches/python/identification_noise_vs_plant.py [--seeds 0 4 7]
        [--robots plant plant-quiet twin twin-quiet]

``plant``: the rapier plant of the CLI (stick–slip law, 48 solver iterations, camera and
potentiometer noise of the seed); ``twin``: the model twin with the same law and the same noise
draws; ``-quiet``: without either noise.
"""

from __future__ import annotations

import argparse

import numpy as np
import rss6
from rss6 import identify, identify_sim
from rss6.identify_sim import DRIVE_DERIVATIVE_FILTER, IMPLICIT_PLANT_ITERATIONS

SHOWN = ["li", "ld", "fc1", "fc2", "fc3", "fc4", "fc5", "fc6", "fv4"]


def robot(kind: str, seed: int) -> rss6.Plant | rss6.ModelSim:
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    kw = {"pid": pid, "seed": seed, "drive_derivative_filter": DRIVE_DERIVATIVE_FILTER,
          "implicit_friction": True}  # fmt: skip
    if kind.endswith("-quiet"):
        kw |= {"potentiometer_noise": 0.0, "pixel_noise": 0.0}
    if kind.startswith("plant"):
        return rss6.Plant(kp, dp, solver_iterations=IMPLICIT_PLANT_ITERATIONS, **kw)
    return rss6.ModelSim(kp, dp, **kw)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 4, 7])
    ap.add_argument(
        "--robots", nargs="+", default=["plant", "plant-quiet", "twin", "twin-quiet"],
        choices=["plant", "plant-quiet", "twin", "twin-quiet"],
    )  # fmt: skip
    args = ap.parse_args()
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    names = identify.parameter_names()
    pt = rss6._rss6.cloe_psi(dp, pid)[0]
    for seed in args.seeds:
        exc = identify.excitation(kp, seed=seed, maxiter=30)
        for kind in args.robots:
            r0 = robot(kind, seed)
            tr = r0.truth()
            d = identify.collect(
                r0, exc, kp_model=kp, sensor_in_base=tr["sensor_in_base"],
                target_in_effector=tr["target_in_effector"], periods=3,
            )  # fmt: skip
            r = identify_sim.estimate_from_initial(d, kp, lp=pid[0])
            pe = rss6._rss6.cloe_psi(r.dynamics, r.pid)[0]
            err = {n: float(np.expm1(pe[j] - pt[j])) for j, n in enumerate(names)}
            sd = dict(zip(r.identified, r.relative_std, strict=True))
            shown = "  ".join(f"{n} {100 * err[n]:+.1f} % (σ {100 * sd[n]:.1f})" for n in SHOWN)
            print(f"seed {seed} {kind:11s} {r.iterations:2d} it., χ² {r.reduced_chi2:.3f}  {shown}")


if __name__ == "__main__":
    main()
