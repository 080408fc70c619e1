"""``rss6 identify``: the command line of the dynamic identification (thesis ch. 5) on a
simulated robot (:func:`rss6.identify_sim.run`)."""

from __future__ import annotations

import argparse
import sys

from rss6._argtypes import count, seed
from rss6.cli import _check_plant, _progress, out_dir

__all__ = ["DESCRIPTION", "add_arguments", "run"]

DESCRIPTION = (
    "With --simulate: design an exciting trajectory (§5.4), run the identification "
    "loop of Fig. 5.1 on the simulated robot whose truth is Table 5.2's identified values "
    "(rss6.identify.table_5_2_truth), identify Ξ and the drive PID gains by CLOE (§5.3) from "
    "Table 5.1, validate on fresh random trajectories, print Tables 5.2–5.4 beside the thesis's, "
    "write Figs. 5.7–5.9 (PNG), an MCAP log per run and tables.txt to --out. Exit status 3 if "
    "CLOE did not converge (the report then shows the last iterate and the cost history), 4 if "
    "the identification run on the robot failed (the visual PID faulted)."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``rss6 identify``."""
    p.add_argument("--simulate", action="store_true", help="identify a simulated robot")
    p.add_argument("--out", default="out-identify", help="output directory (default out-identify/)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the design, noise, validation")
    p.add_argument(
        "--quick",
        action="store_true",
        help="2 s trajectory, 10 CLOE iterations, 2 validation runs: under a minute",
    )
    p.add_argument(
        "--periods",
        type=count(1),
        default=None,
        help="periods of the exciting trajectory in the identification run (default 10; 1 with "
        "--quick)",
    )
    p.add_argument(
        "--plant",
        choices=("auto", "rapier", "model"),
        default="auto",
        help="the simulated robot: rapier plant (default when built) or the analytic-model twin",
    )
    p.add_argument(
        "--as-printed",
        action="store_true",
        help="the loop as the thesis prints it: unfiltered drive derivative (eq. 5.5) and sign "
        "Coulomb friction in the model, CLOE from Table 5.1 (implies --friction-law tanh; default: "
        "5 ms derivative filter, stick–slip friction)",
    )
    p.add_argument(
        "--friction-law",
        choices=("tanh", "implicit"),
        default=None,
        help="joint friction of plant and model: 'implicit' (default) = stick–slip stepped "
        "implicitly in both (plant at 48 solver iterations), a linear start from the recorded "
        "commands and potentiometers with l_p known, CLOE on the recorded commands; 'tanh' = the "
        "plant's own friction and tanh(θ̇/ε) in the model, CLOE from Table 5.1 (does not converge "
        "on the plant; the default with --as-printed)",
    )
    p.add_argument(
        "--no-variation",
        action="store_true",
        help="skip Table 5.5 (re-identification on every validation run: most of a full run's time)",
    )
    p.add_argument(
        "--replicates",
        type=count(0),
        default=16,
        help="each σ is also the spread over N noisy replicate runs of the model twin at the "
        "estimate (default 16; 0: CLOE's σ alone)",
    )
    p.add_argument(
        "--noise",
        choices=("table", "frames"),
        default="table",
        help="the residual's weights: Table 4.1's σ per axis (default) or, in a second pass, the "
        "covariance of the first fit's residual per camera frame (frames; docs/identification.md)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress bars or report on stdout")


def run(args: argparse.Namespace) -> int:
    from rss6 import identify_sim

    if not args.simulate:
        print("rss6: error: identify needs --simulate (the only mode so far)", file=sys.stderr)
        return 2
    quiet = bool(args.quiet)
    if args.plant == "rapier":
        _check_plant("rapier")
    out_dir(args.out)
    report = identify_sim.run(
        args.out,
        quick=args.quick,
        seed=args.seed,
        plant=args.plant,
        progress=lambda total, desc: _progress(total, desc, quiet),
        as_printed=args.as_printed,
        variation=not args.no_variation,
        friction_law=args.friction_law or ("tanh" if args.as_printed else "implicit"),
        periods=args.periods,
        replicates=args.replicates,
        noise=None if args.noise == "table" else args.noise,
    )
    text = report.text()
    (report.files[0].parent / "tables.txt").write_text(text + "\n", encoding="utf-8")
    if not quiet:
        print(text, flush=True)
    if report.run_failed:
        print(f"rss6: the identification run failed: {report.run_failed}", file=sys.stderr)
        return 4
    if not report.converged:
        print(
            f"rss6: CLOE did not converge ({report.error}); cost history "
            f"{[round(float(c), 4) for c in report.cost_history]}",
            file=sys.stderr,
        )
        return 3
    return 0
