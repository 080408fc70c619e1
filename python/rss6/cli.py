"""The ``rss6`` command line.

``rss6 demo``            calibrate a simulated robot by RPBA, then run Experiments 1 and 2 (thesis §6.5)
                         with KJSC, KCSC and DSMC; print Tables 6.1/6.2 beside the thesis's; write
                         MCAP logs and figures to ``--out``.
``rss6 calibrate --simulate``   the calibration study of §4.4.3: Tables 4.3–4.5 over random robots.
``rss6 calibrate --mcap FILE``  collect a calibration on a simulated robot, logging the raw dwells to
                         FILE as it goes, then calibrate from the log.
``rss6 calibrate --from-mcap FILE``  calibrate from a logged collection (also a truncated one).
``rss6 track``           one tracking run (controller × trajectory) with an MCAP log.
``rss6 identify --simulate``  dynamic identification of a simulated robot (thesis §5.6): exciting
                         trajectory, the loop of Fig. 5.1 on the rapier plant, CLOE, Tables 5.2–5.4
                         beside the thesis's, Figs. 5.7–5.9 and MCAP logs in ``--out``.
``rss6 study KIND``      a study on Dask (calibration, identification, discrepancy; rss6.studies).
``rss6 diagnose``        the discrepancy workflow: on logged runs and a model directory, or with
                         ``--simulate EFFECT`` hidden in a simulated robot (rss6.discrepancy.cli).
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, NoReturn

import numpy as np

from rss6._argtypes import count, positive, seed
from rss6.types import CONTROLLERS, TRAJECTORIES, TUNINGS, PlantKind, Robot

if TYPE_CHECKING:
    from numpy.typing import ArrayLike
    from tqdm import tqdm

    from rss6._rss6 import DynamicParams, KinematicParams

__all__ = ["build_parser", "main"]


def _progress(total: int, desc: str, quiet: bool) -> tqdm[NoReturn]:
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, disable=quiet, leave=False, file=sys.stderr)


def make_plant(
    kind: PlantKind,
    kp_true: KinematicParams,
    dp: DynamicParams,
    seed: int,
    sensor_in_base: ArrayLike | None,
    target_in_effector: ArrayLike | None,
) -> Robot:
    """The simulated "real robot" (see :func:`rss6.demo.make_plant`)."""
    from rss6 import demo

    _check_plant(kind)
    return demo.make_plant(kind, kp_true, dp, seed, sensor_in_base, target_in_effector)


def _check_plant(kind: PlantKind) -> None:
    """Exits if ``kind`` asks for the rapier plant and this build has none."""
    import rss6

    if kind == "rapier" and rss6.Plant is None:
        raise SystemExit("rss6: this build has no rapier plant (rss6.Plant); use --plant model")


def out_dir(path: str) -> str:
    """``--out``'s directory checked before the work (made only when something is written): a file
    in its place or in its way, or a place that cannot be written, is an
    :class:`rss6.InvalidInputError` now, not an ``OSError`` after the run."""
    import os
    from pathlib import Path

    from rss6.errors import InvalidInputError

    p = Path(path).absolute()
    if p.exists() and not p.is_dir():
        raise InvalidInputError(f"--out {path} is a file; give a directory")
    q = p
    while not q.exists():
        q = q.parent
    if not q.is_dir():
        raise InvalidInputError(f"--out {path}: {q} is a file, so the directory cannot be made")
    if not os.access(q, os.W_OK | os.X_OK):
        raise InvalidInputError(f"--out {path}: {q} is not writable")
    return path


def cmd_demo(args: argparse.Namespace) -> int:
    from rss6 import demo

    quiet = bool(args.quiet)
    _check_plant(args.plant)
    out_dir(args.out)
    report = demo.run(
        args.out,
        quick=args.quick,
        seed=args.seed,
        plant=args.plant,
        progress=lambda total, desc: _progress(total, desc, quiet),
    )
    if not quiet:
        print(report.text(), flush=True)
    return 0


def _calibrate_log(args: argparse.Namespace, path: str, plant: Robot | None = None) -> int:
    """Calibrates from the MCAP log at ``path`` (RPBA or implicit); with the simulated ``plant`` that
    produced it, also prints Table 4.5's relative pose errors before and after."""
    import rss6
    from rss6 import calibrate

    nominal = rss6.KinematicParams.nominal()
    log = calibrate.read_mcap(path)
    n_all = len(log.used) + len(log.dropped)
    print(
        f"{path}: {len(log.used)} of {n_all} configurations usable"
        + ("" if log.complete else " (the file is truncated: read up to its last whole chunk)")
    )
    for index, why in log.dropped:
        print(f"  configuration {index} left out: {why}")
    if args.method == "implicit":
        result = calibrate.implicit(
            log.data, nominal, calibrate.default_placement()[0], noise=args.noise
        )
    else:
        result = calibrate.rpba(log.data, nominal, noise=args.noise)
    cost = result.cost_history
    print(
        f"{result.method}: {result.iterations} LM steps, cost {cost[0]:.4g} -> {cost[-1]:.4g}, "
        f"rank {result.rank}/{result.parameter_count}, fit statistic {result.fit_statistic:.3f} "
        f"(≈ 1 when the model explains the data; {result.degrees_of_freedom} degrees of freedom)"
    )
    for index, z in result.rejected:
        print(f"  configuration {index} rejected as a gross outlier (normalised residual {z:.3g})")
    for index, why in result.dropped:
        print(f"  configuration {index} left out of the fit: {why}")
    u = result.unidentifiable
    if u:
        print(f"  {len(u)} parameters not identifiable from these data: {', '.join(u[:6])}, …")
    b = np.asarray(result.errors)
    print(
        f"  identified errors: lengths/positions max {np.abs(b[:48]).max() * 1e3:.3f} mm, "
        f"η max {np.abs(b[48:54]).max():.3g} rad/bit, Δθ max {np.degrees(np.abs(b[54:60]).max()):.3f}°"
    )
    if plant is not None:
        lo, hi = calibrate.stroke(nominal)
        n = 50 if args.quick else 100
        unc = calibrate.relative_pose_errors(None, plant, n=n, seed=args.seed, stroke=(lo, hi))
        cal = calibrate.relative_pose_errors(result, plant, n=n, seed=args.seed, stroke=(lo, hi))
        print(
            f"RMS relative pose errors on {n} test configurations (x, y, z mm; α, β, γ 1e-3 rad):"
        )
        for name, e in (("uncalibrated", unc["rms"]), (result.method, cal["rms"])):
            print(f"  {name:13s} " + " ".join(f"{v * 1e3:8.4f}" for v in e))
    if args.out:
        result.params.to_toml(args.out)
        print(f"wrote {args.out}")
    return 0


