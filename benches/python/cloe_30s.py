"""Issue 13's speed figure: one CLOE with the full (identifiable) parameter set on a 30 s
trajectory (1 kHz model, 30 Hz camera), from the thesis's initial model through the linear start,
on the model twin with the stick–slip law (`identify_sim.estimate_from_initial`, l_p held, recorded
commands, per-tick Jacobians while iterating). Prints the wall time of the whole estimate (the
linear start, CLOE and one simulation of the initial model) and of the CLOE call alone, its
iterations and simulations, the per-iteration cost and the quantities left out. Run on an idle
machine.

    python benches/python/cloe_30s.py [--seed 0] [--periods 3] [--prior-log-std 1.0] [--trace]
        [--parameters fc1,fc2,...] [--designed] [--settle-steps 3]

``--prior-log-std``: σ of CLOE's log-prior around the linear start (default 1.0, CLOE's own); a
failure to converge prints the cost history instead of raising. ``--trace``: Φ and the wall time
after every accepted iteration. ``--parameters``: estimate only these quantities (the others stay
at the linear start; l_p stays at the drive's value), e.g. the friction and gains alone.
``--settle-steps``: CLOE's ``settle_steps`` (the *settled* rule's look-back, default 3; 5 until the fourteenth session).
``--designed``: three periods of the designed exciting trajectory instead of a random feasible one
(the default, thesis-size box 10⁻³ m/s, 5·10⁻³ rad/s).
"""

from __future__ import annotations

import argparse
import time
from functools import partial
from typing import Any

import rss6
from rss6 import identify, identify_sim


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--periods", type=int, default=3, help="10 s periods of the excitation")
    ap.add_argument("--prior-log-std", type=float, default=1.0)
    ap.add_argument(
        "--settle-steps", type=int, default=3,
        help="accepted steps the settled stopping rule looks back over (CLOE's default 3)",
    )  # fmt: skip
    ap.add_argument("--trace", action="store_true", help="print Φ after every iteration")
    ap.add_argument("--parameters", default="base", help="comma-separated names, or base")
    ap.add_argument(
        "--designed", action="store_true",
        help="the exciting trajectory rss6 identify --simulate designs (30 generations)",
    )  # fmt: skip
    args = ap.parse_args()
    params: str | list[str] = (
        "base" if args.parameters == "base" else [p.strip() for p in args.parameters.split(",")]
    )
    if args.prior_log_std != 1.0:
        identify.cloe = partial(identify.cloe, prior_log_std=args.prior_log_std)  # type: ignore[assignment]
    if args.settle_steps != 3:
        identify.cloe = partial(identify.cloe, settle_steps=args.settle_steps)  # type: ignore[assignment]
    # The wall time of the identify.cloe call alone, beside the whole estimate's.
    cloe_alone: list[float] = []
    inner_cloe = identify.cloe

    def timed_cloe(*a: Any, **k: Any) -> Any:
        t = time.perf_counter()
        try:
            return inner_cloe(*a, **k)
        finally:
            cloe_alone.append(time.perf_counter() - t)

    identify.cloe = timed_cloe  # type: ignore[assignment]
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    robot = rss6.ModelSim(
        kp,
        dp,
        pid=pid,
        seed=args.seed,
        drive_derivative_filter=identify_sim.DRIVE_DERIVATIVE_FILTER,
        implicit_friction=True,
    )
    tr = robot.truth()
    exc = (
        identify.excitation(kp, seed=args.seed, maxiter=30)
        if args.designed
        else identify.random_excitation(
            kp, harmonics=5, f0=0.1, seed=args.seed, amplitude=(0.001, 0.005)
        )
    )
    data = identify.collect(
        robot,
        exc,
        kp_model=kp,
        sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
        periods=args.periods,
    )
    t0 = time.perf_counter()

    def trace(iteration: int, cost: float) -> None:
        if args.trace:
            print(f"  iteration {iteration:3d}  Φ {cost:10.1f}  {time.perf_counter() - t0:6.1f} s")

    try:
        res = identify_sim.estimate_from_initial(
            data, kp, friction_law="implicit", lp=pid[0], max_iterations=40,
            parameters=params, progress=trace, pot_noise="none",
        )  # fmt: skip
    except rss6.IdentificationError as e:
        wall = time.perf_counter() - t0
        hist = getattr(e, "cost_history", [])
        print(
            f"not converged after {wall:.1f} s: {len(hist)} costs, {hist[0]:.0f} → {hist[-1]:.0f}"
            if len(hist)
            else f"failed after {wall:.1f} s: {e}"
        )
        return
    wall = time.perf_counter() - t0
    print(
        f"{data.duration:.0f} s trajectory, {len(data.t)} frames: CLOE of {len(res.identified)} "
        f"quantities {wall:.1f} s (the linear start and one simulation of the initial model for "
        f"Table 5.3 included; the CLOE call alone {sum(cloe_alone):.1f} s), {res.iterations} iterations, "
        f"{res.simulations} plain simulations, {wall / max(res.iterations, 1):.2f} s per iteration, "
        f"reduced χ² {res.reduced_chi2:.3f}, stopped by {res.converged_by}"
    )
    print(f"not identifiable ({len(res.unidentifiable)}): {', '.join(res.unidentifiable)}")


if __name__ == "__main__":
    main()
