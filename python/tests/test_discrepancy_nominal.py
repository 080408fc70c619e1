"""The nominal quantities (the model's friction and drive gains) refitted inside the model's own
uncertainty before the discrepancy search and after each named effect
(:mod:`rss6.discrepancy.nominal`)."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
import pytest
import rss6
from rss6 import discrepancy, identify
from rss6.discrepancy.nominal import (
    NOMINAL_NAMES,
    NominalFit,
    nominal_difference,
    nominal_variance,
    refit_nominal,
    spreads,
)
from rss6.discrepancy.search import difference_test
from rss6.errors import InvalidInputError
from twin_case import collect as _collect
from twin_case import held_out_costs as _held_out_costs
from twin_case import model as _model
from twin_case import robot as _robot


def _values(m: Any) -> np.ndarray:
    return np.concatenate(
        [np.asarray(m.dynamics.coulomb), np.asarray(m.dynamics.viscous), np.asarray(m.pid)]
    )


def test_spreads_read_groups_and_names_and_refuse_nonsense() -> None:
    w = spreads({"coulomb": 0.1, "fc3": 0.3, "gains": 0.05})
    assert w[NOMINAL_NAMES.index("fc1")] == 0.1 and w[NOMINAL_NAMES.index("fc3")] == 0.3
    assert np.all(w[6:12] == 0.0) and np.all(w[12:] == 0.05)
    assert not spreads(None).any() and not spreads({}).any()
    with pytest.raises(InvalidInputError, match="unknown nominal quantity 'mass'"):
        spreads({"mass": 0.1})
    with pytest.raises(InvalidInputError, match=r"must be in \[0, 1\)"):
        spreads({"viscous": 1.5})
    with pytest.raises(InvalidInputError, match=r"must be in \[0, 1\)"):
        spreads({"lp": float("nan")})


def test_the_spreads_follow_an_identifications_sigma() -> None:
    from types import SimpleNamespace

    result = SimpleNamespace(identified=("platform.m", "fc1", "lp"), relative_std=[0.01, 0.02, 0.3])
    w = discrepancy.nominal_from(result)
    assert w["fc1"] == pytest.approx(0.06) and w["lp"] == 0.5  # 3σ, capped at 0.5
    assert w["fc2"] == 0.1 and w["fv1"] == 0.25 and w["ld"] == 0.05  # not identified: defaults
    assert set(w) == set(NOMINAL_NAMES) and spreads(w)[0] == pytest.approx(0.06)
    with pytest.raises(InvalidInputError, match="2 relative σ"):
        discrepancy.nominal_from(SimpleNamespace(identified=("fc1",), relative_std=[0.1, 0.2]))


def test_the_command_line_reads_the_spreads() -> None:
    from rss6.discrepancy.cli import nominal_of

    assert nominal_of(None) == discrepancy.NOMINAL_SPREAD
    assert nominal_of("none") is None and nominal_of(" None ") is None
    assert nominal_of("fc2=0.2,gains=0.1") == {"fc2": 0.2, "gains": 0.1}
    with pytest.raises(InvalidInputError, match="not name=value"):
        nominal_of("fc2")


def test_the_refit_recovers_an_error_inside_its_box_and_stops_on_the_box(truth: Any) -> None:
    """A residual linear in the quantities (no replay): a target inside the box is reached, one
    outside ends on the box and is flagged, a held quantity does not move and one the data do not
    see stays at the model's value (the prior; without it fc3–fc5 wandered to their box's edges
    on a real run)."""
    model = _model(truth, _robot(truth, 0, None))
    v0 = _values(model)
    target = v0 * (1 + np.array([0.05, -0.08, 0.3, 0, 0.05, 0, 0.2, 0, 0, 0, 0, -0.4, 0.03, 0, 0]))
    # Orthogonal columns scaled to the values (a held or clipped quantity cannot leak into others),
    # informative far beyond the prior — except fc5's, which the data do not see.
    q = np.linalg.qr(np.random.default_rng(0).standard_normal((60, 15)))[0]
    a = q * (1e5 / v0)
    a[:, 4] = 0.0

    def residual(m: Any) -> np.ndarray:
        return np.asarray(a @ (_values(m) - target))

    w = spreads({"coulomb": 0.1, "viscous": 0.25, "gains": 0.05})
    nf = refit_nominal(model, model, w, residual, lambda jobs: [j() for j in jobs], held=[1])
    v = _values(nf.model)
    assert nf.n_free == 14 and nf.converged
    # Inside the box: reached to 1e-8 relative (the prior's pull) in one Gauss–Newton step.
    for i in (0, 6, 12):
        assert v[i] == pytest.approx(target[i], rel=3e-8), NOMINAL_NAMES[i]
    assert v[2] == pytest.approx(v0[2] * 1.1, rel=1e-6) and nf.at_bound[2]  # beyond: on the box
    assert v[11] == pytest.approx(v0[11] * 0.75, rel=1e-6) and nf.at_bound[11]
    assert v[1] == v0[1] and not nf.at_bound[1]  # held
    assert v[4] == pytest.approx(v0[4], rel=1e-9)  # unseen: the prior keeps it at the model's value
    assert not nf.at_bound[[0, 4, 6, 12]].any()
    # The cost left is the held and clipped quantities' (measured within 3e-15 relative).
    best = target.copy()
    best[1], best[2], best[4], best[11] = v0[1], v0[2] * 1.1, v0[4], v0[11] * 0.75
    r = a @ (best - target)
    assert nf.cost_after == pytest.approx(float(r @ r), rel=1e-12)
    assert "fc3 +10 % (on its box)" in nf.summary() and "fc2" not in nf.summary()


def test_a_refit_whose_steps_run_out_says_so(truth: Any) -> None:
    """A residual the linear model does not predict (cubic in fc1): one step does not settle it,
    and the refit does not count itself converged; with more steps it does."""
    model = _model(truth, _robot(truth, 0, None))
    v0 = _values(model)

    def residual(m: Any) -> np.ndarray:
        u = (_values(m)[0] - 1.08 * v0[0]) / (0.01 * v0[0])
        return np.array([u + 0.5 * u**3])

    w = spreads({"fc1": 0.1})
    one = refit_nominal(model, model, w, residual, lambda jobs: [j() for j in jobs], iterations=1)
    assert not one.converged and one.cost_after < one.cost_before
    many = refit_nominal(model, model, w, residual, lambda jobs: [j() for j in jobs], iterations=8)
    assert many.converged and many.cost_after < one.cost_after


def test_the_models_uncertainty_widens_what_it_can_mimic(truth: Any) -> None:
    """An effect fitted on the model as given inherits the nominal quantities' error as a bias.
    Checked by simulation on a linear toy y = J_e θ + J_n δ + e, δ drawn from the prior, θ fitted
    with the nominal quantities held: the estimate moved by the joint fit's one step has the
    variance Wald + :func:`nominal_variance`'s shared part (ratio within ±10 % for 4000 draws:
    sampling error ≈ 2.2 %; measured 0.97 and 1.01), and the interval of the uncorrected estimate
    with the step's square added holds θ in ≥ 95 % of draws (measured 96.3 and 95.1 %; the bound,
    0.95 − 3 × 0.34 % sampling error, 0.94). A column the nominal quantities produce exactly
    carries the prior's variance; one orthogonal to them gains nothing."""
    rng = np.random.default_rng(3)
    model = _model(truth, _robot(truth, 0, None))
    m_rows = 80
    jn = rng.standard_normal((m_rows, 15)) * 0.3
    sig = np.zeros(15)
    sig[[0, 6, 7, 13]] = [0.5, 1.0, 0.2, 2.0]  # the others held (σ 0: no uncertainty)
    jn[:, sig == 0] = 0.0
    je = np.column_stack(
        [jn[:, 6] * 2.0 + 0.3 * rng.standard_normal(m_rows), rng.standard_normal(m_rows)]
    )
    # The library's convention: Jacobians of the residual y − model.
    nf = NominalFit(model, np.zeros(15), np.zeros(15, bool), 1.0, 1.0, True, 4, -jn, sig)
    wald = np.diag(np.linalg.inv(je.T @ je))
    theta = np.array([0.3, -0.2])
    corrected, covered = [], []
    for _ in range(4000):
        y = je @ theta + jn @ (rng.standard_normal(15) * sig) + rng.standard_normal(m_rows)
        est = np.linalg.lstsq(je, y, rcond=None)[0]
        r = y - je @ est
        shared = nominal_variance(-je, nf)
        total = nominal_variance(-je, nf, r)
        step = np.sqrt(np.maximum(total - shared, 0.0))
        # The step's sign: the joint fit's direction, from the shared part's own solve.
        info = np.block(
            [[je.T @ je, je.T @ jn[:, sig > 0]], [jn[:, sig > 0].T @ je, np.zeros((4, 4))]]
        )
        info[2:, 2:] = jn[:, sig > 0].T @ jn[:, sig > 0] + np.diag(1 / sig[sig > 0] ** 2)
        move = (np.linalg.solve(info, np.concatenate([je.T @ r, jn[:, sig > 0].T @ r])))[:2]
        assert np.allclose(np.abs(move), step, rtol=1e-6, atol=1e-12)
        corrected.append(est + move - theta)
        covered.append(np.abs(est - theta) <= 1.96 * np.sqrt(wald + total))
    ratio = np.var(np.array(corrected), axis=0) / (wald + shared)
    assert np.all(np.abs(ratio - 1) < 0.1), ratio
    assert np.all(np.mean(covered, axis=0) >= 0.94), np.mean(covered, axis=0)
    # The column the nominal quantities mimic: their prior more than doubles its variance (2.3×).
    assert shared[0] > 1.5 * wald[0] and shared[1] < 0.1 * wald[1]
    # Nominal columns orthogonal to each other: a column equal to one of them carries that one's
    # prior variance exactly; one orthogonal to them all gains nothing.
    q = np.linalg.qr(rng.standard_normal((m_rows, 16)))[0]
    nf_q = NominalFit(model, np.zeros(15), np.zeros(15, bool), 1.0, 1.0, True, 4, q[:, :15], sig)
    assert nominal_variance(3.0 * q[:, 6:7], nf_q)[0] == pytest.approx(1.0 / 9.0, rel=1e-6)
    assert nominal_variance(q[:, 15:], nf_q)[0] == pytest.approx(0.0, abs=1e-12)
    # No refit, or a Jacobian of another run: nothing added.
    assert not nominal_variance(je, None).any()
    assert not nominal_variance(je[:10], nf).any()


