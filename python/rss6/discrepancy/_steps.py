"""The steps of :func:`rss6.discrepancy.diagnose`: the parts of the runs it uses, the replay pool,
the noise calibration, screening, starting values, the held-out consistency check, ambiguity text."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from functools import partial
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

import rss6
from rss6 import _checks
from rss6.discrepancy.detect import Detection, detect, reference_signatures
from rss6.discrepancy.effects import Change, EffectDef, joint_index
from rss6.discrepancy.model import AppliedEffect, Model, Replay, Run, replay, run_of, simulate
from rss6.discrepancy.noise import NoiseModel
from rss6.discrepancy.nominal import NominalFit, nominal_variance
from rss6.discrepancy.report import (
    CandidateRow,
    NamedEffect,
)
from rss6.discrepancy.search import (
    Calibration,
    Fit,
    Screen,
    Whitener,
    calibrate,
    per_effect,
    robust_se,
    screen,
    signature,
    wald_cov,
)
from rss6.errors import InvalidInputError, Rss6Error

F64 = NDArray[np.float64]

MIN_FRAMES = 90
"""Fewest camera frames a fitting or held-out part may have."""
Progress = Callable[[str, int, int], Any]

MIN_TRANSFER = 0.95
"""Share of the held-out run's own cost reduction that the fitting run's parameters must reach for
an effect whose two fits differ beyond the noise to be named all the same (the model is never the
robot: the difference is then model error, not mimicry). Measured on the rapier plant at 5× (its
model differs from it by 0.1–0.6× the noise with the true effect): the true friction, drive gains
and offset drift transferred 0.989–0.9996 and were rejected by T² (p ≤ 2e-4); mimics — a base tilt
fitted into a wrong minimum, a tilt standing in for a payload — transferred −2.6 and −0.7."""

MAX_NIL = 10
"""Candidates rejected for a practically nil held-out shrink (:data:`MIN_SHRINK`), or whose
predicted change the held-out run does not show, that the search tries past (their fits are kept
while nothing is named, so each try costs one new fit). Measured on the model twin in its own
loop: a 5× backlash was hidden behind an offset drift of joint 2 that shrank the held-out gap by
1.7 % of the floor (2 sufficed). With the model's friction a few per cent off (Coulomb 3 %, viscous
8 %, as CLOE leaves it) the potentiometers rank joint friction first on every scope although it
hardly moves the pose: a hidden 10 ms latency was named after 9 such refusals (2026-11-28)."""

MAX_MIMICS = 0
"""Candidates rejected as mimics (held-out consistency) that the search tries past; 0: it stops at
the first. Measured on the rapier plant (backlash at 5×, whose plant–model gap the library cannot
express): going on past 3 mimics named a spurious offset drift; stopping reports "unexplained"."""

MIN_SHRINK = 0.02
"""Least shrink of the held-out gap (on its best pose axis, as a fraction of the noise floor) for
an effect to be named: an effect of 0.2× the noise shrinks it by 2 %, one of 1× by ≈ 40 %. Measured
on the rapier plant without a hidden effect (replays driven by recorded commands): 3/20 runs named
an offset drift on all joints whose held-out claim passed (p ≈ 0.001) but which shrank the gap by
0.15 % of the floor at most — statistically there, practically nil (the plant is not the twin)."""

MAX_WORSEN = 0.02
"""Most a named effect may make any pose axis's held-out gap worse, as a fraction of its noise
floor. Measured on the twin grid (205 cases) and the plant: 82 correctly named effects worsened an
axis by 0.011 of the floor at most; a camera drift on x named an offset drift of joint 5 or 2
(which moves z and the angles too) worsened one by 0.016–0.025 at 1×, 0.055–0.078 at 2× and
0.28–0.34 at 5×."""


#: Mean square of the whitened √K·b̂ above which the noisy replays' mean is the baseline.
BIAS_THRESHOLD = 2.0


@dataclass
class _Part:
    """A stretch of a run the workflow uses for fitting or for held-out claims: the run, the rows
    (frames) of it, the clean replay of the current model and the calibration of its noise."""

    run: Run
    rows: slice
    calibration: Calibration | None = None
    #: Mean of the noisy replays minus the clean replay (whole run): the noise's systematic part,
    #: set only when it is significant (``bias_statistic``: mean square of √K·b̂ whitened).
    bias: F64 | None = None
    bias_statistic: float = float("nan")

    def baseline(self, replayed: F64) -> F64:
        """A clean replay (whole run) moved to the mean of noisy ones: what the loop is expected to
        measure (with stick–slip friction the noise itself shifts where joints stick)."""
        return replayed if self.bias is None else replayed + self.bias

    @property
    def measured(self) -> F64:
        return self.run.channels[self.rows]

    @property
    def t(self) -> F64:
        return self.run.t[self.rows]


T = TypeVar("T")


def _call(f: Callable[[], T]) -> T:
    return f()


class _Sim:
    """Replays with a pool of threads (the twin releases the GIL while it runs)."""

    def __init__(self, workers: int) -> None:
        self.pool = ThreadPoolExecutor(max(1, workers))

    def many(self, jobs: Sequence[Callable[[], T]]) -> list[T]:
        return list(self.pool.map(_call, jobs))

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def _pose_noise(n: NoiseModel) -> NoiseModel:
    return NoiseModel(n.sigma[:6].copy(), n.ar[:6], n.dof[:6].copy(), n.source)


def _rms(r: F64) -> F64:
    return np.asarray(np.sqrt(np.mean(r * r, axis=0)), dtype=np.float64)


def _start(s: Screen) -> dict[str, float]:
    """The fit's starting values from the one-step estimate of the score test."""
    e = s.effect
    if e.screen == "span":
        # Grid point whose output change best matches the residual (first column = width 0).
        return {e.params[0].name: e.grid[int(np.argmax(np.abs(s.step)))] if len(s.step) else 0.0}
    if e.name == "payload":
        m = float(s.step[0])
        if m <= e.param("mass").scale:
            m = e.param("mass").scale
        return {
            "mass": m,
            **{ax: float(np.clip(s.step[k + 1] / m, -0.19, 0.19)) for k, ax in enumerate("xyz")},
        }
    out = {}
    for p, v in zip(e.params, s.step, strict=True):
        lo, hi = p.bounds
        out[p.name] = float(np.clip(p.null + v, lo, hi))
    return out


