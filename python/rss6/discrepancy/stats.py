"""Statistics of the discrepancy workflow: pure functions on arrays (docs/discrepancy.md).

Every test is one-sided where only one side means "the model misses something" and returns a
p-value valid under a stated noise model (:class:`~rss6.discrepancy.noise.NoiseModel`):

* :func:`energy_test` — residual energy vs the noise floor, Satterthwaite effective sample size for
  the colour; an F test when σ was estimated (its dof), a χ² test when it was given.
* :func:`window_test` — the same on consecutive windows (which time windows disagree), Bonferroni
  over the windows.
* :func:`ljung_box` — whiteness of the prewhitened residual (the statsmodels formula, vectorised).
* :func:`xcorr_test` — cross-correlation with a signature after prewhitening both with the noise
  model's AR filter: the prewhitened residual is white under H0, so ±z/√n bands hold whatever the
  signature's colour (Box–Jenkins); max over lags, Bonferroni over the lags.
* :func:`holm` (statsmodels), :func:`bootstrap_pvalue` (parametric bootstrap, +1 correction).
* :func:`score_test`, :func:`fisher_correlation`, :func:`ambiguous_groups`, :func:`separation`:
  candidates at their null value from the residual Jacobian.
* :func:`fisher_ci`, :func:`profile_ci`: confidence intervals; :func:`spectral_peak`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6.discrepancy.noise import NoiseModel
from rss6.errors import InvalidInputError, ShapeError

__all__ = [
    "ScoreTest",
    "ambiguous_groups",
    "bootstrap_pvalue",
    "energy_test",
    "fisher_ci",
    "fisher_correlation",
    "holm",
    "ljung_box",
    "profile_ci",
    "score_test",
    "separation",
    "spectral_peak",
    "window_test",
    "xcorr_test",
]

F64 = NDArray[np.float64]


def _energy_p(ratio: F64 | float, nu: F64 | float, dof: float) -> F64:
    """P(mean square / σ² ≥ ratio) for a mean square of effective sample size ``nu`` and σ² known
    (``dof`` = ∞: χ²_ν/ν) or estimated with ``dof`` degrees of freedom (F(ν, dof))."""
    from scipy import special

    if np.isinf(dof):
        return np.asarray(special.chdtrc(nu, np.multiply(nu, ratio)), dtype=np.float64)
    return np.asarray(special.fdtrc(nu, dof, ratio), dtype=np.float64)


def energy_test(r: ArrayLike, noise: NoiseModel, axis: int) -> tuple[float, float]:
    """(mean(r²)/σ², p) for one axis's residual ``r`` (N,): is the energy above the noise floor?

    Under H0 mean(r²)/σ² ≈ χ²_ν/ν with ν the effective sample size (:meth:`NoiseModel.ess`,
    Satterthwaite); with an estimated σ (dof ν₂ < ∞) the ratio is F(ν, ν₂). A residual mean counts
    as energy."""
    x = np.asarray(r, dtype=np.float64)
    ratio = float(np.mean(x * x) / noise.sigma[axis] ** 2)
    p = _energy_p(ratio, noise.ess(axis, len(x)), float(noise.dof[axis]))
    return ratio, float(p)


def window_test(
    r: ArrayLike, noise: NoiseModel, axis: int, width: int
) -> tuple[float, F64, NDArray[np.int64]]:
    """Running χ² on consecutive windows of ``width`` frames (the last one takes the remainder):
    the mean square of the prewhitened residual (:meth:`NoiseModel.whiten`, unit variance under
    H0) per window is χ²_W/W exactly for a right noise model (F(W, dof) for an estimated σ) — an
    energy ratio with a Satterthwaite ESS has too light a tail for windows of a few effective
    samples.

    Returns (p for the axis = min(1, n_windows · min p_w), p per window, window start indices
    into ``r``)."""
    u = noise.whiten(r, axis)
    skip = len(noise.ar[axis])
    n = len(u)
    width = max(8, min(width, n))
    starts = np.arange(0, max(n - width, 0) + 1, width)
    ends = np.r_[starts[1:], n]
    c = np.r_[0.0, np.cumsum(u * u)]
    length = (ends - starts).astype(np.float64)
    ratio = (c[ends] - c[starts]) / length
    p = _energy_p(ratio, length, float(noise.dof[axis]))
    return float(min(1.0, len(p) * float(p.min()))), p, (starts + skip).astype(np.int64)


def ljung_box(u: ArrayLike, lags: int, model_df: int = 0) -> tuple[F64, F64]:
    """Ljung–Box Q = n(n+2) Σ_{k≤h} r_k²/(n−k) of each column of ``u`` (n, m) and its p-value
    against χ²_{h − model_df}: the formula of statsmodels' ``acorr_ljungbox``, vectorised."""
    from scipy.stats import chi2

    x = np.asarray(u, dtype=np.float64)
    x = x[:, None] if x.ndim == 1 else x
    n = x.shape[0]
    xc = x - x.mean(axis=0)
    den = np.sum(xc * xc, axis=0)
    k = np.arange(1, lags + 1)
    r = np.array([np.sum(xc[j:] * xc[:-j], axis=0) / den for j in k])
    q = n * (n + 2) * np.sum(r**2 / (n - k)[:, None], axis=0)
    return q, np.asarray(chi2.sf(q, lags - model_df), dtype=np.float64)


