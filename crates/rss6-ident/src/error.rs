//! The crate's error type.

use rss6_core::CoreError;

/// Which calibration method a call refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Method {
    /// Relative-pose-based algorithm (eq. 4.16–4.21): 60 kinematic + 6 external parameters (ᴱχ_t).
    Rpba,
    /// Implicit leg-closure calibration (eq. 4.10–4.15): 60 kinematic + 12 external (ᴼχ_C, ᴱχ_t).
    Implicit,
}

impl core::fmt::Display for Method {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Method::Rpba => write!(f, "RPBA"),
            Method::Implicit => write!(f, "implicit"),
        }
    }
}

/// Every way a calibration call can fail. Never a silent wrong answer: if the data cannot support an
/// estimate the error says why and what is missing.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum IdentError {
    /// Fewer usable configurations than identifiable parameters require.
    #[error(
        "too few usable configurations for {method}: got {got}, need at least {needed} \
         ({params} identifiable parameters, 6 equations per configuration{extra})"
    )]
    TooFewConfigurations {
        /// The method.
        method: Method,
        /// Usable configurations (including the reference configuration 0).
        got: usize,
        /// Minimum number of configurations (including configuration 0).
        needed: usize,
        /// Number of identifiable (gauge-free) parameters.
        params: usize,
        /// Note on how configuration 0 counts.
        extra: &'static str,
    },
    /// The data leave parameter directions beyond the frame (gauge) choices unseen.
    #[error(
        "rank-deficient data: Jacobian rank {rank} < {expected} identifiable parameters; \
         the data cannot see: {}", unseen.join(", ")
    )]
    RankDeficient {
        /// Numerical rank of the gauge-reduced Jacobian.
        rank: usize,
        /// The rank complete data would give.
        expected: usize,
        /// Names of the parameters dominating the unseen directions.
        unseen: Vec<String>,
    },
    /// The reference configuration (index 0) is missing or unusable; every relative pose needs it.
    #[error("reference configuration 0 is unusable: {0}")]
    BadReference(String),
    /// Forward kinematics failed at a configuration that cannot be dropped.
    #[error("forward kinematics failed at configuration {config}: {source}")]
    Fk {
        /// Configuration index in the data.
        config: usize,
        /// The kinematics error.
        #[source]
        source: CoreError,
    },
    /// The calibration ran but its model cannot be trusted: after rejecting gross outliers the fit is
    /// still inconsistent with the noise model, the solver did not converge, or the model explains
    /// the data worse than the starting one. Names the configurations (and parameters) responsible.
    #[error(
        "{method} calibration failed: {why}; fit statistic {fit_statistic:.3}{}{}",
        fmt_list(", configurations", configurations),
        fmt_list(", parameters", parameters)
    )]
    Calibration {
        /// The method.
        method: Method,
        /// What is wrong.
        why: String,
        /// Data indices of the configurations responsible (worst first; rejected ones included).
        configurations: Vec<usize>,
        /// Parameters responsible (rank problems), if any.
        parameters: Vec<String>,
        /// Weighted cost per degree of freedom at the end (≈ 1 for a consistent fit).
        fit_statistic: f64,
    },
    /// Inconsistent or non-finite input (parameters, options, shapes).
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// An error from the kinematics core.
    #[error("kinematics: {0}")]
    Core(#[from] CoreError),
    /// The simulated identification loop failed (the model left its workspace, a stage was singular,
    /// a command was not finite).
    #[error("simulation of the identification loop failed at t = {time:.3} s: {message}")]
    Simulation {
        /// Time from the start of the run (s).
        time: f64,
        /// What failed.
        message: String,
    },
    /// Identification data without camera frames, or frames the model's loop does not produce.
    #[error("no usable camera frames: {0}")]
    NoCameraFrames(String),
    /// Parameters requested for estimation that the data cannot identify.
    #[error("not identifiable from these data: {}", names.join(", "))]
    Unidentifiable {
        /// Names of the unidentifiable parameters.
        names: Vec<String>,
    },
    /// Levenberg–Marquardt stopped without meeting the stopping rules of eq. 5.9.
    #[error("CLOE did not converge in {iterations} iterations (cost history {cost_history:?})")]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// Cost after each accepted iteration (first: the start).
        cost_history: Vec<f64>,
    },
    /// A robot data source failed.
    #[error("robot source: {0}")]
    Source(String),
}

fn fmt_list<T: core::fmt::Display>(label: &str, items: &[T]) -> String {
    if items.is_empty() {
        String::new()
    } else {
        let v: Vec<String> = items.iter().map(ToString::to_string).collect();
        format!("{label} {}", v.join(", "))
    }
}

/// Shorthand for results of this crate.
pub type Result<T> = core::result::Result<T, IdentError>;
