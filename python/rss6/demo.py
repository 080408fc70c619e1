"""The ``rss6 demo`` workflow as a function: :func:`run` returns a :class:`DemoReport`.

On a built-in robot whose true kinematics carry seeded Table 4.2 errors: calibrate it by RPBA on the
plant (thesis ch. 4), then run Experiments 1 and 2 (thesis §6.5) with KJSC, KCSC and DSMC (thesis
tuning) and the DSMC with the low-noise servo ("DSMC-LN"), using the calibrated kinematics and
Table 5.1 dynamics. Writes an MCAP log per run, Figs. 4.8, 6.4, 6.5, 6.7, 6.8, ``tables.txt`` and
``calibrated_kinematics.toml`` to ``out``. The report holds the numbers; :meth:`DemoReport.text`
renders what ``rss6 demo`` prints (``str(report)`` is the same text).

>>> from rss6 import demo
>>> report = demo.run("out", quick=True)                      # doctest: +SKIP
>>> report.tables["exp1"].rmse["DSMC"].shape   # m, rad per axis  # doctest: +SKIP
(6,)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6 import _rss6, calibrate, plots, servo
from rss6.errors import InvalidInputError
from rss6.types import CONTROLLERS, TRAJECTORIES, PlantKind, Robot, TrajectoryName, TuningName

if TYPE_CHECKING:
    from rss6.servo import TrackingResult

__all__ = [
    "EXPERIMENTS",
    "CalibrationSummary",
    "DemoReport",
    "FilterStats",
    "Progress",
    "ServoTable",
    "make_plant",
    "run",
    "servo_table",
]

F64 = NDArray[np.float64]

#: What each named trajectory is, as the tables' titles say it.
EXPERIMENTS: dict[TrajectoryName, str] = {
    "exp1": "Experiment 1 (sinusoid, 0.5 rad/s)",
    "exp2": "Experiment 2 (Fourier, n = 5, ω0 = 0.15 rad/s)",
}
#: The thesis's table columns, in its order.
_THESIS_COLUMNS = ("KJSC", "KCSC", "DSMC")
_AXIS_LABELS = ("x (mm)", "y (mm)", "z (mm)", "α (1e-3 rad)", "β (1e-3 rad)", "γ (1e-3 rad)")
#: (experiment, tracking figure, error figure, thesis table) per experiment.
_FIGURES: tuple[tuple[TrajectoryName, str, str, str], ...] = (
    ("exp1", "6_4", "6_5", "6.1"),
    ("exp2", "6_7", "6_8", "6.2"),
)


class ProgressBar(Protocol):
    """The part of a progress bar (e.g. ``tqdm``) that :func:`run` uses."""

    def update(self, n: int = 1) -> object: ...


#: ``progress(total, description)`` opens a progress bar for ``total`` steps (used as a context
#: manager); :func:`run` calls its ``update(1)`` after each step.
Progress = Callable[[int, str], AbstractContextManager[ProgressBar]]


class _NoBar:
    def update(self, n: int = 1) -> None:
        return None


def _no_progress(total: int, desc: str) -> AbstractContextManager[ProgressBar]:
    return nullcontext(_NoBar())


@dataclass
class CalibrationSummary:
    """Step 1 of the demo: RPBA on the plant and Table 4.5's relative pose errors.

    ``stroke`` (rad) is the actuator stroke of §4.4.1; ``rms_*`` (6,) are RMS relative pose errors
    over ``test_configurations`` random configurations (m, rad), ``thesis_rpba`` Table 4.5's RPBA row.
    """

    stroke: tuple[float, float]
    configurations: int
    dwell: float
    iterations: int
    rank: int
    parameter_count: int
    test_configurations: int
    rms_uncalibrated: F64
    rms_calibrated: F64
    thesis_rpba: F64
    result: _rss6.CalibrationResult | None = field(default=None, repr=False, compare=False)
    #: weighted cost per degree of freedom (≈ 1 when the model explains the data to within the noise)
    fit_statistic: float = float("nan")
    #: configurations the solver rejected as gross outliers: (index, normalised residual)
    rejected: list[tuple[int, float]] = field(default_factory=list)
    #: configurations left out before the fit (failed collection checks, defects): (index, reason)
    dropped: list[tuple[int, str]] = field(default_factory=list)

    def text(self) -> str:
        lo, hi = self.stroke
        lines = [
            (
                f"1. RPBA calibration: stroke ({np.degrees(lo):.1f}°, {np.degrees(hi):.1f}°), "
                f"{self.configurations} configurations + initial, dwell {self.dwell} s, "
                f"{self.iterations} LM steps, rank {self.rank}/{self.parameter_count}"
            ),
            (
                f"   RMS relative pose errors on {self.test_configurations} test configurations "
                "(x, y, z mm; α, β, γ 1e-3 rad):"
            ),
        ]
        for name, e in (("uncalibrated", self.rms_uncalibrated), ("RPBA", self.rms_calibrated)):
            lines.append(f"   {name:13s} " + " ".join(f"{v * 1e3:8.4f}" for v in e))
        lines.append(
            f"   {'thesis RPBA':13s} " + " ".join(f"{v * 1e3:8.4f}" for v in self.thesis_rpba)
        )
        rejected = ", ".join(f"{k} (normalised residual {z:.3g})" for k, z in self.rejected)
        left_out = ", ".join(f"{k} ({why})" for k, why in self.dropped)
        lines.append(
            f"   fit statistic {self.fit_statistic:.3f} (weighted cost per degree of freedom, ≈ 1 when "
            f"the model explains the data to the noise); rejected: {rejected or 'none'}; "
            f"left out: {left_out or 'none'}"
        )
        return "\n".join(lines)


@dataclass
class ServoTable:
    """Table 6.1 or 6.2 of this run beside the thesis's.

    ``rmse``/``mae``: column name ("KJSC", "KCSC", "DSMC", "DSMC-LN") → (6,) per axis (m, rad) at the
    camera frames; ``thesis``: {"rmse"|"mae": {"KJSC"|"KCSC"|"DSMC": 6 values (mm, 1e-3 rad)}};
    ``faults``: column → (time s, reason) of the runs that faulted.
    """

    experiment: TrajectoryName
    title: str
    rmse: dict[str, F64]
    mae: dict[str, F64]
    thesis: Mapping[str, Mapping[str, list[float]]]
    faults: dict[str, tuple[float, str]] = field(default_factory=dict)

    def cells(self, stat: str) -> dict[str, list[float]]:
        """This run's ``stat`` ("rmse" or "mae") per column in the thesis's units (mm, 1e-3 rad)."""
        values = self.rmse if stat == "rmse" else self.mae
        return {n: (np.asarray(v) * 1e3).tolist() for n, v in values.items()}

    def text(self) -> str:
        """The table as text: per axis and statistic, each thesis column as (rss6, thesis), then a
        column per run the thesis has no column for."""
        extra = [n for n in self.rmse if n not in _THESIS_COLUMNS]
        head = (
            f"{'axis':14s} {'stat':5s} "
            + " ".join(f"{n + ' rss6':>10s} {n + ' thesis':>11s}" for n in _THESIS_COLUMNS)
            + "".join(f" {n + ' rss6':>12s}" for n in extra)
        )
        lines = [self.title, "", head, "-" * len(head)]
        ours = {stat: self.cells(stat) for stat in ("rmse", "mae")}
        for k, axis in enumerate(_AXIS_LABELS):
            for stat in ("rmse", "mae"):
                cells = []
                for n in _THESIS_COLUMNS:
                    v = ours[stat][n][k] if n in ours[stat] else float("nan")
                    cells.append(f"{v:10.3f} {self.thesis[stat][n][k]:11.3g}")
                row = f"{axis:14s} {stat.upper():5s} " + " ".join(cells)
                row += "".join(f" {ours[stat][n][k]:12.3f}" for n in extra)
                lines.append(row)
        return "\n".join(lines)


@dataclass
class FilterStats:
    """How the Kalman filter inside one DSMC run did (see :func:`rss6.servo.filter_statistics`):
    ``noise`` and ``rate`` ratios (6,), and the RMSE against the true pose ``rmse_true`` (6,) (m,
    rad). ``servo`` is "tuned" or "low-noise"."""

    experiment: TrajectoryName
    servo: str
    noise: F64
    rate: F64
    rmse_true: F64

    def text(self) -> str:
        return (
            f"   {self.experiment} {self.servo:9s} noise x..γ "
            f"{' '.join(f'{v:4.2f}' for v in self.noise)} | "
            f"rate {' '.join(f'{v:4.2f}' for v in self.rate)} | "
            f"RMSE {np.linalg.norm(self.rmse_true[:3]) * 1e3:.3f} mm "
            f"{np.linalg.norm(self.rmse_true[3:]) * 1e3:.3f} mrad"
        )


@dataclass
class DemoReport:
    """Everything ``rss6 demo`` found and wrote.

    ``plant``: class name of the simulated robot ("Plant" or "ModelSim"); ``tables``: "exp1"/"exp2"
    → :class:`ServoTable`; ``filters``: the DSMC runs' :class:`FilterStats`; ``files``: every file
    written under ``out``; ``elapsed``: wall time (s); ``runs``: the :class:`rss6.servo.TrackingResult`
    of every run (experiment → column name), empty in a report built by hand.
    """

    out: Path
    seed: int
    plant: str
    calibration: CalibrationSummary
    tables: dict[str, ServoTable]
    filters: list[FilterStats]
    files: list[Path]
    elapsed: float
    runs: dict[str, dict[str, TrackingResult]] = field(default_factory=dict, repr=False)

    def header(self) -> str:
        line = f"rss6 demo: robot with Table 4.2 errors (seed {self.seed}) simulated by rss6.{self.plant}"
        if self.plant != "Plant":
            line += (
                "\n  (rapier plant not in this build: using the analytic-model twin as the robot)"
            )
        return line

    def servo_text(self) -> str:
        """Tables 6.1 and 6.2 of this run."""
        return "\n\n".join(t.text() for t in self.tables.values())

    def summary_text(self) -> str:
        """The controllers' RMSE ordering, the cells below the thesis's DSMC, and any faults."""
        verdicts: list[tuple[str, str, bool, bool]] = []
        beats = {"DSMC": 0, "DSMC-LN": 0}
        cells = {"DSMC": 0, "DSMC-LN": 0}
        faults: list[str] = []
        for exp, table in self.tables.items():
            for k, axis in enumerate(servo.AXES):
                rm = {n: table.rmse[n][k] for n in _THESIS_COLUMNS}
                verdicts.append((exp, axis, rm["DSMC"] < rm["KCSC"], rm["KCSC"] < rm["KJSC"]))
            faults += [f"{exp} {n}: {f}" for n, f in table.faults.items()]
            for stat in ("rmse", "mae"):
                thesis_dsmc = np.asarray(table.thesis[stat]["DSMC"])
                ours = table.cells(stat)
                for n in beats:
                    beats[n] += int(np.sum(np.asarray(ours[n]) < thesis_dsmc))
                    cells[n] += len(thesis_dsmc)
        n_axes = len(verdicts)
        dk = [f"{e} {a}" for e, a, d, _ in verdicts if not d]
        kj = [f"{e} {a}" for e, a, _, k in verdicts if not k]
        text = (
            "RMSE ordering (thesis: DSMC < KCSC < KJSC on every axis): "
            f"DSMC < KCSC on {n_axes - len(dk)}/{n_axes} axes"
            + (f" (not on {', '.join(dk)})" if dk else "")
            + f"; KCSC < KJSC on {n_axes - len(kj)}/{n_axes} axes"
            + (f" (not on {', '.join(kj)})" if kj else "")
            + ".\nAgainst the thesis's DSMC (RMSE and MAE cells of both tables): rss6 DSMC lower in "
            + f"{beats['DSMC']}/{cells['DSMC']}, rss6 DSMC with the low-noise servo (DSMC-LN) lower "
            + f"in {beats['DSMC-LN']}/{cells['DSMC-LN']}."
        )
        if faults:
            text += "\nController faults: " + "; ".join(faults)
        return text

    def filter_text(self) -> str:
        """Step 3: the Kalman filter statistics of the DSMC runs."""
        head = (
            "3. Kalman filter inside the DSMC loop, the tuned servo vs the low-noise servo "
            "(std of filter/camera pose error, rms rate error/true rate after 2 s; RMSE vs the true "
            "pose)"
        )
        return "\n".join([head] + [f.text() for f in self.filters])

    def tables_file_text(self) -> str:
        """The contents of ``tables.txt``."""
        return f"{self.servo_text()}\n\n{self.summary_text()}\n\n{self.filter_text()}\n"

    def text(self) -> str:
        """What ``rss6 demo`` prints."""
        n_mcap = sum(1 for f in self.files if f.suffix == ".mcap")
        n_png = sum(1 for f in self.files if f.suffix == ".png")
        return "\n".join(
            [
                self.header(),
                "",
                self.calibration.text(),
                "",
                "2. Servo experiments (rss6 = this run; thesis = Tables 6.1/6.2)",
                "",
                self.servo_text(),
                "",
                self.summary_text(),
                "",
                self.filter_text(),
                "",
                (
                    f"wrote {self.out}/: {n_mcap} MCAP logs, {n_png} figures, tables.txt, "
                    f"calibrated_kinematics.toml ({self.elapsed:.1f} s)"
                ),
            ]
        )

    def __str__(self) -> str:
        return self.text()


def servo_table(
    experiment: TrajectoryName, title: str, runs: Mapping[str, TrackingResult]
) -> ServoTable:
    """The table of ``runs`` (column name → run) on ``experiment`` beside the thesis's table for it
    (Table 6.1 for "exp1", 6.2 for "exp2")."""
    return ServoTable(
        experiment=experiment,
        title=title,
        rmse={n: r.rmse for n, r in runs.items()},
        mae={n: r.mae for n, r in runs.items()},
        thesis=servo.THESIS_TABLES[experiment],
        faults={n: r.fault for n, r in runs.items() if r.fault is not None},
    )


def make_plant(
    kind: PlantKind,
    kp_true: _rss6.KinematicParams,
    dp: _rss6.DynamicParams,
    seed: int,
    sensor_in_base: ArrayLike | None,
    target_in_effector: ArrayLike | None,
) -> Robot:
    """The simulated "real robot": the rapier plant (:class:`rss6.Plant`) if ``kind`` is "rapier",
    or "auto" and this build has it; else the analytic-model twin (:class:`rss6.ModelSim`)."""
    if kind in ("rapier", "auto") and hasattr(_rss6, "Plant"):
        return _rss6.Plant(
            kp_true,
            dp,
            seed=seed,
            sensor_in_base=sensor_in_base,
            target_in_effector=target_in_effector,
        )
    if kind == "rapier":
        raise InvalidInputError("this build has no rapier plant (rss6.Plant); use the model twin")
    return _rss6.ModelSim(
        kp_true, dp, seed=seed, sensor_in_base=sensor_in_base, target_in_effector=target_in_effector
    )


def _calibrate(
    plant: Robot, seed: int, quick: bool, out: Path, progress: Progress
) -> tuple[CalibrationSummary, _rss6.CalibrationResult, F64, list[Path]]:
    """Step 1: RPBA on ``plant``; returns the summary, the result, the estimated ᴼχ_C and the files
    written."""
    nominal = _rss6.KinematicParams.nominal()
    lo, hi = calibrate.stroke(nominal)
    thetas = calibrate.select_configurations(
        nominal, "rpba", seed, candidates=400 if quick else 5000, stroke=(lo, hi)
    )
    dwell = 0.5 if quick else 2.0
    plant.reset(_rss6.home_pose())
    with progress(len(thetas), "calibration: measuring configurations") as bar:
        data = calibrate.collect(
            plant,
            thetas,
            dwell,
            move_time=0.5 if quick else 1.0,
            progress=lambda done, total: bar.update(1),
        )
    result = calibrate.rpba(data, nominal)
    sensor_est = calibrate.sensor_in_base_from_reference(data, result)
    n_test = 50 if quick else 100
    unc = calibrate.relative_pose_errors(None, plant, n=n_test, seed=seed, stroke=(lo, hi))
    cal = calibrate.relative_pose_errors(result, plant, n=n_test, seed=seed, stroke=(lo, hi))
    toml, fig = out / "calibrated_kinematics.toml", out / "fig4_8_relative_pose_errors.png"
    result.params.to_toml(toml)
    plots.relative_pose_errors(unc["errors"], cal["errors"], fig, "Relative pose errors (Fig. 4.8)")
    summary = CalibrationSummary(
        stroke=(lo, hi),
        configurations=len(thetas) - 1,
        dwell=dwell,
        iterations=result.iterations,
        rank=result.rank,
        parameter_count=result.parameter_count,
        test_configurations=n_test,
        rms_uncalibrated=np.asarray(unc["rms"], dtype=np.float64),
        rms_calibrated=np.asarray(cal["rms"], dtype=np.float64),
        thesis_rpba=np.asarray(calibrate.THESIS_TABLE_4_5["RPBA"], dtype=np.float64),
        result=result,
        fit_statistic=result.fit_statistic,
        rejected=list(result.rejected),
        dropped=list(result.dropped),
    )
    return summary, result, sensor_est, [toml, fig]


def run(
    out: str | PathLike[str] = "out",
    *,
    quick: bool = False,
    seed: int = 0,
    plant: PlantKind = "auto",
    progress: Progress | None = None,
) -> DemoReport:
    """Runs the demo (see the module docs), writing its files to ``out`` (created if missing).

    ``quick``: 6 s servo runs, 0.5 s dwells, fewer candidate configurations (under a minute);
    otherwise Experiment 1 runs 25 s and Experiment 2 42 s, dwells 2 s. ``seed``: of the robot's
    errors, its camera placement and the noise. ``plant``: "rapier", "model" (the analytic twin) or
    "auto" (rapier if this build has it). ``progress``: opens progress bars (see :data:`Progress`);
    default none.
    """
    t_start = time.perf_counter()
    bars = progress if progress is not None else _no_progress
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    dp = _rss6.DynamicParams.nominal()

    # The robot: nominal geometry with seeded Table 4.2 errors, camera placed roughly.
    kp_true = _rss6.KinematicParams.perturbed(calibrate.draw_errors(seed))
    sensor_design, target_design = calibrate.default_placement()
    robot = make_plant(
        plant,
        kp_true,
        dp,
        seed,
        calibrate.draw_external(sensor_design, seed + 1),
        calibrate.draw_external(target_design, seed + 2),
    )
    kind = type(robot).__name__

    # 1. Kinematic calibration by RPBA on the plant (thesis ch. 4).
    cal, result, sensor_est, files = _calibrate(robot, seed, quick, out_dir, bars)

    # 2. Servo experiments (thesis §6.5) with the calibrated kinematics and Table 5.1 dynamics:
    # the thesis's three controllers, then the DSMC with the low-noise servo ("DSMC-LN").
    durations: dict[TrajectoryName, float] = (
        {"exp1": 6.0, "exp2": 6.0} if quick else {"exp1": 25.0, "exp2": 42.0}
    )
    to_run: list[tuple[str, TuningName]] = [(c, "tuned") for c in CONTROLLERS]
    to_run.append(("dsmc", "low_noise"))
    runs: dict[str, dict[str, TrackingResult]] = {}
    with bars(len(TRAJECTORIES) * len(to_run), "servo experiments") as bar:
        for exp in TRAJECTORIES:
            runs[exp] = {}
            for controller, tuning in to_run:
                suffix = "" if tuning == "tuned" else f"_{tuning}"
                path = out_dir / f"{exp}_{controller}{suffix}.mcap"
                r = servo.track(
                    robot,
                    controller=controller,
                    trajectory=exp,
                    kp_model=result.params,
                    dp_model=dp,
                    duration=durations[exp],
                    sensor_in_base=sensor_est,
                    target_in_effector=result.target_in_effector,
                    mcap=path,
                    tuning=tuning,
                )
                runs[exp][r.controller + ("-LN" if tuning == "low_noise" else "")] = r
                files.append(path)
                bar.update(1)

    tables: dict[str, ServoTable] = {}
    for exp, fig_t, fig_e, tab in _FIGURES:
        columns = [runs[exp][n] for n in _THESIS_COLUMNS]
        tracking = out_dir / f"fig{fig_t}_{exp}_tracking.png"
        errors = out_dir / f"fig{fig_e}_{exp}_errors.png"
        plots.tracking(
            columns, tracking, f"{EXPERIMENTS[exp]}: tracking (Fig. {fig_t.replace('_', '.')})"
        )
        plots.tracking_errors(
            columns, errors, f"{EXPERIMENTS[exp]}: errors (Fig. {fig_e.replace('_', '.')})"
        )
        files += [tracking, errors]
        title = f"Table {tab} — {EXPERIMENTS[exp]}, {durations[exp]:.0f} s on rss6.{kind}"
        tables[exp] = servo_table(exp, title, runs[exp])

    # 3. How well each DSMC servo's Kalman filter did (the true pose is known in simulation).
    filters = []
    for exp in TRAJECTORIES:
        for label, column in (("tuned", "DSMC"), ("low-noise", "DSMC-LN")):
            r = runs[exp][column]
            noise, rate = servo.filter_statistics(r)
            filters.append(FilterStats(exp, label, noise, rate, r.rmse_true))

    report = DemoReport(
        out=out_dir,
        seed=seed,
        plant=kind,
        calibration=cal,
        tables=tables,
        filters=filters,
        files=files,
        elapsed=0.0,
        runs=runs,
    )
    tables_txt = out_dir / "tables.txt"
    tables_txt.write_text(report.tables_file_text())
    report.files.append(tables_txt)
    report.elapsed = time.perf_counter() - t_start
    return report