def xcorr(u: F64, v: F64, max_lag: int) -> F64:
    """Correlation of u_t with v_{t−ℓ} for ℓ = −max_lag..max_lag (both (n,), means removed; each
    lag normalised by the overall norms, so a white u gives se 1/√n at every lag)."""
    a = u - u.mean()
    b = v - v.mean()
    na, nb = float(np.sqrt(a @ a)), float(np.sqrt(b @ b))
    out = np.zeros(2 * max_lag + 1)
    if na == 0 or nb == 0:
        return out
    for i, lag in enumerate(range(-max_lag, max_lag + 1)):
        out[i] = (a[lag:] @ b[: len(b) - lag]) if lag >= 0 else (a[:lag] @ b[-lag:])
    return out / (na * nb)


def _bartlett_factor(u: F64, v: F64, lags: int) -> F64:
    """Bartlett's variance factor 1 + 2 Σ_{k≤lags} ρ_e(k) ρ_v(k) (floored at 1) per column of v:
    what colour the prewhitening left in both, e = u minus its least-squares fit on the column
    (so a signature present in u does not inflate its own band)."""
    uc = u - u.mean()
    vc = v - v.mean(axis=0)
    beta = (vc.T @ uc) / np.maximum(np.sum(vc * vc, axis=0), 1e-300)
    e = uc[:, None] - vc * beta
    n = len(u)

    def acf(x: F64) -> F64:
        den = np.maximum(np.sum(x * x, axis=0), 1e-300)
        return np.array([np.sum(x[k:] * x[: n - k], axis=0) / den for k in range(1, lags + 1)])

    if lags < 1:
        return np.ones(v.shape[1])
    return np.asarray(np.maximum(1.0, 1.0 + 2.0 * np.sum(acf(e) * acf(vc), axis=0)))


def xcorr_test(
    r: ArrayLike,
    signature: ArrayLike,
    noise: NoiseModel,
    axis: int,
    max_lag: int,
    bartlett_lags: int = 10,
) -> tuple[F64, NDArray[np.int64], F64, F64]:
    """Does residual ``r`` (N,) follow each column of ``signature`` (N,) or (N, S)? Both are
    prewhitened with ``axis``'s AR filter, whose imperfections (an estimated colour) are covered by
    Bartlett's formula over ``bartlett_lags``; returns per column (z at the best lag, that lag in
    frames (> 0: the residual lags the signature), p = min(1, (2L+1)·2Φ(−|z|max)), and the
    correlations (S, 2L+1) at lags −L..L)."""
    from scipy.special import ndtr

    sig = np.asarray(signature, dtype=np.float64)
    sig = sig[:, None] if sig.ndim == 1 else sig
    # A signature constant to rounding (e.g. the model's gravity term along a trajectory) carries
    # nothing; its rounding noise must not be correlated with the residual.
    flat = np.ptp(sig, axis=0) <= 1e-9 * np.max(np.abs(sig), axis=0)
    u = noise.whiten(r, axis)
    v = noise.whiten(np.where(flat, 0.0, sig), axis)
    c = np.array([xcorr(u, v[:, j], max_lag) for j in range(v.shape[1])])
    z = c * np.sqrt(len(u)) / np.sqrt(_bartlett_factor(u, v, bartlett_lags))[:, None]
    best = np.argmax(np.abs(z), axis=1)
    zb = z[np.arange(len(z)), best]
    p = np.minimum(1.0, (2 * max_lag + 1) * 2.0 * ndtr(-np.abs(zb)))
    return zb, (best - max_lag).astype(np.int64), p, c


def holm(pvalues: ArrayLike, alpha: float) -> tuple[NDArray[np.bool_], F64]:
    """Holm's step-down correction: (rejected, adjusted p). Equal to statsmodels'
    ``multipletests(method="holm")`` (checked by the tests), written out because that function
    runs ``gc.collect()`` on every call (0.1 s here, 400 times the arithmetic)."""
    p = np.asarray(pvalues, dtype=np.float64).ravel()
    m = p.size
    order = np.argsort(p, kind="stable")
    adj_sorted = np.minimum(1.0, np.maximum.accumulate((m - np.arange(m)) * p[order]))
    adj = np.empty(m)
    adj[order] = adj_sorted
    return adj <= alpha, adj