def cmd_calibrate_mcap(args: argparse.Namespace) -> int:
    """``rss6 calibrate --mcap FILE``: collect on a simulated robot, logging to FILE, then calibrate."""
    import rss6
    from rss6 import calibrate

    seed = args.seed
    nominal = rss6.KinematicParams.nominal()
    kp_true = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed))
    sensor_design, target_design = calibrate.default_placement()
    plant = make_plant(
        "rapier" if args.plant else "model",
        kp_true,
        rss6.DynamicParams.nominal(),
        seed,
        calibrate.draw_external(sensor_design, seed + 1),
        calibrate.draw_external(target_design, seed + 2),
    )
    lo, hi = calibrate.stroke(nominal)
    method = "implicit" if args.method == "implicit" else "rpba"
    thetas = calibrate.select_configurations(
        nominal, method, seed, candidates=400 if args.quick else 5000, stroke=(lo, hi)
    )
    print(
        f"collecting {len(thetas) - 1} {args.method} configurations + initial on rss6."
        f"{type(plant).__name__} (robot with Table 4.2 errors, seed {seed}), dwell {args.dwell} s; "
        f"logging to {args.mcap} (on disk after every dwell)",
        flush=True,
    )
    plant.reset(rss6.home_pose())
    with _progress(len(thetas), "calibration: measuring configurations", args.quiet) as bar:
        calibrate.collect(
            plant,
            thetas,
            args.dwell,
            move_time=0.5 if args.quick else 1.0,
            progress=lambda d, t: bar.update(1),
            mcap=args.mcap,
        )
    return _calibrate_log(args, args.mcap, plant)


