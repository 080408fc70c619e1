//! What a calibration returns.

use crate::error::Method;
use rss6_core::{KinematicParams, Vec6, N_KIN_ERRORS};

/// A configuration left out of the estimate, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedConfiguration {
    /// Index in [`CalibrationData::configurations`].
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
    /// Calibrated error vector b relative to the parameters passed in (DESIGN.md order).
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
}