def bootstrap_pvalue(
    observed: float,
    simulate_null: Callable[[np.random.Generator], F64],
    statistic: Callable[[F64], float],
    *,
    n: int = 199,
    seed: int = 0,
) -> tuple[float, F64]:
    """Parametric-bootstrap p-value of a statistic whose large values speak against H0:
    (1 + #{T* ≥ T_obs}) / (n + 1) over ``n`` residuals ``simulate_null(rng)`` drawn under the
    fitted null model (exact size for any n: Davison & Hinkley §4.2). Returns (p, the T*)."""
    if n < 1:
        raise InvalidInputError(f"bootstrap needs n >= 1 replicates; got {n}")
    rng = np.random.default_rng(seed)
    null = np.array([float(statistic(simulate_null(rng))) for _ in range(n)])
    return float((1 + np.sum(null >= observed)) / (n + 1)), null


@dataclass(frozen=True)
class ScoreTest:
    """Rao's score (LM) test of a candidate at its null value: ``statistic`` ~ χ²_``dof`` under H0,
    ``p_value``; ``estimate`` the one-step (Gauss–Newton from the null) parameter values and ``se``
    their standard errors (inverse Fisher information)."""

    statistic: float
    dof: int
    p_value: float
    estimate: F64
    se: F64


def _weighted(
    residual: ArrayLike, columns: ArrayLike, sigma: ArrayLike | None, nuisance: ArrayLike | None
) -> tuple[F64, F64]:
    """Whitened residual and candidate columns with the nuisance columns projected out."""
    r = np.asarray(residual, dtype=np.float64).ravel()
    j = np.asarray(columns, dtype=np.float64)
    j = j.reshape(len(r), -1)
    w = np.ones_like(r) if sigma is None else 1.0 / np.asarray(sigma, dtype=np.float64).ravel()
    if w.shape != r.shape:
        raise ShapeError(f"sigma must match the residual ({r.shape}); got {w.shape}")
    rw, jw = r * w, j * w[:, None]
    if nuisance is not None:
        nw = np.asarray(nuisance, dtype=np.float64).reshape(len(r), -1) * w[:, None]
        q, _ = np.linalg.qr(nw)
        jw = jw - q @ (q.T @ jw)
        rw = rw - q @ (q.T @ rw)
    return rw, jw


def score_test(
    residual: ArrayLike,
    columns: ArrayLike,
    *,
    sigma: ArrayLike | None = None,
    nuisance: ArrayLike | None = None,
) -> ScoreTest:
    """Score test that the candidate parameters δ are 0, from the residual r = y − f(θ̂₀) (M,) at
    the null fit and the candidate's Jacobian columns ∂f/∂δ (M, q).

    ``sigma`` (M,): the noise standard deviation of each residual element (the weights are 1/σ²;
    prewhiten coloured noise first); ``nuisance`` (M, n): Jacobian of the refitted nominal
    parameters, projected out (a candidate the nominal fit can mimic scores nothing).
    LM = rᵀWJ (JᵀWJ)⁻¹ JᵀWr ~ χ²_q."""
    from scipy.stats import chi2

    rw, jw = _weighted(residual, columns, sigma, nuisance)
    info = jw.T @ jw
    g = jw.T @ rw
    cov = np.linalg.pinv(info)
    lm = float(g @ cov @ g)
    q = int(np.linalg.matrix_rank(info))
    return ScoreTest(
        lm, q, float(chi2.sf(lm, max(q, 1))), cov @ g, np.sqrt(np.maximum(np.diag(cov), 0.0))
    )


def fisher_correlation(
    candidates: Mapping[str, ArrayLike],
    *,
    sigma: ArrayLike | None = None,
    nuisance: ArrayLike | None = None,
) -> tuple[list[str], F64]:
    """Pairwise correlation of candidates in the Fisher information (nuisance projected out): for
    single columns ρ = I_ab/√(I_aa I_bb); for several columns the largest canonical correlation
    of the two column spaces (≥ 0). Returns (names, matrix)."""
    names = list(candidates)
    if not names:
        return [], np.zeros((0, 0))
    zero = np.zeros(np.asarray(candidates[names[0]]).shape[0])
    cols = [_weighted(zero, np.asarray(candidates[k]), sigma, nuisance)[1] for k in names]
    c = np.eye(len(names))
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            a, b = cols[i], cols[j]
            if a.shape[1] == 1 and b.shape[1] == 1:
                den = float(np.linalg.norm(a) * np.linalg.norm(b))
                rho = float(a[:, 0] @ b[:, 0]) / den if den > 0 else 0.0
            else:
                qa, _ = np.linalg.qr(a)
                qb, _ = np.linalg.qr(b)
                rho = float(np.linalg.svd(qa.T @ qb, compute_uv=False)[0])
            c[i, j] = c[j, i] = rho
    return names, c


