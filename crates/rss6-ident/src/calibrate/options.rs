//! Solver options and progress reports of the calibration methods.

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
    /// RPBA residual weights [x, y, z, α, β, γ] (1/m, 1/rad): default 1/σ of Table 4.1, so
    /// translations and rotations count by their measurement precision.
    pub pose_weights: [f64; 6],
    /// Implicit residual weight (1/m); default 1/σ_position of Table 4.1.
    pub leg_weight: f64,
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
        let sp = 0.0096e-3;
        let sa = 0.0261f64.to_radians();
        CalibrationOptions {
            max_iterations: 60,
            cost_tolerance: 1e-12,
            step_tolerance: 1e-10,
            initial_damping: 1e-4,
            jacobian: JacobianMode::Analytic,
            pose_weights: [1.0 / sp, 1.0 / sp, 1.0 / sp, 1.0 / sa, 1.0 / sa, 1.0 / sa],
            leg_weight: 1.0 / sp,
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
