//! Levenberg–Marquardt on a [`Problem`] in the Table 4.2-scaled, gauge-reduced parameters, with the
//! identifiability checks before and after.

use super::min_configurations;
use super::options::{CalibrationOptions, Convergence, Progress};
use super::problem::{usable, EvalError, Problem, Usable};
use super::result::{CalibrationResult, DroppedConfiguration, RejectedConfiguration};
use crate::data::CalibrationData;
use crate::error::{IdentError, Method, Result};
use crate::model::{Layout, GAUGE_DESCRIPTIONS, N_GAUGE};
use nalgebra::{DMatrix, DVector};

mod outliers;
use outliers::{deletion_outlier, outlier, readmitted};

/// The usable configurations of a problem and those left out.
struct Selected {
    usable: Usable,
    dropped: Vec<DroppedConfiguration>,
}

/// The reduced-coordinates map of the solver: a step z in the gauge-free, Table 4.2-scaled
/// coordinates is the parameter step (Q·z)∘s.
struct Reduction {
    s: DVector<f64>,
    q: DMatrix<f64>,
}

impl Reduction {
    fn new(layout: &Layout, x0: &DVector<f64>, fixed_sensor: bool) -> Self {
        let q = if fixed_sensor {
            layout.free_basis_fixed_sensor(x0)
        } else {
            layout.free_basis(x0)
        };
        Reduction {
            s: layout.scales(),
            q,
        }
    }

    /// The Jacobian scaled by Table 4.2 (columns).
    fn scaled(&self, j: &DMatrix<f64>) -> DMatrix<f64> {
        let mut js = j.clone();
        for c in 0..js.ncols() {
            js.column_mut(c).scale_mut(self.s[c]);
        }
        js
    }

    /// The scaled Jacobian restricted to the free (gauge-complement) directions.
    fn reduce(&self, j: &DMatrix<f64>) -> DMatrix<f64> {
        self.scaled(j) * &self.q
    }

    fn step(&self, z: &DVector<f64>) -> DVector<f64> {
        (&self.q * z).component_mul(&self.s)
    }
}

fn too_few(layout: &Layout, got: usize) -> Result<()> {
    let method = layout.method;
    let needed = min_configurations(method);
    if got < needed {
        return Err(IdentError::TooFewConfigurations {
            method,
            got,
            needed,
            params: layout.n() - N_GAUGE,
            extra: match method {
                Method::Rpba => ", configuration 0 is the reference",
                Method::Implicit => "",
            },
        });
    }
    Ok(())
}

/// Configurations with a defect (NaN, missing frames) or, unless `opts.include_faulty`, a failed
/// collection check are dropped; a bad reference is an error.
fn select(layout: &Layout, data: &CalibrationData, opts: &CalibrationOptions) -> Result<Selected> {
    let mut dropped = Vec::new();
    for (i, c) in data.configurations.iter().enumerate() {
        let excluded = if opts.include_faulty {
            c.defect()
        } else {
            c.exclusion()
        };
        if let Some(reason) = excluded {
            if i == 0 && layout.method == Method::Rpba {
                return Err(IdentError::BadReference(reason));
            }
            dropped.push(DroppedConfiguration { index: i, reason });
        }
    }
    let usable = usable(data, opts.include_faulty);
    too_few(layout, usable.len())?;
    Ok(Selected { usable, dropped })
}

/// Builds the problem and evaluates it at `x0`; configurations where FK fails at the start are
/// dropped. With a noise model the residuals are then weighted by it.
fn start(
    layout: Layout,
    sel: &mut Selected,
    x0: &DVector<f64>,
    opts: &CalibrationOptions,
) -> Result<(Problem, DVector<f64>, DMatrix<f64>)> {
    loop {
        let u = &sel.usable;
        let mut p = Problem::new(layout, u.kappa.clone(), u.cam.clone(), opts);
        match p.eval_full(x0, opts.jacobian) {
            Ok((r, j)) => {
                let Some(noise) = &opts.noise else {
                    return Ok((p, r, j));
                };
                if !p.weigh_by_noise(x0, noise, &u.counts) {
                    return Err(IdentError::InvalidInput(
                        "the noise model gives a singular residual covariance (a zero σ?)".into(),
                    ));
                }
                let (mut r, mut j) = (r, j);
                p.whiten(&mut r, &mut j);
                return Ok((p, r, j));
            }
            Err((l, e)) => {
                if l == 0 && layout.method == Method::Rpba {
                    return Err(IdentError::Fk {
                        config: u.index[0],
                        source: e,
                    });
                }
                sel.dropped.push(DroppedConfiguration {
                    index: u.index[l],
                    reason: format!("forward kinematics failed at the starting parameters: {e}"),
                });
                sel.usable.remove(l);
                too_few(&layout, sel.usable.len())?;
            }
        }
    }
}

