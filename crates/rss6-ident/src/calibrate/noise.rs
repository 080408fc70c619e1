//! Noise weighting of the residuals: the covariance of Φ implied by Table 4.1's noise on the dwell
//! means, propagated to first order, and the whitening that makes ‖W·Φ‖² a χ² variable.
//!
//! Each configuration's means carry the noise of one sample divided by the number of samples averaged
//! (κ: σ_κ²/n_κ per joint; ᶜχ_t: σ_p²/n_c per position and σ_a²/n_c per angle component). RPBA's
//! residual Φ_R^l depends on the reference configuration's κ⁰, ᶜχ_t⁰ as well as on its own, so its
//! residuals are correlated through the reference and are whitened with the Cholesky factor of the
//! full covariance; the implicit residuals of different configurations are independent and are
//! whitened block by block.

use crate::closure::{fk_with_derivative, leg_closure, FkDerivative};
use crate::error::IdentError;
use crate::se3::{iso, pose_difference};
use nalgebra::{DMatrix, DVector};
use rss6_core::{isometry_to_pose, KinematicParams, Mat6, Vec6};

/// Noise of one measurement sample (Table 4.1 by default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasurementNoise {
    /// σ of one potentiometer sample (bit); Table 4.1: 0.2233.
    pub kappa: f64,
    /// σ of one camera position component (m); Table 4.1: 0.0096 mm.
    pub position: f64,
    /// σ of one camera angle (rad); Table 4.1: 0.0261°.
    pub angle: f64,
    /// Covariance of one camera frame's ᶜχ_t [x, y, z, α, β, γ] (m², m·rad, rad²). When set it
    /// replaces `position` and `angle`, so the correlations between components count (a stereo
    /// head's pose noise is strongly correlated between x and β, y and α); see
    /// [`MeasurementNoise::with_dwell_covariance`]. Default `None`.
    pub pose_covariance: Option<Mat6>,
}

impl Default for MeasurementNoise {
    /// Table 4.1.
    fn default() -> Self {
        MeasurementNoise {
            kappa: rss6_sim::POT_NOISE_BITS,
            position: rss6_sim::CMM_POSITION_NOISE,
            angle: rss6_sim::CMM_ANGLE_NOISE,
            pose_covariance: None,
        }
    }
}

impl MeasurementNoise {
    /// Diagonal covariance of a dwell's mean κ (bit²) from `n` samples.
    fn kappa_var(&self, n: f64) -> Vec6 {
        Vec6::repeat(self.kappa * self.kappa / n)
    }

    /// Covariance of a dwell's mean ᶜχ_t (m², m·rad, rad²) from `n` frames.
    fn pose_var(&self, n: f64) -> Mat6 {
        match &self.pose_covariance {
            Some(c) => c / n,
            None => {
                let (p, a) = (
                    self.position * self.position / n,
                    self.angle * self.angle / n,
                );
                Mat6::from_diagonal(&Vec6::new(p, p, p, a, a, a))
            }
        }
    }

    /// This noise with `pose_covariance` pooled from the dwells of `data` that a calibration would
    /// use (no defect, no failed check unless `include_faulty`): Σ = Σ_l S_l·(n_l − 1) / Σ_l (n_l − 1)
    /// over the configurations whose sample covariance S_l of n_l ≥ 2 frames was recorded
    /// ([`crate::ConfigurationData::sensor_pose_cov`]). Returns the pooled degrees of freedom too.
    ///
    /// Errors: [`IdentError::InvalidInput`] when no dwell recorded a covariance (data from arrays
    /// or an older log), the pooled covariance is not finite and positive definite, or it has
    /// fewer than 6 degrees of freedom.
    pub fn with_dwell_covariance(
        mut self,
        data: &crate::CalibrationData,
        include_faulty: bool,
    ) -> Result<(Self, f64), IdentError> {
        let mut sum = Mat6::zeros();
        let mut dof = 0.0;
        for c in &data.configurations {
            let excluded = if include_faulty {
                c.defect()
            } else {
                c.exclusion()
            };
            if let (None, Some(cov)) = (excluded, &c.sensor_pose_cov) {
                if c.camera_frames >= 2 {
                    let w = f64::from(c.camera_frames - 1);
                    sum += Mat6::from_fn(|r, k| cov[r][k]) * w;
                    dof += w;
                }
            }
        }
        if dof == 0.0 {
            return Err(IdentError::InvalidInput(
                "the noise from the dwells needs their camera covariance, and no usable dwell \
                 recorded one (data from arrays or a log written before it was recorded): use \
                 Table 4.1's noise"
                    .into(),
            ));
        }
        let pooled = sum / dof;
        if dof < 6.0 || !pooled.iter().all(|v| v.is_finite()) || pooled.cholesky().is_none() {
            return Err(IdentError::InvalidInput(format!(
                "the dwells' pooled camera covariance ({dof} degrees of freedom) is not positive \
                 definite: too few frames, or a camera that repeats its frames"
            )));
        }
        self.pose_covariance = Some(pooled);
        Ok((self, dof))
    }
}

