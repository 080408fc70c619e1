"""The rss6 command line: --help for every subcommand, demo --quick writes its files."""

import shutil
import subprocess
import sys

import pytest
from rss6 import cli


def run(*args, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "rss6.cli", *args],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_help_documents_every_subcommand():
    r = run("--help")
    assert r.returncode == 0
    for sub in ("demo", "calibrate", "track"):
        assert sub in r.stdout
    for sub in ("demo", "calibrate", "track"):
        h = run(sub, "--help")
        assert h.returncode == 0, h.stderr
        assert "usage: rss6 " + sub in h.stdout


def test_console_script_is_installed():
    exe = shutil.which("rss6")
    if exe is None:
        pytest.skip("rss6 console script not on PATH (package not installed with pip)")
    r = subprocess.run([exe, "--help"], check=False, capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "demo" in r.stdout


def test_no_subcommand_prints_help(capsys):
    assert cli.main([]) == 0
    assert "demo" in capsys.readouterr().out


def test_demo_quick_writes_logs_figures_and_tables(tmp_path):
    out = tmp_path / "out"
    r = run("demo", "--quick", "--out", str(out))
    assert r.returncode == 0, r.stderr[-2000:]
    assert "Table 6.1" in r.stdout and "Table 6.2" in r.stdout and "RPBA" in r.stdout
    for exp in ("exp1", "exp2"):
        for c in ("kjsc", "kcsc", "dsmc"):
            assert (out / f"{exp}_{c}.mcap").stat().st_size > 0
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == [
        "fig4_8_relative_pose_errors.png",
        "fig6_4_exp1_tracking.png",
        "fig6_5_exp1_errors.png",
        "fig6_7_exp2_tracking.png",
        "fig6_8_exp2_errors.png",
    ]
    assert "Table 6.1" in (out / "tables.txt").read_text()
    assert (out / "calibrated_kinematics.toml").exists()


def test_track_subcommand(tmp_path):
    r = run(
        "track",
        "--controller",
        "kcsc",
        "--duration",
        "1",
        "--plant",
        "model",
        "--mcap",
        str(tmp_path / "t.mcap"),
    )
    assert r.returncode == 0, r.stderr
    assert "RMSE" in r.stdout and (tmp_path / "t.mcap").exists()


def test_calibrate_simulate_quick_prints_tables_4_3_to_4_5():
    r = run("calibrate", "--simulate", "--quick", "--robots", "2")
    assert r.returncode == 0, r.stderr[-2000:]
    for t in ("Table 4.3", "Table 4.4", "Table 4.5", "§4.4.1 stroke"):
        assert t in r.stdout
    assert run("calibrate").returncode == 2  # without --simulate: explains and fails
