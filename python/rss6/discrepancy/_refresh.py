"""The loop's bias refreshed at a candidate (:func:`rss6.discrepancy.diagnose`'s
``bias_refresh``, the default since the twenty-sixth session): in a stick–slip loop the baseline
is the mean noisy replay, and its bias moves with the effect — a backlash's dead band is dithered
by the noise (on the twin, 0.67× the camera's σ on x at 1.9 mrad; on the plant's 1× backlash, the
mesh and width move it by 0.04–0.25× the loop's noise floor,
``benches/python/refresh_bias_shift.py``). The bias of the model before any effect made the
whitened cost least at 0.9 of a true width (``benches/python/backlash_response.py``)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial

import numpy as np

from rss6.discrepancy._steps import F64, _noise, _Part, _Sim
from rss6.discrepancy.effects import Change, EffectDef
from rss6.discrepancy.model import AppliedEffect, Model, replay, simulate
from rss6.discrepancy.search import Fit, Whitener, fit_effects, moved_by

__all__ = ["MAX_REFRESH", "REFRESH_TOL", "loop_bias", "refit_at_bias"]

MAX_REFRESH = 3
REFRESH_TOL = 0.2
""":func:`refit_at_bias` refreshes the bias at the refitted values and refits again until no
parameter moves by more than ``REFRESH_TOL`` of its standard error, at most ``MAX_REFRESH`` times
(on the plant's backlash cases 5 of 12 fits still moved 0.35–0.52 SE at the third: at K = 16 the
bias is a noisy function of the width; docs/discrepancy.md, twenty-fifth session)."""


def loop_bias(model: Model, part: _Part, k: int, sim: _Sim, seed: int) -> F64:
    """The bias of ``model``'s loop on ``part``'s run: the mean of ``k`` noisy replays minus its
    clean replay (whole run, every channel)."""
    clean = simulate(model, part.run)
    noise = sim.many([partial(_noise, model, part.run, clean, seed + s) for s in range(k)])
    return np.asarray(np.mean(noise, axis=0), dtype=np.float64)


def refit_at_bias(
    effs: Sequence[tuple[EffectDef, str]],
    f: Fit,
    base_model: Model,
    part: _Part,
    whitener: Whitener,
    bounds: Callable[[EffectDef, str], dict[str, tuple[float, float]]],
    current: F64,
    replays: tuple[int, _Sim, int],
) -> tuple[Fit, tuple[F64, float], str]:
    """``f`` refitted from its values against ``base_model``'s clean replays plus the loop's bias
    at those values (``base_model`` with the effects), refreshed at the refitted values until it
    holds (:data:`REFRESH_TOL`). Returns the refit; its bias and the whitened cost of the
    ``current`` model's clean replay (whole run) on that baseline, what the refit's cost is
    compared with; and a note if the bias did not hold. ``replays``: K, the replay pool and the
    calibration's first seed."""
    k, sim, seed = replays
    applied = list(base_model.applied())
    base = base_model.with_effects(applied)
    refit, moved = f, np.inf
    for _ in range(MAX_REFRESH):
        fitted = [
            AppliedEffect(e.name, sc, dict(v))
            for (e, sc), v in zip(effs, refit.values, strict=True)
        ]
        b = loop_bias(base_model.with_effects(applied + fitted), part, k, sim, seed)

        def simulate_b(c: Change, b: F64 = b) -> F64:
            return (replay(base, part.run, c) + b)[part.rows]

        prev, refit = (
            refit,
            fit_effects(effs, refit.values, part.measured, simulate_b, whitener, bounds=bounds),
        )
        moved = moved_by(prev, refit)
        if moved <= REFRESH_TOL:
            break  # the bias it was fitted against is (within the tolerance) its own
    r0 = whitener.vec(part.measured - (current + b)[part.rows])
    unsettled = (
        f"the loop's bias did not settle in {MAX_REFRESH} refreshes (the last refit moved "
        f"{moved:.2g} standard errors)"
        if moved > REFRESH_TOL
        else ""
    )
    return refit, (b, float(r0 @ r0)), unsettled