def _conflicts(e: EffectDef, scope: str, named: Sequence[AppliedEffect]) -> bool:
    """True if the twin cannot hold ``e`` on ``scope`` beside ``named`` (one instance per twin
    effect), or it is already named on that scope."""
    return any(a.name == e.name and (a.scope == scope or e.name != "joint_friction") for a in named)


def _tell(progress: Progress | None, stage: str, done: int, total: int) -> None:
    if progress is not None:
        progress(stage, done, total)


def _noise(model: Model, run: Run, clean: Replay, seed: int) -> F64:
    """One noisy replay minus ``clean``; for a run whose replays add its potentiometer noise,
    minus the noise-free replay of the noisy one's own estimate of its noise (what the clean
    replay of the run is to the run)."""
    noisy = simulate(model, run, seed=seed)
    if noisy.dither is not None:
        clean = simulate(model, replace(run, pot_dither=noisy.dither))
    return noisy.noise(clean, run)


def _calibrate(parts: Sequence[_Part], model: Model, k: int, sim: _Sim, seed: int) -> list[F64]:
    """Clean replays of ``model`` on each distinct run of ``parts`` and the calibration of each
    part from ``k`` noisy replays (their noise taken at the model's own frames); returns the clean
    replays (whole runs, at the runs' frame times) by part."""
    runs: dict[int, Run] = {}
    for p in parts:
        runs.setdefault(id(p.run), p.run)
    keys = list(runs)
    clean = sim.many([partial(simulate, model, runs[key]) for key in keys])
    clean_by = dict(zip(keys, clean, strict=True))
    noise: dict[int, list[F64]] = {}
    for key in keys:
        r, c = runs[key], clean_by[key]
        noise[key] = sim.many([partial(_noise, model, r, c, seed + s) for s in range(k)])
    out = []
    for p in parts:
        key = id(p.run)
        reps = np.array(noise[key])
        cal0 = calibrate([x[p.rows] for x in reps])
        b = reps.mean(axis=0)
        # Is the mean of the noisy replays away from the clean replay? √K·b̂, whitened with the
        # replays' noise model, has mean square ≈ 1 if b̂ is only its own estimation error. Used
        # when that is above 2 (b̂ carries more than its error): measured 4.6–4.7 with stick–slip
        # friction, 1.09–1.13 with the smooth (tanh) loop — whose b̂ is then left out, as using
        # it cost interval coverage (94 % → 85 % on the 2×/5× twin grid).
        z = cal0.whitener.vec(np.sqrt(k) * b[p.rows])
        p.bias_statistic = float(np.mean(z * z))
        if p.bias_statistic <= BIAS_THRESHOLD:
            p.calibration = cal0
            out.append(clean_by[key].at(p.run))
            continue
        # The baseline is the mean noisy replay (clean + b̂): a nonlinear loop (stick–slip) is not
        # centred on its clean replay. The measured residual against it has variance σ²(K+1)/K,
        # so the noise model is fitted to deviations scaled to that, and the replicates the tests
        # calibrate on are centred deviations scaled by √((K+1)/(K−1)) to the same variance.
        p.bias = b
        dev = [(x - p.bias)[p.rows] for x in reps]
        cal = calibrate([d * np.sqrt((k + 1) / k) for d in dev])
        scale = np.sqrt((k + 1) / (k - 1))
        p.calibration = Calibration(
            cal.noise, cal.whitener, np.array([cal.whitener.vec(d * scale) for d in dev])
        )
        out.append(p.baseline(clean_by[key].at(p.run)))
    return out


