"""rss6.demo: the report's tables and text, built from hand-made runs (no simulation)."""

import math
from pathlib import Path

import numpy as np
import pytest
from rss6 import cli, demo, servo

# Error pattern with a known RMSE and MAE: sqrt((1 + 1 + 1 + 49) / 4) = sqrt(13), (1+1+1+7)/4 = 2.5.
PATTERN = np.array([1.0, -1.0, 1.0, 7.0])
PATTERN_RMSE, PATTERN_MAE = math.sqrt(13.0), 2.5
COLUMNS = ("KJSC", "KCSC", "DSMC", "DSMC-LN")


def scale(column, axis):
    """Error size (m or rad) of a column on an axis: different in every cell, so a cell written to
    the wrong row or column shows."""
    return 1e-4 * (1 + COLUMNS.index(column)) * (1 + 0.1 * axis)


def fake_run(controller, fault=None):
    """A TrackingResult whose camera-frame errors are PATTERN × scale(controller, axis)."""
    m = len(PATTERN)
    errors = np.outer(PATTERN, [scale(controller, k) for k in range(6)])
    zeros = np.zeros((m, 6))
    one = np.zeros((1, 6))
    return servo.TrackingResult(
        controller=controller,
        trajectory="exp",
        time=np.zeros(1),
        desired=one,
        true=one,
        theta_cmd=one,
        torque=one,
        frame_time=np.arange(m) * 0.033,
        frame_desired=zeros,
        measured=-errors,
        frame_true=zeros,
        estimate=zeros,
        estimate_dot=zeros,
        sliding=zeros,
        fault=fault,
    )


