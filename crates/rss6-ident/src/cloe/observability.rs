//! How well the closed loop shows A on a trajectory: eq. 5.13's O_in and the condition number of
//! the output sensitivity CLOE works with — what the camera sees through the loop — beside the
//! torque regressor's that the excitation design maximises (issue 13: "compare both").

use nalgebra::{DMatrix, DVector, Matrix6, Vector6};
use rss6_core::Vec6;

use super::config::{LoopConfig, LoopParams};
use super::consistent::{Consistent, N_PSI};
use super::options::CloeOptions;
use crate::error::{IdentError, Result};
use crate::excitation::{base_columns, observability_of};
use rss6_ctrl::Trajectory;

/// The closed loop's observability of A on one trajectory ([`output_observability`]).
#[derive(Debug, Clone, PartialEq)]
pub struct OutputObservability {
    /// O_in (eq. 5.13: geometric mean of the singular values over √frames) of the identifiable
    /// columns of the noise-weighted output sensitivity ∂(χ_s/σ)/∂log q: dimensionless, so the
    /// masses, inertias, friction and gains count alike.
    pub o_in: f64,
    /// Condition number of the same columns.
    pub condition: f64,
    /// The identifiable quantities (names of [`Consistent::names`]) by the pivoted QR at the
    /// options' threshold, the held ones left out.
    pub identifiable: Vec<String>,
    /// Camera frames of the simulated run (the rows are 6 per frame).
    pub frames: usize,
    /// Per identifiable quantity (same order), the relative standard deviation its estimate would
    /// have from these frames with white noise of the given σ: √diag((GᵀG)⁻¹) of its log — the
    /// Cramér–Rao bound CLOE's Wald σ reaches at this point; `f64::INFINITY` if GᵀG is singular.
    pub relative_std: Vec<f64>,
}

/// The noise-weighted sensitivity G (6 × frames rows, [`N_PSI`] columns) of the loop's camera
/// poses to CLOE's log-parameters ψ at `psi`, each frame's 6 rows whitened by `whiten`
/// ([`whitening`]: diag(1/σ) by default): the matrix whose columns CLOE's identifiability analysis
/// and Gauss–Newton steps use.
pub(super) fn weighted_sensitivity(
    jacobian: &DMatrix<f64>,
    frames: &[usize],
    dadpsi: &DMatrix<f64>,
    whiten: &Matrix6<f64>,
) -> DMatrix<f64> {
    let w = DMatrix::from_column_slice(6, 6, whiten.as_slice());
    let mut g = DMatrix::zeros(6 * frames.len(), N_PSI);
    for (k, &s) in frames.iter().enumerate() {
        let rows = jacobian.rows(6 * s, 6) * dadpsi;
        g.rows_mut(6 * k, 6).copy_from(&(&w * rows));
    }
    g
}

/// The residual weights 1/σ of the pose axes from `noise` = [position (m), angle (rad)].
pub(super) fn noise_weight(noise: [f64; 2]) -> Result<[f64; 6]> {
    let [sp, sa] = noise;
    if !(sp > 0.0 && sa > 0.0 && sp.is_finite() && sa.is_finite()) {
        return Err(IdentError::InvalidInput(
            "noise std must be finite and > 0".into(),
        ));
    }
    Ok([1.0 / sp, 1.0 / sp, 1.0 / sp, 1.0 / sa, 1.0 / sa, 1.0 / sa])
}

/// The residual's whitening W (one camera frame's 6 rows): with a frame covariance Σ
/// ([`CloeOptions::noise_covariance`]), W = L⁻¹ for Σ = L·Lᵀ, so W·Σ·Wᵀ = I and the weighted output
/// error is Σ_k d_kᵀ Σ⁻¹ d_k (generalised least squares over the axes); without, diag(1/σ) from
/// [`CloeOptions::noise`].
pub(super) fn whitening(options: &CloeOptions) -> Result<Matrix6<f64>> {
    let Some(c) = &options.noise_covariance else {
        let w = noise_weight(options.noise)?;
        return Ok(Matrix6::from_diagonal(&Vector6::from_row_slice(&w)));
    };
    let m = Matrix6::from_fn(|i, j| c[i][j]);
    let scale = m.amax();
    if !m.iter().all(|v| v.is_finite()) || scale == 0.0 || (m - m.transpose()).amax() > 1e-9 * scale
    {
        return Err(IdentError::InvalidInput(
            "the noise covariance must be finite, non-zero and symmetric".into(),
        ));
    }
    m.cholesky()
        .and_then(|ch| ch.l().try_inverse())
        .filter(|w| w.iter().all(|v| v.is_finite()))
        .ok_or_else(|| {
            IdentError::InvalidInput("the noise covariance must be positive definite".into())
        })
}

