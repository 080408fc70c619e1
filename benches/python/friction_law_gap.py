"""The plant–twin gap under Table 5.2's friction for each friction law and plant setting
(docs/sim.md, "One friction law for plant and twin"): the same joint commands (3 s of sines per joint,
then held) to each simulator; largest platform-position gap over 4 s against the twin with
the shared implicit law, and the cost per tick.

    python benches/python/friction_law_gap.py
"""

from __future__ import annotations

import time

import numpy as np
import rss6
from rss6 import identify


def main() -> None:
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    th0 = np.asarray(rss6.ik(kp, rss6.home_pose()))
    t = np.arange(4000) * 1e-3
    amp = np.array([0.05, 0.03, 0.04, 0.02, 0.05, 0.03])
    cmds = th0 + amp * np.sin(2 * np.pi * np.outer(t, [0.5, 0.7, 0.3, 1.1, 0.9, 0.4]))
    cmds[3000:] = cmds[2999]

    def run(sim: object) -> tuple[np.ndarray, float]:
        out = []
        t0 = time.perf_counter()
        for c in cmds:
            sim.step_joint_command(c)  # type: ignore[attr-defined]
            out.append(sim.true_pose())  # type: ignore[attr-defined]
        return np.array(out), (time.perf_counter() - t0) / len(cmds)

    ref, _ = run(rss6.ModelSim(kp, dp, pid=pid, implicit_friction=True))
    rows = [
        ("twin, sign law (thesis)", rss6.ModelSim(kp, dp, pid=pid)),
        ("twin, tanh ε = 0.3 rad/s", rss6.ModelSim(kp, dp, pid=pid, friction_smoothing=0.3)),
        ("twin, tanh ε = 1 rad/s", rss6.ModelSim(kp, dp, pid=pid, friction_smoothing=1.0)),
        ("plant, engine friction (default)", rss6.Plant(kp, dp, pid=pid)),
    ]
    for it in (4, 16, 32, 48, 64):
        rows.append(
            (
                f"plant, implicit law, {it} iterations",
                rss6.Plant(kp, dp, pid=pid, implicit_friction=True, solver_iterations=it),
            )
        )
    rows.append(
        (
            "plant, implicit law, 4 iterations + velocity projection",
            rss6.Plant(kp, dp, pid=pid, implicit_friction=True, velocity_projection=True),
        )
    )
    print(f"{'simulator (vs twin with the implicit law)':58s} {'gap µm':>9s} {'µs/tick':>8s}")
    for name, sim in rows:
        poses, per_tick = run(sim)
        gap = np.linalg.norm(poses[:, :3] - ref[:, :3], axis=1).max()
        print(f"{name:58s} {gap * 1e6:9.1f} {per_tick * 1e6:8.0f}")


if __name__ == "__main__":
    main()
