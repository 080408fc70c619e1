"""rss6.plots: PNG files from Figure + FigureCanvasAgg, without touching the caller's matplotlib."""

import subprocess
import sys
import textwrap


def test_plots_leave_the_backend_and_pyplot_alone(tmp_path):
    # In a fresh interpreter whose user chose the SVG backend: every figure is written as a PNG,
    # the backend is still SVG afterwards and pyplot was never imported.
    code = textwrap.dedent(
        f"""
        import sys
        import matplotlib
        matplotlib.use("svg")
        import numpy as np
        sys.path.insert(0, {str(__file__.rsplit("/", 1)[0])!r})
        from test_demo import fake_run
        from rss6 import plots

        rng = np.random.default_rng(0)
        out = {str(tmp_path)!r}
        plots.relative_pose_errors(rng.normal(0, 1e-3, (20, 6)), rng.normal(0, 1e-5, (20, 6)),
                                   out + "/a.png", "title")
        runs = [fake_run(c) for c in ("KJSC", "KCSC", "DSMC")]
        plots.tracking(runs, out + "/b.png", "t")
        plots.tracking_errors(runs, out + "/c.png")
        assert matplotlib.get_backend().lower() == "svg", matplotlib.get_backend()
        assert "matplotlib.pyplot" not in sys.modules
        """
    )
    r = subprocess.run(
        [sys.executable, "-c", code], check=False, capture_output=True, text=True, timeout=120
    )
    assert r.returncode == 0, r.stderr
    for name in ("a", "b", "c"):
        assert (tmp_path / f"{name}.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
