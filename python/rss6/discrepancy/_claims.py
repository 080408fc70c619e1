"""The workflow's claims on the held-out run beyond its predicted change (workflow step 8): the
consistency of an effect's parameters between the two runs, an effect that would take up what an
earlier one's bound stops, and the backward check of the effects named."""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial
from math import inf

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy._steps import _def, _Part, _physical, error_replicates
from rss6.discrepancy.effects import Change, EffectDef
from rss6.discrepancy.model import AppliedEffect, Model, replay
from rss6.discrepancy.nominal import NominalFit, nominal_difference
from rss6.discrepancy.report import NamedEffect
from rss6.discrepancy.search import (
    BOUND_OVERLAP,
    Calibration,
    Fit,
    Screen,
    bound_overlap,
    difference_test,
    fit_effects,
    heldout_test,
    robust_cov_dof,
    wald_cov,
)
from rss6.errors import Rss6Error

F64 = NDArray[np.float64]


def _consistency(
    base_model: Model,
    held: _Part,
    hcal: Calibration,
    prev: Sequence[AppliedEffect],
    s: Screen,
    best: Fit,
    res_at_fit: F64,
    res_before: F64,
    nf: NominalFit | None = None,
    jn_held: F64 | None = None,
    v_fit: tuple[F64, float] | None = None,
) -> tuple[float, float, float, str, Fit | None]:
    """Refits the effects on the held-out run from the fitting run's values and tests that the two
    runs' estimates are of the same parameters: T² of their difference against the sum of their
    covariances as the intervals state them (:func:`~rss6.discrepancy.search.robust_cov_dof` —
    ``v_fit`` the fitting run's with its degrees of freedom, the held-out fit's computed here;
    Hotelling's T² where one is the replicates' — the misfit-scaled Wald or a sandwich,
    whichever is larger: on the rapier plant the residual is 1.4–4× the noise and slow, and a test
    that knew only the noise refused true effects at T² 50–500; without ``v_fit`` the Wald
    covariance scaled by the misfit). Also the *transfer*: the share of the held-out run's own
    cost reduction (from ``res_before``, its whitened residual without the new effect, to its
    refit) that the fitting run's parameters reach (``res_at_fit``) — 1 when they are as good as
    its own, below 0 when they make it worse. (p, p with the model taken as exact, transfer, text
    of the two estimates, the held-out fit or None).

    With the refit ``nf`` and J_n on the held-out run ``jn_held``, the difference of the two
    estimates also carries the model's own uncertainty (:func:`~rss6.discrepancy.nominal.
    nominal_difference`): an error of the nominal quantities biases the two excitations'
    estimates differently, and a test that knows only the noise refuses a true effect for it."""
    effs = [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)]

    def simulate_h(c: Change) -> F64:
        return held.baseline(replay(base_model, held.run, c))[held.rows]

    try:
        hfit = fit_effects(
            effs,
            best.values,
            held.measured,
            simulate_h,
            hcal.whitener,
            bounds=partial(_physical, base_model),
        )
    except Rss6Error as err:
        return 1.0, 1.0, float("-inf"), f"held-out refit failed ({type(err).__name__}: {err})", None
    # A parameter on a bound in either fit has a nonzero score at a constrained optimum: the test
    # is on the free ones (a benchmark effect scaled to its bound was otherwise rejected as a mimic
    # with the truth's values on both runs, e.g. Coulomb 5 vs 4.998 N·m).
    free = np.ones(hfit.jacobian.shape[1], dtype=bool)
    for f in (best, hfit):
        if f.at_bound is not None and f.at_bound.shape == free.shape:
            free &= ~f.at_bound
    names = [p.name for p in s.effect.params]
    text = ", ".join(f"{n} {best.values[-1][n]:.4g} vs {hfit.values[-1][n]:.4g}" for n in names)
    c0, c1 = float(res_before @ res_before), float(res_at_fit @ res_at_fit)
    transfer = (c0 - c1) / (c0 - hfit.cost) if c0 > hfit.cost else float("-inf")
    text += f"; transfer {transfer:.3f}"
    if not free.any():
        return 1.0, 1.0, transfer, text + "; every parameter on a bound: not tested", hfit
    j = hfit.jacobian[:, free]
    d = (np.array(_flat(best.values)) - np.array(_flat(hfit.values)))[free]
    reps = error_replicates(held, base_model)
    v_h, dof_h = robust_cov_dof(hfit, hcal.whitener, len(held.t), replicates=reps)
    vf, dof_f = (
        v_fit if v_fit is not None and v_fit[0].shape == v_h.shape else (wald_cov(best), inf)
    )
    sub = np.ix_(free, free)
    parts = [(vf[sub], dof_f), (v_h[sub], dof_h)]
    model_cov = np.zeros_like(parts[0][0])
    if best.jacobian.shape[1] == free.size:
        model_cov = nominal_difference(best.jacobian[:, free], best.residual_w, j, jn_held, nf)
    t2, p = difference_test(d, parts, model_cov)
    t2_exact, p_exact = difference_test(d, parts)
    text += f"; T² {t2:.3g} on {j.shape[1]} parameters"
    if model_cov.any():
        text += f" ({t2_exact:.3g} with the model taken as exact)"
    elif nf is not None and jn_held is None:
        text += " (the model's own uncertainty not in it: no sensitivity on the held-out run)"
    if not free.all():
        text += f" ({int((~free).sum())} on a bound left out)"
    return p, p_exact, transfer, text, hfit


