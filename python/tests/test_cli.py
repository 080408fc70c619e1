"""The rss6 command line: --help for every subcommand, demo --quick writes its files."""

import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import rss6
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
    for sub in ("demo", "calibrate", "track", "identify", "can-sim"):
        assert sub in r.stdout
    for sub in ("demo", "calibrate", "track", "identify", "can-sim"):
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
        for c in ("kjsc", "kcsc", "dsmc", "dsmc_low_noise"):
            assert (out / f"{exp}_{c}.mcap").stat().st_size > 0
    assert "3. Kalman filter inside the DSMC loop" in r.stdout and "fault" not in r.stdout
    assert "DSMC-LN rss6" in r.stdout and "Against the thesis's DSMC" in r.stdout
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == [
        "fig4_8_relative_pose_errors.png",
        "fig6_4_exp1_tracking.png",
        "fig6_5_exp1_errors.png",
        "fig6_7_exp2_tracking.png",
        "fig6_8_exp2_errors.png",
    ]
    assert "Table 6.1" in (out / "tables.txt").read_text()
    assert (out / "tables.txt").read_text().rstrip("\n") in r.stdout  # the same tables printed
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
    assert "RMSE" in r.stdout
    log = rss6.logs.read_log(tmp_path / "t.mcap", strict=True)
    assert log.metadata["status"] == "finished" and len(log.streams["true_pose"][0]) == 1000
    quick_model = ["--duration", "1", "--plant", "model"]
    low = run("track", "--tuning", "low_noise", *quick_model, "--mcap", str(tmp_path / "l.mcap"))
    assert low.returncode == 0, low.stderr
    assert rss6.logs.read_log(tmp_path / "l.mcap", strict=True).metadata["tuning"] == "low_noise"
    bad = run("track", "--controller", "kjsc", "--tuning", "low_noise", *quick_model)
    assert bad.returncode != 0 and "DSMC only" in bad.stderr and "Traceback" not in bad.stderr


