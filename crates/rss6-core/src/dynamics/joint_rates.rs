//! Forward dynamics under actuator torques that depend on the joint rates (e.g. a smoothed
//! Coulomb law applied as a known torque): θ̇ and the dynamics from one leg geometry.

use super::check_state;
use super::load::Environment;
use super::newton_euler::chi_ddot_at;
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::params::{DynamicParams, KinematicParams};
use crate::types::Vec6;

/// [`super::forward_dynamics_with_env`] under actuator torques that depend on the joint rates: τ_a =
/// `tau_of(θ̇)` at θ̇ = J_θ(χ) χ̇, both from one IK of χ. For a friction law the model's own
/// (eq. 3.48's sign) does not hold, e.g. a smoothed Coulomb torque f_c tanh(θ̇/ε) applied as a
/// known torque on `dp` without its Coulomb part.
///
/// Bit for bit `forward_dynamics_with_env(kp, dp, pose, pose_dot, &tau_of(&(jacobian_theta(kp,
/// pose)? * pose_dot)), env)`, with the same errors, at one IK and geometry less.
///
/// Errors: as [`super::forward_dynamics_with_env`] (a non-finite `tau_of` result is `NonFinite`).
pub fn forward_dynamics_by_joint_rates<F>(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    env: &Environment,
    tau_of: F,
) -> Result<Vec6>
where
    F: FnOnce(&Vec6) -> Vec6,
{
    forward_dynamics_by_joint_rates_from(kp, dp, pose, pose_dot, env, None, tau_of)
}

/// [`forward_dynamics_by_joint_rates`] from the joint angles of an earlier IK of `pose` when known
/// (`theta`: no IK at all), else with one IK; bit for bit the same result. Angles that do not
/// close every leg at the pose (relative error of |l_i|² above 10⁻⁹, e.g. those of an earlier
/// pose) are refused, as [`crate::rk4_step_implicit_friction`] refuses them.
///
/// Errors: as [`forward_dynamics_by_joint_rates`]; [`crate::CoreError::InvalidParameter`] for angles that
/// do not close the legs.
pub fn forward_dynamics_by_joint_rates_from<F>(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    env: &Environment,
    theta: Option<&Vec6>,
    tau_of: F,
) -> Result<Vec6>
where
    F: FnOnce(&Vec6) -> Vec6,
{
    let geom = LegGeometry::at_pose_from(kp, pose, theta)?;
    let tau_a = tau_of(&(geom.j_theta()? * pose_dot));
    check_state(pose_dot, &tau_a)?;
    env.check()?;
    chi_ddot_at(&geom, dp, pose_dot, &tau_a, env)
}
