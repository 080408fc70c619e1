"""The nominal refit's Gauss–Newton steps (rss6.discrepancy.nominal): on the model twin with a
hidden 10 ms latency and the model's friction scaled per joint by 1 + 0.03·N(0, 1) (Coulomb) and
1 + 0.08·N(0, 1) (viscous), refits the friction and drive gains on a 10 s run and prints the
replays it took, the wall time, the whitened cost before and after, whether it counts itself
converged and what moved.

    python benches/python/nominal_refit.py [--draw 1]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import rss6
from rss6 import discrepancy, identify
from rss6.discrepancy._steps import _calibrate, _Part, _Sim
from rss6.discrepancy.model import Model, replay, run_of
from rss6.discrepancy.nominal import refit_nominal, spreads

KP = rss6.KinematicParams.nominal()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--draw", type=int, default=1)
    args = ap.parse_args()
    dp, pid = identify.table_5_2_truth()
    robot = rss6.ModelSim(
        KP,
        dp,
        pid=pid,
        seed=11,
        drive_derivative_filter=5e-3,
        friction_smoothing=1.0,
        effects={"camera_latency": {"latency": 0.01}},
    )
    tr = robot.truth()
    data = identify.collect(
        robot,
        identify.random_excitation(KP, seed=1),
        kp_model=KP,
        sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
    )
    rng = np.random.default_rng(args.draw)
    d = dp.to_dict()
    d["coulomb"] = np.asarray(d["coulomb"]) * (1 + 0.03 * rng.standard_normal(6))
    d["viscous"] = np.asarray(d["viscous"]) * (1 + 0.08 * rng.standard_normal(6))
    model = Model(
        KP,
        rss6.DynamicParams.from_dict(d),
        pid,
        tr["sensor_in_base"],
        tr["target_in_effector"],
        derivative_filter=5e-3,
        friction_smoothing=1.0,
    )
    run = run_of(data, kinematics=KP)
    part = _Part(run, slice(0, len(run.t)))
    sim = _Sim(2)
    try:
        _calibrate([part], model, 16, sim, 1)
        assert part.calibration is not None
        cal = part.calibration
        count = [0]

        def residual(m: Model) -> np.ndarray:
            count[0] += 1
            return np.asarray(
                cal.whitener.vec(part.measured - part.baseline(replay(m, part.run))[part.rows])
            )

        t0 = time.perf_counter()
        nf = refit_nominal(model, model, spreads(discrepancy.NOMINAL_SPREAD), residual, sim.many)
        print(
            f"{count[0]} replays, {time.perf_counter() - t0:.1f} s, whitened cost "
            f"{nf.cost_before:.6g} → {nf.cost_after:.6g}, converged {nf.converged}: {nf.summary()}",
            flush=True,
        )
    finally:
        sim.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