/// Identifiability at the start: the gauge-reduced Jacobian must have full column rank; otherwise the
/// error names the parameters dominating the unseen directions.
fn check_rank(
    layout: &Layout,
    red: &Reduction,
    j: &DMatrix<f64>,
    opts: &CalibrationOptions,
) -> Result<()> {
    let jr = red.reduce(j);
    let k = jr.ncols();
    let svd = jr.svd(false, true);
    let smax = svd.singular_values.max();
    let tol = opts.rank_tolerance * smax;
    let rank = svd.singular_values.iter().filter(|&&v| v > tol).count();
    if rank == k && smax.is_finite() && smax > 0.0 {
        return Ok(());
    }
    let names = layout.names();
    let mut weight = vec![0.0; layout.n()];
    if let Some(vt) = svd.v_t.as_ref() {
        for (row, &sv) in svd.singular_values.iter().enumerate() {
            if sv <= tol {
                let w = &red.q * vt.row(row).transpose();
                for (acc, v) in weight.iter_mut().zip(w.iter()) {
                    *acc += v * v;
                }
            }
        }
    }
    let mut unseen: Vec<String> = weight
        .iter()
        .enumerate()
        .filter(|(_, &w)| w > 0.1)
        .map(|(i, _)| names[i].clone())
        .collect();
    if unseen.is_empty() {
        if let Some((i, _)) = weight.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) {
            unseen.push(names[i].clone());
        }
    }
    Err(IdentError::RankDeficient {
        rank,
        expected: k,
        unseen,
    })
}

/// Where Levenberg–Marquardt ended.
struct LmEnd {
    x: DVector<f64>,
    j: DMatrix<f64>,
    cost_history: Vec<f64>,
    accepted: usize,
    convergence: Convergence,
}

