//! The one record type every runner produces: what happened in one joint-loop tick.

use rss6_core::Vec6;
use rss6_ctrl::{FaultReason, PoseEstimate, Reference};

/// What part of an experiment a tick belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Closed-loop visual servoing ([`crate::servo::track`]).
    Servo,
    /// Moving to calibration configuration `index` (cosine-blended command).
    Move {
        /// Configuration index (0 = the initial configuration).
        index: usize,
    },
    /// Waiting at configuration `index` before averaging.
    Settle {
        /// Configuration index.
        index: usize,
    },
    /// Averaging at configuration `index` (§4.5).
    Dwell {
        /// Configuration index.
        index: usize,
    },
    /// The identification loop of Fig. 5.1 ([`crate::ident::run`]).
    Identification,
    /// Open-loop joint commands (no controller in the loop).
    OpenLoop,
}

impl Phase {
    /// Short name for logs: "servo", "move", "settle", "dwell", "identification", "open_loop".
    pub fn name(&self) -> &'static str {
        match self {
            Phase::Servo => "servo",
            Phase::Move { .. } => "move",
            Phase::Settle { .. } => "settle",
            Phase::Dwell { .. } => "dwell",
            Phase::Identification => "identification",
            Phase::OpenLoop => "open_loop",
        }
    }
}

/// A simulated robot's true state (not visible on a real robot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueState {
    /// True platform pose χ_E (m, rad).
    pub pose: Vec6,
    /// True physical joint angles θ (rad).
    pub theta: Vec6,
    /// True joint rates θ̇ (rad/s).
    pub theta_dot: Vec6,
    /// Drive torques applied during the last tick (N·m).
    pub torque: Vec6,
}

/// One joint-loop tick. Times are robot times (s) at the start of the tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// Robot time at the start of the tick (s).
    pub t: f64,
    /// Which part of the experiment.
    pub phase: Phase,
    /// Potentiometer readings κ the controller saw at the start of the tick (bit).
    pub kappa: Vec6,
    /// Joint command sent during the tick (rad, drive convention).
    pub theta_cmd: Vec6,
    /// The raw camera frame ᶜχ_t consumed at the start of the tick (target in the sensor frame).
    pub sensor_pose: Option<Vec6>,
    /// The same frame as the controller sees it: χ_E in the base frame through the estimated ᴼχ_C
    /// and ᴱχ_t ([`crate::View`]).
    pub camera: Option<Vec6>,
    /// The reference at the start of the tick (servo and identification runs).
    pub reference: Option<Reference>,
    /// The servo's Kalman estimate, on ticks where its camera-rate part ran.
    pub estimate: Option<PoseEstimate>,
    /// The DSMC's held τ_a (N·m) and sliding variable F, when the DSMC runs.
    pub dsmc: Option<(Vec6, Vec6)>,
    /// The controller's latched fault, if any (the held command is then sent).
    pub fault: Option<FaultReason>,
    /// A simulated robot's true state at the start of the tick.
    pub truth: Option<TrueState>,
    /// Drive torques applied during the tick (N·m), if the robot reports them.
    pub torque: Option<Vec6>,
}

impl Record {
    /// A record with only the mandatory fields set.
    pub fn new(t: f64, phase: Phase, kappa: Vec6, theta_cmd: Vec6) -> Self {
        Record {
            t,
            phase,
            kappa,
            theta_cmd,
            sensor_pose: None,
            camera: None,
            reference: None,
            estimate: None,
            dsmc: None,
            fault: None,
            truth: None,
            torque: None,
        }
    }
}