def _flat(values: Sequence[dict[str, float]]) -> list[float]:
    """A fit's values in its Jacobian's column order."""
    return [v for d in values for v in d.values()]


def bound_note(
    best: Fit, defs: Sequence[EffectDef], prev: Sequence[AppliedEffect], s: Screen
) -> str | None:
    """Why the new effect of the joint fit ``best`` (of ``defs``: ``prev`` and then ``s``) is not
    named, or None: an earlier effect ended on a bound of its library range (before the new effect
    was added, or in the joint fit: the new effect can pull it off) — the data want more of it
    than the library allows — and the new effect's signature overlaps it beyond
    :data:`~rss6.discrepancy.search.BOUND_OVERLAP`, so it would take up the shortfall (a payload
    beside a 5× tilt clipped at 0.3 rad, on the plant)."""
    before = [
        any(
            abs(a.params.get(p.name, p.null) - b) <= 1e-3 * p.scale
            for p in e.params
            for b in p.bounds
            if b != p.null
        )
        for a, e in zip(prev, defs[:-1], strict=False)
    ]
    over = [(i, c) for i, c in bound_overlap(best, defs, before) if c > BOUND_OVERLAP]
    if not over:
        return None
    a, c = prev[over[0][0]], over[0][1]
    return (
        f"{s.effect.name} ({s.scope}) not named: {a.name} ({a.scope}) ended on a bound of its "
        f"range and this effect's signature overlaps it (canonical correlation {c:.2f} > "
        f"{BOUND_OVERLAP:g}) — it would take up what that bound stops"
    )


def backward_check(
    base_model: Model,
    named_effects: list[AppliedEffect],
    named: list[NamedEffect],
    held: _Part,
    hcal: Calibration,
    current_held: F64,
    alpha: float,
) -> tuple[list[AppliedEffect], list[NamedEffect], F64, list[str]]:
    """Backward check on the held-out run: an effect named early may only have mimicked part of
    one named later; drops any whose own contribution the held-out run no longer shows (held-out
    test at ``alpha``). (effects, named, held-out replay, notes of those dropped)."""
    dropped: list[str] = []
    n0 = len(base_model.applied())
    for a in list(named_effects[n0:]) if len(named_effects) - n0 >= 2 else []:
        others = [b for b in named_effects if b is not a]
        without = held.baseline(replay(base_model.with_effects(others), held.run))
        delta = hcal.whitener.vec((current_held - without)[held.rows])
        hres = hcal.whitener.vec(held.measured - without[held.rows])
        _, p_drop = heldout_test(delta, hres, hcal.replicates)
        if p_drop > alpha:
            named_effects = others
            current_held = without
            named = [ne for ne in named if (ne.name, ne.scope) != (a.name, a.scope)]
            dropped.append(f"{a.name} ({a.scope}): held-out p = {p_drop:.3g} beside the others")
    return named_effects, named, current_held, dropped
