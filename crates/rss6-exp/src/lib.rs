#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]
// Textbook names (chi, kappa …) mirror the thesis's symbols.
#![allow(non_snake_case)]

pub mod dwell;
mod error;
pub mod ident;
pub mod log;
mod observer;
mod pose_mean;
mod record;
mod robot;
pub mod servo;
mod tabulated;
mod view;

pub use crate::error::{ExpError, Result};
pub use crate::observer::{Flow, Observer, Progress};
pub use crate::pose_mean::{mean_pose, PoseMean};
pub use crate::record::{Phase, Record, TrueState};
pub use crate::robot::Robot;
pub use crate::tabulated::Tabulated;
pub use crate::view::{Convention, Externals, View};
