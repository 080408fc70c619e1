//! rss6-ctrl: real-time controllers for 6-RSS robots (thesis ch. 6): the built-in joint PID model,
//! and (issue 4) the Kalman filter, DSMC, torque-to-position converter and baselines.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod pid;

pub use crate::pid::{JointPid, PidGains};
