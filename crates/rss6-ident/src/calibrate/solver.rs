//! Levenberg–Marquardt on a [`Problem`] in the Table 4.2-scaled, gauge-reduced parameters, with the
//! identifiability checks before and after.

use super::min_configurations;
use super::options::{CalibrationOptions, Progress};
use super::problem::{usable, EvalError, Problem};
use super::result::{CalibrationResult, DroppedConfiguration};
use crate::data::CalibrationData;
use crate::error::{IdentError, Method, Result};
use crate::model::{Layout, GAUGE_DESCRIPTIONS, N_GAUGE};
use nalgebra::{DMatrix, DVector};
use rss6_core::Vec6;

/// The usable configurations of a problem and where they came from.
struct Selected {
    kappa: Vec<Vec6>,
    cam: Vec<Vec6>,
    /// Data index of each usable configuration.
    used: Vec<usize>,
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

/// Configurations with a defect (NaN, missing frames) are dropped; a bad reference is an error.
fn select(layout: &Layout, data: &CalibrationData) -> Result<Selected> {
    let mut dropped = Vec::new();
    for (i, c) in data.configurations.iter().enumerate() {
        if let Some(reason) = c.defect() {
            if i == 0 && layout.method == Method::Rpba {
                return Err(IdentError::BadReference(reason));
            }
            dropped.push(DroppedConfiguration { index: i, reason });
        }
    }
    let (kappa, cam, used) = usable(data);
    too_few(layout, used.len())?;
    Ok(Selected {
        kappa,
        cam,
        used,
        dropped,
    })
}

/// Builds the problem and evaluates it at `x0`; configurations where FK fails at the start are dropped.
fn start(
    layout: Layout,
    sel: &mut Selected,
    x0: &DVector<f64>,
    opts: &CalibrationOptions,
) -> Result<(Problem, DVector<f64>, DMatrix<f64>)> {
    loop {
        let mut p = Problem::new(layout, sel.kappa.clone(), sel.cam.clone(), opts);
        match p.eval_full(x0, opts.jacobian) {
            Ok((r, j)) => return Ok((p, r, j)),
            Err((l, e)) => {
                if l == 0 && layout.method == Method::Rpba {
                    return Err(IdentError::Fk {
                        config: sel.used[0],
                        source: e,
                    });
                }
                sel.dropped.push(DroppedConfiguration {
                    index: sel.used[l],
                    reason: format!("forward kinematics failed at the starting parameters: {e}"),
                });
                sel.kappa.remove(l);
                sel.cam.remove(l);
                sel.used.remove(l);
                too_few(&layout, sel.used.len())?;
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
            if decrease <= opts.cost_tolerance * cost.max(f64::MIN_POSITIVE)
                || z.norm() <= opts.step_tolerance
            {
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
                break;
            }
        }
    }
    Ok(LmEnd {
        x,
        j,
        cost_history,
        accepted,
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

/// Calibrates `layout`'s parameters from `data`, starting at `x0`.
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
    let mut sel = select(&layout, data)?;
    let (mut problem, r, j) = start(layout, &mut sel, &x0, opts)?;
    let red = Reduction::new(
        &layout,
        &x0,
        opts.fix_sensor_pose && method == Method::Implicit,
    );
    check_rank(&layout, &red, &j, opts)?;
    let end = levenberg_marquardt(&mut problem, &red, x0, r, j, opts, progress).map_err(
        |(l, source)| IdentError::Fk {
            config: sel.used[l],
            source,
        },
    )?;
    let id = identifiability(&layout, &red, &end.j, opts);
    let x = end.x;
    Ok(CalibrationResult {
        method,
        params: layout.kp(&x),
        reference: layout.reference,
        errors: layout.errors(&x),
        target_in_effector: layout.target(&x),
        sensor_in_base: layout.sensor(&x),
        cost_history: end.cost_history,
        rank: id.rank,
        parameter_count: layout.n(),
        unidentifiable: id.unidentifiable,
        gauge_directions: id.gauge_directions,
        singular_values: id.singular_values,
        iterations: end.accepted,
        dropped: sel.dropped,
        used: sel.used,
    })
}
