"""rss6.can across two processes: ``rss6 can-sim`` (the drives) and a bridge, over python-can's
``udp_multicast`` inside a network namespace this test creates (``unshare -rn``: ``lo`` up, a
224.0.0.0/4 route on ``lo``, an IPv4 group). A 5 s lockstep run either completes or stops with a
named fault; frames lost on the way are counted."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("can")
pytest.importorskip("canopen")
pytest.importorskip("msgpack", reason="python-can's udp_multicast needs msgpack")

GROUP = "239.74.163.2"

BRIDGE = textwrap.dedent(
    """
    import json, sys, time
    import numpy as np
    import rss6.can as rc
    from rss6.can.simcli import make_bus

    bus = make_bus("udp_multicast", sys.argv[1], "bridge")
    bridge = rc.Bridge(bus, rc.BridgeConfig(wait_timeout=0.05))
    robot = rc.CanRobot(bridge)
    end = time.monotonic() + 20.0
    while True:  # the drives' process may still be starting
        try:
            robot.reset(None)
            break
        except rc.CanFaultError as e:
            if time.monotonic() > end:
                print(json.dumps({"error": f"no drives: {e}"}))
                sys.exit(1)
            time.sleep(0.2)
    n = 5000
    t0 = time.perf_counter()
    for k in range(n):
        theta = 0.1 * np.sin(2 * np.pi * 0.5 * k * 1e-3 + np.arange(6)) * min(1.0, k / 500)
        robot.step_joint_command(theta)
    wall = time.perf_counter() - t0
    st = bridge.stats()
    expected = 6 * (n // 2)
    print(json.dumps({"cycles": st["cycles"], "fault": st["fault"], "wall": wall,
                      "tpdo_expected": expected, "tpdo_accepted": st["accepted"],
                      "rejected": st["rejected"], "lost_waits": st["lost_waits"],
                      "kappa": robot.potentiometers().tolist()}))
    bridge.close()
    bus.shutdown()
    """
)


def test_can_sim_cli_runs_on_a_virtual_bus(capsys: pytest.CaptureFixture[str]) -> None:
    from rss6.cli import main

    assert main(["can-sim", "--channel", "rss6-cli-test", "--seconds", "0.2"]) == 0
    out = capsys.readouterr().out
    assert "rss6 can-sim: drives 1, 2, 3, 4, 5, 6 on virtual rss6-cli-test (model)" in out
    assert "0 ticks" in out and "SWITCH_ON_DISABLED" in out


def _namespace_ok() -> bool:
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return False
    r = subprocess.run(["unshare", "-rn", "sh", "-c", "ip link set lo up"], capture_output=True)
    return r.returncode == 0


@pytest.mark.skipif(
    not _namespace_ok(),
    reason="unshare -rn (user + network namespace) not permitted here, or `ip` missing",
)
def test_two_processes_over_udp_multicast(tmp_path: Path) -> None:
    script = tmp_path / "bridge.py"
    script.write_text(BRIDGE)
    out = tmp_path / "bridge.json"
    py = sys.executable
    shell = textwrap.dedent(
        f"""
        set -e
        ip link set lo up
        ip route add 224.0.0.0/4 dev lo
        {py} -m rss6 can-sim --interface udp_multicast --channel {GROUP} --seconds 120 \\
            > {tmp_path}/sim.txt 2>&1 &
        SIM=$!
        {py} {script} {GROUP} > {out} 2> {tmp_path}/bridge.err || true
        kill -TERM $SIM; wait $SIM || true
        """
    )
    r = subprocess.run(
        ["unshare", "-rn", "sh", "-c", shell], capture_output=True, text=True, timeout=300
    )
    assert r.returncode == 0, r.stderr
    text = out.read_text()
    assert text, (tmp_path / "bridge.err").read_text()
    res = json.loads(text.strip().splitlines()[-1])
    assert "error" not in res, res
    lost = res["tpdo_expected"] - res["tpdo_accepted"]
    print(
        f"udp_multicast: {res['cycles']} cycles in {res['wall']:.1f} s, TPDO1 lost {lost} of "
        f"{res['tpdo_expected']}, lost waits {res['lost_waits']}, fault {res['fault']}"
    )
    assert res["cycles"] == 5000
    if res["fault"] is None:
        assert lost <= res["tpdo_expected"] // 100  # the run completed on a working link
    else:
        assert any(w in res["fault"] for w in ("TPDO1", "heartbeat", "EMCY", "bus error")), res
    sim_out = (tmp_path / "sim.txt").read_text()
    assert "rss6 can-sim: drives 1, 2, 3, 4, 5, 6 on udp_multicast" in sim_out, sim_out