def test_ctrl_c_stops_a_run_with_one_line_and_keeps_its_log(tmp_path):
    """SIGINT (Ctrl-C) mid-run: exit 130, one line saying where the work is, no traceback, and the
    MCAP written so far readable with the run marked as interrupted."""
    log_path = tmp_path / "long.mcap"
    cmd = [sys.executable, "-m", "rss6.cli", "track", "--duration", "3000", "--plant", "model"]
    # The child gets the default SIGINT action even when this test runs with SIGINT ignored (a
    # runner started in the background by a shell without job control): Python installs its
    # KeyboardInterrupt handler only over the default action.
    p = subprocess.Popen(
        [*cmd, "--mcap", str(log_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and p.poll() is None:
        if log_path.exists() and log_path.stat().st_size > 200_000:  # a few seconds on disk
            break
        time.sleep(0.2)
    assert p.poll() is None, "the run ended before it could be interrupted"
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert p.returncode == 130, err[-2000:]
    assert "rss6: interrupted" in err and str(log_path) in err and "Traceback" not in err
    log = rss6.logs.read_log(log_path, strict=True)
    assert log.metadata["status"].startswith("failed: KeyboardInterrupt")
    n = len(log.streams["true_pose"][0])
    assert 0 < n < 3_000_000 and n % 1000 == 0  # whole simulated seconds, flushed as it went


def test_ctrl_c_while_the_command_loads_is_one_line_too(monkeypatch, capsys):
    """Before the work starts, a command spends most of a second importing (scipy, through the
    subcommands' modules): `import rss6` itself loads none of it, and Ctrl-C while the parser is
    built is the same one line and exit 130, not a traceback."""
    code = "import sys, rss6.cli; print(sorted(m for m in ('scipy', 'mcap', 'matplotlib') if m in sys.modules))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and r.stdout.strip() == "[]", r.stdout + r.stderr
    from rss6 import cli

    def interrupted() -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", interrupted)
    assert cli.main(["demo", "--quick"]) == 130
    assert capsys.readouterr().err.strip() == "rss6: interrupted"


def test_calibrate_simulate_quick_prints_tables_4_3_to_4_5():
    r = run("calibrate", "--simulate", "--quick", "--robots", "2")
    assert r.returncode == 0, r.stderr[-2000:]
    for t in ("Table 4.3", "Table 4.4", "Table 4.5", "§4.4.1 stroke"):
        assert t in r.stdout
    bare = run("calibrate")  # without a mode: explains and fails
    assert bare.returncode == 2 and "--from-mcap" in bare.stderr


def test_calibrate_mcap_logs_a_collection_and_from_mcap_calibrates_from_it(tmp_path):
    log, toml = tmp_path / "cal.mcap", tmp_path / "cal.toml"
    r = run("calibrate", "--mcap", str(log), "--quick", "--dwell", "0.2", "--out", str(toml))
    assert r.returncode == 0, r.stderr[-2000:]
    assert "configurations usable" in r.stdout and "RMS relative pose errors" in r.stdout
    rows = [ln.split() for ln in r.stdout.splitlines() if ln.strip().startswith(("uncal", "rpba "))]
    unc, cal = (np.array(row[1:], dtype=float) for row in rows)
    assert np.all(cal < unc / 10), (unc, cal)  # calibrating from the log worked
    # The log alone reproduces the calibration: same report line, same parameter file.
    again = tmp_path / "again.toml"
    f = run("calibrate", "--from-mcap", str(log), "--out", str(again))
    assert f.returncode == 0, f.stderr[-2000:]
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("rpba:"))
    assert line in f.stdout.splitlines() and "truncated" not in f.stdout
    assert again.read_text() == toml.read_text()
    # weighted by the camera covariance the log's dwells recorded: another fit of the same log
    d = run("calibrate", "--from-mcap", str(log), "--noise", "dwells")
    assert d.returncode == 0, d.stderr[-2000:]
    dline = next(ln for ln in d.stdout.splitlines() if ln.startswith("rpba:"))
    assert "fit statistic" in dline and dline != line
    # A log cut short (collection killed mid-way) still calibrates from its finished dwells.
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log.read_bytes()[: log.stat().st_size * 3 // 4])
    c = run("calibrate", "--from-mcap", str(cut))
    assert c.returncode == 0, c.stderr[-2000:]
    assert "the file is truncated" in c.stdout and "left out: not finished" in c.stdout


def test_calibrate_from_a_bad_log_is_a_clear_error(tmp_path):
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"this is not an MCAP file" * 50)
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    servo_log = tmp_path / "servo.mcap"
    rss6.logs.write_run(servo_log, {"torque": (np.arange(3) * 1e-3, np.zeros((3, 6)))}, {"a": "b"})
    for path, kind, words in (
        (garbage, "CorruptLogError", "bad magic"),
        (empty, "TruncatedLogError", "empty"),
        (tmp_path / "missing.mcap", "LogError", "cannot read"),
        (servo_log, "LogError", "not a calibration log"),
    ):
        r = run("calibrate", "--from-mcap", str(path), timeout=120)
        assert r.returncode == 1, (path, r.stdout, r.stderr)
        assert r.stderr.startswith(f"rss6: error: {kind}: ") and words in r.stderr, r.stderr
        assert "Traceback" not in r.stderr and r.stdout == ""


def test_calibrate_modes_are_exclusive(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["calibrate", "--simulate", "--from-mcap", "x.mcap"])
    assert e.value.code == 2 and "not allowed with" in capsys.readouterr().err
    # --out (the calibrated kinematics) has nothing to write in the --simulate study: refused,
    # not silently ignored.
    assert cli.main(["calibrate", "--simulate", "--out", "k.toml"]) == 1
    assert "--out writes the kinematics calibrated by --mcap" in capsys.readouterr().err
    # a study's --noise that belongs to the other study: refused before any task runs
    assert (
        cli.main(["study", "calibration", "--n", "1", "--out", "x.csv", "--noise", "frames"]) == 1
    )
    assert "--noise frames is for the identification study" in capsys.readouterr().err
    assert (
        cli.main(["study", "identification", "--n", "1", "--out", "x.csv", "--noise", "dwells"])
        == 1
    )
    assert "--noise dwells is for the calibration study" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["demo", "--seed", "-1"], "--seed: a seed must be in [0, 2147483647], got -1"),
        (["calibrate", "--simulate", "--seed", "2**40"], "--seed: expected an integer"),
        (["track", "--duration", "0"], "--duration: must be > 0, got 0"),
        (["track", "--duration", "nan"], "--duration: expected a finite number"),
        (["identify", "--simulate", "--replicates", "-1"], "--replicates: must be >= 0, got -1"),
        (["diagnose", "--simulate", "payload", "--magnitude", "-2"], "--magnitude: must be > 0"),
        (["diagnose", "--simulate", "none", "--seed", "2147483648"], "--seed: a seed must be"),
        (["study", "identification", "--n", "0", "--out", "x.csv"], "--n: must be >= 1, got 0"),
        (["study", "discrepancy", "--n", "2", "--out", "x.csv", "--workers", "0"], "--workers"),
    ],
)
def test_a_bad_number_is_a_usage_error_naming_its_option(capsys, argv, message):
    """Negative seeds, non-positive durations and counts stop at the parser (exit 2) with the
    option's name; they used to end in a numpy or PyO3 traceback deep inside a run (a negative
    seed, a negative magnitude) or run with nothing to do."""
    with pytest.raises(SystemExit) as e:
        cli.main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and message in err, err


