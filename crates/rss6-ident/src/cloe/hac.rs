//! The long-run covariance of CLOE's scores under residuals correlated in time,
//! for the sandwich standard deviations of [`super::CloeResult::relative_std`].

use nalgebra::{DMatrix, DVector};

/// Long-run covariance S = Σ_{|l|≤L} w_l Σ_k G_kᵀ γ(l) G_{k−l} of the scores Gᵀr, for residual frames
/// r_k (blocks of `block` consecutive rows, one camera frame each) that are stationary but correlated
/// in time: γ(l) = (1/n) Σ_k r_k r_{k−l}ᵀ is the residual's autocovariance (axes × axes) at lag l
/// frames, w_l = 1 − |l|/(L+1) Bartlett's weights (they keep the tapered autocovariance, and so S,
/// positive semi-definite). For white residuals S ≈ σ² GᵀG, and A⁻¹SA⁻¹ is the Wald covariance.
///
/// Why not Newey–West on the scores s_k = G_kᵀ r_k: at a least-squares optimum Σ_k s_k = 0, and when
/// a parameter's information comes from a window shorter than L (a stick–slip event, a start
/// transient) the lagged score products cancel its variance — on white noise the score estimator
/// gave 0.15–0.7 of the Wald σ for CLOE's friction and gain parameters. The residual autocovariance
/// is estimated from all n frames and hardly feels the p orthogonality constraints.
pub(crate) fn long_run_covariance(
    g: &DMatrix<f64>,
    r: &DVector<f64>,
    block: usize,
    lags: usize,
) -> DMatrix<f64> {
    let p = g.ncols();
    let b = block.max(1);
    let n = g.nrows() / b;
    let mut s = DMatrix::zeros(p, p);
    if n == 0 {
        return s;
    }
    let frame = |k: usize| r.rows(b * k, b);
    let mut tmp = DMatrix::zeros(b, p);
    for l in 0..=lags.min(n - 1) {
        let mut gamma = DMatrix::zeros(b, b);
        for k in l..n {
            gamma.ger(1.0 / n as f64, &frame(k), &frame(k - l), 1.0);
        }
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        let mut h = DMatrix::zeros(p, p);
        for k in l..n {
            tmp.gemm(1.0, &gamma, &g.rows(b * (k - l), b), 0.0);
            h.gemm_tr(1.0, &g.rows(b * k, b), &tmp, 1.0);
        }
        if l == 0 {
            s += h;
        } else {
            s += (&h + h.transpose()) * w;
        }
    }
    s
}

