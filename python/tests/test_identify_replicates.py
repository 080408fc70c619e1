"""σ of CLOE's estimates from noisy replicate runs of the identified model
(``rss6.identify_replicates``; docs/identification.md, "σ from noisy replicates")."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
import rss6
from rss6 import _rss6, identify
from rss6.identify_replicates import bootstrap_deviations, model_output, weighted_residual

T_F = 5e-3
LAW = {"derivative_filter": T_F, "implicit_friction": True}
SUBSET = ["li", "ld"] + [f"fc{i}" for i in range(1, 7)] + [f"fv{i}" for i in range(1, 7)]


def _data(seed: int = 3) -> identify.IdentificationData:
    """The twin (Table 5.2 truth, stick–slip, camera and potentiometer noise) on a 2 s excitation."""
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    robot = rss6.ModelSim(
        kp, dp, pid=pid, seed=seed, drive_derivative_filter=T_F, implicit_friction=True
    )
    exc = identify.random_excitation(kp, harmonics=3, f0=0.5, seed=1, amplitude=(0.01, 0.05))
    tr = robot.truth()
    data = identify.collect(
        robot,
        exc,
        kp_model=kp,
        sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
    )
    assert data.fault is None
    return data


@pytest.fixture(scope="module")
def fitted() -> tuple[identify.IdentificationResult, identify.IdentificationData]:
    data = _data()
    kp = rss6.KinematicParams.nominal()
    dp, pid = identify.table_5_2_truth()
    res = identify.cloe(
        data, kp, dp, pid, parameters=SUBSET, commands="recorded", pot_noise="recorded", **LAW
    )
    return res, data


def test_the_linear_map_is_cloes_own(
    fitted: tuple[identify.IdentificationResult, identify.IdentificationData],
) -> None:
    """The map and the Python replay reproduce CLOE: the residual's χ² to rounding, and a change of
    the model moves the mapped residual by minus that change."""
    res, data = fitted
    assert res.linear_map is not None
    lmap, w = res.linear_map
    assert lmap.shape == (len(res.identified), 6 * data.frames)
    # The whitening of Table 4.1's per-axis weights: diag(1/σ).
    assert w.shape == (6, 6) and np.count_nonzero(w - np.diag(np.diag(w))) == 0
    np.testing.assert_allclose(np.diag(w)[:3], 1 / 0.0096e-3)
    np.testing.assert_allclose(np.diag(w)[3:], 1 / np.deg2rad(0.0261))
    r0 = weighted_residual(res, data, model_output(res, data))
    dof = len(r0) - len(res.identified)
    assert float(r0 @ r0) / dof == pytest.approx(res.reduced_chi2, rel=1e-9)
    # A permuted layout would not do this: the model with log(l_i) moved by ε changes the residual
    # by −G ε e_li, which the map returns as ≈ −ε on l_i and ≈ 0 elsewhere.
    names = identify.parameter_names()
    for name, eps in (("li", 0.01), ("fc2", 0.01)):
        psi, _, _ = _rss6.cloe_psi(res.dynamics, res.pid)
        psi[names.index(name)] += eps
        _, dp, pid = _rss6.cloe_psi(res.dynamics, res.pid, list(psi))
        moved = dataclasses.replace(res, dynamics=dp, pid=pid)
        d = lmap @ (weighted_residual(res, data, model_output(moved, data)) - r0)
        j = res.identified.index(name)
        # Measured: −0.9966 ε and −1.0044 ε; the others at most 0.042 ε and 0.002 ε (bounds ≈ 3×).
        assert d[j] == pytest.approx(-eps, rel=0.015), (name, d[j])
        assert np.max(np.abs(np.delete(d, j))) < 0.13 * eps, (name, d)


def test_replicates_widen_the_sigma_and_refuse_what_they_cannot_use(
    fitted: tuple[identify.IdentificationResult, identify.IdentificationData],
) -> None:
    res, data = fitted
    d = identify.replicate_deviations(res, data, n=4)
    assert d.shape == (4, len(res.identified)) and np.all(np.isfinite(d))
    wide = identify.with_replicates(res, data, n=4)
    np.testing.assert_allclose(wide.relative_std_replicates, d.std(axis=0, ddof=1))
    assert np.all(wide.relative_std >= res.relative_std)
    assert np.all(wide.relative_std >= wide.relative_std_replicates)
    with pytest.raises(rss6.InvalidInputError, match="n must be >= 2"):
        identify.replicate_deviations(res, data, n=1)
    short = identify.IdentificationData.from_arrays(
        data.t[:-5], data.reference, data.measured[:-5], duration=data.duration
    )
    with pytest.raises(rss6.InvalidInputError, match="linear map is for"):
        identify.replicate_deviations(res, short, n=2)


def test_the_bootstrap_refits_each_replicate_and_marks_the_failures(
    fitted: tuple[identify.IdentificationResult, identify.IdentificationData],
) -> None:
    """With ``refit`` each replicate is identified again; a fit that raises leaves a NaN row, and
    a quantity estimated by fewer than half the replicates gets an infinite spread."""
    res, data = fitted
    kp = rss6.KinematicParams.nominal()
    calls: list[int] = []

    def refit(d: identify.IdentificationData) -> identify.IdentificationResult:
        calls.append(d.frames)
        if len(calls) == 2:
            raise rss6.IdentificationError("did not converge (test)")
        return identify.cloe(
            d, kp, res.dynamics, res.pid, parameters=SUBSET, commands="recorded",
            pot_noise="recorded", **LAW,
        )  # fmt: skip

    d = bootstrap_deviations(res, data, refit, n=3)
    assert len(calls) == 3 and np.all(np.isnan(d[1])) and np.all(np.isfinite(d[[0, 2]]))
    # Refits on the twin at the estimate land near it: within a few of CLOE's σ.
    assert np.all(np.abs(d[[0, 2]]) < 5 * res.relative_std), (d, res.relative_std)
    calls.clear()

    def failing(d: identify.IdentificationData) -> Any:
        calls.append(d.frames)
        if len(calls) > 1:
            raise rss6.IdentificationError("did not converge (test)")
        return identify.cloe(
            d, kp, res.dynamics, res.pid, parameters=SUBSET, commands="recorded",
            pot_noise="recorded", **LAW,
        )  # fmt: skip

    wide = identify.with_replicates(res, data, n=3, refit=failing)
    assert np.all(np.isinf(wide.relative_std_replicates)) and np.all(np.isinf(wide.relative_std))
    assert set(wide.poorly_identified) == set(res.identified)


def test_a_failed_replicate_leaves_cloes_sigma_and_the_report_says_so(
    tmp_path: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``rss6 identify --simulate``: CLOE converged, the replicates could not run — the run goes on
    with CLOE's σ and the report's status line names why (not an abort, not a silent σ)."""
    from rss6 import identify_sim

    def fail(*args: Any, **kw: Any) -> Any:
        raise rss6.IdentificationError("replicate 3: the visual PID faulted at t = 1.000 s")

    monkeypatch.setattr(identify, "with_replicates", fail)
    report = identify_sim.run(tmp_path, quick=True, plant="model", variation=False)
    assert report.converged and report.relative_std
    assert "σ from CLOE alone: the noisy replicates failed (replicate 3" in report.text()