@pytest.mark.parametrize(
    "argv",
    [
        ["demo", "--quick", "--plant", "model"],
        ["identify", "--simulate", "--quick", "--plant", "model"],
        ["diagnose", "--simulate", "none", "--plant", "model"],
    ],
)
def test_an_out_directory_that_is_a_file_is_refused_before_the_work(
    capsys, monkeypatch, tmp_path, argv
):
    """`--out` naming a file used to fail with a FileExistsError traceback after the whole run
    (the diagnosis's report could not be written); now the command stops first."""
    from rss6 import demo, identify_sim
    from rss6.discrepancy import benchmark

    def no_work(*args, **kwargs):
        raise AssertionError("the run started")

    for module, name in ((demo, "run"), (identify_sim, "run"), (benchmark, "hidden_case")):
        monkeypatch.setattr(module, name, no_work)
    blocker = tmp_path / "a-file"
    blocker.write_text("keep me", encoding="utf-8")
    assert cli.main([*argv, "--quiet", "--out", str(blocker)]) == 1
    assert f"--out {blocker} is a file; give a directory" in capsys.readouterr().err
    # A file in the way of a directory to be made: refused too, and nothing is created.
    assert cli.main([*argv, "--quiet", "--out", str(blocker / "sub")]) == 1
    assert "is a file, so the directory cannot be made" in capsys.readouterr().err
    assert blocker.read_text(encoding="utf-8") == "keep me"


@pytest.fixture(scope="module")
def identify_quick(tmp_path_factory):
    """One `rss6 identify --simulate --quick` run: the default stick–slip law on the rapier plant
    (measured: 20 s with Table 5.5's two re-identifications)."""
    out = tmp_path_factory.mktemp("identify")
    r = run("identify", "--simulate", "--quick", "--quiet", "--out", str(out), timeout=300)
    return r, out


def test_identify_simulate_quick_writes_tables_figures_and_logs(identify_quick):
    r, out = identify_quick
    assert r.returncode == 0, r.stderr
    text = (out / "tables.txt").read_text(encoding="utf-8")
    for heading in ("Table 5.2", "Table 5.3", "Table 5.4", "Table 5.5"):
        assert heading in text
    for name in ("platform.Sxx", "wrench1.Iz", "link6.It", "fc1", "fv6", "lp", "li", "ld"):
        assert name in text
    assert "cost history" in text
    assert "camera frames in 2 s (1 period)" in text  # --quick: one period of the 2 s design
    # §5.6.3's validation run with other outer-loop gains is in Table 5.4.
    assert "outer gains k_p, k_i, k_d = 0.45, 1.6, 0.002" in text
    for f in ("fig5_7_excitation.png", "fig5_8_identification.png", "fig5_9_validation.png"):
        assert (out / f).stat().st_size > 10_000
    for f in ("identification.mcap", "validation_0.mcap", "validation_1.mcap"):
        log = rss6.logs.read_log(out / f)
        assert log is not None
    assert run("identify").returncode == 2  # --simulate is the only mode
    bad = run("identify", "--simulate", "--periods", "0", "--quiet", "--out", str(out / "bad"))
    # A usage error (exit 2) that names the option, before any work.
    assert bad.returncode == 2 and "--periods: must be >= 1, got 0" in bad.stderr, bad.stderr
    # Each σ is also the spread over 16 noisy replicates (the default; `--replicates 0`: CLOE's).
    assert "the spread over 16 noisy replicates" in text
    bad = run("identify", "--simulate", "--replicates", "1", "--quiet", "--out", str(out / "bad"))
    assert bad.returncode == 1 and "replicates must be 0 or >= 2" in bad.stderr, bad.stderr


