//! CLOE (eq. 5.6–5.9): Levenberg–Marquardt on the noise-weighted output error
//! Φ = Σ_k ‖W(χ_m(t_k) − χ_s(t_k))‖², χ_s from the simulated loop ([`super::simulate`]) and its exact
//! sensitivities, over the consistent parameters ψ ([`super::Consistent`]).
//!
//! Identifiability (Gautier's numerical method, eq. 5.2) is decided on what is measured: QR with
//! column pivoting of the weighted output sensitivity ∂Y/∂ψ at the guess, columns scaled to unit
//! norm, a column kept when |R_ii| > `identifiability_threshold` × the largest |R_ii| (of
//! near-parallel columns the earliest, [`crate::PIVOT_TIE`]). The thesis
//! uses R_ii < 10⁻³ on its regressor; on unit-norm columns the default 10⁻³ is the same rule made
//! unit-free. Unidentifiable entries stay at the guess (the prior) and are reported by name.
//!
//! Stopping rules (eq. 5.9): after an accepted step, converged when Φ dropped by less than 10⁻²
//! residual variances (Φ/(N − p)) at two accepted steps in a row — a change no test on the data
//! could see, whatever the size of Φ (with a model mismatch Φ/(N − p) ≫ 1, and LM then creeps
//! along flat directions for many iterations) — or when the relative change of Φ is at
//! most `tol_cost` **and** every estimated quantity moved by at most `tol_step` relative (or by
//! less than 10 % of its predicted standard deviation: with noise, poorly identified quantities
//! drift along flat directions without changing Φ); also
//! converged when no damping (up to λ = 10¹²) lowers Φ and the residual is orthogonal to every
//! Jacobian column within `tol_gradient` (or Φ is below 10⁻¹⁸ per residual, a residual of 10⁻⁹
//! noise σ: noise-free data fitted to rounding); also **settled** when, over the last [`SETTLE_STEPS`] accepted steps, Φ fell by
//! less than one residual variance in all and no quantity moved by more than half its Wald σ — LM
//! creeping along the kinks of a stick–slip cost (a likelihood ratio below e^0.5 over five steps,
//! every move inside its own error). [`CloeResult::converged_by`] says which rule ended the run.
//! Otherwise [`IdentError::NotConverged`] with the cost history.

use super::closed_loop::{simulate_recorded, Recording};
use super::config::{LoopConfig, LoopParams, StateJacobians};
use super::consistent::{Consistent, N_PSI};
use super::hac::{local_long_run_covariance, long_run_covariance};
use super::lm_step::{lm_step, next_lambda, optimal, shifted, Settle};
use super::observability::{identifiable_columns, unweighted, weighted_sensitivity, whitening};
use super::options::{CloeData, CloeOptions};
use super::result::{Alias, CloeResult, CloeStop};
use crate::error::{IdentError, Result};
use crate::excitation::base_columns;
use nalgebra::{DMatrix, DVector};
use rss6_core::Vec6;
use rss6_ctrl::Trajectory;

struct Eval {
    residual: DVector<f64>,
    cost: f64,
    rms: Vec6,
    /// ∂(weighted χ_s)/∂ψ (all 43 columns).
    g: Option<DMatrix<f64>>,
    /// `LoopRun::inexact_friction` of this simulation.
    inexact: usize,
    /// A plain run's stage calls, for the sensitivity run at the same ψ if the step is taken.
    recording: Option<Recording>,
}

/// Closed-loop output-error identification of A from `data` collected with `cfg`'s loop following
/// `reference`, starting from `guess`.
///
/// Errors: [`IdentError::NoCameraFrames`] (empty data, or data times the model's loop never
/// produces), [`IdentError::Unidentifiable`] (a requested quantity the data cannot see),
/// [`IdentError::NotConverged`], [`IdentError::Simulation`] at the guess, invalid inputs.
pub fn cloe<T: Trajectory + Sync + ?Sized>(
    data: &CloeData,
    cfg: &LoopConfig,
    reference: &T,
    guess: &LoopParams,
    options: &CloeOptions,
) -> Result<CloeResult> {
    cloe_observed(data, cfg, reference, guess, options, &mut |_, _, _| true)
}

