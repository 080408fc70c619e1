#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// Textbook names (j_ad, chi_r, …) mirror the thesis's symbols.
#![allow(non_snake_case)]

#[cfg(feature = "std")]
extern crate std;

mod converter;
mod dsmc;
mod error;
mod kalman;
mod kcsc;
mod kjsc;
mod pid;
mod safety;
pub mod servo;
mod trajectory;

pub use crate::converter::{ConverterOutput, TorqueToPosition};
pub use crate::dsmc::{sat, Dsmc, DsmcGains, DsmcOutput};
pub use crate::error::{CtrlError, FaultReason, Result};
pub use crate::kalman::{
    discrete_noise, input_response, transition, KalmanConfig, PoseEstimate, PoseKalman,
    RICCATI_MAX_ITERATIONS,
};
pub use crate::kcsc::{CartesianPidGains, JointCommand, Kcsc, VisualPid};
pub use crate::kjsc::{JointSpaceGains, Kjsc};
pub use crate::pid::{JointPid, PidGains};
pub use crate::safety::{CommandGuard, CommandLimits, Guarded};
pub use crate::servo::{
    Plant, Scheme, Servo, ServoConfig, ServoTick, HOLD_OFFSET_TIME, POTENTIOMETER_SIGMA_RAD,
};
pub use crate::trajectory::{Fourier, Reference, Sinusoid, Trajectory};