def held_detection(held: _Part, residual: F64, noise: NoiseModel, alpha: float) -> Detection:
    """The Detect step on the held-out run's residual (pose channels) after the final model: what
    decides "unexplained"."""
    ref = np.array([held.run.reference.sample(float(t))[0] for t in held.t])
    sig = reference_signatures(held.t, ref)
    return detect(held.t, residual[:, :6], sig, _pose_noise(noise), alpha)


def replays_note(run: Run) -> str:
    """How the replays were driven, for the report's notes."""
    if run.commands is not None:
        return "replays driven by the run's recorded commands"
    return (
        "replays close the model's own visual PID (commands='simulated', or a run without "
        "per-tick commands)"
    )


def check_options(
    alpha: float, counts: dict[str, tuple[int, int]], reidentify: bool | Sequence[str]
) -> None:
    """``diagnose``'s options checked before any replay: ``alpha`` in (0, 0.5), each count (value,
    least) an int ≥ least, ``reidentify``'s names known to CLOE (not found only once named)."""
    if not 0 < alpha < 0.5:
        raise InvalidInputError(f"alpha must be in (0, 0.5); got {alpha}")
    for name, (value, least) in counts.items():
        _checks.count(value, name, least)
    if not isinstance(reidentify, bool):
        from rss6.identify import parameter_names
        from rss6.identify_linear import requested_names

        requested_names(list(reidentify), parameter_names())


def check_held_out(run: Run, held: Run) -> None:
    """Raises unless ``held`` can be the held-out run of ``run``: the same channels, not the same
    data (every claim is made on the held-out run: on the fitting run none would be held out)."""
    if held.width != run.width:
        raise InvalidInputError(
            f"the validation run has {held.width} channels, the measured run {run.width}"
        )
    if np.array_equal(held.t, run.t) and np.array_equal(held.channels, run.channels):
        raise InvalidInputError(
            "the validation run is the measured run itself: its claims would not be held out "
            "(give another run, or none to hold out the run's second half)"
        )


def check_frames(parts: Sequence[tuple[str, _Part]]) -> None:
    """Raises unless every part has at least :data:`MIN_FRAMES` camera frames."""
    for what, part in parts:
        frames = len(part.t)
        if frames < MIN_FRAMES:
            raise InvalidInputError(
                f"the {what} part has {frames} camera frames; the noise model and the tests need "
                f"at least {MIN_FRAMES} (≈ {MIN_FRAMES / 30:.0f} s at 30 Hz): use longer runs"
            )


def error_replicates(part: _Part, model: Model) -> F64 | None:
    """The part's noisy replays for the runs' errors (:func:`fit_se`, ``search.robust_cov``) where
    the loop is non-smooth — stick–slip friction in ``model``, or noisy replays whose mean leaves
    the clean replay (``part.bias``) —, else None. The replays' spread was added for the
    stick–slip loop, where the sandwiches understate the spread between noise draws ≈ 3×; in a
    smooth loop the sandwiches are consistent and taking the largest of several estimates of one
    variance only biases it up (on the twin's grid it narrowed the intervals of 16 of the 86 cases
    that have some and left every verdict and the coverage as they were; docs/discrepancy.md)."""
    if part.calibration is None or not (model.implicit_friction or part.bias is not None):
        return None
    return part.calibration.replicates


