//! One Levenberg–Marquardt step of CLOE ([`super::estimator`]): the damped Gauss–Newton solve,
//! the first-order optimality test and the *settled* stopping rule.

use nalgebra::{DMatrix, DVector};
use std::collections::VecDeque;

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

/// The damping after the step at `lambda` was rejected: 10λ, or the first 10ᵏλ whose step differs
/// from the rejected `step` by more than 1 % of its norm (λ at most 10¹³). Where λD is still small
/// beside GᵀG (λ far below every eigenvalue that matters, or components clipped to
/// `max_log_step`) the damped step is the rejected one again, and simulating it would only be
/// rejected again: after many accepted steps λ sits at 10⁻¹², twelve decades below the damping a
/// kinked (stick–slip) cost needs. Only solves of the small normal equations, no simulation.
pub(super) fn next_lambda(
    gtg: &DMatrix<f64>,
    gtr: &DVector<f64>,
    lambda: f64,
    max_log_step: f64,
    step: &DVector<f64>,
) -> f64 {
    let mut l = lambda * 10.0;
    while l <= 1e12 {
        match lm_step(gtg, gtr, l, max_log_step) {
            Some(s) if (&s - step).norm() <= 1e-2 * step.norm() => l *= 10.0,
            _ => return l,
        }
    }
    l
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

/// The *settled* rule ([`super::CloeStop::Settled`]): over the last `steps` accepted steps Φ fell
/// by less than one residual variance in all (a likelihood ratio below e^0.5) and no estimated
/// quantity moved by more than half its σ — LM creeping along the kinks of a piecewise-smooth
/// (stick–slip) cost, with nothing a test on the data could see.
pub(super) struct Settle {
    steps: usize,
    /// (Φ, ψ) of the last `steps` + 1 accepted iterates, oldest first.
    window: VecDeque<(f64, Vec<f64>)>,
}

impl Settle {
    /// The rule looking back over `steps` accepted steps (0: never settled), from the start (Φ, ψ).
    pub(super) fn new(steps: usize, cost: f64, psi: &[f64]) -> Self {
        Settle {
            steps,
            window: VecDeque::from([(cost, psi.to_vec())]),
        }
    }

    /// Records an accepted iterate (Φ, ψ) and says whether the estimation has settled, with the
    /// residual variance Φ/(N − p) and `sigma[k]` the σ of ψ[`active[k]`] (`None`, no σ: not settled).
    pub(super) fn push_and_check(
        &mut self,
        cost: f64,
        psi: &[f64],
        variance: f64,
        active: &[usize],
        sigma: Option<&[f64]>,
    ) -> bool {
        if self.steps == 0 {
            return false;
        }
        self.window.push_back((cost, psi.to_vec()));
        if self.window.len() > self.steps + 1 {
            self.window.pop_front();
        }
        let (then, psi_then) = &self.window[0];
        let Some(sigma) = sigma else { return false };
        self.window.len() == self.steps + 1
            && then - cost < variance
            && active
                .iter()
                .zip(sigma)
                .all(|(&j, s)| (psi[j] - psi_then[j]).abs() <= 0.5 * s)
    }
}

#[cfg(test)]
mod tests {
    use super::{lm_step, next_lambda, Settle};
    use nalgebra::{DMatrix, DVector};

    #[test]
    #[allow(clippy::unwrap_used)]
    fn after_a_rejection_the_damping_skips_the_decades_that_leave_the_step_as_it_was() {
        // Diagonal (D = diag): every component is scaled by 1/(1 + λ), so the step moves by more
        // than 1 % only past λ = 1/99: from 10⁻¹², the next damping worth a simulation is 10⁻¹.
        let gtg = DMatrix::from_diagonal(&DVector::from_vec(vec![1e4, 1.0]));
        let gtr = DVector::from_vec(vec![1.0, 0.1]);
        let step = |l| lm_step(&gtg, &gtr, l, 10.0).unwrap();
        let l = next_lambda(&gtg, &gtr, 1e-12, 10.0, &step(1e-12));
        assert!((l / 1e-1 - 1.0).abs() < 1e-9, "λ = {l:e}");
        // Where every decade changes the step: 10λ, as before.
        assert!((next_lambda(&gtg, &gtr, 1.0, 10.0, &step(1.0)) / 10.0 - 1.0).abs() < 1e-12);
        // A component clipped at max_log_step stays clipped: those decades are skipped too.
        let big = DVector::from_vec(vec![1e3, 1e3]);
        let clipped = |l| lm_step(&gtg, &big, l, 0.5).unwrap();
        let l = next_lambda(&gtg, &big, 1e-12, 0.5, &clipped(1e-12));
        assert!((clipped(l) - clipped(1e-12)).norm() > 1e-2 * clipped(1e-12).norm());
        assert!((clipped(l / 10.0) - clipped(1e-12)).norm() <= 1e-2 * clipped(1e-12).norm());
    }

    /// Five accepted steps of `drop` each (Φ in units of a residual variance of 1), ψ[0] moving by
    /// `move_` per step with σ = 1: whether the rule says settled after each.
    fn run(drop: f64, move_: f64, steps: usize) -> Vec<bool> {
        let mut s = Settle::new(steps, 100.0, &[0.0, 0.0]);
        (1..=7)
            .map(|k| {
                let psi = [move_ * k as f64, 0.0];
                s.push_and_check(
                    100.0 - drop * k as f64,
                    &psi,
                    1.0,
                    &[0, 1],
                    Some(&[1.0, 1.0]),
                )
            })
            .collect()
    }

    #[test]
    fn creeping_settles_once_the_window_is_full_and_only_then() {
        // 0.15 variance and 0.05 σ per step: 0.75 and 0.25 over five steps.
        assert_eq!(
            run(0.15, 0.05, 5),
            [false, false, false, false, true, true, true]
        );
    }

    #[test]
    fn a_visible_drop_or_a_move_of_half_a_sigma_is_not_settled() {
        // 0.25 variance per step: 1.25 over five steps, a drop a test could see.
        assert!(run(0.25, 0.0, 5).iter().all(|s| !s));
        // 0.11 σ per step: 0.55 σ over five steps.
        assert!(run(0.0, 0.11, 5).iter().all(|s| !s));
        // The rule turned off.
        assert!(run(0.0, 0.0, 0).iter().all(|s| !s));
    }
}
