//! Time integration of the analytic model: [`ModelState`] and one RK4 step of the forward dynamics.

use super::load::Environment;
use super::newton_euler::forward_dynamics_with_env;
use super::GRAVITY;
use crate::error::{CoreError, Result};
use crate::params::{DynamicParams, KinematicParams};
use crate::types::{Vec3, Vec6};

/// State of the analytic model: pose χ (m, rad) and its rate χ̇ (m/s, rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelState {
    /// χ = [x, y, z, α, β, γ].
    pub pose: Vec6,
    /// χ̇.
    pub pose_dot: Vec6,
}

impl ModelState {
    /// The robot at rest at `pose` (χ̇ = 0).
    pub fn at_rest(pose: &Vec6) -> Self {
        ModelState {
            pose: *pose,
            pose_dot: Vec6::zeros(),
        }
    }
}

/// One classical fourth-order Runge–Kutta step of length `dt` (s) of the forward dynamics with the
/// actuator torques τ_a (N·m) held constant over the step, g = [`GRAVITY`]. Errors as
/// [`crate::forward_dynamics`] at any of the four stages (e.g. a stage state leaving the workspace).
pub fn rk4_step(
    kp: &KinematicParams,
    dp: &DynamicParams,
    state: &ModelState,
    tau_a: &Vec6,
    dt: f64,
) -> Result<ModelState> {
    rk4_step_with_gravity(kp, dp, state, tau_a, dt, &GRAVITY)
}

/// [`rk4_step`] with an arbitrary gravity vector `g` (m/s², base frame).
pub fn rk4_step_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    state: &ModelState,
    tau_a: &Vec6,
    dt: f64,
    g: &Vec3,
) -> Result<ModelState> {
    rk4_step_with_env(kp, dp, state, tau_a, dt, &Environment::with_gravity(*g))
}

/// [`rk4_step`] in the environment `env` (gravity and an optional load fixed to the platform): each
/// stage is [`crate::forward_dynamics_with_env`]. `dt` in s, τ_a in N·m, held over the step.
pub fn rk4_step_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    state: &ModelState,
    tau_a: &Vec6,
    dt: f64,
    env: &Environment,
) -> Result<ModelState> {
    rk4_step_by(state, dt, |p: &Vec6, pd: &Vec6| {
        forward_dynamics_with_env(kp, dp, p, pd, tau_a, env)
    })
}

/// One classical RK4 step of χ̈ = f(χ, χ̇) over `dt` (s): the integrator of [`rk4_step`] for any
/// acceleration function (e.g. forward dynamics with a modified friction law). `f` is called
/// once per stage, in order (it may keep state, e.g. to reuse a first stage already evaluated).
///
/// Errors: [`CoreError::NonFinite`] for a non-finite `dt`; whatever `f` returns.
pub fn rk4_step_by<F>(state: &ModelState, dt: f64, mut f: F) -> Result<ModelState>
where
    F: FnMut(&Vec6, &Vec6) -> Result<Vec6>,
{
    if !dt.is_finite() {
        return Err(CoreError::NonFinite);
    }
    let (p0, v0) = (state.pose, state.pose_dot);
    let a1 = f(&p0, &v0)?;
    let (p2, v2) = (p0 + v0 * (0.5 * dt), v0 + a1 * (0.5 * dt));
    let a2 = f(&p2, &v2)?;
    let (p3, v3) = (p0 + v2 * (0.5 * dt), v0 + a2 * (0.5 * dt));
    let a3 = f(&p3, &v3)?;
    let (p4, v4) = (p0 + v3 * dt, v0 + a3 * dt);
    let a4 = f(&p4, &v4)?;
    Ok(ModelState {
        pose: p0 + (v0 + v2 * 2.0 + v3 * 2.0 + v4) * (dt / 6.0),
        pose_dot: v0 + (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (dt / 6.0),
    })
}
