"""The discrepancy workflow end to end (issue 14): detect, name, add, show the gap shrink.

1. Replay the model on the run (the model twin with the same reference and camera timing, driven
   by the robot's recorded per-tick commands when the run has them, else in its own closed loop)
   and learn the noise from K noisy replays (every channel: poses, potentiometers, and the
   commands when they are not the input).
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

from collections.abc import Mapping, Sequence
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy import stats
from rss6.discrepancy._claims import _consistency, backward_check, bound_note
from rss6.discrepancy._refresh import loop_bias, refit_at_bias
from rss6.discrepancy._steps import (
    MAX_MIMICS,
    MAX_NIL,
    MAX_WORSEN,
    MIN_FRAMES,
    MIN_SHRINK,
    MIN_TRANSFER,
    Progress,
    _best_start,
    _calibrate,
    _conflicts,
    _def,
    _gravity_load,
    _named_run,
    _Part,
    _physical,
    _pose_noise,
    _rms,
    _row,
    _screen_all,
    _separation,
    _Sim,
    _start,
    _tell,
    check_frames,
    check_held_out,
    check_options,
    error_replicates,
    fit_se,
    held_detection,
    intervals,
    on_bounds,
    replays_note,
    with_nominal,
)
from rss6.discrepancy.detect import AXES, Detection, detect, reference_signatures
from rss6.discrepancy.effects import Change, EffectDef
from rss6.discrepancy.effects import candidates as library
from rss6.discrepancy.model import AppliedEffect, Model, replay
from rss6.discrepancy.nominal import (
    NOMINAL_SPREAD,
    NominalFit,
    held_sensitivity,
    refit_step,
    spreads,
)
from rss6.discrepancy.reidentify import reidentify_on
from rss6.discrepancy.report import (
    AMBIGUOUS,
    Ambiguity,
    CandidateRow,
    DiscrepancyReport,
    HeldOut,
    NamedEffect,
    unexplained,
)
from rss6.discrepancy.search import Fit, Screen, fit_effects, heldout_test, mimicry, robust_cov_dof
from rss6.errors import Rss6Error

__all__ = [
    "MAX_MIMICS",
    "MAX_NIL",
    "MAX_WORSEN",
    "MIN_FRAMES",
    "MIN_SHRINK",
    "MIN_TRANSFER",
    "diagnose",
]

F64 = NDArray[np.float64]


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
    commands: str = "recorded",
    nominal: Mapping[str, float] | None = NOMINAL_SPREAD,
    bias_refresh: bool = True,
) -> DiscrepancyReport:
    """Finds where ``model`` disagrees with the ``measured`` run, names the missing effects from
    the library, adds them and shows the gap on the held-out run (module docs).

    ``measured`` / ``validation``: :class:`rss6.identify.IdentificationData`, a
    :class:`~rss6.discrepancy.model.Run` (``run_of(data, pot_noise="recorded")`` replays the run's
    potentiometer noise), or the path of an MCAP written by :func:`rss6.identify.collect`. Without ``validation`` the run's second half is held out (the
    first half selects). ``candidates``: effect names (optionally "name@scope"), default the whole
    library. ``alpha``: family-wise level of the Detect step, of each round's screening (Holm over
    the candidates) and of the held-out claim. ``replicates``: noisy replays of the model that
    calibrate the noise; ``max_effects``: at most this many named; ``refit``: candidates fitted by
    simulation per round; ``reidentify``: re-identify the drive gains and friction with the named
    effects (True) or the named CLOE parameters (:func:`rss6.identify.parameter_names`) by CLOE;
    ``workers``: threads for the replays; ``progress(stage, done, total)``. ``commands``:
    "recorded" (default) drives every replay with the run's own per-tick joint commands when it
    has them (a run from poses alone is replayed in the model's closed loop); "simulated" closes
    the model's visual PID on its own frames and compares the commands too
    (:func:`~rss6.discrepancy.model.run_of`). ``nominal``: relative half-widths of the box inside
    which the model's friction and drive gains are refitted before the search and after each
    named effect — the candidates are screened against that model, and it is the final model's
    (:mod:`rss6.discrepancy.nominal`; keys "coulomb", "viscous", "gains" or CLOE names; None or
    {} holds them: the model taken as exact). ``bias_refresh`` (the default since the twenty-sixth
    session, docs/discrepancy.md): in a stick–slip loop, fit and hold out each candidate against the
    replays' bias at its values; False takes the bias of the model as given for every candidate."""
    counts = {"replicates": (replicates, 8), "max_effects": (max_effects, 1), "refit": (refit, 1)}
    check_options(alpha, {**counts, "workers": (workers, 1)}, reidentify)
    pool = library(candidates)
    spread = spreads(nominal)
    run = _named_run("measured", measured, model, commands)
    n = len(run.t)
    if validation is None:
        fit_part = _Part(run, slice(0, n // 2))
        held = _Part(run, slice(n // 2, n))
    else:
        vrun = _named_run("validation", validation, model, commands)
        check_held_out(run, vrun)
        fit_part = _Part(run, slice(0, n))
        held = _Part(vrun, slice(0, len(vrun.t)))
    check_frames((("fitting", fit_part), ("held-out", held)))
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
            spread,
            bias_refresh,
        )
    finally:
        sim.close()


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
    spread: F64,
    bias_refresh: bool,
) -> DiscrepancyReport:
    _tell(progress, "noisy replays", 0, 1)
    clean_fit, clean_held = _calibrate([fit, held], model, k, sim, seed)
    _tell(progress, "noisy replays", 1, 1)
    assert fit.calibration is not None and held.calibration is not None
    cal, hcal = fit.calibration, held.calibration

    ref = np.array([fit.run.reference.sample(float(t))[0] for t in fit.t])
    sig = reference_signatures(fit.t, ref, gravity_load=_gravity_load(model, ref))
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
    # The nominal refit (module nominal): its model and baselines, for the screening and the
    # final model; fits and held-out claims are on the model as given with the named effects.
    nom: tuple[list[AppliedEffect], Model, F64, F64] | None = None
    last: NominalFit | None = None  # the latest refit: the model's uncertainty
    refit_for: list[AppliedEffect] | None = None  # the named effects it was run with
    jn_held: F64 | None = None  # its J_n on the held-out run, computed when first needed

    def refit_nominal_now() -> None:
        nonlocal nom, last, jn_held, refit_for
        jn_held, refit_for = None, list(named_effects)
        m, nf, nh, text, last = refit_step(
            base_model.with_effects(named_effects),
            model,
            spread,
            fit,
            held,
            (current_fit, current_held),
            sim.many,
        )
        if text:
            notes_fit.append(text)
        nom = None if nf is None or nh is None else (list(named_effects), m, nf, nh)

    if spread.any():
        _tell(progress, "nominal refit", 0, 1)
        refit_nominal_now()
        _tell(progress, "nominal refit", 1, 1)
    mimics = nil = 0
    # Fits against the current residual, kept while nothing is named (a refused one's are reused).
    fit_cache: dict[tuple[str, str], Fit] = {}
    fit_bias: dict[tuple[str, str], tuple[F64, float]] = {}  # bias_refresh: bias, current cost
    committed = (fit.bias, held.bias)  # the baselines' bias of the model with the named effects
    for round_ in range(max_effects + MAX_MIMICS + MAX_NIL):
        fit.bias, held.bias = committed
        if len(named) >= max_effects:
            break
        cands = [
            (e, s)
            for e, s in pool
            if (e.name, s) not in excluded
            and not _conflicts(e, s, named_effects[len(base_model.applied()) :])
        ]
        if not cands:
            break
        cur = base_model.with_effects(named_effects)
        rw = cal.whitener.vec(fit.measured - current_fit[fit.rows])
        # Screened against the refitted nominal quantities: model error inside the model's
        # uncertainty does not rank a candidate first.
        s_model, s_fit = (cur, current_fit) if nom is None else (nom[1], nom[2])
        rw_s = rw if nom is None else cal.whitener.vec(fit.measured - s_fit[fit.rows])
        screens = _screen_all(cands, s_model, fit, s_fit, rw_s, cal, sim, progress, round_)
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
        groups = stats.ambiguous_groups(names_c, corr, names_c, AMBIGUOUS)

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
        if len(order) > 1:
            # How close the round came to an ambiguity: the best candidate's closest mimic.
            near = max(range(1, len(order)), key=lambda j: abs(corr[0, j]))  # not k: replicates
            notes_fit.append(
                f"round {round_ + 1}: {best_label}'s closest mimic {names_c[near]}, "
                f"|ρ| {abs(corr[0, near]):.2f} (ambiguous above {AMBIGUOUS:g})"
            )
        top = [i for i in order if label(i) not in in_group][: max(1, refit)]
        _tell(progress, f"fit round {round_ + 1}", 0, len(top))
        fits: list[tuple[int, Fit]] = []
        prev = named_effects[len(base_model.applied()) :]
        for j, i in enumerate(top):
            s = screens[i]
            cached = fit_cache.get((s.effect.name, s.scope))
            if cached is not None:
                fits.append((i, cached))
                _tell(progress, f"fit round {round_ + 1}", j + 1, len(top))
                continue
            effs = [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)]
            starts = [dict(a.params) for a in prev] + [_start(s)]

            def simulate(c: Change) -> F64:
                return fit.baseline(
                    replay(base_model.with_effects(list(base_model.applied())), fit.run, c)
                )[fit.rows]

            try:
                starts = _best_start(
                    effs,
                    starts,
                    fit.measured,
                    simulate,
                    cal.whitener,
                    sim,
                    partial(_physical, base_model),
                    seed + round_,
                )
                f = fit_effects(
                    effs,
                    starts,
                    fit.measured,
                    simulate,
                    cal.whitener,
                    bounds=partial(_physical, base_model),
                )
                if bias_refresh and fit.bias is not None:
                    f, fit_bias[(s.effect.name, s.scope)], unsettled = refit_at_bias(
                        effs,
                        f,
                        base_model,
                        fit,
                        cal.whitener,
                        partial(_physical, base_model),
                        current_fit if committed[0] is None else current_fit - committed[0],
                        (k, sim, seed),
                    )
                    notes_fit += [f"{s.effect.name} ({s.scope}): {unsettled}"] if unsettled else []
                fits.append((i, f))
                fit_cache[(s.effect.name, s.scope)] = f
            except Rss6Error as err:
                # E.g. the trust region stepping to a model that leaves the workspace.
                notes_fit.append(f"{s.effect.name} ({s.scope}) not fitted: {err}")
            _tell(progress, f"fit round {round_ + 1}", j + 1, len(top))
        if not fits:
            break
        i_best, best = min(fits, key=lambda f: f[1].cost)
        s = screens[i_best]
        j_best = order.index(i_best)
        rivals = [j for j in range(len(order)) if j != j_best]
        k_mimic = max(rivals, key=lambda j: abs(corr[j_best, j])) if rivals else None
        mimic = None if k_mimic is None else (names_c[k_mimic], float(abs(corr[j_best, k_mimic])))
        new_effects = list(base_model.applied()) + [
            AppliedEffect(e.name, sc, v)
            for (e, sc), v in zip(
                [(_def(a.name), a.scope) for a in prev] + [(s.effect, s.scope)],
                best.values,
                strict=True,
            )
        ]
        cand_model = base_model.with_effects(new_effects)
        fit.bias, null_cost = fit_bias.get((s.effect.name, s.scope), (fit.bias, float(rw @ rw)))
        if bias_refresh and held.bias is not None:
            held.bias = loop_bias(cand_model, held, k, sim, seed)
        new_held = held.baseline(replay(cand_model, held.run))
        delta = hcal.whitener.vec((new_held - current_held)[held.rows])
        hres = hcal.whitener.vec(held.measured - current_held[held.rows])
        _, p_held = heldout_test(delta, hres, hcal.replicates)
        rms_new = _rms((held.measured - new_held[held.rows])[:, :6])
        rms_cur = _rms((held.measured - current_held[held.rows])[:, :6])
        # Standard errors from the fitting run (`fit_se`); every effect of the joint fit gets its
        # interval inside its bounds, and the spread between the runs once the held-out run refits.
        se_fit = fit_se(best, cal.whitener, len(fit.t), error_replicates(fit, base_model))
        defs = [_def(a.name) for a in prev] + [s.effect]
        cis = intervals(defs, best.values, se_fit)
        ci = cis[-1]
        dll = 0.5 * (null_cost - best.cost)
        top_row = CandidateRow(
            s.effect.name,
            s.scope,
            dll,
            float(p_adj[i_best]),
            best.values[-1],
            ci,
            rms_new - rms_cur,
            False,
        )
        rows += [
            top_row if i == i_best else _row(sc, float(p_adj[i]), None, None, False)
            for i, sc in enumerate(screens)
        ]
        if p_held > alpha or (not best.converged and best.cost >= null_cost):
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(
                f"{s.effect.name} ({s.scope}) not named: "
                + (
                    f"the held-out run does not show its predicted change (p = {p_held:.2g})"
                    if p_held > alpha
                    else "its fit did not converge and did not lower the cost"
                )
            )
            # A model error the pose hardly sees (friction a few % off moves the potentiometers)
            # can rank above a real effect: try the next, within the same bound as nil shrinks.
            nil += 1
            if nil > MAX_NIL:
                break
            continue
        shrink = float(np.max((rms_cur - rms_new) / hcal.noise.sigma[:6]))
        if shrink < MIN_SHRINK:
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(
                f"{s.effect.name} ({s.scope}) not named: the held-out run shows its predicted "
                f"change (p = {p_held:.2g}) but it shrinks the held-out gap by "
                f"{100 * shrink:.2g} % of the noise floor at most (< {100 * MIN_SHRINK:g} %)"
            )
            # It must not hide a real effect ranked below it: try the next, a bounded number of times.
            nil += 1
            if nil > MAX_NIL:
                break
            continue
        # A real effect does not make an axis it leaves alone worse; a library effect standing in
        # for something outside the library moves axes the discrepancy does not touch.
        worse = (rms_new - rms_cur) / hcal.noise.sigma[:6]
        if float(np.max(worse)) > MAX_WORSEN:
            ax = int(np.argmax(worse))
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(
                f"{s.effect.name} ({s.scope}) not named: it makes the held-out gap on "
                f"{AXES[ax]} worse by {100 * float(worse[ax]):.2g} % of the noise floor "
                f"(> {100 * MAX_WORSEN:g} %) — it mimics something outside the library"
            )
            mimics += 1
            if mimics > MAX_MIMICS:
                break
            continue
        # An earlier effect on a bound: a new one that overlaps it would take up the shortfall.
        note = bound_note(best, defs, prev, s)
        if note is not None:
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(note)
            mimics += 1
            if mimics > MAX_MIMICS:
                break
            continue
        # A real effect has the same parameters on both runs; a library effect that only mimics
        # something outside the library fits differently on another excitation.
        res_new = hcal.whitener.vec(held.measured - new_held[held.rows])
        if jn_held is None and last is not None:
            jn_held = held_sensitivity(cur, held, current_held, last, sim.many)
        reps = error_replicates(fit, base_model)
        v_fit = robust_cov_dof(best, cal.whitener, len(fit.t), replicates=reps)
        p_cons, p_exact, transfer, cons_text, hfit = _consistency(
            base_model, held, hcal, prev, s, best, res_new, hres, last, jn_held, v_fit
        )
        heldout: list[dict[str, tuple[float, float]]] = [{} for _ in best.values]
        if hfit is not None:
            se_h = fit_se(hfit, hcal.whitener, len(held.t), error_replicates(held, base_model))
            heldout = [
                {k: (float(v[k]), float(e[k])) for k in v}
                for v, e in zip(hfit.values, se_h, strict=True)
            ]
            cis = intervals(defs, best.values, se_fit, heldout)
            ci = cis[-1]
        if p_cons < alpha and transfer >= MIN_TRANSFER:
            notes_fit.append(
                f"{s.effect.name} ({s.scope}): the held-out run's own fit differs beyond its noise "
                f"({cons_text}; p = {p_cons:.2g}), but the fitting run's values reach "
                f"{100 * transfer:.1f} % of its gain (≥ {100 * MIN_TRANSFER:g} %): named, the "
                "difference taken as model error"
            )
        elif p_cons < alpha:
            excluded.add((s.effect.name, s.scope))
            notes_fit.append(
                f"{s.effect.name} ({s.scope}) not named: the held-out run wants other parameters "
                f"({cons_text}; p = {p_cons:.2g}) — a mimic of something outside the library, or "
                "model error beyond the model's stated uncertainty"
            )
            mimics += 1
            if mimics > MAX_MIMICS:
                break
            continue
        elif p_exact < alpha:
            notes_fit.append(
                f"{s.effect.name} ({s.scope}): the held-out run's own fit differs beyond its noise "
                f"but within the model's own uncertainty ({cons_text}; p = {p_cons:.2g}): named"
            )
        elif cons_text.startswith("held-out refit failed") or cons_text.endswith("not tested"):
            # The held-out run's own fit could not run, or left nothing free to test.
            notes_fit.append(
                f"{s.effect.name} ({s.scope}): {cons_text}; the consistency of its parameters "
                "between the runs is not tested (named on its held-out change and gap alone)"
            )
        # Earlier effects take their refitted values; the new one carries its held-out claim.
        named = [
            replace(ne, params=dict(a.params), ci=c, se=sf, heldout=dict(ho))
            for a, ne, c, sf, ho in zip(
                new_effects[len(base_model.applied()) :], named, cis, se_fit, heldout, strict=False
            )
        ]
        named.append(
            NamedEffect(
                s.effect.name,
                s.scope,
                dict(best.values[-1]),
                ci,
                p_held,
                rms_new,
                dict(se_fit[-1]),
                dict(heldout[-1]),
                mimic,
            )
        )
        named_effects, committed = new_effects, (fit.bias, held.bias)
        fit_cache.clear()
        fit_bias.clear()
        current_held = new_held
        current_fit = fit.baseline(replay(cand_model, fit.run))
        if spread.any():
            refit_nominal_now()
            named = with_nominal(named, defs, best, se_fit, heldout, last)
            if last is None:
                notes_fit.append(
                    f"{s.effect.name} ({s.scope}): its interval is conditional on the model as "
                    "given — the nominal refit did not run, so the model's own uncertainty is not in it"
                )
        _tell(progress, f"named {s.effect.name} ({s.scope})", round_ + 1, max_effects)

    named_effects, named, current_held, dropped = backward_check(
        base_model, named_effects, named, held, hcal, current_held, alpha
    )
    if spread.any() and refit_for != named_effects:
        refit_nominal_now()  # an effect was dropped: refit with those that stay
    if nom is not None and nom[0] == named_effects:
        base_model, current_held = nom[1].with_effects(base_model.applied()), nom[3]
    final_model = base_model.with_effects(named_effects)
    held_named = held.measured - current_held[held.rows]
    held_after = held_named
    reidentified = False
    after_model = final_model
    notes = list(dropped) + notes_fit + on_bounds(named, base_model)
    notes.append(replays_note(fit.run))
    if reidentify and named:
        _tell(progress, "re-identification", 0, 1)
        after_model, re_held, note = reidentify_on(
            final_model,
            fit,
            held,
            lambda r: float(np.sum(hcal.whitener.vec(r) ** 2)),
            held_named,
            reidentify,
        )
        if re_held is not None:
            held_after, reidentified = re_held, True
        notes.append(note)
        _tell(progress, "re-identification", 1, 1)
    h_det = held_detection(held, held_named, hcal.noise, alpha)
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
        held_out=HeldOut(
            held.t,
            held_before[:, :6],
            held_named[:, :6],
            held_after[:, :6] if reidentified else None,
        ),
        signatures=sig,
    )
