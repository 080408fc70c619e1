//! CLOE's inputs: the measured frames and the options of [`super::cloe`].

use super::config::LoopParams;
use super::result::SETTLE_STEPS;
use rss6_core::Vec6;

/// Measured frames χ_m (end-effector pose in the base frame through the calibrated ᴼχ_C, ᴱχ_t) at
/// the ticks where the identification loop consumed them (s from the start of the run).
#[derive(Debug, Clone, PartialEq)]
pub struct CloeData {
    /// Frame times (s).
    pub t: Vec<f64>,
    /// χ_m (m, rad).
    pub measured: Vec<Vec6>,
}

/// Default [`CloeOptions::hac_lags`]: 30 camera frames (1 s at 30 Hz).
pub const HAC_LAGS: usize = 30;

/// Options of [`cloe`](super::cloe).
#[derive(Debug, Clone, PartialEq)]
pub struct CloeOptions {
    /// Largest number of Jacobian evaluations (LM iterations).
    pub max_iterations: usize,
    /// tol_1 of eq. 5.9: relative change of the cost.
    pub tol_cost: f64,
    /// tol_2 of eq. 5.9: relative change of every estimated quantity.
    pub tol_step: f64,
    /// Noise std of the measured pose: [position (m), angle (rad)]; the residual weights are 1/σ.
    /// Default: Table 4.1 (0.0096 mm, 0.0261°).
    pub noise: [f64; 2],
    /// The covariance of one camera frame's pose noise (x, y, z m; α, β, γ rad), rows = columns;
    /// replaces `noise` when given: the residual is whitened frame by frame (W = L⁻¹, Σ = L·Lᵀ), so
    /// axes whose noise is correlated — a camera's x with its β — are weighted by Σ⁻¹ instead of
    /// one by one (`rss6.identify.cloe(noise="frames")` estimates it from a first fit's residual).
    pub noise_covariance: Option<[[f64; 6]; 6]>,
    /// Relative |R_ii| threshold of the pivoted QR (see the module docs).
    pub identifiability_threshold: f64,
    /// Names (see [`Consistent::names`](super::Consistent::names)) to estimate; `None`: every identifiable one. A requested
    /// name that is not identifiable is an error.
    pub parameters: Option<Vec<String>>,
    /// Names held at the guess as known (with `parameters` = `None`, the identifiable set is chosen
    /// among the others). Closed-loop output error sees Ξ and the drive gains only up to one
    /// common factor (docs/identification.md, "The scale direction"): holding one known quantity,
    /// e.g. `lp` from the drive's data sheet, fixes it.
    pub hold: Vec<String>,
    /// Relative standard deviation above which an estimate is flagged as poorly identified.
    pub poor_std: f64,
    /// Initial LM damping (relative to diag(JᵀJ)).
    pub lambda0: f64,
    /// Largest change of any log-parameter per iteration (0.5: a factor 1.65).
    pub max_log_step: f64,
    /// Iterate on sensitivities with the state Jacobians evaluated once per tick
    /// ([`super::StateJacobians::PerTick`], ≈ 10⁻³ relative, ≈ 1.4× cheaper on two cores), from
    /// the guess on: the identifiability analysis uses the per-tick ones at the guess (their error
    /// does not move the base set, see [`crate::base_columns`]), the final standard deviations
    /// always the exact ones. After the guess, with the implicit friction law, every derivative
    /// of a tick's first stage serves its four stages ([`super::StateJacobians::FirstStage`]: as
    /// accurate there, ≈ 20 % cheaper). A
    /// stop found on the per-tick ones is checked on the exact ones at the same estimate (computed
    /// for the σ anyway): it stands if their LM step predicts Φ to fall by at most one residual
    /// variance (the *settled* rule's bound, a likelihood ratio below e^0.5), else the iterations
    /// go on with exact sensitivities; likewise when no damping lowers Φ.
    pub per_tick_jacobians: bool,
    /// When no step lowers Φ: converged if every |cos| between the residual and a Jacobian column
    /// is at most this (first-order optimality), else [`IdentError::NotConverged`](crate::IdentError::NotConverged).
    pub tol_gradient: f64,
    /// Standard deviation of a Gaussian prior on every estimated log-parameter, centred at the
    /// guess (`Some(1.0)`: a factor e). It adds Σ((ψ − ψ_guess)/σ_prior)² to Φ, so a quantity the
    /// run hardly sees stays near its prior instead of drifting towards 0 or ∞ along a flat
    /// direction of the noisy cost; a well-identified one (σ ≪ σ_prior) moves by a fraction
    /// (σ/σ_prior)² of its distance to the guess. `None`: the pure output error of eq. 5.7
    /// (noise-free checks).
    pub prior_log_std: Option<f64>,
    /// Accepted steps over which the *settled* stopping rule looks back ([`CloeStop::Settled`](super::CloeStop::Settled));
    /// 0 turns the rule off. Default [`SETTLE_STEPS`].
    pub settle_steps: usize,
    /// Lags (camera frames) of the residual autocovariance behind the sandwich standard deviations
    /// (see [`CloeResult::relative_std`](super::CloeResult::relative_std)); 0: residual frames uncorrelated in time.
    pub hac_lags: usize,
    /// Where LM starts instead of the guess (which still centres the prior): identifiability and
    /// `rms_before` are evaluated there, and quantities left unidentifiable stay there. `None`: the
    /// guess (multi-start: `rss6.identify.cloe(restarts=…)`).
    pub initial: Option<LoopParams>,
}

impl Default for CloeOptions {
    fn default() -> Self {
        CloeOptions {
            max_iterations: 20,
            tol_cost: 1e-6,
            tol_step: 1e-5,
            noise: [0.0096e-3, 0.0261_f64.to_radians()],
            noise_covariance: None,
            identifiability_threshold: 1e-3,
            parameters: None,
            hold: Vec::new(),
            poor_std: 0.10,
            lambda0: 1e-3,
            max_log_step: 0.5,
            tol_gradient: 1e-4,
            per_tick_jacobians: false,
            prior_log_std: Some(1.0),
            hac_lags: HAC_LAGS,
            settle_steps: SETTLE_STEPS,
            initial: None,
        }
    }
}
