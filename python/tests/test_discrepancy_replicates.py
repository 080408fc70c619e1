"""The estimator's spread from the noisy replays (`search.replicate_cov`): the errors of the fitted
effects and the held-out consistency test take the larger of it and the sandwiches."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

F64 = NDArray[np.float64]

N_FRAMES = 450
_K = np.arange(N_FRAMES)
# Two runs see one parameter through different signatures on two channels (stacked channel-major,
# the whitener's layout).
J_FIT = np.concatenate([np.sin(2 * np.pi * _K / 150), 0.5 * np.cos(2 * np.pi * _K / 110)])[:, None]
J_HELD = np.concatenate([0.7 * np.cos(2 * np.pi * _K / 90), np.sin(2 * np.pi * _K / 200)])[:, None]


def _noise(rng: np.random.Generator, rho: float, m: int) -> F64:
    """``m`` draws of unit-variance AR(1) noise with ``rho`` on both channels, stacked (m, 2N)."""
    u = rng.standard_normal((m, N_FRAMES + 400, 2))
    e = lfilter([1.0], [1.0, -rho], u, axis=1)[:, 400:] * np.sqrt(1.0 - rho**2)
    return np.asarray(np.concatenate([e[..., 0], e[..., 1]], axis=1), dtype=np.float64)


def _fit(j: F64, y: F64):  # type: ignore[no-untyped-def]
    from rss6.discrepancy.search import Fit

    b = float(j[:, 0] @ y / (j[:, 0] @ j[:, 0]))
    r = y - j[:, 0] * b
    return b, Fit([{"a": b}], [{"a": 0.0}], r, float(r @ r), j, True, "")


def test_replicates_give_the_estimators_spread() -> None:
    # The variance of the least-squares estimate over 4000 independent draws of slow AR(1) noise
    # (ρ = 0.95) against replicate_cov from 400 other draws: ratios 0.92–1.12 over five seeds
    # (sampling error of a variance from 400 draws ≈ 7 %); bound ±0.25, ≈ 2× the worst.
    from rss6.discrepancy.search import replicate_cov

    for seed in range(3):
        rng = np.random.default_rng(10 + seed)
        draws = _noise(rng, 0.95, 4000)
        spread = float(np.var(draws @ J_FIT[:, 0] / (J_FIT[:, 0] @ J_FIT[:, 0])))
        _, fit = _fit(J_FIT, draws[0])
        cov = replicate_cov(fit, _noise(rng, 0.95, 400))
        assert cov is not None and cov.shape == (1, 1)
        assert abs(float(cov[0, 0]) / spread - 1.0) < 0.25, (cov, spread)
        # A layout that is not the fit's (another run's frames) or a single replicate: no estimate.
        assert replicate_cov(fit, _noise(rng, 0.95, 8)[:, :-2]) is None
        assert replicate_cov(fit, _noise(rng, 0.95, 1)) is None
        assert replicate_cov(fit, None) is None


def test_the_consistency_test_with_replicates_keeps_its_size() -> None:
    """Two runs with equal parameters and AR(1) residuals (ρ = 0.9), 400 draws, α = 1 %, K = 16
    replicates per run as the benchmark uses. Measured: Wald refuses 54.8 %, the sandwiches 3.0 %,
    with the replicates too 0.0 % (Hotelling's F where the replicates' covariance is the larger,
    in 67 % of the runs; 0.5 % against χ²) (bound 2 %: the level and two sampling errors); against
    a real difference of 0.8, 58.8 % and 39.0 % (43.5 % against χ²: the max of a 16-draw estimate
    costs power; bound ≥ 30 %). The errors with replicates are never below the sandwiches'."""
    from rss6.discrepancy.noise import NoiseModel
    from rss6.discrepancy.search import Whitener, difference_test, robust_cov_dof, robust_se

    whitener = Whitener(NoiseModel.white([1.0, 1.0]))

    def refused(shift: float) -> float:
        rng = np.random.default_rng(3)
        count = 0
        for _ in range(400):
            bf, ff = _fit(J_FIT, J_FIT[:, 0] + _noise(rng, 0.9, 1)[0])
            bh, fh = _fit(J_HELD, J_HELD[:, 0] * (1.0 + shift) + _noise(rng, 0.9, 1)[0])
            rf, rh = _noise(rng, 0.9, 16), _noise(rng, 0.9, 16)
            parts = [
                robust_cov_dof(ff, whitener, N_FRAMES, replicates=rf),
                robust_cov_dof(fh, whitener, N_FRAMES, replicates=rh),
            ]
            count += difference_test(np.array([bf - bh]), parts)[1] < 0.01
            plain = robust_se(ff, whitener, N_FRAMES)[0]["a"]
            assert robust_se(ff, whitener, N_FRAMES, replicates=rf)[0]["a"] >= plain
        return count / 400

    assert refused(0.0) <= 0.02
    assert refused(0.8) >= 0.30


def test_the_replays_spread_enters_the_errors_only_where_the_loop_is_non_smooth() -> None:
    """Stick–slip friction in the model, or noisy replays whose mean leaves the clean replay (the
    part's bias): the replicates; a smooth loop: none (the sandwiches alone)."""
    from types import SimpleNamespace
    from typing import Any

    from rss6.discrepancy._steps import _Part, error_replicates

    reps = np.ones((4, 10))
    cal: Any = SimpleNamespace(replicates=reps)
    smooth: Any = SimpleNamespace(implicit_friction=False)
    stick_slip: Any = SimpleNamespace(implicit_friction=True)
    run: Any = None
    part = _Part(run, slice(0, 10), cal)
    assert error_replicates(part, smooth) is None
    assert error_replicates(part, stick_slip) is reps
    part.bias = np.zeros(10)
    assert error_replicates(part, smooth) is reps
    assert error_replicates(_Part(run, slice(0, 10)), stick_slip) is None


def test_a_covariance_from_replicates_is_tested_as_estimated() -> None:
    """Two runs' estimates of equal parameters, each with its covariance from 16 replicates (the
    benchmark's K): T² against χ² treats those as known and refuses too often, Hotelling's F with
    Krishnamoorthy–Yu's degrees of freedom keeps the level. Measured on 20 000 draws at α = 1 %:
    χ² 2.1 % and 3.7 % for 2 and 4 parameters, Hotelling 0.88 % and 0.96 %. Here 6000 draws:
    Hotelling within [0.5, 1.6] % (the level ± 3 sampling errors), χ² above 1.6 % for 2
    parameters and 2.5 % for 4."""
    from rss6.discrepancy.search import difference_test

    rng = np.random.default_rng(5)
    for q, chi_low in ((2, 0.016), (4, 0.025)):
        a = rng.standard_normal((q, q))
        chol = np.linalg.cholesky(a @ a.T + q * np.eye(q))
        hot = chi = 0
        n = 6000
        for _ in range(n):
            d = chol @ rng.standard_normal(q) - chol @ rng.standard_normal(q)
            sf = np.cov((chol @ rng.standard_normal((q, 16))).T, rowvar=False)
            sh = np.cov((chol @ rng.standard_normal((q, 16))).T, rowvar=False)
            hot += difference_test(d, [(sf, 15.0), (sh, 15.0)])[1] < 0.01
            chi += difference_test(d, [(sf + sh, np.inf)])[1] < 0.01
        assert 0.005 <= hot / n <= 0.016, (q, hot / n)
        assert chi / n > chi_low, (q, chi / n)
