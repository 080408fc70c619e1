"""The report's PNG figures (matplotlib, each on its own Agg canvas like :mod:`rss6.plots`).

Poses in mm and mrad (×10³ of the SI values); bands are 99 %.
"""

from __future__ import annotations

from collections.abc import Mapping
from os import PathLike

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy.detect import AXES, Detection
from rss6.plots import _LABELS, _TITLES, _figure, _save

__all__ = ["acf", "binned", "gaps", "overlay", "residuals", "xcorr"]

F64 = NDArray[np.float64]
_Z99 = 2.5758293035489004  # two-sided 99 % normal quantile


def residuals(det: Detection, path: str | PathLike[str], title: str = "") -> None:
    """The residual per axis over time with the ±σ noise floor and the 99 % band of one sample,
    and the windows that disagree shaded."""
    fig, axes = _figure()
    t = det.time
    for k, ax in enumerate(axes[: det.residual.shape[1]]):
        s = det.noise.sigma[k] * 1e3
        ax.plot(t, det.residual[:, k] * 1e3, "k", lw=0.6, label="residual")
        ax.fill_between(t, -s, s, color="tab:blue", alpha=0.25, lw=0, label="±σ noise floor")
        ax.axhline(_Z99 * s, color="tab:blue", ls="--", lw=0.8)
        ax.axhline(-_Z99 * s, color="tab:blue", ls="--", lw=0.8, label="99 % of one sample")
        for w in det.windows:
            if w.axis == AXES[k]:
                ax.axvspan(w.start, w.end, color="tab:red", alpha=0.15, lw=0)
        ax.set_ylabel(_LABELS[k])
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("time (s)")
    axes[5].set_xlabel("time (s)")
    axes[0].legend(fontsize=7, loc="upper right")
    fig.suptitle(title or "residual over time (red: windows above the noise floor)")
    _save(fig, path)


