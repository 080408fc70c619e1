"""False-alarm rates and sensitivity of ``rss6.discrepancy.detect`` (issue 14: family-wise false
alarms on no-effect runs ≤ 5 %); the numbers of docs/discrepancy.md.

    python benches/python/discrepancy_false_alarms.py [reps] [closed_loop_runs]

1. Synthetic noise-only residuals, 900 frames × 6 axes at 30 Hz (a 30 s run), reference six 0.1 Hz
   sinusoids: white with σ given; white / AR(1) ρ = 0.6 / AR(1) ρ = 0.9 with the noise estimated
   from first differences or from the 10 s period repeats. ``reps`` runs each (default 2000).
2. Sensitivity: a velocity-sign (Coulomb-like) term of 0.1–0.3 σ on one axis, 100 runs each.
3. Closed loop: ``servo.track`` (DSMC, Experiment 1, 30 s) on ``rss6.ModelSim`` with Table 4.1
   noise (seeds 1..n) minus the same loop replayed without noise (the model's replay), noise
   estimated from first differences, then from three noisy replays of the nominal loop
   (``noise_from_repeats``); then one hidden effect each, with both noise models.
"""

from __future__ import annotations

import sys
import time
from collections import Counter

import numpy as np
import rss6
from rss6 import discrepancy, servo
from scipy.signal import lfilter

N, RATE, SIGMA = 900, 30.0, 1e-5


def ar1(rng: np.random.Generator, rho: float) -> np.ndarray:
    u = rng.standard_normal((N + 200, 6)) * SIGMA * np.sqrt(1 - rho**2)
    return lfilter([1.0], [1.0, -rho], u, axis=0)[200:]


def synthetic(reps: int) -> None:
    t = np.arange(N) / RATE
    ref = np.column_stack([0.01 * np.sin(2 * np.pi * 0.1 * t + k) for k in range(6)])
    sig = discrepancy.reference_signatures(t, ref)
    print(
        f"1. noise-only residuals, {reps} runs each (family-wise α = 0.01, "
        f"{6 * (3 + len(sig))} tests, Holm)"
    )
    cases = [
        ("white, σ given", 0.0, SIGMA, None),
        ("white, from differences", 0.0, None, None),
        ("white, from periods", 0.0, None, 10.0),
        ("AR(1) 0.6, from differences", 0.6, None, None),
        ("AR(1) 0.6, from periods", 0.6, None, 10.0),
        ("AR(1) 0.9, from differences", 0.9, None, None),
        ("AR(1) 0.9, from periods", 0.9, None, 10.0),
    ]
    for name, rho, floor, period in cases:
        rng = np.random.default_rng(100)
        alarms, tests = 0, Counter[str]()
        start = time.perf_counter()
        for _ in range(reps):
            d = discrepancy.detect(t, ar1(rng, rho), sig, noise_floor=floor, period=period)
            alarms += d.detected
            tests.update({r.test.split(" ")[0] for r in d.tests if r.rejected})
        ms = (time.perf_counter() - start) / reps * 1e3
        print(
            f"   {name:30s} {alarms:5d}/{reps} = {100 * alarms / reps:5.2f} %"
            f"  ({dict(tests)}; {ms:.1f} ms per run)"
        )
    print("2. velocity-sign term on y (100 runs each): detected on y / top signature velocity sign")
    for amp in (0.1, 0.15, 0.2, 0.3):
        for floor in (SIGMA, None):
            rng = np.random.default_rng(20)
            hits = top = 0
            for _ in range(100):
                r = ar1(rng, 0.0)
                r[:, 1] += amp * SIGMA * np.sign(sig["velocity"][:, 1])
                d = discrepancy.detect(t, r, sig, noise_floor=floor)
                hits += "y" in d.axes
                top += d.top_signature("y") == "velocity sign"
            label = "σ given" if floor else "σ estimated"
            print(f"   {amp:.2f} σ, {label:12s} {hits:3d} % / {top:3d} %")


def closed_loop(runs: int) -> None:
    kp, dp = rss6.KinematicParams.nominal(), rss6.DynamicParams.nominal()

    def track(seed: int, **kw: object) -> servo.TrackingResult:
        plant = rss6.ModelSim(kp, dp, seed=seed, **kw)  # type: ignore[arg-type]
        return servo.track(plant, "dsmc", "exp1", kp_model=kp, dp_model=dp, duration=30.0)

    replay = track(0, pixel_noise=0.0, potentiometer_noise=0.0)
    sig = discrepancy.reference_signatures(replay.frame_time, replay.frame_desired)
    alarms = 0
    for seed in range(1, runs + 1):
        m = track(seed)
        alarms += discrepancy.detect(m.frame_time, m.measured - replay.measured, sig).detected
    print(
        f"3. closed loop (ModelSim, DSMC, Exp. 1, 30 s) minus its noise-free replay: "
        f"{alarms}/{runs} false alarms"
    )
    noise = discrepancy.noise_from_repeats(
        [track(1000 + i).measured - replay.measured for i in range(3)]
    )
    alarms = 0
    for seed in range(1, runs + 1):
        m = track(seed)
        alarms += discrepancy.detect(
            m.frame_time, m.measured - replay.measured, sig, noise
        ).detected
    print(f"   noise from 3 noisy replays (seeds 1000–1002): {alarms}/{runs} false alarms")
    effects = [
        {"joint_friction": {"coulomb": 0.05, "viscous": 0.0}},
        {"payload": {"mass": 0.5, "x": 0.0, "y": 0.0, "z": 0.0}},
        {"payload": {"mass": 0.1, "x": 0.0, "y": 0.0, "z": 0.0}},
        {"base_tilt": {"roll": 0.005, "pitch": 0.0}},
        {"base_tilt": {"roll": 0.001, "pitch": 0.0}},
    ]
    for eff in effects:
        m = track(1, effects=eff)
        r = m.measured - replay.measured
        for label, model in (("differences", None), ("replays", noise)):
            d = discrepancy.detect(m.frame_time, r, sig, model)
            ratio = np.sqrt(np.mean(r**2, axis=0)) / d.noise.sigma
            tops = {a: d.top_signature(a) for a in d.axes}
            print(f"   {eff} [{label}]: RMS/σ̂ {np.round(ratio, 2)}; {d.summary()}; top {tops}")


if __name__ == "__main__":
    synthetic(int(sys.argv[1]) if len(sys.argv) > 1 else 2000)
    closed_loop(int(sys.argv[2]) if len(sys.argv) > 2 else 20)