/// Newey–West long-run covariance of the per-frame scores s_k = G_kᵀ r_k (frames of `block` rows):
/// S = Σ_{|l|≤L} w_l Σ_k s_k s_{k−l}ᵀ with Bartlett's weights. It sees model error *where it
/// happens* (a start transient whose residual lines up with a parameter's columns), which the
/// stationary form of [`long_run_covariance`] averages over the run; but it cancels the variance of
/// a parameter seen in a window shorter than L (see there), so it is only used as the larger of
/// the two.
pub(crate) fn local_long_run_covariance(
    g: &DMatrix<f64>,
    r: &DVector<f64>,
    block: usize,
    lags: usize,
) -> DMatrix<f64> {
    let p = g.ncols();
    let b = block.max(1);
    let n = g.nrows() / b;
    let mut scores = DMatrix::zeros(n, p);
    for k in 0..n {
        let s = g.rows(b * k, b).tr_mul(&r.rows(b * k, b));
        scores.row_mut(k).copy_from(&s.transpose());
    }
    let mut s = scores.tr_mul(&scores);
    for l in 1..=lags.min(n.saturating_sub(1)) {
        let w = 1.0 - l as f64 / (lags as f64 + 1.0);
        let h = scores.rows(l, n - l).tr_mul(&scores.rows(0, n - l));
        s += (&h + h.transpose()) * w;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_distr::StandardNormal;

    /// Measured worst |σ ratio − 1| over the 20 draws: 0.118; bound 3× that.
    const WINDOW_WORST: f64 = 0.35;

    /// Sandwich variance of the mean of `r` (G = a column of ones, one row per block).
    fn sandwich_var_of_mean(r: &[f64], lags: usize) -> f64 {
        let n = r.len();
        let g = DMatrix::from_element(n, 1, 1.0);
        let s = long_run_covariance(&g, &DVector::from_column_slice(r), 1, lags);
        s[(0, 0)] / (n as f64 * n as f64)
    }

    #[test]
    fn white_residuals_give_the_wald_variance_and_ar1_the_long_run_one() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let n = 200_000;
        let white: Vec<f64> = (0..n).map(|_| rng.sample(StandardNormal)).collect();
        // White: n·var(mean) = 1 (measured 0.9994 with 0 lags, 0.990 with 30; bound 3× the worst).
        for lags in [0, 30] {
            let v = sandwich_var_of_mean(&white, lags) * n as f64;
            assert!((v - 1.0).abs() < 0.03, "lags {lags}: {v}");
        }
        // AR(1) with ρ = 0.5 and unit marginal variance: long-run variance (1 + ρ)/(1 − ρ) = 3;
        // 0 lags sees only the marginal 1.
        let rho: f64 = 0.5;
        let mut x = 0.0;
        let ar: Vec<f64> = white
            .iter()
            .map(|e| {
                x = rho * x + (1.0 - rho * rho).sqrt() * e;
                x
            })
            .collect();
        let v0 = sandwich_var_of_mean(&ar, 0) * n as f64;
        let v30 = sandwich_var_of_mean(&ar, 30) * n as f64;
        assert!((v0 - 1.0).abs() < 0.03, "{v0}");
        // Bartlett's weights at 30 lags lower it by 2/31 · ρ/(1−ρ)² = 0.129: expect 2.871
        // (measured 2.841; bound 3× that deviation).
        assert!((v30 - 2.871).abs() < 0.1, "{v30}");
    }

    #[test]
    fn the_local_form_sees_a_transient_the_stationary_one_averages_away() {
        // A parameter seen in frames 0..60 of 3000, and a slow residual (model error) only there;
        // white noise elsewhere. Measured local / stationary variance ratio 53 (bound a third of
        // that): the stationary form spreads the transient's autocovariance over the whole run.
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let n = 3000;
        let g = DMatrix::from_fn(n, 1, |k, _| if k < 60 { 1.0 } else { 0.0 });
        let mut r = DVector::from_fn(n, |_, _| 0.1 * rng.sample::<f64, _>(StandardNormal));
        for k in 0..60 {
            // A slow wave with a non-zero mean over each half of the window.
            r[k] += if k < 30 { 1.0 } else { -1.0 };
        }
        let stationary = long_run_covariance(&g, &r, 1, 30)[(0, 0)];
        let local = local_long_run_covariance(&g, &r, 1, 30)[(0, 0)];
        assert!(local > 18.0 * stationary, "{local} vs {stationary}");
        // On white residuals and a column spread over the run the local form is near σ² GᵀG
        // (measured 1.11; bound 3× the deviation).
        let e = DVector::from_fn(n, |_, _| rng.sample::<f64, _>(StandardNormal));
        let g2 = DMatrix::from_fn(n, 1, |k, _| (k as f64 * 0.01).sin());
        let wald = g2.column(0).norm_squared();
        let l2 = local_long_run_covariance(&g2, &e, 1, 30)[(0, 0)] / wald;
        assert!((l2 - 1.0).abs() < 0.35, "{l2}");
    }

    #[test]
    fn blocks_are_frames_of_correlated_axes() {
        // Frames r_0 = (1, 1), r_1 = (−1, 1): γ(0) = I, γ(1) = ½ r_1 r_0ᵀ = ½[−1 −1; 1 1].
        // G_0 = (1, 2)ᵀ, G_1 = (3, 4)ᵀ: lag 0 gives 1 + 4 + 9 + 16 = 30; lag 1 G_1ᵀ γ(1) G_0 = 1.5,
        // weighted ½ and counted twice.
        let g = DMatrix::from_row_slice(4, 1, &[1.0, 2.0, 3.0, 4.0]);
        let r = DVector::from_column_slice(&[1.0, 1.0, -1.0, 1.0]);
        let s = long_run_covariance(&g, &r, 2, 0);
        assert!((s[(0, 0)] - 30.0).abs() < 1e-12);
        let s1 = long_run_covariance(&g, &r, 2, 1);
        assert!((s1[(0, 0)] - 31.5).abs() < 1e-12);
    }

    #[test]
    fn information_from_a_short_window_keeps_its_variance() {
        // One parameter seen only in 20 of 2000 frames, white residuals orthogonal to it (a least-
        // squares optimum): the sandwich must stay near the Wald variance (Σ_k g_k² σ²)⁻¹ — the
        // score estimator with 30 lags collapsed here.
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let n = 2000;
        let g = DMatrix::from_fn(n, 1, |k, _| {
            if (900..920).contains(&k) {
                ((k - 900) as f64 * 0.3).sin() + 1.5
            } else {
                0.0
            }
        });
        let mut worst: f64 = 0.0;
        for _ in 0..20 {
            let e = DVector::from_fn(n, |_, _| rng.sample::<f64, _>(StandardNormal));
            let beta = g.column(0).dot(&e) / g.column(0).norm_squared();
            let r = &e - g.column(0) * beta;
            let a = g.column(0).norm_squared();
            let s = long_run_covariance(&g, &r, 1, 30);
            let ratio = (s[(0, 0)] / a / (r.norm_squared() / n as f64)).sqrt();
            worst = worst.max((ratio - 1.0).abs());
        }
        assert!(worst < WINDOW_WORST, "{worst}");
    }
}