def fit_se(
    fit: Fit, whitener: Whitener, n_frames: int, replicates: F64 | None = None
) -> list[dict[str, float]]:
    """Standard errors of ``fit`` from its own run: the larger of the Wald error scaled by the
    misfit (:func:`~rss6.discrepancy.search.wald_cov`) and :func:`robust_se`'s (the sandwiches and
    the spread over the run's noisy ``replicates``)."""
    wald = per_effect(np.sqrt(np.maximum(np.diag(wald_cov(fit)), 0.0)), fit.se)
    rob = robust_se(fit, whitener, n_frames, replicates=replicates)
    return [{k: max(w[k], r[k]) for k in w} for w, r in zip(wald, rob, strict=True)]


Z95 = 1.959963984540054
"""The two-sided 95 % normal quantile."""


def interval_variance(
    sf: float, heldout: tuple[float, float] | None, d: float, nom: float
) -> float:
    """The variance behind a 95 % interval (:func:`intervals`): the fitting run's s.e. ``sf``, the
    model's own ``nom``, and τ² when the held-out run's (estimate − fitting estimate ``d``, s.e.)
    ``heldout`` differs beyond both runs' errors at 5 %."""
    var = sf * sf + nom * nom
    if heldout is not None and np.isfinite(d) and np.isfinite(heldout[1]):
        pooled = sf * sf + heldout[1] ** 2
        if d * d > Z95 * Z95 * pooled:
            var += 0.5 * (d * d - pooled)
    return var


def intervals(
    defs: Sequence[EffectDef],
    values: Sequence[dict[str, float]],
    se: Sequence[dict[str, float]],
    heldout: Sequence[dict[str, tuple[float, float]]] | None = None,
    nominal: Sequence[dict[str, float]] | None = None,
) -> list[dict[str, tuple[float, float]]]:
    """95 % intervals of the fitting run's ``values`` (one dict per effect), inside each
    parameter's bounds. With the held-out run's own estimates ``heldout`` {name: (value, se)}, the
    interval also holds model error that differs between excitations: a random-effects model
    θ_run = θ + b_run + e_run, b ~ N(0, τ²) — DerSimonian–Laird's τ² from the two runs,
    (d² − s_f² − s_h²)/2 for d = θ_f − θ_h — and the half-width 1.96·√(s_f² + τ²), but only if the
    runs differ beyond their errors at 5 % (Cochran's Q = d²/(s_f² + s_h²) > 1.96²). Otherwise the
    fitting run's interval stays as it was: τ² from one difference is noisy, and added whenever it
    is positive it takes an exact model's coverage from 95 % to 98.7 % (96.7 % gated; 95.0 % and
    90.9 % at τ = σ). ``nominal``
    {name: s.e.}: what the model's own uncertainty adds (:func:`nominal_se`), a bias both runs
    share, added in quadrature."""
    out: list[dict[str, tuple[float, float]]] = []
    for i, vals in enumerate(values):
        ho = heldout[i] if heldout is not None else {}
        ci: dict[str, tuple[float, float]] = {}
        for name, v in vals.items():
            nom = nominal[i].get(name, 0.0) if nominal is not None else 0.0
            held = ho.get(name)
            d = v - held[0] if held is not None else 0.0
            h = Z95 * float(np.sqrt(interval_variance(se[i][name], held, d, nom)))
            lo, hi = defs[i].param(name).bounds
            ci[name] = (max(v - h, lo), min(v + h, hi))
        out.append(ci)
    return out


def nominal_se(fit: Fit, nf: NominalFit | None) -> list[dict[str, float]]:
    """:func:`~rss6.discrepancy.nominal.nominal_variance` of ``fit``'s parameters as standard
    errors, one dict per effect in ``fit.se``'s layout."""
    return per_effect(np.sqrt(nominal_variance(fit.jacobian, nf, fit.residual_w)), fit.se)


def with_nominal(
    named: Sequence[NamedEffect],
    defs: Sequence[EffectDef],
    fit: Fit,
    se: Sequence[dict[str, float]],
    heldout: Sequence[dict[str, tuple[float, float]]],
    nf: NominalFit | None,
) -> list[NamedEffect]:
    """``named`` with the intervals of its last ``len(defs)`` effects (those of the joint ``fit``)
    widened by the model's own uncertainty from the refit ``nf`` (:func:`nominal_se`)."""
    extra = nominal_se(fit, nf)
    cis = intervals(defs, fit.values, se, heldout, extra)
    n0 = len(named) - len(cis)
    return list(named[:n0]) + [
        replace(ne, ci=c, nominal_se=x) for ne, c, x in zip(named[n0:], cis, extra, strict=True)
    ]