/// The whitening of a residual vector: W = L⁻¹ with Σ = L·Lᵀ.
#[derive(Debug, Clone)]
pub(super) struct Whitening {
    /// Full lower Cholesky factor (RPBA), or `None` when the blocks are independent.
    full: Option<DMatrix<f64>>,
    /// Lower Cholesky factor of each configuration's 6 × 6 marginal block Σ_ll.
    blocks: Vec<Mat6>,
}

impl Whitening {
    /// W·r.
    pub(super) fn vector(&self, r: &mut DVector<f64>) {
        match &self.full {
            Some(l) => {
                l.solve_lower_triangular_mut(r);
            }
            None => {
                for (k, l) in self.blocks.iter().enumerate() {
                    let mut b = Vec6::from_iterator(r.rows(6 * k, 6).iter().copied());
                    l.solve_lower_triangular_mut(&mut b);
                    r.rows_mut(6 * k, 6).copy_from(&b);
                }
            }
        }
    }

    /// W·J.
    pub(super) fn matrix(&self, j: &mut DMatrix<f64>) {
        match &self.full {
            Some(l) => {
                l.solve_lower_triangular_mut(j);
            }
            None => {
                for (k, l) in self.blocks.iter().enumerate() {
                    let mut b = j.rows(6 * k, 6).into_owned();
                    l.solve_lower_triangular_mut(&mut b);
                    j.rows_mut(6 * k, 6).copy_from(&b);
                }
            }
        }
    }

    /// r_lᵀ Σ_ll⁻¹ r_l / 6 for every residual block of the unweighted residual `raw`: ≈ 1 when the
    /// block is explained to within the noise (its marginal, so the shared reference of RPBA counts).
    pub(super) fn normalized_blocks(&self, raw: &DVector<f64>) -> Vec<f64> {
        self.blocks
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let mut b = Vec6::from_iterator(raw.rows(6 * k, 6).iter().copied());
                if l.solve_lower_triangular_mut(&mut b) {
                    b.norm_squared() / 6.0
                } else {
                    f64::INFINITY
                }
            })
            .collect()
    }
}

const H: f64 = 1e-7;

/// Central-difference 6 × 6 derivative of `f` at `x` (pose-sized input and output).
fn jac6(x: &Vec6, f: &dyn Fn(&Vec6) -> Vec6) -> Mat6 {
    let mut j = Mat6::zeros();
    for k in 0..6 {
        let mut xp = *x;
        let mut xm = *x;
        xp[k] += H;
        xm[k] -= H;
        j.set_column(k, &((f(&xp) - f(&xm)) / (2.0 * H)));
    }
    j
}

/// ∂χ/∂κ (6 × 6) of forward kinematics: θ_i = η_i κ_i + Δθ_i, so it is η_i times the Δθ_i column.
fn fk_kappa_derivative(kp: &KinematicParams, d_b: &crate::closure::Mat6x60) -> Mat6 {
    Mat6::from_fn(|r, c| d_b[(r, 54 + c)] * kp.eta[c])
}

fn var_sum(a: &Mat6, var: &Mat6) -> Mat6 {
    a * var * a.transpose()
}

/// Data of the problem that the covariance needs.
pub(super) struct NoiseInput<'a> {
    pub(super) kp: &'a KinematicParams,
    pub(super) sensor: Vec6,
    pub(super) target: Vec6,
    pub(super) kappa: &'a [Vec6],
    pub(super) cam: &'a [Vec6],
    pub(super) guesses: &'a [Vec6],
    /// RPBA: FK and its derivative at every configuration, if already computed at these parameters.
    pub(super) fk: Option<&'a [FkDerivative]>,
    /// Samples averaged (κ, camera) per configuration.
    pub(super) counts: &'a [(f64, f64)],
}

