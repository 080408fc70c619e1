"""Figures like the thesis's (PNG files).

Figures are built as :class:`matplotlib.figure.Figure` objects rendered by the Agg canvas, so the
caller's matplotlib backend (and pyplot's figure list) is never touched.

* :func:`relative_pose_errors` — Fig. 4.8: relative pose errors per test configuration, uncalibrated
  vs calibrated.
* :func:`tracking` — Figs. 6.4/6.7: desired pose and the measured pose of each controller.
* :func:`tracking_errors` — Figs. 6.5/6.8: tracking errors of each controller.
* :func:`exciting_trajectory` — Fig. 5.7: the exciting trajectory (position and angles).
* :func:`identification_fit` — Figs. 5.8/5.9: measured poses (dots) and the poses the model
  simulates in the loop with the initial and the identified parameters (lines).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from os import PathLike
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from rss6.servo import TrackingResult

__all__ = [
    "exciting_trajectory",
    "identification_fit",
    "relative_pose_errors",
    "tracking",
    "tracking_errors",
]

_LABELS = ("x (mm)", "y (mm)", "z (mm)", "α (mrad)", "β (mrad)", "γ (mrad)")
_TITLES = (
    "(a) along X",
    "(b) along Y",
    "(c) along Z",
    "(d) around α",
    "(e) around β",
    "(f) around γ",
)
# Thesis line styles: KJSC purple dashed, KCSC black dotted, DSMC red dash-dotted.
_STYLE = {"KJSC": ("tab:purple", "--"), "KCSC": ("black", ":"), "DSMC": ("tab:red", "-.")}


def _figure() -> tuple[Figure, list[Axes]]:
    """A 3 × 2 figure on its own Agg canvas; panels in the order x, y, z, α, β, γ (column-wise)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11, 9))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, 2, sharex=True)
    return fig, list(axes.T.ravel())


