//! Typed errors of rss6-sim.

use rss6_core::CoreError;

/// Everything that can go wrong in the simulator, the sensors, the logs and the parameter files.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A kinematic or dynamic computation of rss6-core failed (unreachable pose, singularity …).
    #[error("model computation failed: {0}")]
    Core(CoreError),
    /// A configuration value is out of range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(String),
    /// An effect name that the registry does not know.
    #[error("unknown effect `{name}` (known: {known})")]
    UnknownEffect {
        /// The name asked for.
        name: String,
        /// The registered names, comma separated.
        known: String,
    },
    /// A parameter of an effect is missing, unknown or out of range.
    #[error("effect `{effect}`: {message}")]
    EffectParameter {
        /// The effect's name.
        effect: String,
        /// What is wrong.
        message: String,
    },
    /// The simulated state became non-finite or the loops came apart (the plant diverged).
    #[error("simulation diverged at t = {time} s: {message}")]
    Diverged {
        /// Simulated time (s).
        time: f64,
        /// What was detected.
        message: String,
    },
    /// The optical CMM could not estimate a pose (degenerate reflector geometry).
    #[error("optical CMM: {0}")]
    Cmm(String),
    /// File input/output.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A parameter file could not be parsed or has the wrong shape.
    #[error("{path}: invalid parameter file: {message}")]
    ParamFile {
        /// The file.
        path: String,
        /// What the parser said.
        message: String,
    },
}

impl From<CoreError> for SimError {
    fn from(e: CoreError) -> Self {
        SimError::Core(e)
    }
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, SimError>;