def test_the_consistency_test_allows_for_what_the_model_does_to_each_excitation(
    truth: Any,
) -> None:
    """The held-out consistency test compares an effect's estimates on two excitations, both
    fitted on the model as given; an error of the nominal quantities biases them differently.
    Linear toy, δ drawn from the prior, 2000 draws per case, α = 1 %, the difference tested against
    the two estimates' covariances (:func:`difference_test`): with :func:`nominal_difference`
    added a true effect is refused in ≤ 2 % of draws (measured 0.65 %; 3 × the 0.2 % sampling
    error above α), without it in ≥ 10 % (measured 18.5 %: the failure seen on the plant). A
    parameter that differs between the runs in a direction the nominal quantities cannot mimic is
    still refused in ≥ 71 % of draws (measured 74.3 %, 85.2 % without; the bound 3 sampling errors
    below). Two runs that see the model alike carry nothing."""
    rng = np.random.default_rng(5)
    model = _model(truth, _robot(truth, 0, None))
    m_rows = 120
    sig = np.zeros(15)
    sig[[0, 6, 7, 13]] = [0.5, 1.0, 0.2, 2.0]
    jnf, jnh = (rng.standard_normal((m_rows, 15)) * 0.3 * (sig > 0) for _ in range(2))
    noise = 0.3 * rng.standard_normal((2, m_rows))
    jf = np.column_stack([jnf[:, 6] * 2 + noise[0], rng.standard_normal(m_rows)])
    jh = np.column_stack([jnh[:, 13] * 0.5 + jnh[:, 6] + noise[1], rng.standard_normal(m_rows)])
    # The library's convention: Jacobians of the residual y − model.
    nf = NominalFit(model, np.zeros(15), np.zeros(15, bool), 1.0, 1.0, True, 4, -jnf, sig)
    theta = np.array([0.3, -0.2])

    def refused(shift: np.ndarray) -> tuple[float, float]:
        out = np.zeros(2)
        cov = np.linalg.inv(jf.T @ jf) + np.linalg.inv(jh.T @ jh)  # unit white noise
        for _ in range(2000):
            d = rng.standard_normal(15) * sig
            yf = jf @ theta + jnf @ d + rng.standard_normal(m_rows)
            yh = jh @ (theta + shift) + jnh @ d + rng.standard_normal(m_rows)
            est = np.linalg.lstsq(jf, yf, rcond=None)[0]
            diff = est - np.linalg.lstsq(jh, yh, rcond=None)[0]
            model = nominal_difference(-jf, yf - jf @ est, -jh, -jnh, nf)
            out += [
                difference_test(diff, [(cov, np.inf)], model)[1] < 0.01,
                difference_test(diff, [(cov, np.inf)])[1] < 0.01,
            ]
        return out[0] / 2000, out[1] / 2000

    with_model, exact = refused(np.zeros(2))
    assert with_model <= 0.02 and exact >= 0.10, (with_model, exact)
    assert refused(np.array([0.0, 0.5]))[0] >= 0.71
    assert not nominal_difference(-jf, noise[0], -jf, -jnf, nf).any()
    assert not nominal_difference(-jf, noise[0], -jh, None, nf).any()
    with pytest.raises(InvalidInputError, match="for a difference of 2"):
        difference_test(np.zeros(2), [(np.eye(2), np.inf)], np.zeros((3, 3)))


