"""The discrepancy workflow end to end (issue 14): detect, name, add, show the gap shrink.

1. Replay the model in the run's closed loop (the model twin with the same reference and camera
   timing) and learn the loop's noise from K noisy replays (every channel: poses, potentiometers,
   commands).
2. Detect: :func:`rss6.discrepancy.detect` on the pose residual against that noise.
3. Name: screen every effect × scope of the library at its null value (score test calibrated on
   the replays, Holm over the candidates), fit the strongest ones by simulation (jointly with the
   effects named before, which are refitted), check the fitted effect's prediction on the held-out
   run, name it if it is there; repeat until nothing passes. Candidates whose signatures the data
   cannot tell apart (|ρ| > 0.9) are reported as ambiguous, not named.
4. Add and re-identify: the named effects join the model; optionally the drive gains and friction
   are re-identified with them (CLOE).
5. The gaps per axis on the held-out run — original, with the named effects, re-identified —
   beside the noise floor, and whatever is left that the library does not explain.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

import rss6
from rss6.discrepancy import stats
from rss6.discrepancy.detect import Detection, detect, reference_signatures
from rss6.discrepancy.effects import Change, EffectDef
from rss6.discrepancy.effects import candidates as library
from rss6.discrepancy.model import AppliedEffect, Model, Replay, Run, replay, run_of, simulate
from rss6.discrepancy.noise import NoiseModel
from rss6.discrepancy.report import (
    Ambiguity,
    CandidateRow,
    DiscrepancyReport,
    HeldOut,
    NamedEffect,
    unexplained,
)
from rss6.discrepancy.search import (
    Calibration,
    Fit,
    Screen,
    calibrate,
    fit_effects,
    heldout_test,
    hotelling,
    mimicry,
    screen,
    signature,
)
from rss6.errors import InvalidInputError

__all__ = ["diagnose"]

F64 = NDArray[np.float64]
MIN_FRAMES = 90
"""Fewest camera frames a fitting or held-out part may have."""
Progress = Callable[[str, int, int], Any]


@dataclass
class _Part:
    """A stretch of a run the workflow uses for fitting or for held-out claims: the run, the rows
    (frames) of it, the clean replay of the current model and the calibration of its noise."""

    run: Run
    rows: slice
    calibration: Calibration | None = None

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


def diagnose(
    measured: Any,
    model: Model,
    *,
    validation: Any = None,
    candidates: Sequence[str] | None = None,
    alpha: float = 0.01,
    progress: Progress | None = None,
    replicates: int = 24,
    max_effects: int = 3,
    refit: int = 5,
    reidentify: bool | Sequence[str] = False,
    workers: int = 2,
    seed: int = 1_000_003,
) -> DiscrepancyReport:
    """Finds where ``model`` disagrees with the ``measured`` run, names the missing effects from
    the library, adds them and shows the gap on the held-out run (module docs).

    ``measured`` / ``validation``: :class:`rss6.identify.IdentificationData`, a
    :class:`~rss6.discrepancy.model.Run`, or the path of an MCAP written by
    :func:`rss6.identify.collect`. Without ``validation`` the run's second half is held out (the
    first half selects). ``candidates``: effect names (optionally "name@scope"), default the whole
    library. ``alpha``: family-wise level of the Detect step, of each round's screening (Holm over
    the candidates) and of the held-out claim. ``replicates``: noisy replays of the model that
    calibrate the noise; ``max_effects``: at most this many named; ``refit``: candidates fitted by
    simulation per round; ``reidentify``: re-identify the drive gains and friction with the named
    effects (True) or the named CLOE parameters (:func:`rss6.identify.parameter_names`) by CLOE;
    ``workers``: threads for the replays; ``progress(stage, done, total)``."""
    if not 0 < alpha < 0.5:
        raise InvalidInputError(f"alpha must be in (0, 0.5); got {alpha}")
    if replicates < 8:
        raise InvalidInputError(f"replicates must be >= 8 (got {replicates})")
    pool = library(candidates)
    run = run_of(measured, kinematics=model.kinematics)
    n = len(run.t)
    if validation is None:
        fit_part = _Part(run, slice(0, n // 2))
        held = _Part(run, slice(n // 2, n))
    else:
        vrun = run_of(validation, kinematics=model.kinematics)
        if vrun.width != run.width:
            raise InvalidInputError(
                f"the validation run has {vrun.width} channels, the measured run {run.width}"
            )
        fit_part = _Part(run, slice(0, n))
        held = _Part(vrun, slice(0, len(vrun.t)))
    for what, part in (("fitting", fit_part), ("held-out", held)):
        frames = len(part.t)
        if frames < MIN_FRAMES:
            raise InvalidInputError(
                f"the {what} part has {frames} camera frames; the noise model and the tests need "
                f"at least {MIN_FRAMES} (≈ {MIN_FRAMES / 30:.0f} s at 30 Hz): use longer runs"
            )
    sim = _Sim(workers)
    try:
        return _diagnose(
            fit_part,
            held,
            model,
            pool,
            alpha,
            progress,
            replicates,
            max_effects,
            refit,
            reidentify,
            sim,
            seed,
        )
    finally:
        sim.close()


def _tell(progress: Progress | None, stage: str, done: int, total: int) -> None:
    if progress is not None:
        progress(stage, done, total)


def _noise(model: Model, run: Run, clean: Replay, seed: int) -> F64:
    return simulate(model, run, seed=seed).noise(clean, run)


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
        p.calibration = calibrate([x[p.rows] for x in noise[key]])
        out.append(clean_by[key].at(p.run))
    return out


def _diagnose(
    fit: _Part,
    held: _Part,
    model: Model,
    pool: list[tuple[EffectDef, str]],
    alpha: float,
    progress: Progress | None,
    k: int,
    max_effects: int,
    refit: int,
    reidentify: bool | Sequence[str],
    sim: _Sim,
    seed: int,
) -> DiscrepancyReport:
    _tell(progress, "noisy replays", 0, 1)
    clean_fit, clean_held = _calibrate([fit, held], model, k, sim, seed)
    _tell(progress, "noisy replays", 1, 1)
    assert fit.calibration is not None and held.calibration is not None
    cal, hcal = fit.calibration, held.calibration

    ref = np.array([fit.run.reference.sample(float(t))[0] for t in fit.t])
    sig = reference_signatures(fit.t, ref)
    r0 = fit.measured - clean_fit[fit.rows]
    detection: Detection = detect(fit.t, r0[:, :6], sig, _pose_noise(cal.noise), alpha)

    base_model = model
    named_effects: list[AppliedEffect] = list(model.applied())
    named: list[NamedEffect] = []
    ambiguous: list[Ambiguity] = []
    rows: list[CandidateRow] = []
    held_before = held.measured - clean_held[held.rows]
    current_fit, current_held = clean_fit, clean_held
    excluded: set[tuple[str, str]] = set()
    dropped: list[str] = []
    notes_fit: list[str] = []

    for round_ in range(max_effects):
        cands = [
            (e, s)
            for e, s in pool
            if (e.name, s) not in excluded
            and not _conflicts(e, s, named_effects[len(base_model.applied()) :])
        ]
        if not cands:
            break
        cur = base_model.with_effects(named_effects)
        resid = fit.measured - current_fit[fit.rows]
        rw = cal.whitener.vec(resid)
        screens = _screen_all(cands, cur, fit, current_fit, rw, cal, sim, progress, round_)
        pvals = np.array([s.p_value for s in screens])
        passed, p_adj = stats.holm(pvals, alpha)
        order = [i for i in np.argsort(-np.array([s.t2 for s in screens])) if passed[i]]
        if not order:
            for i, s in enumerate(screens):
                rows.append(_row(s, float(p_adj[i]), None, None, False))
            break
        # Ambiguity among those that passed: the Fisher correlation of their signatures.
        cols = {f"{screens[i].effect.name} ({screens[i].scope})": screens[i].columns for i in order}
        names_c = list(cols)
        corr = mimicry([screens[i] for i in order])
        groups = stats.ambiguous_groups(names_c, corr, names_c, 0.9)

        def label(i: int, screens: list[Screen] = screens) -> str:
            return f"{screens[i].effect.name} ({screens[i].scope})"

        in_group = {g for grp in groups for g in grp}
        best_label = label(order[0])
        if best_label in in_group:
            grp = next(grp for grp in groups if best_label in grp)
            idx = [names_c.index(g) for g in grp]
            rho = max(abs(corr[a, b]) for a in idx for b in idx if a != b)
            ambiguous.append(Ambiguity(tuple(grp), float(rho), _separation(grp, cols, fit)))
            for i in order:
                if label(i) in grp:
                    excluded.add((screens[i].effect.name, screens[i].scope))
            for i, s in enumerate(screens):
                rows.append(_row(s, float(p_adj[i]), None, None, label(i) in grp))
            # What is left may be partly the ambiguous effect's signature: naming anything else
            # from it could name a mimic. Stop here.
            break
        top = [i for i in order if label(i) not in in_group][: max(1, refit)]
        _tell(progress, f"fit round {round_ + 1}", 0, len(top))
        fits: list[tuple[int, Fit]] = []
        prev = named_effects[len(base_model.applied()) :]
        for j, i in enumerate(top):
            s = screens[i]
            effs = [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)]
            starts = [dict(a.params) for a in prev] + [_start(s)]

            def simulate(c: Change) -> F64:
                return replay(base_model.with_effects(list(base_model.applied())), fit.run, c)[
                    fit.rows
                ]

            try:
                fits.append(
                    (
                        i,
                        fit_effects(
                            effs,
                            starts,
                            fit.measured,
                            simulate,
                            cal.whitener,
                            bounds=partial(_physical, base_model),
                        ),
                    )
                )
            except (InvalidInputError, rss6.IdentificationError) as err:
                notes_fit.append(f"{s.effect.name} ({s.scope}) not fitted: {err}")
            _tell(progress, f"fit round {round_ + 1}", j + 1, len(top))
        if not fits:
            break
        i_best, best = min(fits, key=lambda f: f[1].cost)
        s = screens[i_best]
        new_effects = list(base_model.applied()) + [
            AppliedEffect(e.name, sc, v)
            for (e, sc), v in zip(
                [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)],
                best.values,
                strict=True,
            )
        ]
        cand_model = base_model.with_effects(new_effects)
        new_held = replay(cand_model, held.run)
        delta = hcal.whitener.vec((new_held - current_held)[held.rows])
        hres = hcal.whitener.vec(held.measured - current_held[held.rows])
        _, p_held = heldout_test(delta, hres, hcal.replicates)
        rms_new = _rms((held.measured - new_held[held.rows])[:, :6])
        rms_cur = _rms((held.measured - current_held[held.rows])[:, :6])
        dof = max(1, len(best.residual_w) - best.jacobian.shape[1])
        scale = max(1.0, best.cost / dof)
        ci = {
            name: (
                v - 1.96 * best.se[-1][name] * np.sqrt(scale),
                v + 1.96 * best.se[-1][name] * np.sqrt(scale),
            )
            for name, v in best.values[-1].items()
        }
        dll = 0.5 * (float(rw @ rw) - best.cost)
        for i, sc in enumerate(screens):
            if i == i_best:
                rows.append(
                    CandidateRow(
                        sc.effect.name,
                        sc.scope,
                        dll,
                        float(p_adj[i]),
                        best.values[-1],
                        ci,
                        rms_new - rms_cur,
                        False,
                    )
                )
            else:
                rows.append(_row(sc, float(p_adj[i]), None, None, False))
        if p_held > alpha or (not best.converged and best.cost >= float(rw @ rw)):
            excluded.add((s.effect.name, s.scope))
            break
        # A real effect has the same parameters on both runs; a library effect that only mimics
        # something outside the library fits differently on another excitation.
        res_new = hcal.whitener.vec(held.measured - new_held[held.rows])
        p_cons, cons_text = _consistency(base_model, held, hcal, prev, s, best, res_new)
        if p_cons < alpha:
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(
                f"{s.effect.name} ({s.scope}) not named: the held-out run wants other parameters "
                f"({cons_text}; p = {p_cons:.2g}) — it mimics something outside the library"
            )
            # The strongest candidate is a mimic: the weaker ones would mimic the same thing.
            break
        # Earlier effects take their refitted values; the new one carries its held-out claim.
        named = [
            NamedEffect(a.name, a.scope, dict(a.params), ne.ci, ne.p_value, ne.gap_after)
            for a, ne in zip(new_effects[len(base_model.applied()) :], named, strict=False)
        ]
        named.append(
            NamedEffect(s.effect.name, s.scope, dict(best.values[-1]), ci, p_held, rms_new)
        )
        named_effects = new_effects
        current_held = new_held
        current_fit = replay(cand_model, fit.run)
        _tell(progress, f"named {s.effect.name} ({s.scope})", round_ + 1, max_effects)

    # Backward check on the held-out run: an effect named early may only have mimicked part of one
    # named later; drop any whose own contribution the held-out run no longer shows.
    n0 = len(base_model.applied())
    for a in list(named_effects[n0:]) if len(named_effects) - n0 >= 2 else []:
        others = [b for b in named_effects if b is not a]
        without = replay(base_model.with_effects(others), held.run)
        delta = hcal.whitener.vec((current_held - without)[held.rows])
        hres = hcal.whitener.vec(held.measured - without[held.rows])
        _, p_drop = heldout_test(delta, hres, hcal.replicates)
        if p_drop > alpha:
            named_effects = others
            current_held = without
            named = [ne for ne in named if (ne.name, ne.scope) != (a.name, a.scope)]
            dropped.append(f"{a.name} ({a.scope}): held-out p = {p_drop:.3g} beside the others")
    final_model = base_model.with_effects(named_effects)
    held_named = held.measured - current_held[held.rows]
    held_after = held_named
    after_model = final_model
    notes = list(dropped) + notes_fit
    if reidentify and named:
        from rss6 import identify

        last = fit.t[-1] + fit.run.dt
        data = identify.IdentificationData(
            t=fit.t,
            reference=fit.run.reference,
            measured=fit.measured[:, :6],
            duration=float(last),
            dt=fit.run.dt,
        )
        _tell(progress, "re-identification", 0, 1)
        try:
            after_model, note = _reidentify(final_model, data, reidentify)
            held_after = held.measured - replay(after_model, held.run)[held.rows]
            notes.append(note)
        except (InvalidInputError, rss6.IdentificationError) as e:
            notes.append(f"not re-identified: {e}")
        _tell(progress, "re-identification", 1, 1)
    h_det = detect(
        held.t,
        held_named[:, :6],
        reference_signatures(
            held.t, np.array([held.run.reference.sample(float(t))[0] for t in held.t])
        ),
        _pose_noise(hcal.noise),
        alpha,
    )
    return DiscrepancyReport(
        detected=detection,
        named=named,
        ambiguous=ambiguous,
        unexplained=unexplained(h_det),
        gap_before=_rms(held_before[:, :6]),
        gap_named=_rms(held_named[:, :6]),
        gap_after=_rms(held_after[:, :6]),
        noise_floor=hcal.noise.sigma[:6].copy(),
        model=after_model,
        candidates=rows,
        notes=notes,
        held_out=HeldOut(held.t, held_before[:, :6], held_named[:, :6], held_after[:, :6]),
        signatures=sig,
    )


def _consistency(
    base_model: Model,
    held: _Part,
    hcal: Calibration,
    prev: Sequence[AppliedEffect],
    s: Screen,
    best: Fit,
    res_at_fit: F64,
) -> tuple[float, str]:
    """Refits the effects on the held-out run from the fitting run's values and tests that the
    fitting run's parameters are where the held-out run's own fit would put them: the score
    g = Jᵀr of the held-out residual at the fitting run's parameters (J the held-out fit's whitened
    Jacobian), Hotelling's T² against the held-out replicates' Jᵀe with their covariance doubled
    (the fitting run's estimate carries an error of about the same size as the held-out noise's
    projection). (p, text of the two estimates)."""
    effs = [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)]

    def simulate_h(c: Change) -> F64:
        return replay(base_model, held.run, c)[held.rows]

    try:
        hfit = fit_effects(
            effs,
            best.values,
            held.measured,
            simulate_h,
            hcal.whitener,
            bounds=partial(_physical, base_model),
        )
    except (InvalidInputError, rss6.IdentificationError):
        return 1.0, "held-out refit failed"
    j = hfit.jacobian
    g = j.T @ res_at_fit
    t2, p = hotelling(g / np.sqrt(2.0), hcal.replicates @ j)
    names = [p.name for p in s.effect.params]
    text = (
        ", ".join(f"{n} {best.values[-1][n]:.4g} vs {hfit.values[-1][n]:.4g}" for n in names)
        + f"; T² {t2:.3g} on {j.shape[1]} parameters"
    )
    return p, text


def _physical(model: Model, e: EffectDef, scope: str) -> dict[str, tuple[float, float]]:
    """Bounds that keep the model physical: added friction may not take the model's own below 0
    (on the joint of the scope, or on every joint)."""
    if e.name != "joint_friction":
        return {}
    fc = np.asarray(model.dynamics.coulomb, dtype=np.float64)
    fv = np.asarray(model.dynamics.viscous, dtype=np.float64)
    j = None if scope == "all joints" else int(scope.removeprefix("joint "))
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
            return replay(model, fit.run, c)[fit.rows]

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


REIDENTIFY_DEFAULT: tuple[str, ...] = (
    *(f"fc{i}" for i in range(1, 7)),
    *(f"fv{i}" for i in range(1, 7)),
    "lp",
    "li",
    "ld",
)
"""What ``reidentify=True`` re-identifies: the friction and the drive gains (the quantities CLOE
sees best in this loop; docs/identification.md)."""


def loop_effects(model: Model) -> tuple[Any, tuple[float, float, float], dict[str, Any]]:
    """The model's effects as the identification loop takes them: (dynamics with the named
    friction, drive gains with the named mismatch, keyword arguments of
    :func:`rss6.identify.cloe` / :func:`rss6.identify.simulate`: camera latency, gravity of a
    tilted base, payload as a load, offset drift). Raises :class:`rss6.InvalidInputError` for an
    effect the identification loop cannot express (backlash)."""
    from scipy.spatial.transform import Rotation

    from rss6.discrepancy.model import dynamics_with

    c = model.change()
    dp = dynamics_with(model.dynamics, c)
    g0 = [float(g) for g in model.pid]
    pid = (g0[0] * (1 + c.gains[0]), g0[1] * (1 + c.gains[1]), g0[2] * (1 + c.gains[2]))
    kw: dict[str, Any] = {"camera_latency": model.camera_latency}
    for name, params in c.twin.items():
        if name == "camera_latency":
            kw["camera_latency"] += params["latency"]
        elif name == "base_tilt":
            r = Rotation.from_euler("XY", [params["roll"], params["pitch"]]).as_matrix()
            kw["gravity"] = r.T @ np.array([0.0, 0.0, -9.81])
        elif name == "payload":
            com = [params["x"], params["y"], params["z"]]
            kw["load"] = (params["mass"], com, np.eye(3) * params.get("inertia", 0.0))
        elif name == "joint_offset_drift":
            rate = np.zeros(6)
            if "joint" in params:
                rate[int(params["joint"])] = params["rate"]
            else:
                rate[:] = params["rate"]
            kw["offset_drift"] = rate
        else:
            raise InvalidInputError(
                f"the identification loop cannot express {name!r}: re-identify without it"
            )
    return dp, pid, kw


def _reidentify(model: Model, data: Any, which: bool | Sequence[str]) -> tuple[Model, str]:
    """CLOE of ``which`` (True: :data:`REIDENTIFY_DEFAULT`) on the fitting run with the named
    effects; the re-identified model (its named friction and gain mismatch folded into the
    dynamics and gains, the other effects kept) and a note."""
    from rss6 import identify

    chosen: Sequence[str] = REIDENTIFY_DEFAULT if isinstance(which, bool) else which
    names = list(chosen)
    dp, pid, kw = loop_effects(model)
    res = identify.cloe(
        data,
        model.kinematics,
        dp,
        pid,
        parameters=names,
        derivative_filter=model.derivative_filter,
        friction_smoothing=model.friction_smoothing,
        torque_limit=model.torque_limit,
        **kw,
    )
    kept = [a for a in model.applied() if a.name not in ("joint_friction", "pid_gains")]
    out = model.with_effects(kept).with_dynamics(res.dynamics, res.pid)
    return out, f"re-identified {len(names)} quantities in {res.iterations} CLOE iterations"
