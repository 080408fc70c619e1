"""``rss6 study calibration|identification|discrepancy --n N --out FILE [--scheduler ADDR]
[--workers K]``: a study on Dask (a LocalCluster of K process workers, or the cluster at ADDR);
prints the study's summary. Rerunning with the same ``--out`` resumes."""

from __future__ import annotations

import argparse
from typing import Any

from rss6._argtypes import count, seed
from rss6.errors import InvalidInputError

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``study`` subcommand's arguments."""
    p.add_argument("kind", choices=("calibration", "identification", "discrepancy"))
    p.add_argument(
        "--n",
        type=count(1),
        required=True,
        help="robots / trajectories / no-effect cases (discrepancy: with the effects)",
    )
    p.add_argument("--out", required=True, help="records file (CSV); rerun to resume")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://HOST:8786)")
    p.add_argument("--workers", type=count(1), default=2, help="local worker processes (default 2)")
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument(
        "--seeds",
        type=count(1),
        default=1,
        help="discrepancy: seeds per effect × magnitude (seed, seed + 1, …; default 1)",
    )
    p.add_argument(
        "--plant",
        action="store_true",
        help="calibration: the rapier plant; discrepancy: the rapier plant",
    )
    p.add_argument(
        "--quick",
        action="store_true",
        help="identification: 2 s trajectories, 10 iterations, the drive gains only",
    )
    p.add_argument(
        "--friction-law",
        choices=("tanh", "implicit"),
        default=None,
        help="identification: joint friction of robot and model (implicit, the default: "
        "stick–slip, linear start with l_p known, CLOE on the recorded commands); discrepancy: "
        "the robot's and model's friction law (default implicit on the plant — the plant then "
        "follows the model to ≈ 1.5 µm — and tanh on the twin)",
    )

    p.add_argument(
        "--pot-noise",
        choices=("recorded", "model", "none"),
        default="recorded",
        help="identification: the model's drive replays the potentiometer noise estimated from "
        "the recorded readings (recorded, the default), then against the first estimate's model "
        "in a second pass (model), or reads clean angles (none)",
    )
    p.add_argument(
        "--replicates",
        type=count(0),
        default=16,
        help="identification: each σ is also the spread over N noisy replicate runs of the model "
        "twin at the estimate, the larger kept (default 16; 0: CLOE's σ alone)",
    )
    p.add_argument(
        "--bootstrap",
        action="store_true",
        help="identification: identify each replicate again (the parametric bootstrap; ≈ N + 1 "
        "times the work) instead of carrying it through CLOE's linear map",
    )
    p.add_argument(
        "--noise",
        choices=("table", "frames", "dwells"),
        default="table",
        help="the residual's weights — Table 4.1's σ per axis (table, the default); "
        "identification: in a second pass, the frames' covariance estimated from the first "
        "(frames: camera axes whose noise is correlated are weighted together); calibration: "
        "the camera covariance pooled from the dwells' own frames (dwells)",
    )
    p.add_argument(
        "--replicate-bias",
        action="store_true",
        help="identification: move each estimate by minus its replicates' mean deviation (the "
        "procedure's bias at the estimate) and widen its σ by that mean's error",
    )
    p.add_argument(
        "--profile",
        default="",
        metavar="NAMES",
        help="identification: also the 95 %% profile-likelihood interval of these comma-separated "
        "quantities (e.g. fv1,fv3; ≈ 5–7 CLOE runs each per trajectory), and how often it holds "
        "the truth",
    )
    p.add_argument(
        "--solver-iterations",
        type=count(1),
        default=None,
        help="identification, and discrepancy with --plant: the rapier plant's solver "
        "iterations (default: identification 48, discrepancy 100 — docs/sim.md)",
    )


def run(args: argparse.Namespace) -> int:
    """Runs the study and prints its summary."""
    from rss6 import studies

    # A count below 1 is refused by the study functions themselves.
    if args.solver_iterations is not None and (
        args.kind == "calibration" or (args.kind == "discrepancy" and not args.plant)
    ):
        raise InvalidInputError(
            "--solver-iterations needs the rapier plant (identification, or --plant)"
        )
    wrong = {"frames": "identification", "dwells": "calibration"}.get(args.noise)
    if wrong is not None and args.kind != wrong:
        raise InvalidInputError(f"--noise {args.noise} is for the {wrong} study")
    common: dict[str, Any] = {
        "out": args.out,
        "client": args.scheduler,
        "workers": args.workers,
        "seed": args.seed,
    }
    if args.kind == "calibration":
        df = studies.calibration_study(args.n, plant=args.plant, noise=args.noise, **common)
        print(studies.summary_calibration(df))
    elif args.kind == "identification":
        df = studies.identification_variation(
            args.n,
            robot="plant",
            quick=args.quick,
            parameters=["lp", "li", "ld"] if args.quick else "base",
            friction_law=args.friction_law or "implicit",
            pot_noise=args.pot_noise,
            solver_iterations=args.solver_iterations,
            replicates=args.replicates,
            bootstrap=args.bootstrap,
            profile=[n for n in args.profile.split(",") if n],
            noise=None if args.noise == "table" else args.noise,
            replicate_bias=args.replicate_bias,
            **common,
        )
        print(studies.summary_identification(df))
    else:
        from rss6.discrepancy.benchmark import cases

        if args.seeds < 1:
            raise InvalidInputError(f"--seeds must be >= 1, got {args.seeds}")
        specs = cases(
            seeds=tuple(range(args.seed, args.seed + args.seeds)),
            n_null=args.n,
            robot="plant" if args.plant else "twin",
            friction_law=args.friction_law or ("implicit" if args.plant else "tanh"),
            **({"solver_iterations": args.solver_iterations} if args.plant else {}),
        )
        df = studies.discrepancy_benchmark(specs, **common)
        print(studies.summary_discrepancy(df))
    bad = int((df["status"] != "ok").sum())
    if bad:
        print(f"{bad} tasks ended in an error (their records say why)")
    return 0
