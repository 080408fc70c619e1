"""Calibration weighted by Table 4.1's independent camera noise against the covariance pooled from
the dwells' own frames (``calibrate.rpba(..., noise="dwells")``): on random robots (Table 4.2
errors) simulated by the model twin with the stereo CMM, prints per robot and method the fit
statistic (≈ 1 when the noise model is right) and the RMS relative pose errors on 100 test
configurations, then the mean over robots and the ratio dwells / table. Also prints the pooled
covariance's correlations (the stereo head's x–β and y–α).

    python benches/python/calibration_noise.py [--robots 8] [--seed 0] [--dwell 2.0]
        [--candidates 2000] [--plant]

``--plant``: the rapier plant (its PID and stick–slip drives) instead of the model twin.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import rss6
from rss6 import calibrate

AXES = ("x", "y", "z", "α", "β", "γ")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--dwell", type=float, default=2.0)
    ap.add_argument("--candidates", type=int, default=2000)
    ap.add_argument("--plant", action="store_true")
    args = ap.parse_args()
    nominal = rss6.KinematicParams.nominal()
    dp = rss6.DynamicParams.nominal()
    stroke = calibrate.stroke(nominal)
    sets = {
        m: calibrate.select_configurations(
            nominal, m, seed=args.seed, candidates=args.candidates, stroke=stroke
        )
        for m in ("rpba", "implicit")
    }
    sensor0, _ = calibrate.default_placement()
    rows: dict[tuple[str, str], list[tuple[float, np.ndarray]]] = {}
    pooled: list[np.ndarray] = []
    t0 = time.perf_counter()
    for r in range(args.robots):
        seed = args.seed + 100 + r
        truth = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed=seed))
        for method, thetas in sets.items():
            robot = (
                rss6.Plant(truth, dp, seed=seed)
                if args.plant
                else rss6.ModelSim(truth, dp, seed=seed)
            )
            data = calibrate.collect(robot, thetas, dwell=args.dwell)
            cov = data.sensor_pose_cov
            w = data.camera_frames - 1
            pooled.append(np.tensordot(w, cov, axes=1) / w.sum())
            for noise in ("table", "dwells"):
                try:
                    if method == "rpba":
                        res = calibrate.rpba(data, nominal, noise=noise)
                    else:
                        res = calibrate.implicit(data, nominal, sensor0, noise=noise)
                except rss6.Rss6Error as e:
                    print(f"robot {seed} {method:8s} {noise:6s}: {type(e).__name__}: {e}")
                    continue
                rms = calibrate.relative_pose_errors(res, robot, n=100, stroke=stroke)["rms"]
                rows.setdefault((method, noise), []).append((res.fit_statistic, rms))
                print(
                    f"robot {seed} {method:8s} {noise:6s}: fit statistic {res.fit_statistic:6.3f}, "
                    f"RMS x y z {1e6 * rms[0]:.2f} {1e6 * rms[1]:.2f} {1e6 * rms[2]:.2f} µm, "
                    f"α β γ {1e6 * rms[3]:.1f} {1e6 * rms[4]:.1f} {1e6 * rms[5]:.1f} µrad",
                    flush=True,
                )
    c = np.mean(pooled, axis=0)
    sd = np.sqrt(np.diag(c))
    corr = c / np.outer(sd, sd)
    print(f"\n{args.robots} robots in {time.perf_counter() - t0:.0f} s")
    print("pooled camera σ per frame: x y z " + " ".join(f"{1e6 * v:.2f}" for v in sd[:3]) + " µm, "
          "α β γ " + " ".join(f"{1e6 * v:.1f}" for v in sd[3:]) + " µrad")  # fmt: skip
    pairs = [(i, j) for i in range(6) for j in range(i + 1, 6)]
    strong = sorted(pairs, key=lambda p: -abs(corr[p]))[:4]
    print(
        "strongest correlations: "
        + ", ".join(f"{AXES[i]}–{AXES[j]} {corr[i, j]:+.2f}" for i, j in strong)
    )
    for method in sets:
        table, dwells = rows.get((method, "table"), []), rows.get((method, "dwells"), [])
        if not table or not dwells:
            continue
        ft = np.array([f for f, _ in table])
        fd = np.array([f for f, _ in dwells])
        rt = np.mean([r for _, r in table], axis=0)
        rd = np.mean([r for _, r in dwells], axis=0)
        print(
            f"{method:8s} fit statistic mean (max): table {ft.mean():.2f} ({ft.max():.2f}), "
            f"dwells {fd.mean():.2f} ({fd.max():.2f}); mean RMS dwells / table per axis "
            + " ".join(f"{a} {d / t:.2f}" for a, d, t in zip(AXES, rd, rt, strict=True))
        )


if __name__ == "__main__":
    main()
