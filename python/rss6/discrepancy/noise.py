"""The noise model the discrepancy tests are honest about: per pose axis a marginal σ and an AR(p)
colour, given (Table 4.1, white) or estimated from the residual.

Residual samples are the camera frames, taken as evenly spaced (missing frames dropped); the AR lag
is one frame.

Estimators and their bias (docs/discrepancy.md):

* :func:`noise_from_periods` — the reference repeats with a period of P frames (an exciting
  trajectory of f0 = 0.1 Hz repeats every 300 frames): d_t = r_{t+P} − r_t cancels everything that
  repeats, model error included, so σ² = E d²/2 and the colour is an AR fit to d (its ACF is 2γ(h)
  for h ≪ P). Unbiased for stationary noise; a systematic part that does not repeat (a drift, the
  start transient) stays in d and biases σ̂ *up* (the tests lose power, they do not cry wolf).
* :func:`noise_from_differences` — no repetition: the first differences of a signal that is smooth
  at the frame rate are noise, and under an AR(1) noise model their lag-1 correlation ρ_d = −(1−ρ)/2
  gives ρ and σ² = var(d)/(2(1−ρ)) (method of moments). Exact for AR(1) noise; a smooth systematic
  part adds O((ω·Δt)²) of its power; noise whose colour is not AR(1) biases it either way. Its
  sampling error is carried as the degrees of freedom of σ̂² so the energy tests use an F, not a χ².
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6 import _checks
from rss6.errors import InvalidInputError, ShapeError

__all__ = [
    "NoiseModel",
    "as_residual",
    "fit_ar",
    "noise_from_differences",
    "noise_from_periods",
    "noise_from_repeats",
]

F64 = NDArray[np.float64]


def as_residual(residual: ArrayLike, name: str = "residual") -> F64:
    """``residual`` as a float array (N, 6) (a vector (N,) becomes (N, 1)), checked finite."""
    r = np.asarray(residual, dtype=np.float64)
    if r.ndim == 1:
        r = r[:, None]
    if r.ndim != 2 or r.shape[0] < 8:
        raise ShapeError(f"{name} must have shape (N, axes) with N >= 8; got {r.shape}")
    if not np.all(np.isfinite(r)):
        raise InvalidInputError(f"{name} contains NaN or infinity")
    return r


@dataclass(frozen=True)
class NoiseModel:
    """Stationary zero-mean Gaussian noise per axis: x_t = Σ_i φ_i x_{t−i} + u_t.

    ``sigma`` (axes,): marginal standard deviation (the noise floor, m or rad); ``ar``: per axis the
    AR coefficients φ (p,) (empty: white); ``dof`` (axes,): degrees of freedom of σ̂² (∞ when given);
    ``source``: "given", "periods", "repeats" or "differences"."""

    sigma: F64
    ar: tuple[F64, ...]
    dof: F64
    source: str

    @classmethod
    def white(cls, sigma: ArrayLike) -> NoiseModel:
        """Known white noise of standard deviation ``sigma`` per axis (e.g. Table 4.1)."""
        s = np.atleast_1d(np.asarray(sigma, dtype=np.float64))
        if s.ndim != 1 or not np.all(np.isfinite(s)) or np.any(s <= 0):
            raise InvalidInputError(f"noise floor must be positive and finite per axis; got {s}")
        return cls(s, tuple(np.zeros(0) for _ in s), np.full(s.shape, np.inf), "given")

    @property
    def axes(self) -> int:
        """Number of axes."""
        return int(self.sigma.shape[0])

    def acf(self, axis: int, nlags: int) -> F64:
        """Theoretical autocorrelation ρ_0..ρ_nlags of ``axis``."""
        return _acf(tuple(float(c) for c in self.ar[axis]), nlags).copy()

    def whiten(self, x: ArrayLike, axis: int) -> F64:
        """u_t = x_t − Σ φ_i x_{t−i} with ``axis``'s φ, scaled to unit variance under the model
        (x in the axis's units); the first p samples, which are not innovations, are dropped. ``x``
        (N,) or (N, m) (filtered along N)."""
        from scipy.signal import lfilter

        phi = self.ar[axis]
        a = np.asarray(x, dtype=np.float64)
        u = lfilter(np.r_[1.0, -phi], [1.0], a, axis=0)[len(phi) :]
        rho = self.acf(axis, len(phi))
        s_u = self.sigma[axis] * np.sqrt(max(1.0 - float(phi @ rho[1:]), 1e-12))
        return np.asarray(u / s_u, dtype=np.float64)

    def ess(self, axis: int, n: int) -> float:
        """Effective sample size of a mean square over ``n`` consecutive samples:
        n / (1 + 2 Σ_h (1 − h/n) ρ_h²) (Satterthwaite; n for white noise)."""
        if len(self.ar[axis]) == 0:
            return float(n)
        rho = self.acf(axis, min(n - 1, 400))[1:]
        h = np.arange(1, len(rho) + 1)
        return float(n / (1.0 + 2.0 * np.sum((1.0 - h / n) * rho**2)))

    def simulate(self, n: int, rng: np.random.Generator) -> F64:
        """One noise realisation (n, axes), started in the stationary state (a burn-in)."""
        from scipy.signal import lfilter

        out = np.empty((n, self.axes))
        for k in range(self.axes):
            phi = self.ar[k]
            burn = 0 if len(phi) == 0 else 200
            u = rng.standard_normal(n + burn)
            x = lfilter([1.0], np.r_[1.0, -phi], u)[burn:]
            out[:, k] = x * self.sigma[k] / np.sqrt(_ar_variance(phi))
        return out


@lru_cache(maxsize=4096)
def _acf(phi: tuple[float, ...], nlags: int) -> F64:
    """Autocorrelation ρ_0..ρ_nlags of AR(φ) (statsmodels ``arma_acf``), cached: the tests ask
    for the same model's ACF many times."""
    if len(phi) <= 1:  # white or AR(1): ρ_h = φ^h
        return np.asarray((phi[0] if phi else 0.0) ** np.arange(nlags + 1.0), dtype=np.float64)
    from statsmodels.tsa.arima_process import arma_acf

    return np.asarray(arma_acf(np.r_[1.0, -np.array(phi)], [1.0], lags=nlags + 1), dtype=np.float64)


def _ar_variance(phi: F64) -> float:
    """Marginal variance of an AR(p) process with unit innovation variance."""
    if len(phi) == 0:
        return 1.0
    from statsmodels.tsa.arima_process import arma_acf

    rho = arma_acf(np.r_[1.0, -phi], [1.0], lags=len(phi) + 1)
    return float(1.0 / max(1.0 - float(phi @ rho[1:]), 1e-12))


def fit_ar(x: F64, max_order: int) -> tuple[F64, float]:
    """Yule–Walker AR fit of order chosen by AIC (Levinson–Durbin, statsmodels): (φ, marginal
    variance about zero)."""
    from statsmodels.tsa.stattools import acovf

    return _ar_from_acov(acovf(x, nlag=_order(max_order), fft=False, demean=False), len(x))


def _order(max_order: int) -> int:
    """``max_order`` checked: an int ≥ 0 (0: white noise)."""
    return _checks.count(max_order, "max_order")


def _ar_from_acov(acov: F64, n: int) -> tuple[F64, float]:
    from statsmodels.tsa.stattools import levinson_durbin

    max_order = len(acov) - 1
    if acov[0] <= 0:
        raise InvalidInputError("a residual axis is identically zero: no noise to model")
    if max_order == 0:
        return np.zeros(0), float(acov[0])
    _, _, _, sig, phi = levinson_durbin(acov, nlags=max_order, isacov=True)
    var = np.r_[acov[0], np.asarray(sig)[1:]]
    aic = n * np.log(np.maximum(var, 1e-300)) + 2.0 * np.arange(max_order + 1)
    p = int(np.argmin(aic))
    coef = np.asarray(phi)[1 : p + 1, p].astype(np.float64) if p > 0 else np.zeros(0)
    return coef, float(acov[0])


def noise_from_repeats(residuals: Sequence[ArrayLike], *, max_order: int = 30) -> NoiseModel:
    """The noise model from K ≥ 2 repeats of the same run (same reference and camera timing):
    real repeats of an experiment, or noisy replays of the model in its closed loop (the fitted null
    model). Whatever repeats cancels in the deviations from the mean run, r_k − r̄, scaled by
    √(K/(K−1)) to the noise's variance; σ² is their mean square, the colour an AR(p ≤
    ``max_order``, AIC) fit to their pooled autocovariance; dof of σ̂² = (K−1)·ESS. Unbiased for
    noise that is stationary and independent between repeats; the residual under test should not
    be one of the repeats."""
    from statsmodels.tsa.stattools import acovf

    rs = [as_residual(r) for r in residuals]
    if len(rs) < 2 or any(r.shape != rs[0].shape for r in rs):
        raise InvalidInputError(
            f"noise from repeats needs >= 2 residuals of one shape; got {[r.shape for r in rs]}"
        )
    k_runs, (n, m) = len(rs), rs[0].shape
    max_order = _order(max_order)
    mean = np.mean(rs, axis=0)
    dev = [(r - mean) * np.sqrt(k_runs / (k_runs - 1)) for r in rs]
    sig = np.empty(m)
    ars: list[F64] = []
    for k in range(m):
        acov = np.mean([acovf(d[:, k], nlag=max_order, fft=False, demean=False) for d in dev], 0)
        phi, var = _ar_from_acov(acov, n * (k_runs - 1))
        sig[k] = np.sqrt(var)
        ars.append(phi)
    model = NoiseModel(sig, tuple(ars), np.full(m, np.inf), "repeats")
    dof = np.array([(k_runs - 1) * model.ess(k, n) for k in range(m)])
    return NoiseModel(sig, tuple(ars), dof, "repeats")


def noise_from_periods(residual: ArrayLike, period: int, *, max_order: int = 30) -> NoiseModel:
    """The noise model from differences of repeated periods: ``period`` frames P (the run must hold
    at least two periods). σ² = mean(d²)/2 over d_t = r_{t+P} − r_t; the colour is an AR(p ≤
    ``max_order``, AIC) fit to d; dof of σ̂² = ESS of d."""
    r = as_residual(residual)
    n = r.shape[0]
    if period < 1 or n < 2 * period:
        raise InvalidInputError(
            f"noise from periods needs at least two periods: {n} frames, period {period}"
        )
    d = r[period:] - r[:-period]
    sig = np.empty(r.shape[1])
    ars: list[F64] = []
    dof = np.empty(r.shape[1])
    for k in range(r.shape[1]):
        phi, var = fit_ar(d[:, k], max_order)
        sig[k] = np.sqrt(var / 2.0)
        ars.append(phi)
    model = NoiseModel(sig, tuple(ars), np.full(r.shape[1], np.inf), "periods")
    for k in range(r.shape[1]):
        dof[k] = model.ess(k, len(d))
    return NoiseModel(sig, tuple(ars), dof, "periods")


def noise_from_differences(residual: ArrayLike) -> NoiseModel:
    """The AR(1) noise model from first differences (method of moments; bias in the module doc).

    ρ = 1 + 2 ρ_d(1) (clipped to [−0.9, 0.98]), σ² = var(d)/(2(1 − ρ)); dof of σ̂² = 2/var(log σ̂²)
    by the delta method with Bartlett's variances of var(d) and ρ_d(1) under the fitted model."""
    r = as_residual(residual)
    n = r.shape[0]
    d = np.diff(r, axis=0)
    g0 = np.mean(d * d, axis=0)
    g1 = np.mean(d[1:] * d[:-1], axis=0)
    if np.any(g0 <= 0):
        raise InvalidInputError("a residual axis is constant: no noise to model")
    rho = np.clip(1.0 + 2.0 * g1 / g0, -0.9, 0.98)
    sig = np.sqrt(g0 / (2.0 * (1.0 - rho)))
    dof = np.array([_differences_dof(float(p), n - 1) for p in rho])
    return NoiseModel(sig, tuple(np.array([p]) for p in rho), dof, "differences")


def _differences_dof(rho: float, n: int) -> float:
    """Degrees of freedom of σ̂² from :func:`noise_from_differences` for AR(1) noise of lag-1
    correlation ``rho`` and ``n`` differences."""
    # ACF of d for AR(1): ρ_d(0) = 1, ρ_d(h) = −(1−ρ)/2 · ρ^(h−1), h ≥ 1.
    h = np.arange(1, 200)
    rd = np.r_[1.0, -(1.0 - rho) / 2.0 * rho ** (h - 1.0)]
    full = np.r_[rd[:0:-1], rd]  # lags −199..199
    var_log_g0 = 2.0 / n * float(np.sum(full**2))
    r1 = float(rd[1])
    k = np.arange(-198, 199)

    def at(j: NDArray[np.int64]) -> F64:
        return np.asarray(rd[np.minimum(np.abs(j), 199)], dtype=np.float64)

    bart = at(k) ** 2 + at(k + 1) * at(k - 1) + 2 * r1**2 * at(k) ** 2 - 4 * r1 * at(k) * at(k + 1)
    var_r1 = float(np.sum(bart)) / n
    var_log = var_log_g0 + var_r1 / r1**2
    return 2.0 / var_log
