"""The "Detect" step of issue 14: where does a residual disagree with the noise?

:func:`detect` takes a residual r = measured − model (N, 6) at the camera times, however it was
simulated, and runs one family of tests per axis — residual energy vs the noise floor, energy in
consecutive windows, whiteness (Ljung–Box), cross-correlation with each signature — then Holm's
correction over the whole axes × tests family, so the chance of any false alarm on a run without a
missing effect is at most ``alpha`` (measured: docs/discrepancy.md).

>>> import numpy as np
>>> from rss6 import discrepancy
>>> rng = np.random.default_rng(0)
>>> t = np.arange(900) / 30.0
>>> ref = 0.01 * np.sin(2 * np.pi * 0.2 * t)[:, None] * np.ones(6)
>>> sig = discrepancy.reference_signatures(t, ref)
>>> clean = discrepancy.detect(t, 1e-5 * rng.standard_normal((900, 6)), sig, noise_floor=1e-5)
>>> clean.detected
False
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.signal import lfilter

from rss6 import _checks
from rss6.discrepancy import stats
from rss6.discrepancy.noise import (
    NoiseModel,
    as_residual,
    fit_ar,
    noise_from_differences,
    noise_from_periods,
)
from rss6.errors import InvalidInputError, ShapeError

__all__ = ["AXES", "Detection", "TestRow", "Window", "detect", "reference_signatures"]

F64 = NDArray[np.float64]

#: Pose axis names, in the order of χ.
AXES = ("x", "y", "z", "α", "β", "γ")


@dataclass(frozen=True)
class TestRow:
    """One test of the family: ``axis``, ``test`` ("energy", "windows", "whiteness" or
    "xcorr <signature>"), its ``statistic`` (energy: mean r²/σ²; windows: the worst window's p;
    whiteness: Q; xcorr: z at the best lag), raw and Holm-adjusted p, whether it was rejected and a
    short ``detail``."""

    axis: str
    test: str
    statistic: float
    p_value: float
    p_adjusted: float
    rejected: bool
    detail: str


@dataclass(frozen=True)
class Window:
    """A stretch [start, end) s of one axis whose residual energy exceeds the noise floor;
    ``ratio``: its RMS over σ."""

    axis: str
    start: float
    end: float
    ratio: float


@dataclass(frozen=True)
class Detection:
    """Result of :func:`detect`. ``detected``: any test of the family rejected after Holm;
    ``axes``: the axes that disagree; ``windows``: where; ``tests``: every test; ``noise``: the noise
    model used; ``correlations`` {signature: (6, 2L+1)} of the prewhitened residual with the
    prewhitened signature at lags −L..L frames, ``lags`` (2L+1,) s; ``time``, ``residual`` as given."""

    detected: bool
    axes: tuple[str, ...]
    windows: tuple[Window, ...]
    tests: tuple[TestRow, ...]
    noise: NoiseModel
    alpha: float
    rate: float
    time: F64
    residual: F64
    correlations: dict[str, F64] = field(default_factory=dict)
    lags: F64 = field(default_factory=lambda: np.zeros(1))

    def signatures(self, axis: str | None = None) -> list[TestRow]:
        """The rejected cross-correlation tests (of ``axis``, or all), strongest |z| first."""
        rows = [
            r
            for r in self.tests
            if r.test.startswith("xcorr ") and r.rejected and (axis is None or r.axis == axis)
        ]
        return sorted(rows, key=lambda r: -abs(r.statistic))

    def top_signature(self, axis: str) -> str | None:
        """The signature the residual of ``axis`` follows most strongly, if any passed."""
        rows = self.signatures(axis)
        return rows[0].test.removeprefix("xcorr ") if rows else None

    def summary(self) -> str:
        """One line: the verdict of the Detect step."""
        if not self.detected:
            return f"no discrepancy at family-wise α = {self.alpha:g} ({len(self.tests)} tests)"
        parts = []
        for a in self.axes:
            failed = [r.test for r in self.tests if r.axis == a and r.rejected]
            parts.append(f"{a}: {', '.join(failed)}")
        return "discrepancy on " + "; ".join(parts)


def reference_signatures(
    t: ArrayLike, reference: ArrayLike, *, gravity_load: ArrayLike | None = None
) -> dict[str, F64]:
    """Physical signatures from the reference pose χ_d (N, 6) at the camera times ``t`` (N,):
    "velocity", "velocity sign", "acceleration" (finite differences), "reference" (its
    cross-correlation at a non-zero lag is a time-shifted reference), "workspace radius" (distance
    of the reference position from its mean, one column for every axis), "time" (elapsed time
    from the run's middle, one column: a slow drift of the sensor or the robot, which the
    closed loop's low-frequency noise hides from the energy test) and, if given,
    "gravity load" (N, 6): e.g. the gravity wrench along each axis from the model."""
    tt = np.asarray(t, dtype=np.float64)
    x = as_residual(reference, "reference")
    if x.shape[0] != tt.shape[0]:
        raise ShapeError(f"reference has {x.shape[0]} rows, t has {tt.shape[0]}")
    v = np.gradient(x, tt, axis=0)
    a = np.gradient(v, tt, axis=0)
    rad = np.linalg.norm(x[:, :3] - x[:, :3].mean(axis=0), axis=1)
    out = {
        "velocity": v,
        "velocity sign": np.sign(v),
        "acceleration": a,
        "reference": x - x.mean(axis=0),
        "workspace radius": np.repeat(rad[:, None], x.shape[1], axis=1),
        "time": (tt - tt.mean())[:, None],
    }
    if gravity_load is not None:
        out["gravity load"] = as_residual(gravity_load, "gravity_load")
    return out


def _noise(r: F64, noise_floor: ArrayLike | NoiseModel | None, period: int | None) -> NoiseModel:
    if isinstance(noise_floor, NoiseModel):
        return noise_floor
    if noise_floor is None:
        return noise_from_periods(r, period) if period else noise_from_differences(r)
    s = np.asarray(noise_floor, dtype=np.float64)
    if s.shape not in ((), (1,), (r.shape[1],)):
        raise ShapeError(
            f"noise_floor must be one σ or one per axis ({r.shape[1]},); got {s.shape}"
        )
    return NoiseModel.white(np.broadcast_to(s, (r.shape[1],)))


def detect(
    t: ArrayLike,
    residual: ArrayLike,
    signatures: Mapping[str, ArrayLike],
    noise_floor: ArrayLike | NoiseModel | None = None,
    alpha: float = 0.01,
    *,
    period: float | None = None,
    window: float = 1.0,
    max_lag: float = 0.1,
    lb_lags: int = 20,
) -> Detection:
    """Tests a residual (N, 6) at camera times ``t`` (N,) s against its noise.

    ``signatures``: {name: (N,) or (N, 6)} (a (N, 6) signature is used column by column; see
    :func:`reference_signatures`). ``noise_floor``: σ per axis (white, e.g. Table 4.1), a
    :class:`NoiseModel`, or None to estimate it from the residual (from differences of repeated
    periods if ``period`` s is given, else from first differences; docs/discrepancy.md).
    ``alpha``: family-wise error rate over all axes × tests (Holm). ``window`` s: width of the
    windows of the running energy test; ``max_lag`` s: lags searched for each signature;
    ``lb_lags``: Ljung–Box lags."""
    tt = np.asarray(t, dtype=np.float64)
    r = as_residual(residual)
    n, m = r.shape
    if tt.shape != (n,) or np.any(np.diff(tt) <= 0):
        raise ShapeError(f"t must be increasing with shape ({n},); got {tt.shape}")
    if not 0 < alpha < 1:
        raise InvalidInputError(f"alpha must be in (0, 1); got {alpha}")
    if not (np.isfinite(window) and window > 0 and np.isfinite(max_lag) and max_lag >= 0):
        raise InvalidInputError(
            f"window must be finite and > 0 s and max_lag finite and >= 0 s; got {window}, {max_lag}"
        )
    _checks.count(lb_lags, "lb_lags", 1)
    rate = 1.0 / float(np.median(np.diff(tt)))
    noise = _noise(r, noise_floor, None if period is None else round(period * rate))
    if noise.axes != m:
        raise ShapeError(f"noise model has {noise.axes} axes, residual {m}")
    sigs = {k: as_residual(v, f"signature {k!r}") for k, v in signatures.items()}
    for key, v in sigs.items():
        if v.shape[0] != n or v.shape[1] not in (1, m):
            raise ShapeError(
                f"signature {key!r} must have shape ({n},) or ({n}, {m}); got {v.shape}"
            )
    width = max(8, round(window * rate))
    lag = max(0, round(max_lag * rate))
    names = AXES if m == 6 else tuple(f"axis {k}" for k in range(m))

    raw: list[tuple[str, str, float, float, str]] = []
    window_p: dict[int, tuple[F64, NDArray[np.int64]]] = {}
    corr: dict[str, F64] = {key: np.zeros((m, 2 * lag + 1)) for key in sigs}
    for k in range(m):
        ratio, p = stats.energy_test(r[:, k], noise, k)
        raw.append((names[k], "energy", ratio, p, f"RMS/σ = {np.sqrt(ratio):.3g}"))
        pw, per, starts = stats.window_test(r[:, k], noise, k, width)
        window_p[k] = (per, starts)
        raw.append((names[k], "windows", float(per.min()), pw, f"{len(per)} windows"))
        if noise.source != "given":
            # An estimated colour is not exact: from first differences it assumes AR(1), which a
            # real closed loop does not meet (its noise needs AR orders up to 27,
            # docs/discrepancy.md); from period differences its coefficients carry their own
            # sampling noise, which inflates Q. Test what an AR(p ≤ 30, AIC) fitted to the
            # residual cannot absorb, over p + lb_lags lags against χ²_lb_lags (Ljung–Box on ARMA
            # residuals).
            x = r[:, k] - r[:, k].mean()
            phi, _ = fit_ar(x, 30)
            u, fitted = lfilter(np.r_[1.0, -phi], [1.0], x)[len(phi) :], len(phi)
        else:
            u, fitted = noise.whiten(r[:, k], k), 0
        h = min(lb_lags + fitted, len(u) // 4)
        q, plb = stats.ljung_box(u, h, fitted)
        raw.append((names[k], "whiteness", float(q[0]), float(plb[0]), f"Ljung–Box Q, {h} lags"))
        cols = np.column_stack([s[:, k if s.shape[1] > 1 else 0] for s in sigs.values()])
        if sigs:
            z, best, px, c = stats.xcorr_test(r[:, k], cols, noise, k, lag)
            for j, name in enumerate(sigs):
                corr[name][k] = c[j]
                raw.append(
                    (
                        names[k],
                        f"xcorr {name}",
                        float(z[j]),
                        float(px[j]),
                        f"lag {best[j] / rate:+.3f} s",
                    )
                )
    rejected, adjusted = stats.holm([x[3] for x in raw], alpha)
    rows = tuple(
        TestRow(a, test, s, p, float(pa), bool(rj), d)
        for (a, test, s, p, d), pa, rj in zip(raw, adjusted, rejected)
    )
    axes = tuple(a for a in names if any(row.rejected for row in rows if row.axis == a))
    windows: list[Window] = []
    for k, a in enumerate(names):
        if not any(row.rejected for row in rows if row.axis == a and row.test == "windows"):
            continue
        per, starts = window_p[k]
        bad = per * len(per) <= alpha
        ends = np.r_[starts[1:], n]
        i = 0
        while i < len(per):
            if not bad[i]:
                i += 1
                continue
            j = i
            while j + 1 < len(per) and bad[j + 1]:
                j += 1
            seg = r[starts[i] : ends[j], k]
            end = float(tt[ends[j] - 1] + 1.0 / rate)
            rms = float(np.sqrt(np.mean(seg**2)) / noise.sigma[k])
            windows.append(Window(a, float(tt[starts[i]]), end, rms))
            i = j + 1
    return Detection(
        detected=bool(np.any(rejected)),
        axes=axes,
        windows=tuple(windows),
        tests=rows,
        noise=noise,
        alpha=alpha,
        rate=rate,
        time=tt,
        residual=r,
        correlations=corr,
        lags=np.arange(-lag, lag + 1) / rate,
    )
