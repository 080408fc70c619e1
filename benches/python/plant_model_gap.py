"""How far the model is from the rapier plant when both carry the same effect (issue 14, docs/
discrepancy.md "The model is not the robot"): noise-free plant runs (shared stick–slip law,
48 solver iterations) with each benchmark effect at the 5× magnitude, replayed on the model driven
by the run's recorded commands, without and with the true effect. Prints the pose residual RMS per
axis in units of Table 4.1's camera noise.

    python benches/python/plant_model_gap.py [--solver-iterations 48] [--magnitude 5]
        [--payload-com X Y Z] [EFFECT@SCOPE ...]

``--payload-com``: the payload's centre of mass in ΣE (m; the benchmark's is 0.02 0 0), to tell a
gap that follows the offset from one that follows the mass.
"""

from __future__ import annotations

import argparse

import numpy as np
import rss6
from rss6 import identify
from rss6.discrepancy import benchmark as bm
from rss6.discrepancy.model import Model, replay, run_of

#: The benchmark grid's library effects (benchmark.cases' defaults).
EFFECTS = sorted(
    {
        str(c["effect"])
        for c in bm.cases(magnitudes=(5.0,), n_null=0)
        if isinstance(c["effect"], str) and c["effect"] not in bm.OUT_OF_LIBRARY
    }
)


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--solver-iterations", type=int, default=48)
    ap.add_argument("--magnitude", type=float, default=5.0, help="effect size, × camera noise")
    ap.add_argument("--payload-com", type=float, nargs=3, metavar=("X", "Y", "Z"), default=None)
    ap.add_argument("effects", nargs="*", help=f"EFFECT or EFFECT@SCOPE (default: {EFFECTS})")
    a = ap.parse_args()
    if a.payload_com is not None:
        bm.REFERENCE["payload"].update(zip("xyz", a.payload_com, strict=True))
    iterations, args = a.solver_iterations, a.effects
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    exc = identify.random_excitation(kp, seed=1000)

    def plant(hidden: dict | None, gains: tuple[float, ...] = tuple(pid)) -> rss6.Plant:
        return rss6.Plant(
            kp,
            dp,
            pid=tuple(float(g) for g in gains),
            seed=1,
            effects=hidden,
            drive_derivative_filter=5e-3,
            implicit_friction=True,
            solver_iterations=iterations,
            pixel_noise=0.0,
            potentiometer_noise=0.0,
        )

    tr = plant(None).truth()
    model = Model(
        kp,
        dp,
        pid,
        tr["sensor_in_base"],
        tr["target_in_effector"],
        derivative_filter=5e-3,
        implicit_friction=True,
    )

    def collect(robot: rss6.Plant) -> identify.IdentificationData:
        return identify.collect(
            robot,
            exc,
            kp_model=kp,
            sensor_in_base=tr["sensor_in_base"],
            target_in_effector=tr["target_in_effector"],
        )

    def rms(x: np.ndarray) -> np.ndarray:
        return np.round(np.sqrt(np.mean(x[:, :6] ** 2, axis=0)) / bm.CAMERA_SIGMA, 2)

    run0 = run_of(collect(plant(None)))
    print("no effect: model − plant, RMS / σ per axis", rms(run0.channels - replay(model, run0)))
    print(f"plant: {iterations} solver iterations")
    for name in args or EFFECTS:
        e, scope = bm._split(name)
        params, got = bm.magnitude(model, run0, name, a.magnitude)
        params = e.check(params, scope)
        c = e.apply(params, scope)
        hidden = bm.robot_effects(e, params, scope)
        gains = tuple(g * (1 + d) for g, d in zip(pid, c.gains, strict=True))
        run = run_of(collect(plant(hidden or None, gains)))
        print(f"{name} at {got:.2f}× ({params})")
        print("   without the effect", rms(run.channels - replay(model, run)))
        print("   with the true effect", rms(run.channels - replay(model, run, c)))


if __name__ == "__main__":
    main()
