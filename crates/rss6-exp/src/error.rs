//! Errors of the experiment layer.

use rss6_core::CoreError;
use rss6_ctrl::CtrlError;
use rss6_sim::SimError;

/// Why an experiment could not run or was stopped.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExpError {
    /// Bad argument (shape, range, NaN); the message says which.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// The simulated robot failed (diverged, bad configuration …).
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A controller could not be built or stepped.
    #[error("controller: {0}")]
    Ctrl(#[from] CtrlError),
    /// Kinematics or dynamics failed (unreachable pose, singular configuration, no FK convergence).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// The robot (a real one, or one implemented outside Rust) reported an error.
    #[error("robot: {0}")]
    Robot(String),
    /// The robot could not assemble at calibration configuration `index` (the simulation came apart
    /// or the kinematics failed while moving there or dwelling).
    #[error("the robot cannot assemble at configuration {index}: {why}")]
    CannotAssemble {
        /// Configuration index (order of visit; 0 = initial).
        index: usize,
        /// What failed.
        why: String,
    },
    /// No camera frame arrived during the dwell at configuration `index`: the camera lost the target.
    #[error("the camera lost the target at configuration {index} (no frame during the dwell ending at t = {time:.3} s)")]
    TargetLost {
        /// Configuration index (order of visit; 0 = initial).
        index: usize,
        /// Robot time (s) at the end of the dwell.
        time: f64,
    },
    /// The observer stopped the run (Ctrl-C, a progress callback that raised, a cancelled study).
    #[error("stopped by the observer at t = {time:.3} s")]
    Stopped {
        /// Robot time (s) of the last tick run.
        time: f64,
    },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The MCAP writer or reader failed.
    #[error("MCAP: {0}")]
    Mcap(String),
    /// A log is not in the project's format or is damaged.
    #[error("{path}: not a readable rss6 log: {why}")]
    CorruptLog {
        /// The file.
        path: String,
        /// What is wrong.
        why: String,
    },
}

impl From<mcap::McapError> for ExpError {
    fn from(e: mcap::McapError) -> Self {
        ExpError::Mcap(e.to_string())
    }
}

/// Result alias of the experiment layer.
pub type Result<T> = std::result::Result<T, ExpError>;
