//! The crate's error and fault types: small, `Copy`, no strings, so they can cross a real-time boundary.

use core::fmt;
use rss6_core::CoreError;

/// Why a controller entered its fault state. Readable with `fault()` on every controller and on
/// [`crate::Servo`]; the controller keeps returning [`CtrlError::Faulted`] with this reason (and holds its
/// last safe command) until `reset`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum FaultReason {
    /// A camera pose measurement contained NaN or ±∞.
    NonFiniteMeasurement,
    /// A potentiometer reading (or the joint angle derived from it) contained NaN or ±∞.
    NonFiniteJoint,
    /// The reference (χ_d, χ̇_d, χ̈_d) contained NaN or ±∞.
    NonFiniteReference,
    /// The controller produced a non-finite torque or joint command (e.g. from a model blow-up).
    NonFiniteCommand,
    /// No camera frame for `age` seconds, longer than the configured limit.
    StaleCamera {
        /// Time since the last accepted frame (s).
        age: f64,
    },
    /// A model evaluation (IK, Jacobian, dynamics) failed at the measured pose.
    Model(CoreError),
    /// J_θ = J_ad J_s (eq. 5.3) at the estimate could not be factorised (a type-II or Euler singularity,
    /// or numerically so): no actuator torque or joint rate can be solved for.
    SingularJacobian,
    /// A tick's time stamp lay before the previous tick's (or before the start/reset time).
    TimeWentBackwards {
        /// How far back the time stamp jumped (s, > 0).
        by: f64,
    },
}

/// Every way a call into `rss6-ctrl` can fail.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CtrlError {
    /// The controller is (or just went) into its fault state; the reason says why. The last safe command
    /// is still available from the controller (`held_command()` / `last_command()`).
    Faulted(FaultReason),
    /// An argument was NaN or ±∞ (for calls that do not latch a fault, e.g. the Kalman filter).
    NonFinite,
    /// A time step was not strictly positive and finite (s).
    InvalidTimeStep(f64),
    /// A configuration value is out of range (non-positive gain, empty stroke …).
    InvalidParameter(&'static str),
    /// A model evaluation in rss6-core failed.
    Core(CoreError),
    /// J_θ (eq. 5.3) is singular at the requested pose (calls that do not latch a fault).
    SingularJacobian,
}

impl From<CoreError> for CtrlError {
    fn from(e: CoreError) -> Self {
        CtrlError::Core(e)
    }
}

impl fmt::Display for FaultReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FaultReason::NonFiniteMeasurement => write!(f, "camera measurement is NaN or infinite"),
            FaultReason::NonFiniteJoint => write!(f, "potentiometer reading is NaN or infinite"),
            FaultReason::NonFiniteReference => write!(f, "reference trajectory is NaN or infinite"),
            FaultReason::NonFiniteCommand => write!(f, "controller output is NaN or infinite"),
            FaultReason::StaleCamera { age } => {
                write!(f, "no camera frame for {age:.3} s (stale camera data)")
            }
            FaultReason::Model(e) => write!(f, "model evaluation failed: {e}"),
            FaultReason::SingularJacobian => write!(f, "J_theta is singular at the estimated pose"),
            FaultReason::TimeWentBackwards { by } => {
                write!(f, "time stamp went backwards by {by:.3e} s")
            }
        }
    }
}

impl fmt::Display for CtrlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CtrlError::Faulted(r) => write!(f, "controller faulted: {r}"),
            CtrlError::NonFinite => write!(f, "input contains NaN or infinity"),
            CtrlError::InvalidTimeStep(dt) => {
                write!(f, "time step must be > 0 and finite, got {dt}")
            }
            CtrlError::InvalidParameter(what) => write!(f, "invalid parameter: {what}"),
            CtrlError::Core(e) => write!(f, "rss6-core: {e}"),
            CtrlError::SingularJacobian => write!(f, "J_theta is singular at this pose"),
        }
    }
}

impl core::error::Error for CtrlError {}

/// Shorthand for results of this crate.
pub type Result<T> = core::result::Result<T, CtrlError>;

/// `true` if every element is finite.
pub(crate) fn all_finite(xs: &[f64]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

/// `Err(InvalidTimeStep)` unless `dt` is finite and > 0.
pub(crate) fn check_dt(dt: f64) -> Result<()> {
    if dt.is_finite() && dt > 0.0 {
        Ok(())
    } else {
        Err(CtrlError::InvalidTimeStep(dt))
    }
}

/// A latched fault: the first reason wins until [`FaultLatch::clear`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct FaultLatch {
    reason: Option<FaultReason>,
}

impl FaultLatch {
    pub(crate) fn get(&self) -> Option<FaultReason> {
        self.reason
    }
    /// Latches `r` (unless already faulted) and returns the error to hand back.
    pub(crate) fn trip(&mut self, r: FaultReason) -> CtrlError {
        if self.reason.is_none() {
            self.reason = Some(r);
        }
        CtrlError::Faulted(self.reason.unwrap_or(r))
    }
    /// `Err(Faulted)` if latched.
    pub(crate) fn check(&self) -> Result<()> {
        match self.reason {
            Some(r) => Err(CtrlError::Faulted(r)),
            None => Ok(()),
        }
    }
    pub(crate) fn clear(&mut self) {
        self.reason = None;
    }
    /// The checks every controller step starts with: not latched, a valid `dt`, a finite reference
    /// (latches `NonFiniteReference` otherwise).
    pub(crate) fn admit(
        &mut self,
        reference: &crate::trajectory::Reference,
        dt: f64,
    ) -> Result<()> {
        self.check()?;
        check_dt(dt)?;
        if !reference.is_finite() {
            return Err(self.trip(FaultReason::NonFiniteReference));
        }
        Ok(())
    }
    /// [`Self::admit`] plus a finite pose estimate and rate (latches `NonFiniteMeasurement`
    /// otherwise).
    pub(crate) fn admit_estimate(
        &mut self,
        reference: &crate::trajectory::Reference,
        estimate: &crate::kalman::PoseEstimate,
        dt: f64,
    ) -> Result<()> {
        self.admit(reference, dt)?;
        if !(all_finite(estimate.pose.as_slice()) && all_finite(estimate.pose_dot.as_slice())) {
            return Err(self.trip(FaultReason::NonFiniteMeasurement));
        }
        Ok(())
    }
}
