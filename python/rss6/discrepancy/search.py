"""The numerical pieces of :func:`rss6.discrepancy.diagnose`: whitening of multi-channel residuals,
candidate signatures, the score test calibrated on noisy replays, fits of effect parameters by
simulation, and the held-out test of a fitted effect.

Noise: the closed loop colours the sensors' noise and couples the channels (the commands are the
visual PID's response to the camera's noise). Residuals are whitened channel by channel with an
AR model learnt from K noisy replays of the model (:func:`rss6.discrepancy.noise_from_repeats`);
what per-channel whitening misses (the coupling between channels, an imperfect AR fit) is absorbed
by calibrating every test statistic on the same replays: the score vector's covariance is
estimated from them (Hotelling's T², an F reference with K − q + 1 degrees of freedom), and a
held-out projection's variance likewise (a t reference with K degrees of freedom)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy.effects import Change, EffectDef
from rss6.discrepancy.noise import NoiseModel, noise_from_repeats
from rss6.errors import InvalidInputError

F64 = NDArray[np.float64]

__all__ = [
    "HAC_LAGS",
    "Calibration",
    "Fit",
    "Screen",
    "Whitener",
    "calibrate",
    "fit_effects",
    "heldout_test",
    "hotelling",
    "mimicry",
    "moved_by",
    "per_effect",
    "robust_se",
    "signature",
]


@dataclass(frozen=True)
class Whitener:
    """Channel-wise AR prewhitening to unit variance (the first p samples of each channel, which
    are not innovations, dropped) of (N, C) series into one vector."""

    noise: NoiseModel

    def vec(self, x: F64) -> F64:
        """(N, C) → (M,)."""
        return np.concatenate([self.noise.whiten(x[:, c], c) for c in range(x.shape[1])])

    def cols(self, j: F64) -> F64:
        """(N, C, q) → (M, q)."""
        return np.concatenate([self.noise.whiten(j[:, c, :], c) for c in range(j.shape[1])])


@dataclass(frozen=True)
class Calibration:
    """What the noisy replays of the null model give: the noise model (σ and AR colour per
    channel), the whitener, and the K whitened noise realisations (K, M) the tests are calibrated
    on."""

    noise: NoiseModel
    whitener: Whitener
    replicates: F64

    @property
    def k(self) -> int:
        """Number of replicates."""
        return int(self.replicates.shape[0])


def calibrate(noise: Sequence[F64], *, max_order: int = 20) -> Calibration:
    """The calibration from K noise realisations of the closed loop (each (N, C): noisy replays of
    the model minus its noise-free replay): noise model (repeats), whitened replicates for the
    tests."""
    if len(noise) < 4:
        raise InvalidInputError(f"need at least 4 noisy replays, got {len(noise)}")
    devs = [np.asarray(n, dtype=np.float64) for n in noise]
    model = noise_from_repeats(devs, max_order=max_order)
    w = Whitener(model)
    reps = np.array([w.vec(d) for d in devs])
    return Calibration(model, w, reps)


def hotelling(g: F64, g_reps: F64) -> tuple[float, float]:
    """(T², p) of the score vector ``g`` (q,) against K zero-mean replicates ``g_reps`` (K, q) of
    it under the null: T² = gᵀS⁻¹g with S = Σ g_k g_kᵀ/K; (K − q + 1)/(K q)·T² ~ F(q, K − q + 1)
    for Gaussian noise. Directions the replicates do not see (rank deficiency) are dropped."""
    from scipy.stats import f as f_dist

    k = g_reps.shape[0]
    s = g_reps.T @ g_reps / k
    u, sv, _ = np.linalg.svd(s)
    keep = sv > 1e-12 * max(float(sv[0]), 1e-300)
    q = int(keep.sum())
    if q == 0 or k - q + 1 <= 0:
        return 0.0, 1.0
    z = u[:, keep].T @ g
    t2 = float(np.sum(z * z / sv[keep]))
    stat = (k - q + 1) / (k * q) * t2
    return t2, float(f_dist.sf(stat, q, k - q + 1))


@dataclass(frozen=True)
class Screen:
    """A candidate's screening at the null: its whitened signature columns (M, q), the score
    statistic T² and p-value (Hotelling, calibrated on the replicates), the one-step estimate of
    its parameters (in the signature's coordinates) and its names."""

    effect: EffectDef
    scope: str
    columns: F64
    coords: tuple[str, ...]
    t2: float
    p_value: float
    step: F64


def signature(
    effect: EffectDef,
    scope: str,
    simulate: Callable[[Change], F64],
    clean: F64,
) -> tuple[F64, tuple[str, ...]]:
    """Raw signature columns (N, C, q) of ``effect`` on ``scope`` at the null model and their
    coordinate names: forward differences of the replay at each parameter's scale ("score"
    effects; the payload in mass and first moments m·x, m·y, m·z, which are linear at null), or the
    output changes over the effect's grid ("span" effects)."""
    cols: list[F64] = []
    names: list[str] = []
    if effect.screen == "span":
        p = effect.params[0]
        for v in effect.grid:
            cols.append(simulate(effect.apply({p.name: v}, scope)) - clean)
            names.append(f"{p.name}={v:g}")
        return np.stack(cols, axis=-1), tuple(names)
    if effect.name == "payload":
        m = effect.param("mass").scale * 4.0
        c = 0.05
        base = simulate(effect.apply({"mass": m}, scope))
        cols.append((base - clean) / m)
        names.append("mass")
        for ax in ("x", "y", "z"):
            out = simulate(effect.apply({"mass": m, ax: c}, scope))
            cols.append((out - base) / (m * c))
            names.append(f"mass·{ax}")
        return np.stack(cols, axis=-1), tuple(names)
    for p in effect.params:
        h = p.scale if p.bounds[1] > p.null else -p.scale
        cols.append((simulate(effect.apply({p.name: p.null + h}, scope)) - clean) / h)
        names.append(p.name)
    return np.stack(cols, axis=-1), tuple(names)


def screen(
    effect: EffectDef,
    scope: str,
    raw: F64,
    coords: tuple[str, ...],
    residual_w: F64,
    cal: Calibration,
) -> Screen:
    """The score test of one candidate: its whitened columns J, g = Jᵀr, T² against the
    replicates' Jᵀe_k. "span" candidates use the two leading directions of their grid's output
    changes (an orthonormal basis: the test is of that span)."""
    j = cal.whitener.cols(raw)
    if effect.screen == "span":
        u, sv, _ = np.linalg.svd(j, full_matrices=False)
        keep = min(2, int(np.sum(sv > 1e-9 * max(float(sv[0]), 1e-300))))
        j = u[:, :keep] * sv[:keep]
    g = j.T @ residual_w
    t2, p = hotelling(g, cal.replicates @ j)
    info = j.T @ j
    step = np.asarray(np.linalg.lstsq(info, g, rcond=None)[0], dtype=np.float64)
    return Screen(effect, scope, j, coords, t2, p, step)


@dataclass(frozen=True)
class Fit:
    """Fitted effect parameters: ``values`` per effect (list of dicts in the order of the
    effects fitted), their Wald standard errors, the whitened residual, its sum of squares, the
    whitened Jacobian at the optimum (M, n), whether the optimiser converged, its message, and
    which parameters (the Jacobian's columns) ended on a bound (within 10⁻³ of their scale)."""

    values: list[dict[str, float]]
    se: list[dict[str, float]]
    residual_w: F64
    cost: float
    jacobian: F64
    converged: bool
    message: str
    at_bound: NDArray[np.bool_] | None = None


def fit_effects(
    effects: Sequence[tuple[EffectDef, str]],
    starts: Sequence[dict[str, float]],
    measured: F64,
    simulate: Callable[[Change], F64],
    whitener: Whitener,
    *,
    max_nfev: int = 12,
    bounds: Callable[[EffectDef, str], dict[str, tuple[float, float]]] | None = None,
) -> Fit:
    """Least squares of the whitened residual over the parameters of ``effects`` jointly (bounded
    trust region, forward-difference Jacobian by simulation at each parameter's scale), from
    ``starts``, inside each parameter's bounds narrowed by ``bounds(effect, scope)`` (e.g. what
    keeps the model physical). Effects that are not smooth (backlash) are fitted the same way on their own
    parameter; the replay is deterministic, so the differences are of the model, not of noise."""
    from scipy.optimize import least_squares

    layout = [(e, s, p) for e, s in effects for p in e.params]
    x0 = np.array(
        [starts[i].get(p.name, p.null) for i, (e, s) in enumerate(effects) for p in e.params]
    )
    narrow = [bounds(e, s) if bounds is not None else {} for e, s in effects]
    lo = np.array(
        [
            max(p.bounds[0], narrow[i].get(p.name, p.bounds)[0])
            for i, (e, _) in enumerate(effects)
            for p in e.params
        ]
    )
    hi = np.array(
        [
            min(p.bounds[1], narrow[i].get(p.name, p.bounds)[1])
            for i, (e, _) in enumerate(effects)
            for p in e.params
        ]
    )
    scale = np.array([p.scale for _, _, p in layout])
    # Start strictly inside: scipy's trf scales steps by the distance to a bound, so a start on a
    # bound (e.g. a latency whose one-step estimate was negative, clipped to 0) never moves.
    span = np.where(np.isfinite(hi - lo), hi - lo, np.inf)
    margin = np.minimum(scale, 0.25 * span)
    x0 = np.clip(x0, lo + margin, hi - margin)

    def values(x: F64) -> list[dict[str, float]]:
        out: list[dict[str, float]] = []
        k = 0
        for e, _ in effects:
            out.append({p.name: float(x[k + i]) for i, p in enumerate(e.params)})
            k += len(e.params)
        return out

    def change(x: F64) -> Change:
        c = Change()
        for (e, s), v in zip(effects, values(x), strict=True):
            c = c.merged(e.apply(v, s))
        return c

    cache: dict[bytes, F64] = {}

    def res(x: F64) -> F64:
        key = np.asarray(x, dtype=np.float64).tobytes()
        if key not in cache:
            cache[key] = whitener.vec(measured - simulate(change(x)))
        return cache[key]

    def jac(x: F64) -> F64:
        r0 = res(x)
        cols = []
        for i in range(len(x)):
            h = scale[i] if x[i] + scale[i] <= hi[i] else -scale[i]
            xi = x.copy()
            xi[i] += h
            cols.append((res(xi) - r0) / h)
        return np.column_stack(cols)

    sol = least_squares(
        res, x0, jac=jac, bounds=(lo, hi), x_scale=scale, max_nfev=max_nfev, method="trf"
    )
    r = res(sol.x)
    jm = jac(sol.x)
    cov = np.linalg.pinv(jm.T @ jm)
    se_all = np.sqrt(np.maximum(np.diag(cov), 0.0))
    se: list[dict[str, float]] = []
    k = 0
    for e, _ in effects:
        se.append({p.name: float(se_all[k + i]) for i, p in enumerate(e.params)})
        k += len(e.params)
    tol = 1e-3 * scale
    at_bound = (sol.x <= lo + tol) | (sol.x >= hi - tol)
    return Fit(
        values(sol.x), se, r, float(r @ r), jm, bool(sol.success), str(sol.message), at_bound
    )


HAC_LAGS = 30
"""Bartlett lags (camera frames, 1 s) of :func:`robust_se`'s long-run covariance."""


def _sandwiches(fit: Fit, whitener: Whitener, n_frames: int, lags: int) -> tuple[F64, F64] | None:
    """:func:`robust_se`'s two sandwich covariances (stationary, local), or None if the residual's
    layout is not the whitener's."""
    j, r = fit.jacobian, fit.residual_w
    lens = [n_frames - len(whitener.noise.ar[c]) for c in range(whitener.noise.axes)]
    m = min(lens)
    if sum(lens) != len(r) or m < 2:
        return None
    jt = np.zeros((m, len(lens), j.shape[1]))
    rt = np.zeros((m, len(lens)))
    start = 0
    for c, n in enumerate(lens):
        seg = slice(start + n - m, start + n)
        jt[:, c, :] = j[seg]
        rt[:, c] = r[seg]
        start += n
    p = j.shape[1]

    def lagged(h: int) -> F64:
        """Σ_t J_tᵀ γ(h) J_{t−h}."""
        gamma = rt[h:].T @ rt[: m - h] / m
        return jt[h:].reshape(-1, p).T @ (gamma @ jt[: m - h]).reshape(-1, p)

    g = np.einsum("tcp,tc->tp", jt, rt)  # per-frame scores
    s = lagged(0)
    s_local = g.T @ g
    for h in range(1, min(lags, m - 1) + 1):
        w = 1.0 - h / (lags + 1.0)
        sh = lagged(h)
        s += w * (sh + sh.T)
        gh = g[h:].T @ g[: m - h]
        s_local += w * (gh + gh.T)
    a = np.linalg.pinv(j.T @ j)
    return a @ s @ a, a @ s_local @ a


def robust_se(
    fit: Fit, whitener: Whitener, n_frames: int, lags: int = HAC_LAGS, replicates: F64 | None = None
) -> list[dict[str, float]]:
    """Standard errors of ``fit`` that do not trust the noise model: the larger of two sandwiches
    (JᵀJ)⁻¹ S (JᵀJ)⁻¹ over ``lags`` frames with Bartlett's weights (channels aligned on their last
    common frames). *Stationary*: S = Σ_h w_h Σ_t J_tᵀ γ(h) J_{t−h}, γ(h) the whitened residual's
    autocovariance across channels. *Local*: Newey–West on the per-frame scores J_tᵀ r_t, which
    sees model error where it happens (a start transient) but, as the scores sum to zero at the
    optimum, cancels the variance of an effect seen in a window shorter than ``lags`` (median 0.55
    of Wald on white noise) — the stationary form does not. Both equal the Wald errors in
    expectation when the residual is the noise model's; larger when the residual holds slow model
    error the effect's signature overlaps (on the rapier plant an offset drift's rate was biased
    2–17 % low with Wald intervals a tenth of that). With ``replicates`` (the noisy replays'
    whitened noise, :func:`replicate_cov`) their errors too, if larger: in the stick–slip loop the
    sandwiches understate the spread between two noise draws ≈ 3× (docs/discrepancy.md).
    ``fit.se`` if neither layout is the fit's."""
    sw = _sandwiches(fit, whitener, n_frames, lags)
    rep = replicate_cov(fit, replicates)
    if sw is None and rep is None:
        return fit.se
    var = np.zeros(fit.jacobian.shape[1])
    if sw is not None:
        var = np.maximum(np.diag(sw[0]), np.diag(sw[1]))
    if rep is not None:
        var = np.maximum(var, np.diag(rep))
    return per_effect(np.sqrt(np.maximum(var, 0.0)), fit.se)


BOUND_OVERLAP = 0.5
"""Canonical correlation above which an effect's signature overlaps an earlier one's that ended on
a bound of its range (:func:`bound_overlap`): the new effect is then not named. On the rapier
plant a payload beside a 5× tilt clipped at 0.3 rad overlapped it by 0.6–0.7 at screening."""


def bound_overlap(
    fit: Fit, effects: Sequence[EffectDef], before: Sequence[bool] = ()
) -> list[tuple[int, float]]:
    """For each earlier effect of a joint ``fit`` of ``effects`` (all but the last) with a
    parameter on a bound other than its null value — in this fit, or before the last effect was
    added (``before``, one flag per earlier effect: the new effect can pull it off its bound) —:
    (its index, the largest canonical correlation between its whitened Jacobian columns and the
    last effect's — the cosine of the smallest angle between what the two can change)."""
    if fit.at_bound is None or fit.at_bound.shape != (fit.jacobian.shape[1],):
        return []
    cols, k = [], 0
    for e in effects:
        cols.append(list(range(k, k + len(e.params))))
        k += len(e.params)
    if k != fit.jacobian.shape[1] or not cols:
        return []

    def basis(c: list[int]) -> F64:
        u, sv, _ = np.linalg.svd(fit.jacobian[:, c], full_matrices=False)
        keep: F64 = u[:, sv > 1e-9 * max(float(sv[0]), 1e-300)] if len(sv) else u[:, :0]
        return keep

    last = basis(cols[-1])
    out = []
    for i, (e, c) in enumerate(zip(effects[:-1], cols[:-1], strict=True)):
        values = [fit.values[i][p.name] for p in e.params]
        if not (i < len(before) and before[i]) and not any(
            fit.at_bound[j] and abs(v - p.null) > 1e-3 * p.scale
            for j, v, p in zip(c, values, e.params, strict=True)
        ):
            continue
        sv = np.linalg.svd(basis(c).T @ last, compute_uv=False)
        out.append((i, float(sv[0]) if len(sv) else 0.0))
    return out


def wald_cov(fit: Fit) -> F64:
    """The Wald covariance of all of ``fit``'s parameters scaled by the misfit (reduced χ² when
    above 1)."""
    j = fit.jacobian
    dof = max(1, len(fit.residual_w) - j.shape[1])
    cov: F64 = np.linalg.pinv(j.T @ j) * max(1.0, fit.cost / dof)
    return cov


def replicate_cov(fit: Fit, replicates: F64 | None) -> F64 | None:
    """The fit's parameter covariance under the loop's own noise, linearised: the sample covariance
    of (JᵀJ)⁻¹Jᵀr_k over the K whitened noise realisations r_k of the noisy replays (None if their
    layout is not the fit's, or K < 2). It sees what one run's residual cannot: how the loop's
    noise moves the estimate. Free: the replays are already run for the score tests."""
    j = fit.jacobian
    if replicates is None or replicates.ndim != 2 or replicates.shape[1] != j.shape[0]:
        return None
    if replicates.shape[0] < 2:
        return None
    d = replicates @ j @ np.linalg.pinv(j.T @ j).T
    return np.atleast_2d(np.cov(d, rowvar=False, ddof=1))


def robust_cov(
    fit: Fit, whitener: Whitener, n_frames: int, lags: int = HAC_LAGS, replicates: F64 | None = None
) -> F64:
    """The covariance of all of ``fit``'s parameters that does not trust the noise model: of
    :func:`wald_cov`, :func:`robust_se`'s two sandwiches and :func:`replicate_cov` (with
    ``replicates``), the largest relative to the Wald one
    (trace of JᵀJ·C: free of the parameters' units) — the full matrix behind the errors of the
    intervals, whose correlations a test of several parameters needs."""
    return robust_cov_dof(fit, whitener, n_frames, lags, replicates)[0]


def robust_cov_dof(
    fit: Fit, whitener: Whitener, n_frames: int, lags: int = HAC_LAGS, replicates: F64 | None = None
) -> tuple[F64, float]:
    """:func:`robust_cov` and the degrees of freedom of its estimate: K − 1 when the covariance of
    the K replicates is the largest, ∞ otherwise (the misfit-scaled Wald covariance and the
    sandwiches rest on hundreds of frames and are taken as known)."""
    wald = wald_cov(fit)
    sw = _sandwiches(fit, whitener, n_frames, lags)
    rep = replicate_cov(fit, replicates)
    cands = [wald, *(sw or ()), *(() if rep is None else (rep,))]
    info = fit.jacobian.T @ fit.jacobian
    k = max(range(len(cands)), key=lambda i: float(np.trace(info @ cands[i])))
    if rep is None or replicates is None or k != len(cands) - 1:
        return np.asarray(cands[k], dtype=np.float64), np.inf
    return np.asarray(rep, dtype=np.float64), float(len(replicates) - 1)


def difference_test(
    d: F64, parts: Sequence[tuple[F64, float]], extra: F64 | None = None
) -> tuple[float, float]:
    """(T², p) that two estimates differing by ``d`` (q,) are of the same parameters: T² =
    dᵀ(C + extra)⁻¹d on the directions the covariance sees (its rank q). ``parts``: the two
    estimates' covariances (q, q) with the degrees of freedom of each (∞: known), C their sum;
    ``extra``: a known covariance of the difference (e.g. the model's own uncertainty). With
    every part known, T² is χ²(q). A part estimated from K replicates makes T² Hotelling's:
    (ν − q + 1)/(νq)·T² ~ F(q, ν − q + 1), ν from the parts by Krishnamoorthy and Yu's
    approximation (2004) — treating a 16-sample covariance as known rejected true effects."""
    from scipy.stats import chi2, f

    c = np.zeros((len(d), len(d)))
    for cov, _ in parts:
        if cov.shape != c.shape:
            raise InvalidInputError(f"covariance {cov.shape} for a difference of {len(d)}")
        c = c + cov
    if extra is not None:
        if extra.shape != c.shape:
            raise InvalidInputError(f"covariance {extra.shape} for a difference of {len(d)}")
        c = c + extra
    u, sv, _ = np.linalg.svd(0.5 * (c + c.T))
    keep = sv > 1e-12 * max(float(sv[0]), 1e-300) if len(sv) else sv > 0
    q = int(keep.sum())
    if q == 0:
        return 0.0, 1.0
    uk = u[:, keep]
    z = uk.T @ d
    t2 = float(np.sum(z * z / sv[keep]))
    # Krishnamoorthy–Yu: ν = (q + q²) / Σ_i [tr((C_i C⁻¹)²) + tr(C_i C⁻¹)²] / ν_i.
    inv = uk @ np.diag(1.0 / sv[keep]) @ uk.T
    den = 0.0
    for cov, nu in parts:
        if np.isfinite(nu):
            a = cov @ inv
            den += (float(np.trace(a @ a)) + float(np.trace(a)) ** 2) / max(nu, 1.0)
    if den <= 0.0:
        return t2, float(chi2.sf(t2, q))
    nu = max((q + q * q) / den, float(q))
    return t2, float(f.sf(t2 * (nu - q + 1) / (nu * q), q, nu - q + 1))


def per_effect(flat: F64, like: Sequence[dict[str, float]]) -> list[dict[str, float]]:
    """``flat`` (one value per fitted parameter, in the fit's order) as one dict per effect with
    the names and layout of ``like`` (e.g. :attr:`Fit.se`)."""
    out: list[dict[str, float]] = []
    k = 0
    for d in like:
        out.append({name: float(flat[k + i]) for i, name in enumerate(d)})
        k += len(d)
    return out


def heldout_test(delta_w: F64, residual_w: F64, replicates: F64) -> tuple[float, float]:
    """(z, one-sided p) that the held-out residual contains the change ``delta_w`` a fitted effect
    predicts there (both whitened, (M,)): s = ⟨δ, r⟩, its null variance from the held-out run's
    replicates (K, M), p from Student's t with K degrees of freedom."""
    from scipy.stats import t as t_dist

    s = float(delta_w @ residual_w)
    reps = replicates @ delta_w
    v = float(np.mean(reps * reps))
    if v <= 0:
        return 0.0, 1.0
    z = s / np.sqrt(v)
    return z, float(t_dist.sf(z, replicates.shape[0]))


def mimicry(screens: Sequence[Screen]) -> F64:
    """How well each candidate's signature *as the data shows it* can be produced by another:
    ρ_ab = ‖P_b d_a‖/‖d_a‖ with d_a = J_a δ̂_a (the one-step fitted direction of a) and P_b the
    projector on b's columns; the matrix holds min(ρ_ab, ρ_ba) — two candidates are confounded
    when each can mimic the other's fit. For one-parameter candidates this is |ρ| of their Fisher
    information."""
    n = len(screens)
    dirs = []
    spans = []
    for s in screens:
        d = s.columns @ s.step
        nd = float(np.linalg.norm(d))
        dirs.append(d / nd if nd > 0 else d)
        spans.append(np.linalg.qr(s.columns)[0])
    rho = np.eye(n)
    for a in range(n):
        for b in range(a + 1, n):
            ab = float(np.linalg.norm(spans[b].T @ dirs[a]))
            ba = float(np.linalg.norm(spans[a].T @ dirs[b]))
            rho[a, b] = rho[b, a] = min(ab, ba)
    return rho


def moved_by(a: Fit, b: Fit) -> float:
    """The largest change of a parameter from fit ``a`` to fit ``b``, in ``b``'s standard errors."""
    out = 0.0
    for va, vb, sb in zip(a.values, b.values, b.se, strict=True):
        for key, x in vb.items():
            se = sb.get(key, 0.0)
            d = abs(x - va[key])
            out = max(out, d / se if se > 0 else (0.0 if d == 0 else np.inf))
    return out
