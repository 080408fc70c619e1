//! The crate's one error type: small, `Copy`, no strings, so it can cross a real-time boundary.

use core::fmt;

/// Which Jacobian was found singular.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SingularKind {
    /// Type-I (inverse-kinematic) singularity: a diagonal entry of J_a1 (eq. 3.29) vanished, i.e. a wrench
    /// and its link are collinear in the base plane.
    TypeI,
    /// Type-II (direct-kinematic) singularity: J_a2 (eq. 3.29) lost rank.
    TypeII,
    /// The leg-length Jacobian J' of the equivalent Stewart platform (eq. 3.19) lost rank inside FK.
    StewartJacobian,
    /// The Euler-rate Jacobian J_e (eq. 3.22) is singular (|β| = π/2).
    Euler,
    /// A matrix handed in by the caller (e.g. a mass matrix) could not be factorised.
    Matrix,
    /// The homeomorphism condition (eq. 4.22) failed: the forward kinematics may not be unique there.
    Homeomorphism,
}

/// Every way a call into `rss6-core` can fail.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CoreError {
    /// An input contained NaN or ±∞.
    NonFinite,
    /// The pose cannot be reached: for `leg` (0-based) the link cannot meet the wrench circle.
    /// `excess` = |cos| − 1 > 0 measures how far out of reach it is (dimensionless).
    Unreachable {
        /// Leg index, 0..6.
        leg: u8,
        /// How far the circle-intersection cosine lies beyond ±1.
        excess: f64,
    },
    /// The pose is reachable but neither IK solution of `leg` lies in the branch θ ∈ (−π/2, π/2].
    OutOfBranch {
        /// Leg index, 0..6.
        leg: u8,
        /// The closer of the two solutions (rad).
        theta: f64,
    },
    /// An iterative solver hit its iteration bound without meeting its tolerance.
    NotConverged {
        /// Iterations used (equals the bound).
        iterations: u32,
        /// Largest leg-length residual at the last iterate (m).
        residual: f64,
    },
    /// A Jacobian needed by the computation is singular.
    Singular(SingularKind),
    /// A parameter is out of its physical range (non-positive length or mass, zero gain …).
    InvalidParameter(&'static str),
}

impl fmt::Display for CoreError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CoreError::NonFinite => write!(f, "input contains NaN or infinity"),
            CoreError::Unreachable { leg, excess } => write!(
                f,
                "pose unreachable: leg {} cannot close (circle-intersection cosine exceeds 1 by {:.3e})",
                leg + 1,
                excess
            ),
            CoreError::OutOfBranch { leg, theta } => write!(
                f,
                "pose outside the working branch: leg {} would need theta = {:.4} rad, outside (-pi/2, pi/2]",
                leg + 1,
                theta
            ),
            CoreError::NotConverged { iterations, residual } => write!(
                f,
                "solver did not converge in {iterations} iterations (leg-length residual {residual:.3e} m)"
            ),
            CoreError::Singular(kind) => write!(f, "singular configuration: {kind:?}"),
            CoreError::InvalidParameter(what) => write!(f, "invalid parameter: {what}"),
        }
    }
}

impl core::error::Error for CoreError {}

/// Shorthand for results of this crate.
pub type Result<T> = core::result::Result<T, CoreError>;

/// `Err(NonFinite)` unless every element is finite.
pub(crate) fn check_finite(xs: &[f64]) -> Result<()> {
    if xs.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(CoreError::NonFinite)
    }
}
