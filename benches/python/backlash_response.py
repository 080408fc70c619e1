"""Why the discrepancy benchmark's backlash widths come out low under the stick–slip law (issue 14,
docs/discrepancy.md "A slow drift found by elapsed time, backlash sized by its width").

    python benches/python/backlash_response.py

1. The plant and the model twin in their closed loops, noise-free, on the benchmark's excitation of
   seed 0 with the stick–slip (implicit) friction law: the pose change from the mesh at width 0
   and from widths of 0.38 and 1.9 mrad, in units of the camera's σ per axis — does the plant's
   drive train respond to a width as the twin's does?
2. The benchmark's 5× backlash case of seed 0 with the twin as the robot under that law: how much
   the mean noisy replay's bias moves with the width, and the unwhitened misfit of the fitting run
   and of the mean noisy replay at the true width against the replay at f × the true width plus
   the null model's bias.
3. On the same case, the cost the search minimises (every channel, whitened by the null model's
   noise model) with the null model's bias, as the workflow does, and with the replays' bias at
   f × the width.
"""

from __future__ import annotations

import numpy as np
import rss6
from rss6 import identify
from rss6.discrepancy import benchmark as bm
from rss6.discrepancy.effects import get
from rss6.discrepancy.model import replay, run_of, simulate
from rss6.discrepancy.search import calibrate

F64 = np.ndarray


def _rms(x: F64) -> F64:
    return np.round(np.sqrt(np.mean(x * x, axis=0)) / bm.CAMERA_SIGMA, 2)


def responses() -> None:
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    exc = identify.random_excitation(kp, seed=1000, harmonics=5)

    def make(cls: type, width: float | None) -> object:
        kw = {
            "drive_derivative_filter": bm._T_F,
            "implicit_friction": True,
            "pixel_noise": 0.0,
            "potentiometer_noise": 0.0,
        }
        if cls is rss6.Plant:
            kw.update(bm._PLANT_IMPLICIT)
        eff = None if width is None else {"backlash": {"width": width}}
        return cls(kp, dp, pid=tuple(float(g) for g in pid), seed=1, effects=eff, **kw)

    print("1. closed loop, noise-free, pose change / camera σ (x y z α β γ)")
    for name, cls in (("plant", rss6.Plant), ("twin", rss6.ModelSim)):
        tr = make(cls, None).truth()
        runs = {
            w: identify.collect(
                make(cls, w),
                exc,
                kp_model=kp,
                sensor_in_base=tr["sensor_in_base"],
                target_in_effector=tr["target_in_effector"],
            ).measured[:, :6]
            for w in (None, 0.0, 0.38e-3, 1.9e-3)
        }
        print(f"   {name}: mesh at width 0 {_rms(runs[0.0] - runs[None])}")
        for w in (0.38e-3, 1.9e-3):
            print(f"   {name}: width {w * 1e3:.2f} mrad beyond width 0 {_rms(runs[w] - runs[0.0])}")


def misfit() -> None:
    spec = {
        "robot": "twin",
        "friction_law": "implicit",
        "effect": "backlash",
        "magnitude": 5.0,
        "seed": 0,
    }
    case = bm.hidden_case(spec)
    m, run = case.model, run_of(case.fit, commands="recorded")
    e, w = get("backlash"), case.params["backlash"]["width"]

    def mean_noisy(width: float, k: int = 16) -> tuple[F64, F64]:
        change = e.apply({"width": width}, "all joints")
        clean = simulate(m, run, change)
        dev = [simulate(m, run, change, seed=100 + s).noise(clean, run)[:, :6] for s in range(k)]
        return clean.at(run)[:, :6], np.mean(dev, axis=0)

    c0, b0 = mean_noisy(0.0)
    cw, bw = mean_noisy(w)
    print(f"2. twin as the robot, stick–slip law, 5× backlash of seed 0 (width {w * 1e3:.3f} mrad)")
    print(f"   clean effect of the width {_rms(cw - c0)}")
    print(
        f"   mean-replay bias at width 0 {_rms(b0)}, at the width {_rms(bw)}, moved {_rms(bw - b0)}"
    )
    for f in (0.8, 0.85, 0.9, 0.95, 1.0, 1.05):
        cf = replay(m, run, e.apply({"width": f * w}, "all joints"))[:, :6]
        r = (run.channels[:, :6] - cf - b0) / bm.CAMERA_SIGMA
        q = (cw + bw - cf - b0) / bm.CAMERA_SIGMA
        print(
            f"   f = {f:.2f}: fitting run's unwhitened misfit {float(np.sum(r * r)):.0f}; "
            f"against the mean noisy replay at the width {float(np.sum(q * q)):.0f}"
        )
    # 3. The cost the search minimises: the fitting run's residual on every channel, whitened by
    # the noise model of the null model's replays, with the null model's bias (what the workflow
    # does) or with the bias of the replays at f × the width.
    change0 = e.apply({"width": 0.0}, "all joints")
    clean0 = simulate(m, run, change0)
    dev0 = [simulate(m, run, change0, seed=100 + s).noise(clean0, run) for s in range(16)]
    bias0 = np.mean(dev0, axis=0)
    white = calibrate([d - bias0 for d in dev0]).whitener
    print("3. whitened cost of the fitting run (every channel), bias of the null model / at f × w")
    for f in (0.8, 0.85, 0.9, 0.95, 1.0, 1.05):
        ch = e.apply({"width": f * w}, "all joints")
        clean = simulate(m, run, ch)
        dev = [simulate(m, run, ch, seed=100 + s).noise(clean, run) for s in range(16)]
        r0 = white.vec(run.channels - clean.at(run) - bias0)
        r1 = white.vec(run.channels - clean.at(run) - np.mean(dev, axis=0))
        print(f"   f = {f:.2f}: {float(r0 @ r0):.0f} / {float(r1 @ r1):.0f}")


if __name__ == "__main__":
    responses()
    misfit()