/// Levenberg–Marquardt from (`x`, `r`, `j`) with Marquardt's diagonal damping.
#[allow(clippy::too_many_arguments)]
fn levenberg_marquardt(
    problem: &mut Problem,
    red: &Reduction,
    mut x: DVector<f64>,
    mut r: DVector<f64>,
    mut j: DMatrix<f64>,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> core::result::Result<LmEnd, EvalError> {
    let mut cost = r.norm_squared();
    let mut cost_history = vec![cost];
    let mut lambda = opts.initial_damping;
    let mut accepted = 0;
    let mut convergence = Convergence::IterationLimit;
    for iteration in 1..=opts.max_iterations {
        let jr = red.reduce(&j);
        let a = jr.transpose() * &jr;
        let g = jr.transpose() * &r;
        let mut damped = a.clone();
        for d in 0..damped.nrows() {
            damped[(d, d)] += lambda * a[(d, d)].max(1e-30);
        }
        let Some(chol) = damped.cholesky() else {
            lambda *= 10.0;
            continue;
        };
        let z = -chol.solve(&g);
        let x_new = &x + red.step(&z);
        let new_cost = match problem.eval(&x_new, false) {
            Ok(e) => e.r.norm_squared(),
            Err(_) => f64::INFINITY,
        };
        if new_cost < cost {
            let decrease = cost - new_cost;
            x = x_new;
            (r, j) = problem.eval_full(&x, opts.jacobian)?;
            cost = new_cost;
            cost_history.push(cost);
            accepted += 1;
            lambda = (lambda / 10.0).max(1e-15);
            progress(&Progress {
                iteration,
                cost,
                damping: lambda,
            });
            if decrease <= opts.cost_tolerance * cost.max(f64::MIN_POSITIVE) {
                convergence = Convergence::CostTolerance;
                break;
            }
            if z.norm() <= opts.step_tolerance {
                convergence = Convergence::StepTolerance;
                break;
            }
        } else {
            lambda *= 10.0;
            progress(&Progress {
                iteration,
                cost,
                damping: lambda,
            });
            if lambda > 1e12 {
                convergence = Convergence::NoFurtherDecrease;
                break;
            }
        }
    }
    Ok(LmEnd {
        x,
        j,
        cost_history,
        accepted,
        convergence,
    })
}

/// Identifiability at the solution: singular values and rank of the full scaled Jacobian, the
/// parameters with ≥ 5 % of their scaled unit vector in a gauge direction, the gauge descriptions.
struct Identifiability {
    singular_values: Vec<f64>,
    rank: usize,
    unidentifiable: Vec<String>,
    gauge_directions: Vec<String>,
}

fn identifiability(
    layout: &Layout,
    red: &Reduction,
    j: &DMatrix<f64>,
    opts: &CalibrationOptions,
) -> Identifiability {
    let names = layout.names();
    let sv = red.scaled(j).singular_values();
    let mut singular_values: Vec<f64> = sv.iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let smax = singular_values.first().copied().unwrap_or(0.0);
    let rank = singular_values
        .iter()
        .filter(|&&v| v > opts.rank_tolerance * smax)
        .count();
    // gauge projector diagonal in the scaled metric
    let unidentifiable = (0..layout.n())
        .filter(|&i| 1.0 - red.q.row(i).norm_squared() >= 0.05)
        .map(|i| names[i].clone())
        .collect();
    let gauge_directions = GAUGE_DESCRIPTIONS
        .iter()
        .map(|d| match layout.method {
            Method::Rpba => d.replace(", with sensor pose", ""),
            Method::Implicit => d.to_string(),
        })
        .collect();
    Identifiability {
        singular_values,
        rank,
        unidentifiable,
        gauge_directions,
    }
}

/// The fit at the end of one solve: per-block normalised residuals and the fit statistic.
struct Fit {
    /// (usable index, r_lᵀΣ_ll⁻¹r_l/6) per residual block.
    blocks: Vec<(usize, f64)>,
    chi2: f64,
    dof: usize,
}

impl Fit {
    fn statistic(&self) -> f64 {
        if self.blocks.is_empty() {
            f64::NAN
        } else {
            self.chi2 / self.dof.max(1) as f64
        }
    }

    /// The median normalised residual (≈ 0.891, the median of χ²₆/6, when the noise model holds).
    fn median(&self) -> f64 {
        let mut v: Vec<f64> = self.blocks.iter().map(|b| b.1).collect();
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(0.0)
    }

    /// Usable indices of the blocks, worst first.
    fn worst_first(&self) -> Vec<(usize, f64)> {
        let mut v = self.blocks.clone();
        v.sort_by(|a, b| b.1.total_cmp(&a.1));
        v
    }
}

fn assess(problem: &mut Problem, end: &LmEnd, free: usize) -> core::result::Result<Fit, EvalError> {
    let e = problem.eval(&end.x, false)?;
    let blocks = match e
        .raw
        .as_ref()
        .and_then(|raw| problem.normalized_blocks(raw))
    {
        Some(z) => z
            .into_iter()
            .enumerate()
            .map(|(k, v)| (problem.block_configuration(k), v))
            .collect(),
        None => Vec::new(),
    };
    Ok(Fit {
        blocks,
        chi2: e.r.norm_squared(),
        dof: e.r.len().saturating_sub(free),
    })
}

/// The configurations to blame for a bad fit: the rejected ones and the 5 worst, as data indices.
fn blame(fit: &Fit, used: &[usize], rejected: &[RejectedConfiguration]) -> Vec<usize> {
    let mut v: Vec<usize> = fit
        .worst_first()
        .iter()
        .take(5)
        .map(|&(l, _)| used[l])
        .collect();
    v.extend(rejected.iter().map(|r| r.index));
    v
}

/// The error for a fit that cannot be trusted, or `None`.
fn verdict(
    method: Method,
    fit: &Fit,
    end: &LmEnd,
    used: &[usize],
    rejected: &[RejectedConfiguration],
    opts: &CalibrationOptions,
) -> Option<IdentError> {
    let start = end.cost_history.first().copied().unwrap_or(f64::NAN);
    let last = end.cost_history.last().copied().unwrap_or(f64::NAN);
    let why = if !end.convergence.converged() {
        format!(
            "Levenberg–Marquardt did not converge in {} iterations (cost {start:.4e} → {last:.4e})",
            opts.max_iterations
        )
    } else if last > start || last.is_nan() {
        format!("the model explains the data worse than the start (cost {start:.4e} → {last:.4e})")
    } else if opts.noise.is_some()
        && (fit.statistic() > opts.max_fit_statistic || fit.statistic().is_nan())
    {
        format!(
            "the fit is inconsistent with the noise model after rejecting {} configuration(s) \
             (statistic > {}; median normalised residual {:.3})",
            rejected.len(),
            opts.max_fit_statistic,
            fit.median()
        )
    } else {
        return None;
    };
    Some(IdentError::Calibration {
        method,
        why,
        configurations: blame(fit, used, rejected),
        parameters: Vec::new(),
        fit_statistic: fit.statistic(),
    })
}

/// Calibrates `layout`'s parameters from `data`, starting at `x0`: solve, reject the worst gross
/// outlier and solve again from `x0` (at most `opts.max_rejections` times), then check the fit.
pub(super) fn solve(
    layout: Layout,
    data: &CalibrationData,
    x0: DVector<f64>,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let method = layout.method;
    if x0.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::InvalidInput(
            "starting parameters contain NaN or infinity".into(),
        ));
    }
    layout.kp(&x0).validate()?;
    let pooled;
    let opts = match (opts.noise_from_dwells, &opts.noise) {
        (false, _) => opts,
        (true, None) => {
            return Err(IdentError::InvalidInput(
                "noise_from_dwells needs a noise model (noise is None)".into(),
            ))
        }
        (true, Some(noise)) => {
            let (noise, _) = noise.with_dwell_covariance(data, opts.include_faulty)?;
            pooled = CalibrationOptions {
                noise: Some(noise),
                ..*opts
            };
            &pooled
        }
    };
    let mut sel = select(&layout, data, opts)?;
    let red = Reduction::new(
        &layout,
        &x0,
        opts.fix_sensor_pose && method == Method::Implicit,
    );
    let mut rejected: Vec<RejectedConfiguration> = Vec::new();
    let all = sel.usable.clone();
    let mut readmission_done = false;
    loop {
        let (mut problem, r, j) = start(layout, &mut sel, &x0, opts)?;
        check_rank(&layout, &red, &j, opts)?;
        let fk_error = |(l, source): EvalError| IdentError::Fk {
            config: sel.usable.index[l],
            source,
        };
        let end = levenberg_marquardt(&mut problem, &red, x0.clone(), r, j, opts, progress)
            .map_err(fk_error)?;
        let fit = assess(&mut problem, &end, red.q.ncols()).map_err(fk_error)?;
        if rejected.len() < opts.max_rejections {
            let used = &sel.usable.index;
            let found = outlier(&fit, opts).or_else(|| {
                verdict(method, &fit, &end, used, &rejected, opts)
                    .and_then(|_| deletion_outlier(layout, &sel, &x0, &red, opts))
            });
            if let Some((l, z, threshold)) = found {
                rejected.push(RejectedConfiguration {
                    index: sel.usable.index[l],
                    normalized_residual: z,
                    threshold,
                });
                sel.usable.remove(l);
                too_few(&layout, sel.usable.len())?;
                continue;
            }
        }
        let used = sel.usable.index.clone();
        if let Some(e) = verdict(method, &fit, &end, &used, &rejected, opts) {
            return Err(e);
        }
        if !rejected.is_empty() && !readmission_done {
            // A gross outlier pulls the first fits toward itself, so a good configuration can look
            // worse than the outlier and be rejected before it. Once the fit is accepted, each
            // rejected one is tested against it; those that fit it are taken back and the data
            // solved again (once: a configuration rejected again stays out).
            readmission_done = true;
            let back = readmitted(layout, &all, &used, &rejected, &x0, &end, &fit, &red, opts);
            if !back.is_empty() {
                rejected.retain(|r| !back.contains(&r.index));
                sel.usable = all.only(|i| used.contains(&i) || back.contains(&i));
                continue;
            }
        }
        let id = identifiability(&layout, &red, &end.j, opts);
        let x = &end.x;
        return Ok(CalibrationResult {
            method,
            params: layout.kp(x),
            reference: layout.reference,
            errors: layout.errors(x),
            target_in_effector: layout.target(x),
            sensor_in_base: layout.sensor(x),
            rank: id.rank,
            parameter_count: layout.n(),
            unidentifiable: id.unidentifiable,
            gauge_directions: id.gauge_directions,
            singular_values: id.singular_values,
            iterations: end.accepted,
            dropped: sel.dropped,
            normalized_residuals: fit.blocks.iter().map(|&(l, z)| (used[l], z)).collect(),
            fit_statistic: fit.statistic(),
            degrees_of_freedom: fit.dof,
            convergence: end.convergence,
            cost_history: end.cost_history,
            used,
            rejected,
        });
    }
}