/// The frames' χ_m − χ_s from their whitened residual (6 rows each): W⁻¹ per frame.
pub(super) fn unweighted(residual: &DVector<f64>, whiten: &Matrix6<f64>) -> Vec<Vec6> {
    let Some(l) = whiten.try_inverse() else {
        return Vec::new();
    };
    (0..residual.len() / 6)
        .map(|k| l * Vec6::from_column_slice(residual.rows(6 * k, 6).as_slice()))
        .collect()
}

/// The quantities not held (indices into [`Consistent::names`]) and, among them, the identifiable
/// ones by the pivoted QR of their columns of `g` at `threshold`, in pivot order.
pub(super) fn identifiable_columns(
    g: &DMatrix<f64>,
    hold: &[String],
    threshold: f64,
) -> Result<(Vec<usize>, Vec<usize>)> {
    let names = Consistent::names();
    let held: Vec<usize> = hold
        .iter()
        .map(|h| {
            names.iter().position(|n| n == h).ok_or_else(|| {
                IdentError::InvalidInput(format!(
                    "unknown parameter {h:?} to hold; known: {}",
                    names.join(", ")
                ))
            })
        })
        .collect::<Result<_>>()?;
    let free: Vec<usize> = (0..N_PSI).filter(|k| !held.contains(k)).collect();
    let base = base_columns(&g.select_columns(&free), threshold)
        .into_iter()
        .map(|k| free[k])
        .collect();
    Ok((free, base))
}

/// The observability of A through the closed loop `cfg` on `reference` at the parameters `at`:
/// the loop is simulated with sensitivities (no data needed), weighted by `options.noise`, the
/// quantities named in `options.hold` left out, the identifiable ones chosen by the pivoted QR at
/// `options.identifiability_threshold`, then [`observability_of`] of their columns. One
/// simulation with sensitivities: 0.6–0.8 s for a 10 s run on two cores.
///
/// Errors: as [`super::simulate`]; [`IdentError::InvalidInput`] for a noise that is not finite
/// and > 0, an unknown held name or no identifiable quantity.
pub fn output_observability<T: Trajectory + Sync + ?Sized>(
    cfg: &LoopConfig,
    at: &LoopParams,
    reference: &T,
    options: &CloeOptions,
) -> Result<OutputObservability> {
    let weight = whitening(options)?;
    let cons = Consistent::new(at)?;
    let psi = cons.psi(at)?;
    let a = cons.params(&psi);
    let run = super::simulate(cfg, &a, reference, Some(&Consistent::a_columns()))?;
    let jacobian = run
        .jacobian
        .as_ref()
        .ok_or_else(|| IdentError::InvalidInput("the loop returned no sensitivities".into()))?;
    let frames: Vec<usize> = (0..run.chi.len()).collect();
    let g = weighted_sensitivity(jacobian, &frames, &cons.jacobian(&psi), &weight);
    let (_, base) = identifiable_columns(&g, &options.hold, options.identifiability_threshold)?;
    if base.is_empty() {
        return Err(IdentError::InvalidInput(
            "the loop shows none of the quantities on this trajectory".into(),
        ));
    }
    let (o_in, condition) = observability_of(&g, &base, frames.len())?;
    let gb = g.select_columns(&base);
    let relative_std = match gb.tr_mul(&gb).cholesky() {
        Some(c) => c.inverse().diagonal().iter().map(|v| v.sqrt()).collect(),
        None => vec![f64::INFINITY; base.len()],
    };
    Ok(OutputObservability {
        o_in,
        condition,
        identifiable: {
            let names = Consistent::names();
            base.iter().map(|&k| names[k].clone()).collect()
        },
        frames: frames.len(),
        relative_std,
    })
}