def test_identify_simulate_quick_with_tanh_friction_does_not_converge_and_says_so(tmp_path):
    """With --friction-law tanh (the plant's own friction, tanh in the model) CLOE from Table 5.1
    does not converge on the rapier plant in the quick run (Φ 2.67e4 → 6.02e3 in 10 iterations;
    docs/identification.md): exit status 3, the report says so with its cost history. If this
    starts converging, the docs' account of the tanh path is out of date."""
    if rss6.Plant is None:
        pytest.skip("built without the rapier plant")
    r = run(
        "identify", "--simulate", "--quick", "--quiet", "--no-variation",
        "--friction-law", "tanh", "--out", str(tmp_path), timeout=300,
    )  # fmt: skip
    assert r.returncode == 3, r.stderr[-2000:]
    text = (tmp_path / "tables.txt").read_text(encoding="utf-8")
    assert "DID NOT CONVERGE" in text and "did not converge" in r.stderr
    assert "cost history" in text and "tanh" in text


def test_identify_simulate_quick_with_stick_slip_identifies_on_the_plant(identify_quick):
    """The default `--friction-law implicit`: plant and model share the stick–slip law; a linear start
    from the recorded commands and potentiometers (l_p known), then CLOE on the recorded commands
    (docs/identification.md, "Stick–slip"). Measured on the rapier plant (seed 0, 12.6 s): 12
    iterations, reduced χ² 4.24, l_i +0.8 %, l_d −5.9 %, f_c within 8.8 %, validation position RMS
    0.07–0.20 of the initial model's; bounds ≈ 3×."""
    if rss6.Plant is None:
        pytest.skip("built without the rapier plant")
    r, out = identify_quick
    assert r.returncode == 0, r.stderr[-2000:]
    text = (out / "tables.txt").read_text(encoding="utf-8")
    assert "converged in" in text and "stick–slip" in text
    # The report says which stopping rule ended CLOE, in words.
    from rss6.identify_report import _STOP_RULES

    assert any(f"iterations ({why})" in text for why in _STOP_RULES.values()), text[:600]
    rows = {
        w[0]: (float(w[2]), float(w[3]))
        for w in (line.split() for line in text.splitlines())
        if len(w) >= 4 and w[0] in {"li", "ld", "fc1", "fc2", "fc3", "fc4", "fc5", "fc6"}
    }
    err = {n: est / truth - 1 for n, (est, truth) in rows.items()}
    assert abs(err["li"]) < 0.025 and abs(err["ld"]) < 0.18, err
    assert max(abs(err[f"fc{i}"]) for i in range(1, 7)) < 0.27, err
    val = [
        line.split() for line in text.splitlines() if line.strip().split()[1:2] == ["identified"]
    ]
    init = [line.split() for line in text.splitlines() if line.strip().startswith("initial ")]
    # Two validation runs and the run with other outer-loop gains (§5.6.3), the same criterion.
    assert len(val) == 3 and len(init) == 3 and val[2][0] == "gains"
    for v, i in zip(val, init):
        ratio = np.array(v[2:5], float) / np.array(i[1:4], float)
        assert np.all(ratio < 0.6), (v, i)
    # Against the plant's noise-free pose the criterion holds on the angles too (measured on
    # this run: 0.033–0.098 on x, y, z, 0.020–0.143 on α, β, γ; bound ≈ 3×).
    m = re.search(r"noise-free pose at the frame times: identified/initial RMS "
                  r"([\d.]+)–([\d.]+) on x, y, z, ([\d.]+)–([\d.]+) on", text)  # fmt: skip
    assert m is not None, text[-1500:]
    assert max(float(m.group(2)), float(m.group(4))) < 0.45, m.group(0)


def test_identify_noise_frames_reaches_cloe(monkeypatch, tmp_path):
    """`rss6 identify --simulate --noise frames` runs CLOE whitened by the frames' covariance (the
    default is Table 4.1's per-axis weights); a quick run on the model twin reports it."""
    from rss6 import identify
    from rss6.cli import main

    seen: list[object] = []
    cloe = identify.cloe

    def recording(*args, **kw):
        seen.append(kw.get("noise"))
        return cloe(*args, **kw)

    monkeypatch.setattr(identify, "cloe", recording)
    out = tmp_path / "id"
    args = ["--quick", "--plant", "model", "--no-variation", "--quiet", "--out", str(out)]
    assert main(["identify", "--simulate", *args, "--noise", "frames"]) == 0
    assert seen[0] == "frames"
    text = (out / "tables.txt").read_text(encoding="utf-8")
    assert "each frame's residual whitened by its covariance" in text
    bad = run("identify", "--simulate", "--noise", "diagonal")
    assert bad.returncode == 2 and "--noise" in bad.stderr