def test_an_interval_without_the_models_uncertainty_says_so(
    truth: Any, excitation: identify.Excitation, monkeypatch: pytest.MonkeyPatch
) -> None:
    """When the nominal refit cannot run, a named effect's interval cannot hold the model's own
    uncertainty: the report must say it is conditional on the model, not pass it off as the
    usual one."""
    import importlib

    dg = importlib.import_module("rss6.discrepancy.diagnose")

    def failing(model: Any, *args: Any) -> Any:
        return model, None, None, "nominal quantities not refitted: (test)", None

    monkeypatch.setattr(dg, "refit_step", failing)
    hidden = {"camera_latency": {"latency": 0.02}}
    fit, val = _robot(truth, 11, hidden), _robot(truth, 12, hidden)
    rep = discrepancy.diagnose(
        _collect(fit, excitation),
        _model(truth, fit),
        validation=_collect(val, excitation),
        candidates=["camera_latency", "pid_gains"],
    )
    assert [e.name for e in rep.named] == ["camera_latency"], rep.table()
    assert not any(rep.named[0].nominal_se.values())  # nothing from the model: 0
    assert any("its interval is conditional on the model as given" in n for n in rep.notes)


def _refit_notes(notes: list[str]) -> list[str]:
    return [n for n in notes if n.startswith("nominal refit")]


