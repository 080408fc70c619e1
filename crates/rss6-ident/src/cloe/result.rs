//! What [`cloe`](super::cloe) returns: the estimate, what the data could and could not identify,
//! the standard deviations, the fit and the stopping rule that ended it.

use super::config::LoopParams;
use nalgebra::DMatrix;
use rss6_core::Vec6;

/// Default of [`CloeOptions::settle_steps`](super::CloeOptions::settle_steps): the accepted steps
/// over which [`CloeStop::Settled`] looks back.
pub const SETTLE_STEPS: usize = 3;

/// Which stopping rule ended a converged [`cloe`](super::cloe) (its module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CloeStop {
    /// Eq. 5.9: relative change of Φ ≤ `tol_cost` and of every quantity ≤ `tol_step` (or a step
    /// below 10 % of every σ).
    Tolerances,
    /// Φ fell by < 10⁻² residual variances at two accepted steps in a row.
    Invisible,
    /// Over the last `settle_steps` ([`SETTLE_STEPS`]) accepted steps Φ fell by < 1 residual variance in all and
    /// no quantity moved by more than half its (Wald) σ: creeping with no visible effect.
    Settled,
    /// No damping lowers Φ and the residual is orthogonal to every column (or Φ is at rounding).
    Stationary,
}

impl CloeStop {
    /// A short name: `"tolerances"`, `"invisible"`, `"settled"`, `"stationary"`.
    pub fn as_str(self) -> &'static str {
        match self {
            CloeStop::Tolerances => "tolerances",
            CloeStop::Invisible => "invisible",
            CloeStop::Settled => "settled",
            CloeStop::Stationary => "stationary",
        }
    }
}

/// How an unidentifiable quantity shows in the output: as a combination of estimated ones.
#[derive(Debug, Clone, PartialEq)]
pub struct Alias {
    /// The unidentifiable quantity.
    pub name: String,
    /// (estimated quantity, relative coefficient), largest |coefficient| first.
    pub like: Vec<(String, f64)>,
    /// ‖h_u − Σ c h‖ / ‖h_u‖ of the combination.
    pub residual: f64,
}

/// What [`cloe`](super::cloe) returns.
#[derive(Debug, Clone, PartialEq)]
pub struct CloeResult {
    /// The estimate (unidentifiable entries at the guess).
    pub params: LoopParams,
    /// ψ of the estimate.
    pub psi: Vec<f64>,
    /// Names of the estimated quantities, in pivot order.
    pub identified: Vec<String>,
    /// Names of the quantities the data cannot identify (kept at the guess).
    pub unidentifiable: Vec<String>,
    /// For each unidentifiable quantity, in the order of `unidentifiable`: the estimated quantities
    /// that absorb it — (name, c) with a relative change δ of it moving the output at the guess as
    /// relative changes c·δ of those do (|c| ≥ 0.05, largest first, at most 4) — and the relative
    /// residual of that combination (≈ 0: a base combination; near 1: the output hardly sees it).
    pub aliases: Vec<Alias>,
    /// Relative standard deviation of every estimated quantity (same order as `identified`): the
    /// largest of [`relative_std_wald`](Self::relative_std_wald) and two sandwiches A⁻¹ S A⁻¹,
    /// A = GᵀG (prior rows included), over [`CloeOptions::hac_lags`](super::CloeOptions::hac_lags) frames with Bartlett weights:
    /// *stationary*, S = Σ_l w_l Σ_k G_kᵀ γ(l) G_{k−l} with γ(l) the residual's autocovariance
    /// between frames l apart, and *local*, Newey–West on the per-frame scores G_kᵀ r_k (it sees
    /// model error where it happens, a start transient; alone it cancels the variance of a quantity
    /// seen in a short window). The Wald value assumes white residuals of the weighted size; the
    /// sandwiches also see residuals correlated in time (the loop's own model error), which the
    /// spread over trajectories shows.
    pub relative_std: Vec<f64>,
    /// The Wald relative standard deviation alone: sqrt(Φ/(N − p) · (GᵀG)⁻¹_kk).
    pub relative_std_wald: Vec<f64>,
    /// The estimator's linear map at the estimate, (GᵀG)⁻¹ G_sᵀ (p × 6F; GᵀG with the prior's rows,
    /// G_s the output rows of the estimated quantities, columns in the residual's order: frame k's
    /// axis i at 6k + i, weighted by [`residual_weight`](Self::residual_weight)): a change δr of the
    /// weighted residual moves the estimated logs by this times δr. It carries noise realisations
    /// to the estimate (the Python `rss6.identify_replicates`). 0 × 0 if GᵀG is singular.
    pub estimator_map: DMatrix<f64>,
    /// The residual's weights 1/σ per axis (x, y, z, α, β, γ; from `CloeOptions::noise`): the
    /// diagonal of [`residual_whitening`](Self::residual_whitening).
    pub residual_weight: [f64; 6],
    /// The whitening W of each frame's residual (rows of W; diag(1/σ) unless
    /// `CloeOptions::noise_covariance` was given): the weighted residual is W·(χ_m − χ_s).
    pub residual_whitening: [[f64; 6]; 6],
    /// χ_m − χ_s at the estimate, one row per camera frame (m, rad).
    pub residual: Vec<Vec6>,
    /// Estimated quantities whose relative standard deviation exceeds `poor_std`.
    pub poorly_identified: Vec<String>,
    /// RMS of χ_m − χ_s per axis at the guess (m, rad).
    pub rms_before: Vec6,
    /// RMS of χ_m − χ_s per axis at the estimate (m, rad).
    pub rms_after: Vec6,
    /// Φ (with the prior's term, if any) at the start and after every accepted step.
    pub cost_history: Vec<f64>,
    /// Jacobian evaluations (LM iterations).
    pub iterations: usize,
    /// Φ/(N − p) at the estimate (the output error alone, without the prior's term): ≈ 1 when the residual is the camera noise of `noise`; well
    /// above 1 means a model discrepancy (or a minimum the non-smooth loop kept LM from leaving).
    pub reduced_chi2: f64,
    /// Simulations without sensitivities (rejected trial steps included).
    pub simulations: usize,
    /// Ticks of the loop at the estimate whose implicit friction solve stopped at its sweep bound
    /// (`LoopConfig::implicit_friction`): χ_s there is the last Gauss–Seidel iterate, not the exact
    /// law. 0 expected (and always 0 for the other laws); anything else is reported, not hidden.
    pub inexact_friction_ticks: usize,
    /// The stopping rule that ended the estimation.
    pub converged_by: CloeStop,
}
