#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]
// Textbook names (chi, kappa, tau …) mirror the thesis's symbols.
#![allow(non_snake_case)]

mod effects;
mod error;
mod params_file;
#[cfg(feature = "rapier")]
mod plant;
mod sensors;
mod sim;
mod twin;
mod validation;

pub use crate::effects::{
    build_effects, make_effect, Backlash, BacklashEffect, BaseTilt, CameraLatency, Effect,
    EffectConstructor, EffectSetup, EffectSpec, JointFriction, JointOffsetDrift, Payload,
    PayloadEffect, G0, REGISTRY,
};
pub use crate::error::{Result, SimError};
pub use crate::params_file::{
    load_dynamic_params, load_kinematic_params, load_pid_gains, load_truth, save_dynamic_params,
    save_kinematic_params, save_pid_gains, save_truth, BodiesFile, BodyFile, DynamicParamsFile,
    KinematicParamsFile, PidGainsFile, TruthFile,
};
#[cfg(feature = "rapier")]
pub use crate::plant::{Plant, RapierPhysics};
pub use crate::sensors::{
    kabsch, measure_with, Camera, CmmConfig, CMM_ANGLE_NOISE, CMM_POSITION_NOISE,
    DEFAULT_PIXEL_NOISE, POT_NOISE_BITS, TARGET_RADIUS,
};
pub use crate::sim::{
    default_sensor_in_base, default_target_in_effector, Physics, Robot, RobotSim, SimConfig,
    SolverConfig, TJoint, Truth, DEFAULT_TORQUE_LIMIT,
};
pub use crate::twin::{ModelPhysics, ModelSim};
pub use crate::validation::{compare, pose_distance, DiffSample, ExcitingTrajectory};
