//! Solver options and progress reports of the calibration methods.

use super::noise::MeasurementNoise;

/// How the Jacobian of the residuals is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JacobianMode {
    /// Analytic (implicit differentiation of the leg closure for the FK derivative). Default.
    Analytic,
    /// Forward differences of eq. 4.25 with step ε·σ_j/1 mm per parameter (ε = 10⁻⁶ as in the thesis
    /// gives 10⁻⁶ m for lengths).
    FiniteDifference {
        /// ε of eq. 4.25.
        epsilon: f64,
    },
}

/// Solver options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// Maximum LM iterations (accepted and rejected steps).
    pub max_iterations: usize,
    /// Stop when the relative cost decrease of an accepted step is below this.
    pub cost_tolerance: f64,
    /// Stop when the scaled step norm is below this.
    pub step_tolerance: f64,
    /// Initial Marquardt damping λ (relative to diag JᵀJ).
    pub initial_damping: f64,
    /// Jacobian computation.
    pub jacobian: JacobianMode,
    /// Noise of one sample (default Table 4.1). The residuals are weighted by the inverse square root
    /// of the covariance this noise gives the dwell means (see `noise.rs`), so the weighted cost is a
    /// χ² variable and its value per degree of freedom the fit statistic. `None`: the fixed weights
    /// below, no fit statistic, no outlier rejection.
    pub noise: Option<MeasurementNoise>,
    /// Replace `noise`'s camera part by the covariance of one frame pooled from the dwells' own
    /// scatter ([`MeasurementNoise::with_dwell_covariance`]): the stereo head's correlated pose noise
    /// (x with β, y with α) and its depth noise as measured, instead of Table 4.1's independent
    /// components. Needs data whose dwells recorded it (the dwell runner does). Default `false`.
    pub noise_from_dwells: bool,
    /// Fixed RPBA residual weights [x, y, z, α, β, γ] (1/m, 1/rad) when `noise` is `None`: default
    /// 1/σ of Table 4.1, so translations and rotations count by their measurement precision.
    pub pose_weights: [f64; 6],
    /// Fixed implicit residual weight (1/m) when `noise` is `None`; default 1/σ_position of Table 4.1.
    pub leg_weight: f64,
    /// Use configurations that failed a collection check ([`crate::ConfigurationData::fault`]).
    /// Default `false`: they are left out and listed in [`super::CalibrationResult::dropped`].
    pub include_faulty: bool,
    /// A configuration is a gross outlier when its normalised residual (r_lᵀΣ_ll⁻¹r_l/6, ≈ 1 for
    /// noise alone) exceeds `outlier_threshold` and `outlier_ratio` × the median normalised residual.
    /// Default 9: χ²₆ > 54 has probability 4·10⁻¹⁰ under the noise model.
    pub outlier_threshold: f64,
    /// See `outlier_threshold`. Default 10: the worst configuration must stand out from the rest.
    pub outlier_ratio: f64,
    /// Most gross outliers rejected (one per refit, worst first). Default 3.
    pub max_rejections: usize,
    /// Largest fit statistic (weighted cost per degree of freedom) accepted after rejection; above it
    /// the data are inconsistent with the noise model and the solver returns
    /// [`crate::IdentError::Calibration`]. Default 10 (see `docs/calibration.md` for the values
    /// measured on the analytic generator and the rapier plant).
    pub max_fit_statistic: f64,
    /// Singular values below `rank_tolerance`·σ_max count as zero.
    pub rank_tolerance: f64,
    /// Starting value of ᴱχ_t (m, rad); default [`crate::NOMINAL_TARGET_IN_EFFECTOR`].
    pub target_guess: [f64; 6],
    /// Implicit only: hold ᴼχ_C at its (rough) guess instead of estimating it, as when the base frame
    /// is taken from a separate, rough measurement. Default `false`.
    pub fix_sensor_pose: bool,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        let sp = rss6_core::thesis::POSE_POSITION_NOISE;
        let sa = rss6_core::thesis::POSE_ANGLE_NOISE;
        CalibrationOptions {
            max_iterations: 60,
            cost_tolerance: 1e-12,
            step_tolerance: 1e-10,
            initial_damping: 1e-4,
            jacobian: JacobianMode::Analytic,
            noise: Some(MeasurementNoise::default()),
            noise_from_dwells: false,
            pose_weights: [1.0 / sp, 1.0 / sp, 1.0 / sp, 1.0 / sa, 1.0 / sa, 1.0 / sa],
            leg_weight: 1.0 / sp,
            include_faulty: false,
            outlier_threshold: 9.0,
            outlier_ratio: 10.0,
            max_rejections: 3,
            max_fit_statistic: 10.0,
            rank_tolerance: 1e-9,
            target_guess: crate::generator::NOMINAL_TARGET_IN_EFFECTOR,
            fix_sensor_pose: false,
        }
    }
}

/// Progress of the solver, passed to the callback after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Iteration number (accepted + rejected steps so far).
    pub iteration: usize,
    /// Current cost Σ‖W·r‖².
    pub cost: f64,
    /// Current damping λ.
    pub damping: f64,
}

/// How the Levenberg–Marquardt iteration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Convergence {
    /// An accepted step decreased the cost by less than `cost_tolerance` (relative).
    CostTolerance,
    /// The scaled step fell below `step_tolerance`.
    StepTolerance,
    /// No step decreased the cost any more (damping above 10¹²): a minimum to working precision.
    NoFurtherDecrease,
    /// `max_iterations` ran out while the cost was still decreasing: not converged.
    IterationLimit,
}

impl Convergence {
    /// `true` unless the iteration limit ended the solve.
    pub fn converged(&self) -> bool {
        !matches!(self, Convergence::IterationLimit)
    }
}
