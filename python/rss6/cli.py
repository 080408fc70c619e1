"""The ``rss6`` command line.

``rss6 demo``            calibrate a simulated robot by RPBA, then run Experiments 1 and 2 (thesis §6.5)
                         with KJSC, KCSC and DSMC; print Tables 6.1/6.2 beside the thesis's; write
                         MCAP logs and figures to ``--out``.
``rss6 calibrate --simulate``   the calibration study of §4.4.3: Tables 4.3–4.5 over random robots.
``rss6 calibrate --mcap FILE``  collect a calibration on a simulated robot, logging the raw dwells to
                         FILE as it goes, then calibrate from the log.
``rss6 calibrate --from-mcap FILE``  calibrate from a logged collection (also a truncated one).
``rss6 track``           one tracking run (controller × trajectory) with an MCAP log.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["build_parser", "main"]

EXPERIMENTS = {
    "exp1": "Experiment 1 (sinusoid, 0.5 rad/s)",
    "exp2": "Experiment 2 (Fourier, n = 5, ω0 = 0.15 rad/s)",
}
CONTROLLERS = ("kjsc", "kcsc", "dsmc")


def _progress(total: int, desc: str, quiet: bool) -> Any:
    from tqdm import tqdm  # type: ignore[import-untyped]

    return tqdm(total=total, desc=desc, disable=quiet, leave=False, file=sys.stderr)


def make_plant(
    kind: str, kp_true: Any, dp: Any, seed: int, sensor_in_base: Any, target_in_effector: Any
) -> Any:
    """The simulated "real robot": the rapier plant if available (``kind`` "rapier" or "auto"), else
    the analytic-model twin."""
    import rss6

    if kind in ("rapier", "auto") and rss6.Plant is not None:
        return rss6.Plant(
            kp_true,
            dp,
            seed=seed,
            sensor_in_base=sensor_in_base,
            target_in_effector=target_in_effector,
        )
    if kind == "rapier":
        raise SystemExit("rss6: this build has no rapier plant (rss6.Plant); use --plant model")
    return rss6.ModelSim(
        kp_true, dp, seed=seed, sensor_in_base=sensor_in_base, target_in_effector=target_in_effector
    )


def _say(msg: str, quiet: bool = False) -> None:
    if not quiet:
        print(msg, flush=True)


def cmd_demo(args: argparse.Namespace) -> int:
    import rss6
    from rss6 import calibrate, plots, servo

    t_start = time.perf_counter()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    quick, quiet, seed = args.quick, args.quiet, args.seed
    nominal = rss6.KinematicParams.nominal()
    dp = rss6.DynamicParams.nominal()

    # The default robot: nominal geometry with seeded Table 4.2 errors, camera placed roughly.
    kp_true = rss6.KinematicParams.perturbed(calibrate.draw_errors(seed))
    sensor_design, target_design = calibrate.default_placement()
    sensor_true = calibrate.draw_external(sensor_design, seed + 1)
    target_true = calibrate.draw_external(target_design, seed + 2)
    plant = make_plant(args.plant, kp_true, dp, seed, sensor_true, target_true)
    kind = type(plant).__name__
    _say(f"rss6 demo: robot with Table 4.2 errors (seed {seed}) simulated by rss6.{kind}", quiet)
    if kind != "Plant":
        _say(
            "  (rapier plant not in this build: using the analytic-model twin as the robot)", quiet
        )

    # 1. Kinematic calibration by RPBA on the plant (thesis ch. 4).
    lo, hi = calibrate.stroke(nominal)
    thetas = calibrate.select_configurations(
        nominal, "rpba", seed, candidates=400 if quick else 5000, stroke=(lo, hi)
    )
    dwell = 0.5 if quick else 2.0
    plant.reset(rss6.home_pose())
    with _progress(len(thetas), "calibration: measuring configurations", quiet) as bar:
        data = calibrate.collect(
            plant,
            thetas,
            dwell,
            move_time=0.5 if quick else 1.0,
            progress=lambda d, t: bar.update(1),
        )
    result = calibrate.rpba(data, nominal)
    sensor_est = calibrate.sensor_in_base_from_reference(data, result)
    n_test = 50 if quick else 100
    unc = calibrate.relative_pose_errors(None, plant, n=n_test, seed=seed, stroke=(lo, hi))
    cal = calibrate.relative_pose_errors(result, plant, n=n_test, seed=seed, stroke=(lo, hi))
    result.params.to_toml(out / "calibrated_kinematics.toml")
    plots.relative_pose_errors(
        unc["errors"],
        cal["errors"],
        out / "fig4_8_relative_pose_errors.png",
        "Relative pose errors (Fig. 4.8)",
    )
    _say(
        f"\n1. RPBA calibration: stroke ({np.degrees(lo):.1f}°, {np.degrees(hi):.1f}°), "
        f"{len(thetas) - 1} configurations + initial, dwell {dwell} s, {result.iterations} LM steps, "
        f"rank {result.rank}/{result.parameter_count}",
        quiet,
    )
    _say(
        f"   RMS relative pose errors on {n_test} test configurations (x, y, z mm; α, β, γ 1e-3 rad):",
        quiet,
    )
    for name, e in (("uncalibrated", unc["rms"]), ("RPBA", cal["rms"])):
        _say(f"   {name:13s} " + " ".join(f"{v * 1e3:8.4f}" for v in e), quiet)
    thesis = np.asarray(calibrate.THESIS_TABLE_4_5["RPBA"]) * 1e3
    _say(f"   {'thesis RPBA':13s} " + " ".join(f"{v:8.4f}" for v in thesis), quiet)

    # 2. Servo experiments (thesis §6.5) with the calibrated kinematics and Table 5.1 dynamics.
    durations = {"exp1": 6.0, "exp2": 6.0} if quick else {"exp1": 25.0, "exp2": 42.0}
    results: dict[str, dict[str, Any]] = {}

    def run_servo(exp: str, controller: str, tuning: str = "thesis") -> Any:
        suffix = "" if tuning == "thesis" else f"_{tuning}"
        return servo.track(
            plant,
            controller=controller,
            trajectory=exp,
            kp_model=result.params,
            dp_model=dp,
            duration=durations[exp],
            sensor_in_base=sensor_est,
            target_in_effector=result.target_in_effector,
            mcap=out / f"{exp}_{controller}{suffix}.mcap",
            tuning=tuning,
        )

    # The three controllers of the thesis, then the DSMC with the low-noise servo ("DSMC-LN").
    runs_to_do = [(c, "thesis") for c in CONTROLLERS] + [("dsmc", "low_noise")]
    with _progress(len(EXPERIMENTS) * len(runs_to_do), "servo experiments", quiet) as bar:
        for exp in EXPERIMENTS:
            results[exp] = {}
            for c, tuning in runs_to_do:
                r = run_servo(exp, c, tuning)
                results[exp][r.controller + ("-LN" if tuning == "low_noise" else "")] = r
                bar.update(1)
    tables = []
    verdicts: list[tuple[str, str, bool, bool]] = []
    faults: list[str] = []
    beats = {"DSMC": 0, "DSMC-LN": 0}
    cells = {"DSMC": 0, "DSMC-LN": 0}
    for exp, fig_t, fig_e, tab in (("exp1", "6_4", "6_5", "6.1"), ("exp2", "6_7", "6_8", "6.2")):
        runs = [results[exp][n] for n in ("KJSC", "KCSC", "DSMC")]
        plots.tracking(
            runs,
            out / f"fig{fig_t}_{exp}_tracking.png",
            f"{EXPERIMENTS[exp]}: tracking (Fig. {fig_t.replace('_', '.')})",
        )
        plots.tracking_errors(
            runs,
            out / f"fig{fig_e}_{exp}_errors.png",
            f"{EXPERIMENTS[exp]}: errors (Fig. {fig_e.replace('_', '.')})",
        )
        text = plots.table_text(
            results[exp],
            servo.THESIS_TABLES[exp],
            f"Table {tab} — {EXPERIMENTS[exp]}, {durations[exp]:.0f} s on rss6.{kind}",
        )
        tables.append(text)
        for k, ax in enumerate(servo.AXES):
            rm = {n: results[exp][n].rmse[k] for n in ("KJSC", "KCSC", "DSMC")}
            verdicts.append((exp, ax, rm["DSMC"] < rm["KCSC"], rm["KCSC"] < rm["KJSC"]))
        for n, r in results[exp].items():
            if r.fault is not None:
                faults.append(f"{exp} {n}: {r.fault}")
        for stat in ("rmse", "mae"):
            thesis_dsmc = servo.THESIS_TABLES[exp][stat]["DSMC"]
            for n in ("DSMC", "DSMC-LN"):
                ours = results[exp][n].table()[stat]
                beats[n] += int(np.sum(np.asarray(ours) < np.asarray(thesis_dsmc)))
                cells[n] += len(thesis_dsmc)
    report = "\n\n".join(tables)
    n_axes = len(verdicts)
    dk = [f"{e} {a}" for e, a, d, _ in verdicts if not d]
    kj = [f"{e} {a}" for e, a, _, k in verdicts if not k]
    summary = (
        f"RMSE ordering (thesis: DSMC < KCSC < KJSC on every axis): DSMC < KCSC on {n_axes - len(dk)}/{n_axes} axes"
        + (f" (not on {', '.join(dk)})" if dk else "")
        + f"; KCSC < KJSC on {n_axes - len(kj)}/{n_axes} axes"
        + (f" (not on {', '.join(kj)})" if kj else "")
        + ".\nAgainst the thesis's DSMC (RMSE and MAE cells of both tables): rss6 DSMC lower in "
        + f"{beats['DSMC']}/{cells['DSMC']}, rss6 DSMC with the low-noise servo (DSMC-LN) lower in "
        + f"{beats['DSMC-LN']}/{cells['DSMC-LN']}."
    )
    if faults:
        summary += "\nController faults: " + "; ".join(faults)

    # 3. How well each DSMC servo's Kalman filter did (the true pose is known in simulation).
    lines = [
        (
            "3. Kalman filter inside the DSMC loop, thesis tuning vs the low-noise servo "
            "(std of filter/camera pose error, rms rate error/true rate after 2 s; RMSE vs the true pose)"
        )
    ]
    for exp in EXPERIMENTS:
        for name, r in (("thesis", results[exp]["DSMC"]), ("low-noise", results[exp]["DSMC-LN"])):
            noise, rate = servo.filter_statistics(r)
            lines.append(
                f"   {exp} {name:9s} noise x..γ {' '.join(f'{v:4.2f}' for v in noise)} | "
                f"rate {' '.join(f'{v:4.2f}' for v in rate)} | "
                f"RMSE {np.linalg.norm(r.rmse_true[:3]) * 1e3:.3f} mm "
                f"{np.linalg.norm(r.rmse_true[3:]) * 1e3:.3f} mrad"
            )
    kalman = "\n".join(lines)
    (out / "tables.txt").write_text(report + "\n\n" + summary + "\n\n" + kalman + "\n")
    _say("\n2. Servo experiments (rss6 = this run; thesis = Tables 6.1/6.2)\n", quiet)
    _say(report, quiet)
    _say("\n" + summary, quiet)
    _say("\n" + kalman, quiet)
    _say(
        f"\nwrote {out}/: 8 MCAP logs, 5 figures, tables.txt, calibrated_kinematics.toml "
        f"({time.perf_counter() - t_start:.1f} s)",
        quiet,
    )
    return 0


def _calibrate_log(args: argparse.Namespace, path: str, plant: Any = None) -> int:
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
        result = calibrate.implicit(log.data, nominal, calibrate.default_placement()[0])
    else:
        result = calibrate.rpba(log.data, nominal)
    cost = result.cost_history
    print(
        f"{result.method}: {result.iterations} LM steps, cost {cost[0]:.4g} -> {cost[-1]:.4g}, "
        f"rank {result.rank}/{result.parameter_count}"
    )
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
    print(f"§4.4.3 study over {robots} random robots ({source}, dwell {args.dwell} s)")
    rows = _rss6.calibration_study(
        th_r,
        th_i,
        robots=robots,
        seed=args.seed,
        dwell=args.dwell,
        stroke=(lo, hi),
        plant=args.plant,
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
        "--seed", type=int, default=0, help="seed of the robot's errors and the noise (default 0)"
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
        "--out", metavar="TOML", help="with --mcap/--from-mcap: write the calibrated kinematics"
    )
    c.add_argument("--quiet", action="store_true", help="no progress bar")
    c.add_argument(
        "--robots", type=int, default=None, help="number of random robots (default 20, --quick 3)"
    )
    c.add_argument(
        "--dwell", type=float, default=2.0, help="dwell per configuration (s, default 2)"
    )
    c.add_argument("--seed", type=int, default=0, help="seed (default 0)")
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
    t.add_argument("--trajectory", choices=tuple(EXPERIMENTS), default="exp1")
    t.add_argument("--duration", type=float, default=20.0, help="seconds (default 20)")
    t.add_argument(
        "--tuning",
        choices=("thesis", "low_noise"),
        default="thesis",
        help="servo tuning: the thesis's (default) or the low-noise DSMC servo (DSMC only)",
    )
    t.add_argument(
        "--true-kinematics", help="TOML file of the robot's true kinematics (default nominal)"
    )
    t.add_argument(
        "--model-kinematics", help="TOML file of the controller's kinematics (default nominal)"
    )
    t.add_argument("--plant", choices=("auto", "rapier", "model"), default="auto")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument(
        "--mcap", help="log the run to this MCAP file (as it goes: on disk every simulated second)"
    )
    t.set_defaults(func=cmd_track)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rss6`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    from rss6.errors import Rss6Error

    try:
        return int(args.func(args))
    except Rss6Error as e:
        print(f"rss6: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