def test_a_latency_is_named_when_the_models_friction_is_a_few_percent_off(
    truth: Any, excitation: identify.Excitation
) -> None:
    """The model is never exact: Coulomb friction 3 % and viscous 8 % off per joint (what CLOE
    leaves) move the potentiometers enough that, with the model held, joint friction ranked first
    on every scope though it hardly moves the pose: 9 candidates were refused (held-out gap shrunk
    < 2 % of the floor) before the hidden 10 ms latency was named (until 2026-11-28 the search
    stopped after 3 and said "unexplained"). With the nominal refit inside the model's uncertainty
    the latency is named first (0 refusals). The refit takes the viscous error per joint from
    3.5 % RMS to 1.3 % (Coulomb, which this run hardly sees, stays near the model by the prior).
    Re-identification (CLOE, poses alone) is run, its loop's latency taken from the measured
    frames, and not kept: the held-out potentiometers disagree (whitened cost 3484 → 144 348)."""
    rng = np.random.default_rng(1)
    hidden = {"camera_latency": {"latency": 0.01}}
    fit, val = _robot(truth, 11, hidden), _robot(truth, 12, hidden)
    model = _model(truth, fit)
    d = model.dynamics.to_dict()
    d["coulomb"] = np.asarray(d["coulomb"]) * (1 + 0.03 * rng.standard_normal(6))
    d["viscous"] = np.asarray(d["viscous"]) * (1 + 0.08 * rng.standard_normal(6))
    model = model.with_dynamics(rss6.DynamicParams.from_dict(d), model.pid)
    rep = discrepancy.diagnose(
        _collect(fit, excitation), model, validation=_collect(val, excitation), reidentify=True
    )
    assert rep.verdict == "named: camera_latency (sensor)", rep.table()
    assert not any(" not named" in n for n in rep.notes), rep.notes
    lo, hi = rep.named[0].ci["latency"]
    assert lo <= 0.01 <= hi, rep.named[0]
    first = _refit_notes(rep.notes)[0]
    assert "not kept" not in first, first
    costs = re.search(r"fitting cost ([0-9.e+-]+) → ([0-9.e+-]+)", first)
    assert costs is not None and float(costs.group(2)) < 0.8 * float(costs.group(1)), first

    def viscous_error(m: Any) -> float:
        e = np.asarray(m.dynamics.viscous) / np.asarray(truth[0].viscous) - 1
        return float(np.sqrt(np.mean(e * e)))

    assert viscous_error(rep.model) < 0.6 * viscous_error(model)
    rel = np.asarray(rep.model.dynamics.viscous) / np.asarray(model.dynamics.viscous) - 1
    assert np.all(np.abs(rel) <= discrepancy.NOMINAL_SPREAD["viscous"] + 1e-9)
    note = next(n for n in rep.notes if n.startswith("re-identified"))
    assert "the loop's latency 10 ms, the first frame's time" in note, note
    c_named, c_after = _held_out_costs(note)
    assert c_after > c_named and "not kept" in note, note