def ambiguous_groups(
    names: Sequence[str], corr: ArrayLike, among: Sequence[str], threshold: float = 0.9
) -> list[tuple[str, ...]]:
    """Groups of the candidates ``among`` (e.g. those that passed) linked by |ρ| > ``threshold``
    (connected components); singletons are left out."""
    c = np.abs(np.asarray(corr, dtype=np.float64))
    idx = [list(names).index(a) for a in among]
    seen: set[int] = set()
    groups: list[tuple[str, ...]] = []
    for i in idx:
        if i in seen:
            continue
        comp, stack = {i}, [i]
        while stack:
            a = stack.pop()
            for b in idx:
                if b not in comp and c[a, b] > threshold:
                    comp.add(b)
                    stack.append(b)
        seen |= comp
        if len(comp) > 1:
            groups.append(tuple(names[k] for k in sorted(comp)))
    return groups


def separation(
    a: ArrayLike, b: ArrayLike, *, sigma: ArrayLike | None = None, nuisance: ArrayLike | None = None
) -> F64:
    """Where two single-column candidates differ: the part of b's whitened, unit-norm column that a's
    cannot mimic, per residual element (M,). Its largest entries name the samples (times, axes) an
    excitation must weigh more to separate them."""
    m = np.asarray(a).size
    zero = np.zeros(m)
    _, ja = _weighted(zero, np.asarray(a), sigma, nuisance)
    _, jb = _weighted(zero, np.asarray(b), sigma, nuisance)
    ua = ja[:, 0] / np.linalg.norm(ja[:, 0])
    ub = jb[:, 0] / np.linalg.norm(jb[:, 0])
    return np.asarray(ub - (ua @ ub) * ua, dtype=np.float64)


def fisher_ci(
    estimate: ArrayLike,
    jacobian: ArrayLike,
    *,
    sigma: ArrayLike | None = None,
    level: float = 0.95,
    scale: float = 1.0,
) -> tuple[F64, F64, F64]:
    """Wald intervals from the Fisher information JᵀWJ (J (M, q), weights 1/σ²): (low, high, se).
    ``scale``: the fit statistic χ²/dof, applied when > 1 so a misfit widens the intervals."""
    from scipy.stats import norm

    x = np.asarray(estimate, dtype=np.float64).ravel()
    _, jw = _weighted(np.zeros(np.asarray(jacobian).shape[0]), jacobian, sigma, None)
    cov = np.linalg.pinv(jw.T @ jw) * max(1.0, scale)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    z = float(norm.ppf(0.5 + level / 2))
    return x - z * se, x + z * se, se


def profile_ci(
    profile: Callable[[float], float], estimate: float, se: float, *, level: float = 0.95
) -> tuple[float, float]:
    """Profile-likelihood interval of one parameter: ``profile(v)`` is −2 log L (for Gaussian noise
    the weighted sum of squares) minimised over the other parameters with this one held at v; the
    interval is where it rises by χ²₁(level) above its value at ``estimate``. ``se`` (e.g. Fisher's)
    sets the first bracket, doubled until the rise is reached (≤ 20 times)."""
    from scipy.optimize import brentq
    from scipy.stats import chi2

    base = profile(estimate)
    target = float(chi2.ppf(level, 1))

    def rise(v: float) -> float:
        return profile(v) - base - target

    ends = []
    for sign in (-1.0, 1.0):
        step = max(abs(se), 1e-12)
        for _ in range(20):
            if rise(estimate + sign * step) > 0:
                break
            step *= 2.0
        else:
            ends.append(sign * np.inf)
            continue
        lo, hi = sorted((estimate, estimate + sign * step))
        ends.append(float(brentq(rise, lo, hi, xtol=1e-10 * max(1.0, abs(step)))))
    return ends[0], ends[1]


def spectral_peak(r: ArrayLike, rate: float) -> float:
    """Frequency (Hz) of the largest Welch periodogram peak of ``r`` (N,) sampled at ``rate``
    (Hz); the zero-frequency bin is skipped."""
    from scipy.signal import welch

    x = np.asarray(r, dtype=np.float64)
    f, pxx = welch(x - x.mean(), fs=rate, nperseg=min(len(x), 512))
    return float(f[1 + int(np.argmax(pxx[1:]))])