def parse(table_text):
    """{(axis index, stat): [numbers of the row]} of a rendered ServoTable."""
    rows = {}
    lines = table_text.splitlines()
    assert lines[2].split()[:2] == ["axis", "stat"] and set(lines[3]) == {"-"}
    for i, line in enumerate(lines[4:]):
        stat = line[15:20].strip()
        assert stat == ("RMSE" if i % 2 == 0 else "MAE"), line
        rows[(i // 2, stat.lower())] = [float(v) for v in line[20:].split()]
    assert len(rows) == 12
    return rows


# Cells of the thesis's Tables 6.1 and 6.2 as printed in the thesis: (experiment, stat, column, axis,
# value in mm or 1e-3 rad). One per axis, spread over the columns and both statistics.
THESIS_CELLS = [
    ("exp1", "rmse", "DSMC", 0, 0.44),
    ("exp1", "rmse", "KJSC", 3, 14.8),
    ("exp1", "mae", "KCSC", 4, 3.3),
    ("exp2", "mae", "KJSC", 5, 13.7),
    ("exp2", "rmse", "DSMC", 2, 1.3),
    ("exp2", "mae", "KCSC", 1, 1.0),
]


@pytest.mark.parametrize("exp", ["exp1", "exp2"])
def test_servo_table_puts_each_value_in_its_cell(exp):
    table = demo.servo_table(exp, "title", {c: fake_run(c) for c in COLUMNS})
    rows = parse(table.text())
    for k in range(6):
        for stat, factor in (("rmse", PATTERN_RMSE), ("mae", PATTERN_MAE)):
            row = rows[(k, stat)]
            ours = row[0:6:2] + row[6:]  # KJSC, KCSC, DSMC rss6 columns, then DSMC-LN
            expected = [scale(c, k) * factor * 1e3 for c in COLUMNS]
            np.testing.assert_allclose(ours, expected, atol=5e-4)  # printed with 3 decimals
    for e, stat, column, axis, value in THESIS_CELLS:
        if e == exp:
            thesis_col = 1 + 2 * ("KJSC", "KCSC", "DSMC").index(column)
            assert rows[(axis, stat)][thesis_col] == value


def report(tmp_path, faults=False):
    runs = {
        c: fake_run(c, (1.5, "estimate not finite") if faults and c == "KCSC" else None)
        for c in COLUMNS
    }
    cal = demo.CalibrationSummary(
        stroke=(-1.0, 1.0),
        configurations=22,
        dwell=0.5,
        iterations=9,
        rank=60,
        parameter_count=66,
        test_configurations=50,
        rms_uncalibrated=np.full(6, 3e-3),
        rms_calibrated=np.full(6, 4e-5),
        thesis_rpba=np.full(6, 5e-5),
    )
    filters = [
        demo.FilterStats(
            exp, name, np.full(6, 0.5), np.full(6, 0.25), np.r_[3e-4, 4e-4, 0, 0, 0, 0]
        )
        for exp in ("exp1", "exp2")
        for name in ("tuned", "low-noise")
    ]
    out = Path(tmp_path)
    files = [out / f"{e}_{c}.mcap" for e in ("exp1", "exp2") for c in ("kjsc", "kcsc")]
    files += [out / "fig.png", out / "tables.txt"]
    return demo.DemoReport(
        out=out,
        seed=3,
        plant="ModelSim",
        calibration=cal,
        tables={e: demo.servo_table(e, f"Table {e}", runs) for e in ("exp1", "exp2")},
        filters=filters,
        files=files,
        elapsed=12.34,
    )


def test_report_text_sections_and_summary(tmp_path):
    r = report(tmp_path)
    text = r.text()
    assert str(r) == text
    lines = text.splitlines()
    assert lines[0] == "rss6 demo: robot with Table 4.2 errors (seed 3) simulated by rss6.ModelSim"
    assert "analytic-model twin" in lines[1] and lines[2] == ""
    assert lines[3].startswith("1. RPBA calibration: stroke (-57.3°, 57.3°), 22 configurations")
    assert lines[3].endswith("9 LM steps, rank 60/66")
    assert lines[5].split() == ["uncalibrated"] + ["3.0000"] * 6
    assert lines[7].split() == ["thesis", "RPBA"] + ["0.0500"] * 6
    # rss6's columns grow KJSC < KCSC < DSMC < DSMC-LN (scale()): the ordering fails on every axis
    assert "DSMC < KCSC on 0/12 axes" in text and "KCSC < KJSC on 0/12 axes" in text
    assert "3. Kalman filter inside the DSMC loop" in text
    assert "   exp2 low-noise noise x..γ 0.50 0.50 0.50 0.50 0.50 0.50 | rate 0.25" in text
    assert "RMSE 0.500 mm 0.000 mrad" in text
    assert lines[-1] == (
        f"wrote {tmp_path}/: 4 MCAP logs, 1 figures, tables.txt, calibrated_kinematics.toml (12.3 s)"
    )
    assert r.tables_file_text().rstrip("\n") in text and "Controller faults" not in text
    faulty = report(tmp_path, faults=True).summary_text()
    assert faulty.endswith(
        "Controller faults: exp1 KCSC: (1.5, 'estimate not finite'); "
        "exp2 KCSC: (1.5, 'estimate not finite')"
    )


def test_cells_below_the_thesis_dsmc_are_counted(tmp_path):
    # rss6 DSMC cells: 0.3·(1 + 0.1 k) mm (or 1e-3 rad) × √13 (RMSE: 1.082 1.190 1.298 1.406 1.514
    # 1.623) or × 2.5 (MAE: 0.750 0.825 0.900 0.975 1.050 1.125); DSMC-LN: 0.4·(1 + 0.1 k) × the
    # same. Counted by hand against the thesis's DSMC columns of Tables 6.1/6.2:
    # DSMC    exp1 RMSE y β, MAE β γ; exp2 RMSE z α β γ, MAE α β      → 10 of 24 cells
    # DSMC-LN exp1 RMSE β, MAE β;     exp2 RMSE α β γ,   MAE α β      → 7 of 24 cells
    summary = report(tmp_path).summary_text()
    assert "rss6 DSMC lower in 10/24" in summary
    assert "(DSMC-LN) lower in 7/24" in summary


def test_cli_demo_prints_the_report(tmp_path, monkeypatch, capsys):
    r = report(tmp_path)
    seen = {}

    def fake_run(out, **kw):
        seen.update(kw, out=out)
        return r

    monkeypatch.setattr(demo, "run", fake_run)
    assert cli.main(["demo", "--quick", "--out", str(tmp_path), "--seed", "3"]) == 0
    assert capsys.readouterr().out == r.text() + "\n"
    assert seen["out"] == str(tmp_path) and seen["quick"] and seen["seed"] == 3
    assert seen["plant"] == "auto" and callable(seen["progress"])
    assert cli.main(["demo", "--quiet", "--out", str(tmp_path)]) == 0
    assert capsys.readouterr().out == ""