/// RPBA: Φ^l = Δ(L(ᶜM_t⁰⁻¹ᶜM_t^l), L(X⁰⁻¹X^l)) with X^l = FK(κ^l)·ᴱM_t; the covariance of all
/// residuals (6(m − 1) square) from the noise of κ⁰, ᶜχ_t⁰ (shared) and κ^l, ᶜχ_t^l.
pub(super) fn rpba_whitening(
    input: &NoiseInput<'_>,
    noise: &MeasurementNoise,
) -> Option<Whitening> {
    let m = input.kappa.len();
    let mt = iso(&input.target);
    let computed;
    let fks = match input.fk {
        Some(f) => f,
        None => {
            computed = (0..m)
                .map(|l| fk_with_derivative(input.kp, &input.kappa[l], &input.guesses[l]).ok())
                .collect::<Option<Vec<_>>>()?;
            computed.as_slice()
        }
    };
    let (c0, f0) = (input.cam[0], fks[0].pose);
    let var_c0 = noise.pose_var(input.counts[0].1.max(1.0));
    let var_k0 = Mat6::from_diagonal(&noise.kappa_var(input.counts[0].0.max(1.0)));
    let dk0 = fk_kappa_derivative(input.kp, &fks[0].d_b);
    let n = 6 * (m - 1);
    // shared part: G0 = [∂Φ/∂ᶜχ_t⁰, ∂Φ/∂κ⁰] stacked over l
    let mut g0 = DMatrix::zeros(n, 12);
    let mut sigma = DMatrix::zeros(n, n);
    let mut own = Vec::with_capacity(m - 1);
    for (l, fk_l) in fks.iter().enumerate().skip(1) {
        let (cl, fl) = (input.cam[l], fk_l.pose);
        let model =
            |f0: &Vec6, fl: &Vec6| isometry_to_pose(&((iso(f0) * mt).inverse() * iso(fl) * mt));
        let rel = |c0: &Vec6, cl: &Vec6| isometry_to_pose(&(iso(c0).inverse() * iso(cl)));
        let pp = model(&f0, &fl);
        let rel_l = rel(&c0, &cl);
        let d_c0 = jac6(&c0, &|c| pose_difference(&rel(c, &cl), &pp));
        let d_cl = jac6(&cl, &|c| pose_difference(&rel(&c0, c), &pp));
        let d_f0 = jac6(&f0, &|f| pose_difference(&rel_l, &model(f, &fl)));
        let d_fl = jac6(&fl, &|f| pose_difference(&rel_l, &model(&f0, f)));
        let d_k0 = d_f0 * dk0;
        let d_kl = d_fl * fk_kappa_derivative(input.kp, &fk_l.d_b);
        let row = 6 * (l - 1);
        g0.view_mut((row, 0), (6, 6)).copy_from(&d_c0);
        g0.view_mut((row, 6), (6, 6)).copy_from(&d_k0);
        let var_cl = noise.pose_var(input.counts[l].1.max(1.0));
        let var_kl = Mat6::from_diagonal(&noise.kappa_var(input.counts[l].0.max(1.0)));
        let s_own = var_sum(&d_cl, &var_cl) + var_sum(&d_kl, &var_kl);
        let s_shared = var_sum(&d_c0, &var_c0) + var_sum(&d_k0, &var_k0);
        own.push(s_own + s_shared);
        sigma.view_mut((row, row), (6, 6)).copy_from(&s_own);
    }
    let mut var0 = DMatrix::zeros(12, 12);
    var0.view_mut((0, 0), (6, 6)).copy_from(&var_c0);
    var0.view_mut((6, 6), (6, 6)).copy_from(&var_k0);
    sigma += &g0 * var0 * g0.transpose();
    let full = sigma.cholesky()?.l();
    let blocks = own
        .into_iter()
        .map(|s| s.cholesky().map(|c| c.l()))
        .collect::<Option<Vec<_>>>()?;
    Some(Whitening {
        full: Some(full),
        blocks,
    })
}

/// Implicit: Φ_I^l = closure(κ^l, ᴼM_C·ᶜM_t^l·ᴱM_t⁻¹); independent 6 × 6 blocks from the noise of κ^l
/// and ᶜχ_t^l.
pub(super) fn implicit_whitening(
    input: &NoiseInput<'_>,
    noise: &MeasurementNoise,
) -> Option<Whitening> {
    let m_oc = iso(&input.sensor);
    let mt_inv = iso(&input.target).inverse();
    let blocks = (0..input.kappa.len())
        .map(|l| {
            let kappa = input.kappa[l];
            let phi = |c: &Vec6| leg_closure(input.kp, &kappa, &(m_oc * iso(c) * mt_inv)).phi;
            let d_c = jac6(&input.cam[l], &phi);
            let c = leg_closure(input.kp, &kappa, &(m_oc * iso(&input.cam[l]) * mt_inv));
            let d_k = Mat6::from_fn(|r, j| c.d_b[(r, 54 + j)] * input.kp.eta[j]);
            let var_c = noise.pose_var(input.counts[l].1.max(1.0));
            let var_k = Mat6::from_diagonal(&noise.kappa_var(input.counts[l].0.max(1.0)));
            (var_sum(&d_c, &var_c) + var_sum(&d_k, &var_k))
                .cholesky()
                .map(|c| c.l())
        })
        .collect::<Option<Vec<_>>>()?;
    Some(Whitening { full: None, blocks })
}