def _save(fig: Figure, path: str | PathLike[str]) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def relative_pose_errors(
    uncalibrated: ArrayLike, calibrated: ArrayLike, path: str | PathLike[str], title: str = ""
) -> None:
    """Fig. 4.8: errors (n, 6) (m, rad) of the uncalibrated and the calibrated model per test
    configuration, in mm and mrad."""
    u = np.asarray(uncalibrated) * 1e3
    c = np.asarray(calibrated) * 1e3
    fig, axes = _figure()
    for k, ax in enumerate(axes):
        ax.plot(np.arange(1, len(u) + 1), u[:, k], "b.-", lw=0.8, ms=3, label="uncalibrated")
        ax.plot(np.arange(1, len(c) + 1), c[:, k], "r.-", lw=0.8, ms=3, label="calibrated")
        ax.set_ylabel(_LABELS[k])
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("test configuration")
    axes[5].set_xlabel("test configuration")
    axes[0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    _save(fig, path)


def tracking(results: Sequence[TrackingResult], path: str | PathLike[str], title: str = "") -> None:
    """Figs. 6.4/6.7: the desired trajectory (blue solid) and the measured pose of each run
    (:class:`rss6.servo.TrackingResult`) in the thesis's line styles."""
    _per_axis(results, lambda r: r.measured, path, title, desired=True)


def tracking_errors(
    results: Sequence[TrackingResult], path: str | PathLike[str], title: str = ""
) -> None:
    """Figs. 6.5/6.8: tracking errors χ_d − χ_measured of each run."""
    _per_axis(results, lambda r: r.errors, path, title, desired=False)


def _per_axis(
    results: Sequence[TrackingResult],
    series: Callable[[TrackingResult], NDArray[np.float64]],
    path: str | PathLike[str],
    title: str,
    desired: bool,
) -> None:
    """Six panels (x, y, z in mm; α, β, γ in 1e-3 rad): ``series(run)`` at the camera frames of each
    run, with the desired pose of the first run underneath if ``desired``."""
    fig, axes = _figure()
    for k, ax in enumerate(axes):
        if desired:
            first = results[0]
            ax.plot(first.time, first.desired[:, k] * 1e3, "tab:blue", lw=1.2, label="desired")
        for r in results:
            color, ls = _STYLE.get(r.controller, ("gray", "-"))
            ax.plot(
                r.frame_time, series(r)[:, k] * 1e3, color=color, ls=ls, lw=1.0, label=r.controller
            )
        ax.set_ylabel(_LABELS[k])
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("time (s)")
    axes[5].set_xlabel("time (s)")
    axes[0].legend(fontsize=8)
    if title:
        fig.suptitle(title)
    _save(fig, path)


def table_text(
    measured: Mapping[str, TrackingResult],
    thesis: Mapping[str, Mapping[str, Sequence[float]]],
    title: str,
) -> str:
    """A text table of RMSE/MAE per axis: ours beside the thesis's (mm and 1e-3 rad).

    Runs of ``measured`` under names the thesis has no column for (e.g. "DSMC-LN", the low-noise
    servo) get an rss6 column of their own at the end.
    """
    names = ["KJSC", "KCSC", "DSMC"]
    extra = [n for n in measured if n not in names]
    axes = ["x (mm)", "y (mm)", "z (mm)", "α (1e-3 rad)", "β (1e-3 rad)", "γ (1e-3 rad)"]
    lines = [title, ""]
    head = (
        f"{'axis':14s} {'stat':5s} "
        + " ".join(f"{n + ' rss6':>10s} {n + ' thesis':>11s}" for n in names)
        + "".join(f" {n + ' rss6':>12s}" for n in extra)
    )
    lines.append(head)
    lines.append("-" * len(head))
    for k, ax in enumerate(axes):
        for stat in ("rmse", "mae"):
            cells = []
            for n in names:
                ours = measured[n].table()[stat][k] if n in measured else float("nan")
                cells.append(f"{ours:10.3f} {thesis[stat][n][k]:11.3g}")
            row = f"{ax:14s} {stat.upper():5s} " + " ".join(cells)
            row += "".join(f" {measured[n].table()[stat][k]:12.3f}" for n in extra)
            lines.append(row)
    return "\n".join(lines)


def exciting_trajectory(
    t: ArrayLike, pose: ArrayLike, path: str | PathLike[str], title: str = ""
) -> None:
    """Fig. 5.7: the exciting trajectory χ_d(t) (``pose`` (N, 6), m and rad) — (a) positions in mm,
    (b) angles in mrad."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    tt = np.asarray(t, dtype=np.float64)
    p = np.asarray(pose, dtype=np.float64)
    fig = Figure(figsize=(9, 6))
    FigureCanvasAgg(fig)
    a, b = fig.subplots(2, 1, sharex=True)
    for i, n in enumerate("xyz"):
        a.plot(tt, p[:, i] * 1e3, label=n)
    for i, n in enumerate("αβγ"):
        b.plot(tt, p[:, 3 + i] * 1e3, label=n)
    a.set_ylabel("position (mm)")
    b.set_ylabel("angle (mrad)")
    b.set_xlabel("t (s)")
    a.set_title("(a) positional trajectory")
    b.set_title("(b) angular trajectory")
    for ax in (a, b):
        ax.legend(loc="upper right")
        ax.grid(True, alpha=0.3)
    if title:
        fig.suptitle(title)
    _save(fig, path)


def identification_fit(
    t: ArrayLike,
    measured: ArrayLike,
    simulated: Mapping[str, ArrayLike],
    path: str | PathLike[str],
    title: str = "",
) -> None:
    """Figs. 5.8/5.9: the measured poses (black dots) and each simulated pose trajectory of
    ``simulated`` (label → (N, 6); "initial" green, "identified" blue as in the thesis)."""
    fig, axes = _figure()
    tt = np.asarray(t, dtype=np.float64)
    m = np.asarray(measured, dtype=np.float64)
    colours = {"initial": "tab:green", "identified": "tab:blue"}
    for i, ax in enumerate(axes):
        ax.plot(tt, m[:, i] * 1e3, "k.", ms=3, label="measured")
        for label, sim in simulated.items():
            ax.plot(tt, np.asarray(sim)[:, i] * 1e3, color=colours.get(label), label=label)
        ax.set_ylabel(_LABELS[i])
        ax.set_title(_TITLES[i])
        ax.grid(True, alpha=0.3)
    axes[2].set_xlabel("t (s)")
    axes[5].set_xlabel("t (s)")
    axes[0].legend(loc="upper right")
    if title:
        fig.suptitle(title)
    _save(fig, path)