def _physical(model: Model, e: EffectDef, scope: str) -> dict[str, tuple[float, float]]:
    """Bounds that keep the model physical: added friction may not take the model's own below 0
    (on the joint of the scope, or on every joint)."""
    if e.name != "joint_friction":
        return {}
    fc = np.asarray(model.dynamics.coulomb, dtype=np.float64)
    fv = np.asarray(model.dynamics.viscous, dtype=np.float64)
    j = joint_index(scope)
    c_min = float(fc.min() if j is None else fc[j])
    v_min = float(fv.min() if j is None else fv[j])
    return {"coulomb": (-c_min, np.inf), "viscous": (-v_min, np.inf)}


def _def(name: str) -> EffectDef:
    from rss6.discrepancy.effects import get

    return get(name)


def _row(s: Screen, p_adj: float, est: dict[str, float] | None, ci: Any, amb: bool) -> CandidateRow:
    return CandidateRow(
        s.effect.name,
        s.scope,
        0.5 * s.t2,
        p_adj,
        est or {c: float(v) for c, v in zip(s.coords, s.step, strict=False)},
        ci or {},
        np.full(6, np.nan),
        amb,
    )


def _separation(group: Sequence[str], cols: dict[str, F64], part: _Part) -> str:
    """Where the first two signatures of an ambiguous group differ most (whitened): the part of the
    first's leading direction the second cannot mimic, at its largest, as a channel and a time of
    the fitting run — the excitation should weigh that motion more."""
    from rss6.discrepancy.model import CHANNELS

    a, b = cols[group[0]], cols[group[1]]
    ua = np.linalg.svd(a, full_matrices=False)[0][:, 0]
    qb, _ = np.linalg.qr(b)
    diff = ua - qb @ (qb.T @ ua)
    where = int(np.argmax(np.abs(diff)))
    assert part.calibration is not None
    lags = [len(phi) for phi in part.calibration.noise.ar]
    n = len(part.t)
    for ch, p in enumerate(lags):
        if where < n - p:
            t = float(part.t[min(where + p, n - 1)])
            return (
                f"excite where their signatures differ most: channel {CHANNELS[ch]} near "
                f"t = {t:.2f} s (a longer or faster motion there, or another excitation)"
            )
        where -= n - p
    return "excite where their signatures differ most"


def _screen_all(
    cands: Sequence[tuple[EffectDef, str]],
    model: Model,
    fit: _Part,
    clean: F64,
    rw: F64,
    cal: Calibration,
    sim: _Sim,
    progress: Progress | None,
    round_: int,
) -> list[Screen]:
    stage = f"screening round {round_ + 1}"
    _tell(progress, stage, 0, len(cands))
    out: list[Screen] = []
    for j, (e, s) in enumerate(cands):

        def simulate(c: Change) -> F64:
            return fit.baseline(replay(model, fit.run, c))[fit.rows]

        raw, coords = _signature_parallel(e, s, simulate, clean[fit.rows], sim)
        out.append(screen(e, s, raw, coords, rw, cal))
        _tell(progress, stage, j + 1, len(cands))
    return out


def _signature_parallel(
    e: EffectDef, s: str, simulate: Callable[[Change], F64], clean: F64, sim: _Sim
) -> tuple[F64, tuple[str, ...]]:
    """:func:`signature` with its replays run on the pool: the changes are collected first."""
    changes: list[Change] = []

    def record(c: Change) -> F64:
        changes.append(c)
        return clean

    signature(e, s, record, clean)
    results = sim.many([partial(simulate, c) for c in changes])
    it = iter(results)
    return signature(e, s, lambda c: next(it), clean)


#: Multiples of the score test's one-step estimate tried as starts besides it (a line along it).
STEP_MULTIPLES = (0.5, 2.0, 4.0)
#: Quasi-random starts (scrambled Sobol, inside the bounds) tried besides the line, by default
#: (an effect's ``sobol`` sets its own).
SOBOL_STARTS = EffectDef.sobol