/// [`cloe`] that calls `progress(iteration, Φ, ψ)` after every accepted step (iteration 0: the
/// guess; ψ as in [`Consistent`], anchored at `guess`), so a caller can keep the last iterate of a
/// run that does not converge. When it returns `false` the estimation stops with
/// [`IdentError::NotConverged`] and the cost history so far (the bindings' Ctrl-C).
pub fn cloe_observed<T: Trajectory + Sync + ?Sized>(
    data: &CloeData,
    cfg: &LoopConfig,
    reference: &T,
    guess: &LoopParams,
    options: &CloeOptions,
    progress: &mut dyn FnMut(usize, f64, &[f64]) -> bool,
) -> Result<CloeResult> {
    if data.t.is_empty() || data.t.len() != data.measured.len() {
        return Err(IdentError::NoCameraFrames(format!(
            "{} frame times and {} poses",
            data.t.len(),
            data.measured.len()
        )));
    }
    if data
        .measured
        .iter()
        .any(|m| m.iter().any(|v| !v.is_finite()))
        || data.t.iter().any(|t| !t.is_finite())
    {
        return Err(IdentError::InvalidInput(
            "measured frames and times must be finite".into(),
        ));
    }
    let weight = whitening(options)?;
    let cons = Consistent::new(guess)?;
    let names = Consistent::names();
    let a_cols = Consistent::a_columns();
    let mut sims = 0usize;

    // Per-tick sensitivities: at the guess, where identifiability is decided, the state Jacobians
    // once per tick (`PerTick`); while iterating, with the implicit friction law, every derivative
    // of a tick's first stage (`FirstStage`: as accurate there, ≈ 20 % cheaper, but it moves
    // near-parallel columns enough to change the base set's tie-breaks).
    let mut cfg_tick = cfg.clone();
    cfg_tick.state_jacobians = StateJacobians::PerTick;
    let mut cfg_fast = cfg_tick.clone();
    if cfg.implicit_friction {
        cfg_fast.state_jacobians = StateJacobians::FirstStage;
    }
    type Rec = Option<Recording>;
    let evaluate_with =
        |psi: &[f64], cols: &[usize], c: &LoopConfig, rec: Rec, sims: &mut usize| -> Result<Eval> {
            let (a, jac) = (cons.params(psi), !cols.is_empty());
            let (run, recording) =
                simulate_recorded(c, &a, reference, jac.then_some(cols), rec, !jac)?;
            *sims += 1;
            let idx = run.frames_at(&data.t, cfg.dt)?;
            let n = data.t.len();
            let mut residual = DVector::zeros(6 * n);
            let mut sq = Vec6::zeros();
            for (k, &s) in idx.iter().enumerate() {
                let d = data.measured[k] - run.chi[s];
                residual.rows_mut(6 * k, 6).copy_from(&(weight * d));
                for i in 0..6 {
                    sq[i] += d[i] * d[i];
                }
            }
            let rms = sq.map(|v| (v / n as f64).sqrt());
            let g = match (&run.jacobian, jac) {
                (Some(ja), true) => {
                    let dadpsi = cons.jacobian_rows(psi, cols);
                    Some(weighted_sensitivity(ja, &idx, &dadpsi, &weight))
                }
                _ => None,
            };
            Ok(Eval {
                cost: residual.norm_squared(),
                residual,
                rms,
                g,
                inexact: run.inexact_friction,
                recording,
            })
        };

    let psi_prior: Vec<f64> = cons.psi(guess)?.to_vec();
    let mut psi = match &options.initial {
        Some(start) => cons.psi(start)?.to_vec(),
        None => psi_prior.clone(),
    };
    let prior_w = match options.prior_log_std {
        None => 0.0,
        Some(s) if s.is_finite() && s > 0.0 => 1.0 / s,
        Some(s) => {
            return Err(IdentError::InvalidInput(format!(
                "the prior's log-std must be finite and > 0, got {s}"
            )))
        }
    };
    // With per-tick sensitivities on, the ones at the guess are per tick too: identifiability is
    // decided on them (their ≈ 10⁻³ error does not move the base set: `base_columns`' tie rule),
    // and the σ come from the exact ones at the stop.
    let guess_cfg = if options.per_tick_jacobians {
        &cfg_tick
    } else {
        cfg
    };
    let mut cur = evaluate_with(&psi, &a_cols, guess_cfg, None, &mut sims)?;
    // Whether `cur`'s sensitivities are the exact ones (the final σ need them).
    let mut cur_exact = !options.per_tick_jacobians;
    // Set when a stop found on per-tick sensitivities is refused by the exact ones.
    let mut exact_only = false;
    let rms_before = cur.rms;
    // Identifiability at the guess.
    let g0 = cur
        .g
        .as_ref()
        .ok_or_else(|| IdentError::InvalidInput("the loop returned no sensitivities".into()))?;
    let (free, base) = identifiable_columns(g0, &options.hold, options.identifiability_threshold)?;
    let held: Vec<usize> = (0..N_PSI).filter(|k| !free.contains(k)).collect();
    let active: Vec<usize> = match &options.parameters {
        None => base.clone(),
        Some(req) => {
            let mut act = Vec::new();
            for r in req {
                match names.iter().position(|n| n == r) {
                    Some(k) => act.push(k),
                    None => {
                        return Err(IdentError::InvalidInput(format!(
                            "unknown parameter {r:?}; known: {}",
                            names.join(", ")
                        )))
                    }
                }
            }
            if let Some(&k) = act.iter().find(|k| held.contains(k)) {
                return Err(IdentError::InvalidInput(format!(
                    "{} is both requested and held",
                    names[k]
                )));
            }
            // The others stay at the guess, so identifiability is decided among these alone.
            let ok = base_columns(&g0.select_columns(&act), options.identifiability_threshold);
            let bad: Vec<String> = (0..act.len())
                .filter(|k| !ok.contains(k))
                .map(|k| names[act[k]].clone())
                .collect();
            if !bad.is_empty() {
                return Err(IdentError::Unidentifiable { names: bad });
            }
            act
        }
    };
    // Sensitivities only of the columns of A the active ψ move: the others' would go unused.
    let moved = cons.columns_moved_by(&psi, &active);
    let unidentifiable: Vec<String> = free
        .iter()
        .copied()
        .filter(|k| !base.contains(k))
        .map(|k| names[k].clone())
        .collect();
    let aliases: Vec<Alias> = {
        let local: Vec<usize> = base
            .iter()
            .filter_map(|b| free.iter().position(|f| f == b))
            .collect();
        crate::excitation::aliases(&g0.select_columns(&free), &local)
            .into_iter()
            .map(|(u, c, residual)| {
                let mut like: Vec<(String, f64)> = local
                    .iter()
                    .zip(&c)
                    .filter(|(_, v)| v.abs() >= 0.05)
                    .map(|(&j, &v)| (names[free[j]].clone(), v))
                    .collect();
                like.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
                like.truncate(4);
                Alias {
                    name: names[free[u]].clone(),
                    like,
                    residual,
                }
            })
            .collect()
    };

    // The prior as extra residual rows √w(ψ_guess − ψ) with unit-weight Jacobian rows.
    let prior_cost = |psi: &[f64]| -> f64 {
        active
            .iter()
            .map(|&j| (prior_w * (psi[j] - psi_prior[j])).powi(2))
            .sum()
    };
    let augment = |g: &DMatrix<f64>, r: &DVector<f64>, psi: &[f64]| {
        let (n, p) = (g.nrows(), active.len());
        let extra = if prior_w > 0.0 { p } else { 0 };
        let mut ga = DMatrix::zeros(n + extra, p);
        ga.rows_mut(0, n).copy_from(&g.select_columns(&active));
        let mut ra = DVector::zeros(n + extra);
        ra.rows_mut(0, n).copy_from(r);
        for (k, &j) in active.iter().enumerate().take(extra) {
            ga[(n + k, k)] = prior_w;
            ra[n + k] = prior_w * (psi_prior[j] - psi[j]);
        }
        (ga, ra)
    };
    // Φ's decrease predicted by the LM step at λ on `e`'s sensitivities (prior included).
    let predicted_gain = |e: &Eval, psi: &[f64], lambda: f64| -> Result<f64> {
        let g =
            e.g.as_ref()
                .ok_or_else(|| IdentError::InvalidInput("missing sensitivities".into()))?;
        let (ga, ra) = augment(g, &e.residual, psi);
        let (gtg, gtr) = (ga.tr_mul(&ga), ga.tr_mul(&ra));
        Ok(lm_step(&gtg, &gtr, lambda, options.max_log_step)
            .map_or(0.0, |d| 2.0 * d.dot(&gtr) - (&gtg * &d).dot(&d)))
    };
    let mut lambda = options.lambda0;
    // The trial at 10λ on another core (`LoopConfig::parallel_stages`; not from a rayon worker).
    let speculate = cfg.parallel_stages
        && rayon::current_thread_index().is_none()
        && rayon::current_num_threads() > 1;
    let mut history = vec![cur.cost + prior_cost(&psi)];
    let mut iterations = 1usize;
    let mut converged_by = None;
    let mut previous_invisible = false;
    let mut settle = Settle::new(options.settle_steps, history[0], &psi);
    let mut stopped = !progress(0, history[0], &psi);
    'outer: while iterations <= options.max_iterations && !stopped {
        let g = cur
            .g
            .as_ref()
            .ok_or_else(|| IdentError::InvalidInput("missing sensitivities".into()))?;
        let (ga, ra) = augment(g, &cur.residual, &psi);
        let cur_total = cur.cost + prior_cost(&psi);
        let gtg = ga.tr_mul(&ga);
        let gtr = ga.tr_mul(&ra);
        // The trial at 10λ, evaluated beside the one at λ in case that is rejected.
        let mut spare: Option<(f64, Result<Eval>)> = None;
        loop {
            let Some(step) = lm_step(&gtg, &gtr, lambda, options.max_log_step) else {
                lambda *= 10.0;
                if lambda > 1e12 {
                    break 'outer;
                }
                continue;
            };
            let trial = shifted(&psi, &active, &step);
            let rel_step = step.iter().map(|d| d.exp_m1().abs()).fold(0.0, f64::max);
            let next = match spare.take() {
                Some((l, e)) if l == lambda => e,
                _ => {
                    // Both cores: the same path as one trial at a time, one wasted simulation
                    // when the first is taken.
                    let l10 = next_lambda(&gtg, &gtr, lambda, options.max_log_step, &step);
                    let next = lm_step(&gtg, &gtr, l10, options.max_log_step)
                        .filter(|_| speculate && l10 <= 1e12)
                        .map(|s| shifted(&psi, &active, &s));
                    let (e, e10, n10) = std::thread::scope(|scope| {
                        let other = next.as_ref().map(|t| {
                            scope.spawn(|| {
                                let mut n = 0;
                                (evaluate_with(t, &[], cfg, None, &mut n), n)
                            })
                        });
                        let e = evaluate_with(&trial, &[], cfg, None, &mut sims);
                        match other.map(|h| h.join()) {
                            Some(Ok((e10, n))) => (e, Some(e10), n),
                            _ => (e, None, 0),
                        }
                    });
                    sims += n10;
                    spare = e10.map(|e| (l10, e));
                    e
                }
            };
            match next {
                Ok(e) if e.cost + prior_cost(&trial) < cur_total => {
                    let (total, rec) = (e.cost + prior_cost(&trial), e.recording.clone());
                    let rel_cost = (cur_total - total) / cur_total.max(f64::MIN_POSITIVE);
                    psi = trial;
                    history.push(total);
                    if !progress(iterations, total, &psi) {
                        stopped = true;
                        break 'outer;
                    }
                    lambda = (lambda / 10.0).max(1e-12);
                    // tol_2 of eq. 5.9, or a step below 10 % of every predicted σ (poorly
                    // identified quantities drift along flat directions without any effect).
                    let dof = (cur.residual.len() as f64 - active.len() as f64).max(1.0);
                    // Φ's drop in units of the residual variance: below 10⁻² it is statistically
                    // invisible (a likelihood ratio of e^0.005), whatever Φ's size.
                    let chi2_drop = (cur_total - total) / (e.cost / dof).max(f64::MIN_POSITIVE);
                    // Wald σ of each active ψ at the current iterate.
                    let sigma: Option<Vec<f64>> = gtg.clone().cholesky().map(|c| {
                        let inv = c.inverse();
                        (0..active.len())
                            .map(|k| (e.cost / dof * inv[(k, k)]).sqrt())
                            .collect()
                    });
                    let sigma_small = sigma
                        .as_ref()
                        .is_some_and(|s| (0..active.len()).all(|k| step[k].abs() <= 0.1 * s[k]));
                    let invisible = chi2_drop <= 1e-2;
                    let both_invisible = invisible && previous_invisible;
                    previous_invisible = invisible;
                    let settled =
                        settle.push_and_check(total, &psi, e.cost / dof, &active, sigma.as_deref());
                    let rule = if both_invisible {
                        Some(CloeStop::Invisible)
                    } else if rel_cost <= options.tol_cost
                        && (rel_step <= options.tol_step || sigma_small)
                    {
                        Some(CloeStop::Tolerances)
                    } else if settled {
                        Some(CloeStop::Settled)
                    } else {
                        None
                    };
                    if let Some(r) = rule {
                        let per_tick = !cur_exact;
                        cur = evaluate_with(&psi, &moved, cfg, rec.clone(), &mut sims)?;
                        cur_exact = true;
                        // A stop found on per-tick sensitivities stands if the exact ones see less
                        // than one residual variance left to gain (the settled rule's bound);
                        // else iterate on the exact ones.
                        if per_tick && predicted_gain(&cur, &psi, lambda)? > cur.cost / dof {
                            exact_only = true;
                            iterations += 1;
                            if iterations > options.max_iterations {
                                break 'outer;
                            }
                            continue 'outer;
                        }
                        converged_by = Some(r);
                        break 'outer;
                    }
                    iterations += 1;
                    if iterations > options.max_iterations {
                        cur = evaluate_with(&psi, &moved, cfg, rec.clone(), &mut sims)?;
                        break 'outer;
                    }
                    // Per-tick sensitivities (≈ 10⁻³ relative) until a stop; the exact ones check it.
                    let fast = options.per_tick_jacobians && !exact_only;
                    cur = evaluate_with(
                        &psi,
                        &moved,
                        if fast { &cfg_fast } else { cfg },
                        rec,
                        &mut sims,
                    )?;
                    cur_exact = !fast;
                    continue 'outer;
                }
                _ => {
                    lambda = next_lambda(&gtg, &gtr, lambda, options.max_log_step, &step);
                    if lambda > 1e12 && !cur_exact {
                        // No step of the per-tick sensitivities lowers Φ: try the exact ones.
                        cur = evaluate_with(&psi, &moved, cfg, cur.recording.take(), &mut sims)?;
                        (cur_exact, exact_only, lambda) = (true, true, options.lambda0);
                        iterations += 1;
                        if iterations > options.max_iterations {
                            break 'outer;
                        }
                        continue 'outer;
                    }
                    if lambda > 1e12 {
                        // No step lowers Φ: a minimum to the precision of Φ if the residual is
                        // orthogonal to every column (first-order optimality) or Φ is at the
                        // simulation's rounding (noise-free data: measured 0.8–1.0 × 10⁻²⁰ per
                        // residual on a 2 s run, so 10⁻¹⁸, a residual of 10⁻⁹ σ), else a failure.
                        converged_by = (optimal(&ga, &ra, options.tol_gradient)
                            || cur.cost <= 1e-18 * cur.residual.len() as f64)
                            .then_some(CloeStop::Stationary);
                        break 'outer;
                    }
                }
            }
        }
    }
    let Some(converged_by) = converged_by.filter(|_| !stopped) else {
        return Err(IdentError::NotConverged {
            iterations: iterations.min(options.max_iterations),
            cost_history: history,
        });
    };
    if !cur_exact {
        cur = evaluate_with(&psi, &moved, cfg, None, &mut sims)?;
    }
    // Relative standard deviations from the exact Jacobian and the residual variance.
    let g = cur
        .g
        .as_ref()
        .ok_or_else(|| IdentError::InvalidInput("missing sensitivities".into()))?;
    let n_data = g.nrows();
    let (ga, _) = augment(g, &cur.residual, &psi);
    let dof = (n_data as f64 - active.len() as f64).max(1.0);
    let sigma2 = cur.cost / dof;
    let (relative_std_wald, relative_std, estimator_map) = match ga.tr_mul(&ga).cholesky() {
        Some(c) => {
            let inv = c.inverse();
            let wald: Vec<f64> = (0..active.len())
                .map(|k| (sigma2 * inv[(k, k)]).sqrt())
                .collect();
            let gs = g.select_columns(&active);
            let stationary = long_run_covariance(&gs, &cur.residual, 6, options.hac_lags);
            let local = local_long_run_covariance(&gs, &cur.residual, 6, options.hac_lags);
            let sw = &inv * stationary * &inv;
            let sl = &inv * local * &inv;
            let robust = (0..active.len())
                .map(|k| {
                    let v = sw[(k, k)].max(sl[(k, k)]).max(0.0);
                    wald[k].max(v.sqrt())
                })
                .collect();
            let map = &inv * gs.transpose();
            (wald, robust, map)
        }
        None => (
            vec![f64::INFINITY; active.len()],
            vec![f64::INFINITY; active.len()],
            DMatrix::zeros(0, 0),
        ),
    };
    let identified: Vec<String> = active.iter().map(|&k| names[k].clone()).collect();
    let poorly_identified = identified
        .iter()
        .zip(&relative_std)
        .filter(|(_, s)| **s > options.poor_std)
        .map(|(n, _)| n.clone())
        .collect();
    Ok(CloeResult {
        params: cons.params(&psi),
        psi,
        identified,
        unidentifiable,
        aliases,
        relative_std,
        relative_std_wald,
        estimator_map,
        residual_weight: weight.diagonal().into(),
        residual_whitening: weight.transpose().into(),
        residual: unweighted(&cur.residual, &weight),
        poorly_identified,
        rms_before,
        rms_after: cur.rms,
        cost_history: history,
        iterations: iterations.min(options.max_iterations),
        reduced_chi2: sigma2,
        simulations: sims,
        inexact_friction_ticks: cur.inexact,
        converged_by,
    })
}
