//! One Levenberg–Marquardt step of CLOE ([`super::estimator`]): the damped Gauss–Newton solve
//! and the first-order optimality test.

use nalgebra::{DMatrix, DVector};

/// The step δ of (GᵀG + λD) δ = Gᵀr, D = Marquardt's scaling diag(GᵀG) floored at 10⁻⁸ of its
/// largest entry (so that nearly flat directions are damped too), each component clipped to
/// ±`max_log_step`: no quantity changes by more than a factor e^max_log_step per iteration (flat
/// directions of a short run would otherwise throw a log-parameter towards 0 or ∞). `None` if the
/// damped matrix is not positive definite.
pub(super) fn lm_step(
    gtg: &DMatrix<f64>,
    gtr: &DVector<f64>,
    lambda: f64,
    max_log_step: f64,
) -> Option<DVector<f64>> {
    let n = gtg.nrows();
    let top = (0..n).map(|k| gtg[(k, k)]).fold(0.0, f64::max);
    let mut lhs = gtg.clone();
    for k in 0..n {
        lhs[(k, k)] += lambda * gtg[(k, k)].max(1e-8 * top).max(f64::MIN_POSITIVE);
    }
    let mut step = lhs.cholesky()?.solve(gtr);
    for d in step.iter_mut() {
        *d = d.clamp(-max_log_step, max_log_step);
    }
    Some(step)
}

/// ψ with `step` added to its `active` components.
pub(super) fn shifted(psi: &[f64], active: &[usize], step: &DVector<f64>) -> Vec<f64> {
    let mut trial = psi.to_vec();
    for (k, &j) in active.iter().enumerate() {
        trial[j] += step[k];
    }
    trial
}

/// max_k |g_kᵀ r| / (‖g_k‖ ‖r‖) ≤ tol: the residual is orthogonal to every column.
pub(super) fn optimal(g: &DMatrix<f64>, r: &DVector<f64>, tol: f64) -> bool {
    let rn = r.norm();
    if rn == 0.0 {
        return true;
    }
    g.column_iter().all(|c| {
        let cn = c.norm();
        cn == 0.0 || (c.dot(r) / (cn * rn)).abs() <= tol
    })
}