def cmd_calibrate(args: argparse.Namespace) -> int:
    import rss6
    from rss6 import _rss6, calibrate

    if args.from_mcap:
        return _calibrate_log(args, args.from_mcap)
    if args.mcap:
        return cmd_calibrate_mcap(args)
    if not args.simulate:
        print(
            "rss6 calibrate: choose --simulate (the study of §4.4.3), --mcap FILE (collect on a "
            "simulated robot, logging to FILE) or --from-mcap FILE (calibrate from a logged "
            "collection)",
            file=sys.stderr,
        )
        return 2
    if args.out:
        from rss6.errors import InvalidInputError

        raise InvalidInputError("--out writes the kinematics calibrated by --mcap or --from-mcap")
    t0 = time.perf_counter()
    nominal = rss6.KinematicParams.nominal()
    lo, hi = calibrate.stroke(nominal)
    cand = 400 if args.quick else 5000
    th_r = calibrate.select_configurations(
        nominal, "rpba", args.seed, candidates=cand, stroke=(lo, hi)
    )
    th_i = calibrate.select_configurations(
        nominal, "implicit", args.seed, candidates=cand, stroke=(lo, hi)
    )
    robots = args.robots if args.robots is not None else (3 if args.quick else 20)
    print(
        f"§4.4.1 stroke: ({np.degrees(lo):.1f}°, {np.degrees(hi):.1f}°)   [thesis (−57.1°, 57.1°)]"
    )
    print(
        f"§4.4.2 configurations: RPBA {len(th_r) - 1} + initial, implicit {len(th_i) - 1} + initial   "
        f"[thesis 22 and 34]"
    )
    source = (
        "the rapier plant and its stereo CMM"
        if args.plant
        else "analytic generator, Table 4.1 noise"
    )
    weights = "; weighted by the dwells' camera covariance" if args.noise == "dwells" else ""
    print(f"§4.4.3 study over {robots} random robots ({source}, dwell {args.dwell} s{weights})")
    rows = _rss6.calibration_study(
        th_r,
        th_i,
        robots=robots,
        seed=args.seed,
        dwell=args.dwell,
        stroke=(lo, hi),
        plant=args.plant,
        noise=args.noise,
    )

    def mp(vals: Sequence[float]) -> str:
        v = np.asarray(vals, dtype=float)
        return f"{v.mean():.4g} (p95 {np.percentile(v, 95):.4g})"

    th = calibrate.THESIS_TABLES_4_3_4_4
    for tab, key, name in (("4.3", "implicit", "implicit"), ("4.4", "rpba", "RPBA")):
        print(f"\nTable {tab} — {name}: mean (95th percentile) over robots; thesis in brackets")
        pe = [r[f"{key}_param_error"] for r in rows]
        rs = [r[f"{key}_residual"] for r in rows]
        t = th[name]
        print(
            f"  ‖b − b_true‖ (Table 4.2 σ units, gauge-aligned)  before {mp([p[0] for p in pe])} "
            f"[{t['param_error'][0]}]   after {mp([p[1] for p in pe])} [{t['param_error'][1]}]"
        )
        print(
            f"  Σ‖Φ‖                                             before {mp([p[0] for p in rs])} "
            f"[{t['residual'][0]}]   after {mp([p[1] for p in rs])} [{t['residual'][1]}]"
        )
    print(
        "\nTable 4.5 — RMS relative pose errors (x, y, z mm; α, β, γ rad): mean (95th percentile)"
    )
    for key, name in (
        ("rms_uncalibrated", "uncalibrated"),
        ("rms_implicit", "implicit"),
        ("rms_rpba", "RPBA"),
    ):
        v = np.array([r[key] for r in rows])
        scale = np.r_[1e3, 1e3, 1e3, 1, 1, 1]
        mean = v.mean(0) * scale
        p95 = np.percentile(v, 95, axis=0) * scale
        thesis = np.asarray(calibrate.THESIS_TABLE_4_5[name]) * scale
        print(
            f"  {name:13s} "
            + "  ".join(f"{m:.3g} ({p:.3g}) [{t:.2g}]" for m, p, t in zip(mean, p95, thesis))
        )
    print(f"\n({time.perf_counter() - t0:.1f} s)")
    return 0


