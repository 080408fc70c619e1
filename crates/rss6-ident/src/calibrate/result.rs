//! What a calibration returns.

use super::options::Convergence;
use crate::error::Method;
use rss6_core::{KinematicParams, Vec6, N_KIN_ERRORS};

/// A configuration left out of the estimate, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedConfiguration {
    /// Index in [`crate::CalibrationData::configurations`].
    pub index: usize,
    /// Reason (missing frames, NaN, FK failure …).
    pub reason: String,
}

/// Outcome of a calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationResult {
    /// Method used.
    pub method: Method,
    /// Calibrated kinematic parameters.
    pub params: KinematicParams,
    /// The parameters the calibration started from (the nominal model; b is relative to them).
    pub reference: KinematicParams,
    /// Calibrated error vector b relative to the parameters passed in (docs/architecture.md order).
    pub errors: [f64; N_KIN_ERRORS],
    /// Calibrated ᴱχ_t (m, rad).
    pub target_in_effector: Vec6,
    /// Calibrated ᴼχ_C (implicit only).
    pub sensor_in_base: Option<Vec6>,
    /// Cost Σ‖W·r‖² at the start and after every accepted step.
    pub cost_history: Vec<f64>,
    /// Numerical rank of the Table 4.2-scaled Jacobian at the solution (full parameter set).
    pub rank: usize,
    /// Number of parameters (66 or 72).
    pub parameter_count: usize,
    /// Parameters that are not individually identifiable: those with ≥ 5 % of their (scaled) unit
    /// vector in the Jacobian's null space, i.e. in a gauge (frame-choice) direction.
    pub unidentifiable: Vec<String>,
    /// The null-space (gauge) directions removed from the problem, described.
    pub gauge_directions: Vec<String>,
    /// Singular values of the scaled Jacobian at the solution, descending.
    pub singular_values: Vec<f64>,
    /// Accepted LM steps.
    pub iterations: usize,
    /// Configurations that were left out, with the reason.
    pub dropped: Vec<DroppedConfiguration>,
    /// Indices of the configurations used.
    pub used: Vec<usize>,
    /// Gross outliers rejected by the solver, in the order rejected.
    pub rejected: Vec<RejectedConfiguration>,
    /// Normalised residual r_lᵀΣ_ll⁻¹r_l/6 of every used configuration at the solution, as (data
    /// index, value); ≈ 1 when the noise explains it. RPBA's reference configuration 0 has none (it is
    /// in every other residual). Empty without noise weighting.
    pub normalized_residuals: Vec<(usize, f64)>,
    /// Fit statistic: weighted cost per degree of freedom, χ²/(equations − free parameters); ≈ 1 when
    /// the model explains the data to within the noise model. NaN without noise weighting.
    pub fit_statistic: f64,
    /// Degrees of freedom of the fit statistic (equations − identifiable parameters).
    pub degrees_of_freedom: usize,
    /// How the final Levenberg–Marquardt iteration ended.
    pub convergence: Convergence,
}

/// A configuration the solver rejected as a gross outlier.
#[derive(Debug, Clone, PartialEq)]
pub struct RejectedConfiguration {
    /// Index in [`crate::CalibrationData::configurations`].
    pub index: usize,
    /// Its normalised residual when it was rejected.
    pub normalized_residual: f64,
    /// The threshold it exceeded: max(`outlier_threshold`, `outlier_ratio` × the median normalised
    /// residual of that fit).
    pub threshold: f64,
}