def _best_start(
    effs: Sequence[tuple[EffectDef, str]],
    starts: Sequence[dict[str, float]],
    measured: F64,
    simulate: Callable[[Change], F64],
    whitener: Any,
    sim: _Sim,
    bounds: Callable[[EffectDef, str], dict[str, tuple[float, float]]],
    seed: int,
) -> list[dict[str, float]]:
    """The fit's starts with the new (last) effect's values replaced by the best of a small global
    stage: the one-step estimate, multiples of it (:data:`STEP_MULTIPLES`), the effect's
    ``sobol`` Sobol points inside its bounds (default :data:`SOBOL_STARTS`) and its ``scan`` of its
    first parameter, each scored by one replay (the others' values kept). With stick–slip friction
    the signature at the null is not the effect's large-scale response: a base tilt of
    (0.3, 0.3) rad on the plant was fitted from its one-step estimate to (0.09, −0.24) (pose
    residual 6× the noise; 0.3× at the truth)."""
    from scipy.stats import qmc

    e, scope = effs[-1]
    narrow = bounds(e, scope)
    lo = np.array([max(p.bounds[0], narrow.get(p.name, p.bounds)[0]) for p in e.params])
    hi = np.array([min(p.bounds[1], narrow.get(p.name, p.bounds)[1]) for p in e.params])
    null = np.array([p.null for p in e.params])
    one = np.array([starts[-1].get(p.name, p.null) for p in e.params])
    pts = [one] + [np.clip(null + m * (one - null), lo, hi) for m in STEP_MULTIPLES]
    u = qmc.Sobol(len(e.params), scramble=True, seed=seed).random(e.sobol)
    pts += list(lo + u * (hi - lo))
    for v in e.scan:
        # The first parameter on the effect's scan, the others at null and at the one-step start.
        for rest in (null, one):
            x = np.array(rest, dtype=np.float64)
            x[0] = v
            pts.append(np.clip(x, lo, hi))

    def change(x: F64) -> Change:
        c = Change()
        for (ei, si), v in zip(effs[:-1], starts[:-1], strict=True):
            c = c.merged(ei.apply(v, si))
        return c.merged(
            e.apply({p.name: float(v) for p, v in zip(e.params, x, strict=True)}, scope)
        )

    def cost(x: F64) -> float:
        try:
            r = whitener.vec(measured - simulate(change(x)))
        except Rss6Error:
            # A start the model cannot run (e.g. a drift that takes a leg out of reach) is no start.
            return float("inf")
        return float(r @ r)

    costs = sim.many([partial(cost, x) for x in pts])
    best = pts[int(np.argmin(costs))]
    return [*starts[:-1], {p.name: float(v) for p, v in zip(e.params, best, strict=True)}]


def on_bounds(named: Sequence[NamedEffect], model: Model) -> list[str]:
    """Notes on named effects' parameters that ended on a bound of the fit (the library's or the
    physical one, within 10⁻³ of the parameter's scale): the data may want a value beyond it, and
    the estimate and its interval are clipped there."""
    notes = []
    for ne in named:
        e = _def(ne.name)
        narrow = _physical(model, e, ne.scope)
        for p in e.params:
            v = ne.params.get(p.name)
            if v is None:
                continue
            lo = max(p.bounds[0], narrow.get(p.name, p.bounds)[0])
            hi = min(p.bounds[1], narrow.get(p.name, p.bounds)[1])
            for side, b in (("lower", lo), ("upper", hi)):
                if abs(v - b) > 1e-3 * p.scale:
                    continue
                at = f"{ne.name} ({ne.scope}): {p.name} = {v:.4g} {p.unit}"
                if b == p.null:
                    # Only an effect that is not null at its null value can be named there
                    # (backlash: its rotor and gear mesh at width 0).
                    notes.append(
                        f"{at} at its null value, the {side} bound: the effect is named for what "
                        f"it changes besides {p.name}"
                    )
                else:
                    notes.append(
                        f"{at} on its {side} bound ({b:.4g}): the data may want a value beyond "
                        "it (estimate and interval clipped there)"
                    )
    return notes


def _named_run(what: str, data: Any, model: Model, commands: str) -> Run:
    """:func:`run_of`, its errors saying which run ("measured" or "validation") they are about."""
    try:
        return run_of(data, kinematics=model.kinematics, commands=commands)
    except InvalidInputError as e:
        raise type(e)(f"the {what} run: {e}") from None


def _gravity_load(model: Model, ref: F64) -> F64:
    """The gravity load along the reference (N,): RMS over the joints of the static actuator torques
    (the model's inverse dynamics at rest), about its mean — in χ coordinates gravity is constant
    along a trajectory, in joint space it is not."""
    zero = np.zeros(6)
    tau = np.array(
        [rss6.inverse_dynamics(model.kinematics, model.dynamics, p, zero, zero) for p in ref]
    )
    load = np.sqrt(np.mean(tau * tau, axis=1))
    return np.asarray(load - load.mean(), dtype=np.float64)
