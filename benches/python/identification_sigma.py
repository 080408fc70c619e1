"""How honest CLOE's σ is (docs/identification.md, "How honest is the σ" and "Filtering χ_m"):
identifications of random thesis-size trajectories on the model twin (stick–slip law, the study's
task `rss6.studies.tasks.identification_task`), optionally with the twin's potentiometer noise off
or χ_m low-passed, or CLOE replaying the recorded potentiometer noise in the model's drive
(``--pot-replay recorded``; ``model``: a second pass replaying the readings minus the first
estimate's angles, ``identify.cloe(pot_noise="model")``; ``exact``: the twin's true noise, docs/identification.md "Replaying the potentiometer noise"); prints per quantity the bias and spread of log(estimate/truth), the RMS of the
reported σ and of its Wald part, and the median residual RMS. For the plant, use
`rss6 study identification --n 10` (its summary prints σ / spread).

    python benches/python/identification_sigma.py [--n 10] [--pot-noise on|off] [--cutoff HZ]
        [--pot-replay none|recorded|model|exact] [--robot twin|plant]
    python benches/python/identification_sigma.py --estimate-error   # potentiometer_noise's error
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from typing import Any

import numpy as np
import rss6
from rss6 import identify
from rss6.studies import tasks

NAMES = ["fc1", "fc2", "fc3", "fc4", "fc5", "fc6", "fv4", "li", "ld"]


def run(
    seed: int, pot_noise: bool, cutoff: float | None, replay: str, robot: str
) -> dict[str, Any]:
    """One identification; the twin's constructor and CLOE patched in this worker only."""
    if not pot_noise:
        cls = rss6.ModelSim

        def twin(*a: Any, **k: Any) -> Any:
            k["potentiometer_noise"] = 0.0
            return cls(*a, **k)

        rss6.ModelSim = twin  # type: ignore[misc]  # the task builds rss6.ModelSim for "twin"
    if cutoff is not None:
        identify.cloe = partial(identify.cloe, measured_cutoff=cutoff)  # type: ignore[assignment]
    if replay == "exact" and not getattr(identify.cloe, "exact_noise", False):
        # The twin's true noise: its reading minus the true angle (a simulation only).
        inner = identify.cloe

        def exact(data: identify.IdentificationData, *a: Any, **k: Any) -> Any:
            kp = rss6.KinematicParams.nominal()
            theta = np.array([rss6.ik(kp, p) for p in np.asarray(data.true_pose)])
            kappa = np.asarray(data.kappa)
            read = kp.theta_from_reading(kappa)
            k.pop("pot_noise", None)
            return inner(data, *a, pot_noise=read - theta, **k)

        exact.exact_noise = True  # type: ignore[attr-defined]  # a worker runs several tasks
        identify.cloe = exact  # type: ignore[assignment]
    return tasks.identification_task(
        {
            "seed": seed,
            "robot": robot,
            "friction_law": "implicit",
            "pot_noise": "recorded" if replay == "exact" else replay,
        }
    )


def estimate_error() -> None:
    """RMS of (potentiometer_noise − the twin's true noise) / noise at the sampling ticks, for a
    thesis-size and a fast 2 s trajectory and three cut-offs."""
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    for name, exc in (
        ("thesis-size", identify.random_excitation(kp, seed=0, amplitude=(0.001, 0.005))),
        (
            "fast 2 s",
            identify.random_excitation(kp, harmonics=3, f0=0.5, seed=1, amplitude=(0.01, 0.05)),
        ),
    ):
        robot = rss6.ModelSim(
            kp, dp, pid=pid, seed=3, drive_derivative_filter=5e-3, implicit_friction=True
        )
        tr = robot.truth()
        d = identify.collect(
            robot, exc, kp_model=kp, sensor_in_base=tr["sensor_in_base"],
            target_in_effector=tr["target_in_effector"],
        )  # fmt: skip
        theta = np.array([rss6.ik(kp, p) for p in np.asarray(d.true_pose)])
        noise = kp.theta_from_reading(np.asarray(d.kappa)) - theta
        kappa = np.asarray(d.kappa)
        fresh = np.concatenate(([0], 1 + np.flatnonzero(np.any(kappa[1:] != kappa[:-1], axis=1))))
        line = []
        for cutoff in (50.0, 100.0, 150.0):
            est = identify.potentiometer_noise(d, cutoff=cutoff)
            err = np.std(est[fresh] - noise[fresh]) / np.std(noise[fresh])
            line.append(f"{cutoff:.0f} Hz {err:.2f}")
        print(
            f"{name:12s} noise RMS {np.std(noise[fresh]):.2e} rad; error/noise: " + ", ".join(line)
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=10)
    ap.add_argument("--pot-noise", default="on", choices=("on", "off"))
    ap.add_argument("--cutoff", type=float, default=None)
    ap.add_argument("--pot-replay", default="none", choices=("none", "recorded", "exact", "model"))
    ap.add_argument("--robot", default="twin", choices=("twin", "plant"))
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--estimate-error", action="store_true")
    args = ap.parse_args()
    if args.estimate_error:
        estimate_error()
        return
    dp, pid = identify.table_5_2_truth()
    truth = dict(
        zip(identify.parameter_names(), np.exp(np.asarray(rss6._rss6.cloe_psi(dp, pid)[0])))
    )
    job = partial(
        run,
        pot_noise=args.pot_noise == "on",
        cutoff=args.cutoff,
        replay=args.pot_replay,
        robot=args.robot,
    )
    with ProcessPoolExecutor(args.workers) as ex:
        recs = list(ex.map(job, range(args.n)))
    ok = [r for r in recs if r.get("status", "ok") == "ok"]
    print(
        f"{args.robot}, potentiometer noise {args.pot_noise}, cutoff {args.cutoff}, "
        f"noise replayed {args.pot_replay}: {len(ok)}/{args.n} ok"
    )
    for n in NAMES:
        rel = np.array([np.log(r[f"est_{n}"] / truth[n]) for r in ok])
        s = np.array([r[f"std_{n}"] for r in ok if f"std_{n}" in r])
        w = np.array([r[f"wald_{n}"] for r in ok if f"wald_{n}" in r])
        print(
            f"{n:4s} bias {rel.mean():+.4f} spread {rel.std(ddof=1):.4f} "
            f"σ-rms {np.sqrt((s**2).mean()):.4f} wald-rms {np.sqrt((w**2).mean()):.4f}"
        )
    rms = np.median([[r[f"rms_after_{a}"] for a in "xyzabg"] for r in ok], axis=0)
    print("residual RMS after (µm, µrad), median:", np.round(1e6 * rms, 2))


if __name__ == "__main__":
    main()
