"""The discrepancy workflow with a model that is a few per cent off: a hidden effect in the model
twin (default a 10 ms camera latency), and the model's Coulomb and viscous friction scaled per
joint by 1 + σ·N(0, 1) (default σ 3 % and 8 %, what CLOE leaves on the plant). Prints per draw the
verdict, the number of candidates refused on the way, the wall time, the friction error of the
model given and of the report's model against the truth, and the nominal refit's notes.

    python benches/python/discrepancy_model_error.py [--draws 1 2 3] [--coulomb 0.03]
        [--viscous 0.08] [--latency 0.01] [--reidentify] [--hold-nominal]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import rss6
from rss6 import discrepancy, identify

KP = rss6.KinematicParams.nominal()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--draws", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--coulomb", type=float, default=0.03)
    ap.add_argument("--viscous", type=float, default=0.08)
    ap.add_argument("--latency", type=float, default=0.01)
    ap.add_argument("--reidentify", action="store_true")
    ap.add_argument(
        "--hold-nominal",
        action="store_true",
        help="hold the model's friction and gains (no nominal refit: the model taken as exact)",
    )
    args = ap.parse_args()
    dp, pid = identify.table_5_2_truth()
    exc = identify.random_excitation(KP, seed=1)
    hidden = {"camera_latency": {"latency": args.latency}}

    def robot(seed: int) -> rss6.ModelSim:
        return rss6.ModelSim(
            KP,
            dp,
            pid=pid,
            seed=seed,
            drive_derivative_filter=5e-3,
            friction_smoothing=1.0,
            effects=hidden,
        )

    def collect(r: rss6.ModelSim) -> identify.IdentificationData:
        tr = r.truth()
        return identify.collect(
            r,
            exc,
            kp_model=KP,
            sensor_in_base=tr["sensor_in_base"],
            target_in_effector=tr["target_in_effector"],
        )

    tr = robot(0).truth()
    for draw in args.draws:
        rng = np.random.default_rng(draw)
        d = dp.to_dict()
        d["coulomb"] = np.asarray(d["coulomb"]) * (1 + args.coulomb * rng.standard_normal(6))
        d["viscous"] = np.asarray(d["viscous"]) * (1 + args.viscous * rng.standard_normal(6))
        model = discrepancy.Model(
            KP,
            rss6.DynamicParams.from_dict(d),
            pid,
            tr["sensor_in_base"],
            tr["target_in_effector"],
            derivative_filter=5e-3,
            friction_smoothing=1.0,
        )
        t0 = time.perf_counter()
        rep = discrepancy.diagnose(
            collect(robot(11)),
            model,
            validation=collect(robot(12)),
            reidentify=args.reidentify,
            nominal=None if args.hold_nominal else discrepancy.NOMINAL_SPREAD,
        )
        refused = sum(" not named" in n for n in rep.notes)
        est = "; ".join(
            f"{n.name} {', '.join(f'{k}={v:.4g} [{n.ci[k][0]:.4g}, {n.ci[k][1]:.4g}]' for k, v in n.params.items())}"
            for n in rep.named
        )
        print(
            f"draw {draw}: {rep.verdict} ({refused} refused; {time.perf_counter() - t0:.0f} s) {est}",
            flush=True,
        )

        def rms_error(m: discrepancy.Model, what: str) -> float:
            e = np.asarray(getattr(m.dynamics, what)) / np.asarray(getattr(dp, what)) - 1
            return 100 * float(np.sqrt(np.mean(e * e)))

        print(
            "  friction error against the truth, RMS over the joints: Coulomb "
            f"{rms_error(model, 'coulomb'):.2f} % → {rms_error(rep.model, 'coulomb'):.2f} %, viscous "
            f"{rms_error(model, 'viscous'):.2f} % → {rms_error(rep.model, 'viscous'):.2f} % "
            "(the model given → the report's model)",
            flush=True,
        )
        for n in rep.notes:
            if n.startswith(("re-identified", "not re-identified", "nominal")):
                print(f"  {n}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
