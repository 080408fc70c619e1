#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// Textbook names (j_ad, m_tilde, chi_d …) mirror the thesis's symbols.
#![allow(non_snake_case)]

#[cfg(feature = "std")]
extern crate std;

mod dynamics;
mod error;
mod fk;
mod ik;
mod jacobian;
mod leg_jacobians;
mod params;
mod pose;
mod regressor;
pub mod thesis;
mod types;
mod workspace;

pub use crate::dynamics::{
    coriolis, coriolis_twist, dynamics_terms, dynamics_terms_with_env, dynamics_terms_with_gravity,
    forward_dynamics, forward_dynamics_by_joint_rates, forward_dynamics_by_joint_rates_from,
    forward_dynamics_jacobians_with_env, forward_dynamics_with_env, forward_dynamics_with_gravity,
    friction, friction_twist, gravity, gravity_twist, gravity_with, gravity_with_env,
    implicit_friction, inverse_dynamics, inverse_dynamics_derivatives_with_env,
    inverse_dynamics_with_env, inverse_dynamics_with_gravity, joint_friction,
    joint_friction_smooth, kinetic_energy, kinetic_energy_with_env, link_transverse_inertia,
    mass_matrix, mass_matrix_twist, mass_matrix_with_env, platform_inertia,
    potential_energy_with_env, potential_energy_with_gravity, rk4_step, rk4_step_by,
    rk4_step_implicit_friction, rk4_step_implicit_friction_observed, rk4_step_with_env,
    rk4_step_with_gravity, wrench_axial_inertia, DynamicsTerms, Environment, ForwardJacobians,
    FrictionStep, JacobianRequest, ModelState, PlatformLoad, GRAVITY,
};
pub use crate::error::{CoreError, Result, SingularKind};
pub use crate::fk::{fk, fk_theta_newton, FkOptions, FkSolution};
pub use crate::ik::{ik, ik_leg, ik_reading, platform_joints_in_base, wrap_angle, wrench_tips};
pub use crate::jacobian::{
    jacobian_a1, jacobian_a2, jacobian_ad, jacobian_stewart, jacobian_theta, LegGeometry,
    TYPE_I_TOLERANCE,
};
pub use crate::leg_jacobians::{leg_jacobians, leg_jacobians_from_geometry, LegJacobians};
pub use crate::params::{
    home_pose, leg_side, Body, DynamicParams, KinematicParams, BASE_RADIUS, ETA_NOMINAL, HOME_Z,
    N_DYN, N_KIN_ERRORS, PAIR_HALF_SPACING, PLATFORM_HALF_ANGLE_DEG, PLATFORM_RADIUS, THETA0_DEG,
    WRENCH_LENGTH,
};
pub use crate::pose::{
    check_pose, compose, euler_from_rotation, euler_rate_jacobian, euler_rate_jacobian_dot,
    inverse as pose_inverse, isometry_to_pose, pose_rotation, pose_to_isometry, rotation, twist,
    twist_dot, twist_jacobian, twist_jacobian_dot, twist_jacobian_inverse,
};
pub use crate::regressor::{regressor, regressor_tau_g, regressor_with_gravity, Regressor};
pub use crate::types::{LegJacobian, Mat3, Mat3x6, Mat6, Vec3, Vec6, LEGS};
pub use crate::workspace::{
    homeomorphism_check, scan_box, singularity_check, type_i_check, type_ii_check, verify_box,
    BoxLimits, BoxReport, BoxViolation, HomeomorphismCheck, PoseBox, SingularityCheck, TypeICheck,
    TypeIICheck, ViolationKind, DOCUMENTED_BOX_HALF_WIDTH, MAX_POINTS_PER_AXIS, TYPE_I_SIGNS,
};