def binned(
    det: Detection, signatures: Mapping[str, F64], path: str | PathLike[str], bins: int = 4
) -> None:
    """Mean residual per axis (in units of σ) binned by each signature: by sign for a sign
    signature, else by quantile; error bars: 99 % of the bin mean under the noise model (its
    effective sample size)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = list(signatures) or ["time"]
    fig = Figure(figsize=(10, 2.6 * len(names)))
    FigureCanvasAgg(fig)
    axs = np.atleast_1d(fig.subplots(len(names), 1, squeeze=False)[:, 0])
    r, m = det.residual, det.residual.shape[1]
    for ax, name in zip(axs, names):
        s = signatures.get(name, det.time[:, None])
        s = s[:, None] if s.ndim == 1 else s
        sign = bool(np.all(np.isin(np.unique(s), (-1.0, 0.0, 1.0))))
        width = 0.8 / m
        for k in range(m):
            col = s[:, k if s.shape[1] > 1 else 0]
            if sign:
                labels, idx = ["−", "+"], (col > 0).astype(int)
            else:
                edges = np.quantile(col, np.linspace(0, 1, bins + 1))
                idx = np.clip(np.searchsorted(edges, col, side="right") - 1, 0, bins - 1)
                labels = [f"Q{i + 1}" for i in range(bins)]
            means, errs = [], []
            for b in range(len(labels)):
                x = r[idx == b, k] / det.noise.sigma[k]
                nu = det.noise.ess(k, max(len(x), 2)) if len(x) > 1 else 1.0
                means.append(float(x.mean()) if len(x) else np.nan)
                errs.append(_Z99 / np.sqrt(nu))
            pos = np.arange(len(labels)) + (k - (m - 1) / 2) * width
            ax.bar(pos, means, width, yerr=errs, label=AXES[k] if m == 6 else str(k), capsize=2)
        ax.set_xticks(np.arange(len(labels)), labels)
        ax.set_ylabel("mean residual / σ")
        ax.set_title(f"binned by {name}", fontsize=9)
        ax.axhline(0, color="k", lw=0.6)
        ax.grid(alpha=0.3, axis="y")
    axs[0].legend(fontsize=7, ncol=m)
    _save(fig, path)


def acf(det: Detection, path: str | PathLike[str], nlags: int = 30) -> None:
    """Autocorrelation of the prewhitened residual per axis with the 99 % band of white noise."""
    from statsmodels.tsa.stattools import acf as sm_acf

    fig, axes = _figure()
    for k, ax in enumerate(axes[: det.residual.shape[1]]):
        u = det.noise.whiten(det.residual[:, k], k)
        a = np.asarray(sm_acf(u, nlags=nlags, fft=True))
        band = _Z99 / np.sqrt(len(u))
        lags = np.arange(len(a)) / det.rate
        ax.vlines(lags[1:], 0, a[1:], color="k", lw=1.0)
        ax.fill_between(lags, -band, band, color="tab:blue", alpha=0.25, lw=0)
        ax.set_ylabel("ACF")
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("lag (s)")
    axes[5].set_xlabel("lag (s)")
    fig.suptitle("autocorrelation of the prewhitened residual (band: 99 %, white noise)")
    _save(fig, path)


def xcorr(det: Detection, path: str | PathLike[str]) -> None:
    """Cross-correlation of the prewhitened residual with each prewhitened signature against lag,
    with the 99 % band (Bonferroni over the lags, as the test uses)."""
    from scipy.stats import norm

    fig, axes = _figure()
    n = len(det.time)
    nl = len(det.lags)
    band = float(norm.isf(0.005 / nl)) / np.sqrt(n)
    for k, ax in enumerate(axes[: det.residual.shape[1]]):
        for name, c in det.correlations.items():
            ax.plot(det.lags, c[k], ".-", lw=0.8, label=name)
        ax.axhspan(-band, band, color="tab:blue", alpha=0.2, lw=0)
        ax.set_ylabel("correlation")
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("lag (s): > 0, the residual lags the signature")
    axes[5].set_xlabel("lag (s)")
    axes[0].legend(fontsize=7)
    fig.suptitle("cross-correlation with the signatures (prewhitened; band 99 %)")
    _save(fig, path)


def overlay(
    t: F64,
    curves: Mapping[str, F64],
    noise_floor: F64,
    path: str | PathLike[str],
    title: str = "held-out run: residual before and after",
) -> None:
    """Residuals (N, 6) of several models on the held-out run, overlaid, with the ±σ floor."""
    fig, axes = _figure()
    styles = [("tab:gray", 0.9), ("tab:orange", 0.9), ("tab:green", 1.0)]
    for k, ax in enumerate(axes):
        s = noise_floor[k] * 1e3
        ax.fill_between(t, -s, s, color="tab:blue", alpha=0.2, lw=0, label="±σ")
        for (name, r), (color, lw) in zip(curves.items(), styles):
            ax.plot(t, r[:, k] * 1e3, color=color, lw=lw, label=name)
        ax.set_ylabel(_LABELS[k])
        ax.set_title(_TITLES[k], fontsize=9)
        ax.grid(alpha=0.3)
    axes[2].set_xlabel("time (s)")
    axes[5].set_xlabel("time (s)")
    axes[0].legend(fontsize=7)
    fig.suptitle(title)
    _save(fig, path)


def gaps(
    rows: Mapping[str, F64],
    noise_floor: F64,
    path: str | PathLike[str],
    run: str = "the held-out run",
) -> None:
    """Residual RMS per axis of each model (mm, mrad) beside the noise floor, log scale."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 3.5))
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    series = {**rows, "noise floor": noise_floor}
    width = 0.8 / len(series)
    for i, (name, v) in enumerate(series.items()):
        ax.bar(np.arange(6) + (i - (len(series) - 1) / 2) * width, v * 1e3, width, label=name)
    ax.set_xticks(np.arange(6), [f"{a} ({'mm' if i < 3 else 'mrad'})" for i, a in enumerate(AXES)])
    ax.set_yscale("log")
    ax.set_ylabel("RMS")
    ax.set_title(f"residual RMS per axis on {run}", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, axis="y")
    _save(fig, path)