def cmd_track(args: argparse.Namespace) -> int:
    import rss6
    from rss6 import servo

    kp_true = (
        rss6.KinematicParams.load(args.true_kinematics)
        if args.true_kinematics
        else rss6.KinematicParams.nominal()
    )
    kp_model = (
        rss6.KinematicParams.load(args.model_kinematics)
        if args.model_kinematics
        else rss6.KinematicParams.nominal()
    )
    dp = rss6.DynamicParams.nominal()
    plant = make_plant(args.plant, kp_true, dp, args.seed, None, None)
    with _progress(round(args.duration), f"{args.controller} on {args.trajectory}", False) as bar:
        r = servo.track(
            plant,
            args.controller,
            args.trajectory,
            kp_model,
            dp,
            args.duration,
            mcap=args.mcap,
            progress=lambda t, d: bar.update(round(t + 1e-3) - bar.n),
            tuning=args.tuning,
        )
    print(f"{r.controller} on {args.trajectory} ({args.duration} s, rss6.{type(plant).__name__})")
    print("RMSE (x, y, z mm; α, β, γ 1e-3 rad): " + " ".join(f"{v:.3f}" for v in r.table()["rmse"]))
    print("MAE  (x, y, z mm; α, β, γ 1e-3 rad): " + " ".join(f"{v:.3f}" for v in r.table()["mae"]))
    if r.fault:
        print(f"fault at t = {r.fault[0]:.3f} s: {r.fault[1]}")
    if args.mcap:
        print(f"wrote {args.mcap}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="rss6",
        description="Calibration, simulation and visual servoing of 6-RSS parallel robots (Li 2020).",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND")

    d = sub.add_parser(
        "demo",
        help="calibrate a simulated robot (RPBA), then run Experiments 1 and 2 with KJSC, KCSC, DSMC",
        description="On a built-in robot whose true kinematics carry seeded Table 4.2 errors: calibrate it "
        "by RPBA on the plant, then run the servo Experiments 1 and 2 (thesis §6.5) with KJSC, KCSC and "
        "DSMC using the calibrated kinematics and Table 5.1 dynamics. Prints the RMSE/MAE tables beside "
        "the thesis's Tables 6.1/6.2 and writes an MCAP log per run, figures like Figs. 4.8, 6.4, 6.5, "
        "6.7, 6.8 and tables.txt to --out.",
    )
    d.add_argument(
        "--quick",
        action="store_true",
        help="short runs (6 s, 0.5 s dwell): finishes in under a minute",
    )
    d.add_argument("--out", default="out", help="output directory (default: out/)")
    d.add_argument(
        "--seed", type=seed, default=0, help="seed of the robot's errors and the noise (default 0)"
    )
    d.add_argument(
        "--plant",
        choices=("auto", "rapier", "model"),
        default="auto",
        help="the simulated robot: rapier plant, analytic model twin, or auto (rapier if built)",
    )
    d.add_argument("--quiet", action="store_true", help="no progress bars or report on stdout")
    d.set_defaults(func=cmd_demo)

    c = sub.add_parser(
        "calibrate",
        help="kinematic calibration: the study of thesis §4.4.3 (--simulate), a logged collection "
        "(--mcap FILE) or a calibration from a log (--from-mcap FILE)",
        description="With --simulate: the actuator stroke (§4.4.1), the optimal configuration sets (§4.4.2) "
        "and the simulation study of §4.4.3 over random robots with Table 4.2 errors and Table 4.1 noise, "
        "printing Tables 4.3, 4.4 and 4.5 (mean and 95th percentile) beside the thesis's. "
        "With --mcap FILE: visit the optimal configurations on a simulated robot, logging the raw "
        "potentiometer and camera samples of every dwell to FILE as the collection goes, then calibrate "
        "from the log and print the relative pose errors before and after. With --from-mcap FILE: "
        "calibrate from such a log.",
    )
    mode = c.add_mutually_exclusive_group()
    mode.add_argument("--simulate", action="store_true", help="run the simulation study")
    mode.add_argument(
        "--mcap",
        metavar="FILE",
        help="collect a calibration on a simulated robot with Table 4.2 errors (seed --seed), "
        "logging the raw dwells to FILE as it goes (on disk after every dwell), then calibrate from it",
    )
    mode.add_argument(
        "--from-mcap",
        metavar="FILE",
        help="calibrate from a collection logged by --mcap or rss6.calibrate.collect(..., mcap=...); "
        "a truncated log (collection killed mid-way) gives its finished configurations",
    )
    c.add_argument(
        "--method",
        choices=("rpba", "implicit"),
        default="rpba",
        help="with --mcap/--from-mcap: the calibration method (default rpba)",
    )
    c.add_argument(
        "--noise",
        choices=("table", "dwells"),
        default="table",
        help="the camera noise the residuals are weighted by: Table 4.1's independent components "
        "(default), or the covariance of one frame pooled from the dwells' own scatter (the stereo "
        "head's correlated components as measured; docs/calibration.md)",
    )
    c.add_argument(
        "--out", metavar="TOML", help="with --mcap/--from-mcap: write the calibrated kinematics"
    )
    c.add_argument("--quiet", action="store_true", help="no progress bar")
    c.add_argument(
        "--robots",
        type=count(1),
        default=None,
        help="number of random robots (default 20, --quick 3)",
    )
    c.add_argument(
        "--dwell", type=positive, default=2.0, help="dwell per configuration (s, default 2)"
    )
    c.add_argument("--seed", type=seed, default=0, help="seed (default 0)")
    c.add_argument(
        "--quick",
        action="store_true",
        help="fewer candidates and robots (--mcap: also shorter moves, 50 test configurations)",
    )
    c.add_argument(
        "--plant",
        action="store_true",
        help="collect the data on the rapier plant (slow) instead of rss6-ident's analytic generator "
        "(--simulate) or the analytic-model twin (--mcap)",
    )
    c.set_defaults(func=cmd_calibrate)

    t = sub.add_parser(
        "track",
        help="one tracking run of a controller on Experiment 1 or 2 with an MCAP log",
        description="Runs one servo experiment on the simulated robot and prints RMSE/MAE per axis.",
    )
    t.add_argument("--controller", choices=CONTROLLERS, default="dsmc")
    t.add_argument("--trajectory", choices=TRAJECTORIES, default="exp1")
    t.add_argument("--duration", type=positive, default=20.0, help="seconds (default 20)")
    t.add_argument(
        "--tuning",
        choices=TUNINGS,
        default="tuned",
        help="servo tuning: rss6's tuning for Tables 6.1/6.2 (default; the thesis's filter noise) or "
        "the low-noise DSMC servo (DSMC only)",
    )
    t.add_argument(
        "--true-kinematics", help="TOML file of the robot's true kinematics (default nominal)"
    )
    t.add_argument(
        "--model-kinematics", help="TOML file of the controller's kinematics (default nominal)"
    )
    t.add_argument("--plant", choices=("auto", "rapier", "model"), default="auto")
    t.add_argument("--seed", type=seed, default=0)
    t.add_argument(
        "--mcap", help="log the run to this MCAP file (as it goes: on disk every simulated second)"
    )
    t.set_defaults(func=cmd_track)

    from rss6 import identify_cli

    i = sub.add_parser(
        "identify",
        help="dynamic identification (thesis ch. 5) of a simulated robot by CLOE (--simulate)",
        description=identify_cli.DESCRIPTION,
    )
    identify_cli.add_arguments(i)
    i.set_defaults(func=identify_cli.run)

    from rss6.discrepancy import cli as diagnose_cli

    g = sub.add_parser(
        "diagnose",
        help="find where the model and the robot disagree and name the missing effect (issue 14)",
        description=diagnose_cli.__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    diagnose_cli.add_arguments(g)
    g.set_defaults(func=diagnose_cli.run)

    from rss6.studies import cli as study_cli

    st = sub.add_parser(
        "study",
        help="studies at scale on Dask: calibration, identification variation, discrepancy benchmark",
        description=study_cli.__doc__,
    )
    study_cli.add_arguments(st)
    st.set_defaults(func=study_cli.run)

    s = sub.add_parser(
        "can-sim",
        help="simulated CiA 402 drives on a CAN bus (needs rss6[can]), for a bridge or your tools",
        description="Six simulated drives (CSP, the EDS rss6 ships) wrapping a simulated robot on a "
        "python-can bus: each SYNC steps the robot one tick, TPDO1 every 2nd SYNC, heartbeats, EMCY "
        "on a following error. See docs/can.md.",
    )
    try:
        from rss6.can import simcli
    except ImportError:  # python-can / canopen not installed
        s.set_defaults(func=_can_missing)
    else:
        simcli.add_arguments(s)
        s.set_defaults(func=simcli.run)
    return p


def _can_missing(args: argparse.Namespace) -> int:
    print(
        "rss6: error: can-sim needs python-can and canopen: pip install 'rss6[can]'",
        file=sys.stderr,
    )
    return 1


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rss6`` console script."""
    try:  # the parser imports the subcommands' modules (scipy among them: ≈ 0.7 s)
        parser = build_parser()
        args = parser.parse_args(argv)
    except KeyboardInterrupt:
        print("rss6: interrupted", file=sys.stderr)
        return 130
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    from rss6.errors import Rss6Error

    try:
        return int(args.func(args))
    except Rss6Error as e:
        print(f"rss6: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        # A disk that fills or a path that vanishes mid-run: one line, and what was kept.
        print(f"rss6: error: {type(e).__name__}: {e}{_kept(args)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        # Ctrl-C: one line instead of a traceback, and where the work done so far is.
        print(f"rss6: interrupted{_kept(args)}", file=sys.stderr)
        return 130


def _kept(args: argparse.Namespace) -> str:
    """Where an interrupted command left what it had written (files are written as the work goes)."""
    out = getattr(args, "out", None) or getattr(args, "mcap", None)
    if not out:
        return ""
    if args.command == "study":
        return f"; the records finished so far are in {out}: rerun the same command to resume"
    return f"; what was written before it is in {out}"


if __name__ == "__main__":
    sys.exit(main())