def test_correct_bias_moves_each_estimate_by_minus_its_replicates_mean(
    fitted: tuple[identify.IdentificationResult, identify.IdentificationData],
) -> None:
    """``with_replicates(correct_bias=True)``: the replicates' truth is the estimate, so their mean
    deviation is the procedure's bias there; each identified log-quantity moves by minus it, its σ
    widens by that mean's standard error, and the RMS after is the moved model's."""
    res, data = fitted
    d = identify.replicate_deviations(res, data, n=4)
    plain = identify.with_replicates(res, data, n=4)
    moved = identify.with_replicates(res, data, n=4, correct_bias=True)
    np.testing.assert_allclose(moved.replicate_bias, d.mean(axis=0), rtol=1e-12)
    names = identify.parameter_names()
    before = np.exp(np.asarray(_rss6.cloe_psi(res.dynamics, res.pid)[0]))
    after = np.exp(np.asarray(_rss6.cloe_psi(moved.dynamics, moved.pid)[0]))
    cols = [names.index(q) for q in res.identified]
    np.testing.assert_allclose(after[cols], before[cols] * np.exp(-d.mean(axis=0)), rtol=1e-9)
    others = [j for j in range(len(names)) if j not in cols]
    np.testing.assert_allclose(after[others], before[others], rtol=1e-12)
    se = d.std(axis=0, ddof=1) / 2.0
    np.testing.assert_allclose(moved.relative_std, np.hypot(plain.relative_std, se), rtol=1e-12)
    rms = np.sqrt(np.mean((data.measured - model_output(moved, data)) ** 2, axis=0))
    np.testing.assert_allclose(moved.rms_after, rms, rtol=1e-12)
    assert not np.allclose(moved.rms_after, res.rms_after, rtol=1e-9, atol=0.0)
    assert len(plain.replicate_bias) == 0  # only when asked
