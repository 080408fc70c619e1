//! Joint friction stepped implicitly over one control tick: the one friction law of the plant, the
//! model twin and CLOE.
//!
//! Over a tick of length dt the friction torque τ_f is held, like the drive torque τ_a. It is the
//! torque for which the joint rates predicted at the end of the tick by one step of the
//! friction-free dynamics at the current configuration,
//!
//! ```text
//! w = θ̇ + dt J_ad M⁻¹ (J_adᵀ (τ_a − τ_f) − b) = w₀ − K τ_f,      K = dt J_ad M⁻¹ J_adᵀ
//! ```
//!
//! (M, b: twist-space mass matrix and velocity + gravity forces; J_ad: θ̇ = J_ad v) obey Coulomb +
//! viscous friction (eq. 3.48) with sign(0) the whole interval [−1, 1]:
//!
//! ```text
//! τ_f,i = f_c,i sign(w_i) + f_v,i w_i   if w_i ≠ 0;     |τ_f,i| ≤ f_c,i   if w_i = 0 (the joint sticks).
//! ```
//!
//! This is implicit Euler for the friction alone (the time-stepping of Moreau and Jean): a joint
//! whose drive torque stays below f_c sticks, no step overshoots zero velocity, and the step is
//! stable for any f_c, f_v and dt — no smoothing ε and no stiffness limit, unlike f_c sign(θ̇) or
//! f_c tanh(θ̇/ε) inside an explicit integrator. The conditions above are the optimality
//! conditions of the strictly convex problem
//!
//! ```text
//! min_τ ½ τᵀ K τ − τᵀ w₀ + Σ_i ψ_i(τ_i),    ψ_i(τ) = max(|τ| − f_c,i, 0)² / (2 f_v,i)
//! ```
//!
//! (ψ_i is the indicator of |τ| ≤ f_c,i when f_v,i = 0), solved by Gauss–Seidel over the joints
//! (each coordinate in closed form) with an active-set polish: once the sweeps have settled which
//! joints stick and which way the others slip, one 6 × 6 linear solve gives the exact solution,
//! accepted only if it satisfies every condition. Both loops are bounded.
//!
//! The same function drives the rapier plant (on the plant's own state and true parameters, with
//! `SimConfig::implicit_friction`) and the analytic twin, so a friction estimate on either means
//! the same thing. Because the law predicts the step with the model's dynamics, an engine follows
//! it only as far as its own step agrees with the model: rapier at its default 4 solver iterations
//! responds to a torque from rest ≈ 2× faster than the model, enough to break sticks the model
//! holds (measured in rss6-sim's docs).
//!
//! (A variant applied after the engine's step, on its own end-of-step rates, was tried: it sticks
//! exactly on rapier's state, but the stick band f_c/l_p is 3–14 mrad with Table 5.2's friction, so
//! an O(dt) change of discretisation moves where joints stick by mrad — 0.5 mm of platform motion
//! against the twin. The law must be the same discrete map in both simulators.)

use super::integration::{rk4_step_by, ModelState};
use super::load::Environment;
use super::newton_euler::{
    accel_from, chi_ddot_at, factor, solve6, twist_dynamics_at, TwistDynamics,
};
use super::{check_finite, check_state};
use crate::error::{CoreError, Result};
use crate::jacobian::LegGeometry;
use crate::params::{DynamicParams, KinematicParams};
use crate::types::{Mat6, Vec6, LEGS};
use nalgebra::{Cholesky, U6};

/// Gauss–Seidel sweeps at most.
const MAX_SWEEPS: u32 = 400;
/// A polish is tried after every this many sweeps.
const POLISH_EVERY: u32 = 2;
/// Relative tolerance of the stick / slip conditions accepted from a polish.
const TOL: f64 = 1e-9;

/// The friction torque held over one tick and what it implies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionStep {
    /// τ_f (N·m), opposing the motion: the joint torque is τ_a − τ_f.
    pub torque: Vec6,
    /// Predicted joint rates w at the end of the tick (rad/s); 0 where a joint sticks.
    pub rate: Vec6,
    /// w₀: the predicted rates without friction (rad/s).
    pub free_rate: Vec6,
    /// K = dt J_ad M⁻¹ J_adᵀ (rad/s per N·m): w = w₀ − K τ_f.
    pub compliance: Mat6,
    /// Platform twist change −dt M⁻¹ J_adᵀ τ_f (m/s, rad/s) that the friction makes over the tick.
    pub twist_change: Vec6,
    /// Which joints stick (w_i = 0, |τ_f,i| ≤ f_c,i).
    pub stuck: [bool; LEGS],
    /// Gauss–Seidel sweeps used.
    pub sweeps: u32,
    /// `true` when the active-set solution was accepted (exact up to rounding); `false` when the
    /// sweep bound was reached first and `torque` is the last Gauss–Seidel iterate.
    pub exact: bool,
}

/// The implicit friction torque of one tick of length `dt` (s) from the state (χ, χ̇), the held
/// drive torques τ_a (N·m) and the environment (gravity, load). Friction coefficients are `dp`'s `coulomb` and
/// `viscous` (negative values are treated as 0).
///
/// Errors: IK errors, [`CoreError::NonFinite`], [`CoreError::Singular`] (type I, or a mass matrix
/// that is not positive definite), [`CoreError::InvalidParameter`] for dt ≤ 0.
pub fn implicit_friction(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
    dt: f64,
) -> Result<FrictionStep> {
    // The checks in the order callers have always seen their errors (repeated inside: cheap).
    check_state(pose_dot, tau_a)?;
    check_dt(dt)?;
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    implicit_friction_at(&geom, dp, pose_dot, tau_a, env, dt).map(|(s, ..)| s)
}

/// [`implicit_friction`] at a known geometry (the environment already checked); also returns the
/// twist dynamics and the Cholesky factor of M it used, for the tick's first RK4 stage.
fn implicit_friction_at(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
    dt: f64,
) -> Result<(FrictionStep, TwistDynamics, Cholesky<f64, U6>)> {
    check_state(pose_dot, tau_a)?;
    check_dt(dt)?;
    let td = twist_dynamics_at(geom, dp, pose_dot, env)?;
    let TwistDynamics {
        bias,
        theta_dot,
        j_ad_t,
        ..
    } = td;
    let chol = factor(&td)?;
    let x = chol.solve(&j_ad_t);
    let k = j_ad_t.transpose() * x * dt;
    let k = (k + k.transpose()) * 0.5;
    let w0 = theta_dot + j_ad_t.transpose() * chol.solve(&(j_ad_t * tau_a - bias)) * dt;
    check_finite(k.as_slice())?;
    check_finite(w0.as_slice())?;
    let fc = Vec6::from_fn(|i, _| dp.coulomb[i].max(0.0));
    let fv = Vec6::from_fn(|i, _| dp.viscous[i].max(0.0));
    let mut s = solve(&k, &w0, &fc, &fv);
    s.twist_change = -(x * s.torque) * dt;
    Ok((s, td, chol))
}

/// One tick of the implicit friction law: the friction τ_f of [`implicit_friction`], then one RK4
/// step ([`crate::rk4_step_with_env`]) of the friction-free model (`dp` with zero Coulomb and
/// viscous coefficients) under τ_a − τ_f. The result is bit for bit that of the two calls; the
/// first stage reuses the friction step's mass matrix and forces (four dynamics evaluations per
/// tick instead of five). `theta`: the joint angles of `state.pose` when already known (from
/// [`crate::ik`] at that pose), else `None` (one IK more). Angles that do not close every leg at
/// the pose (relative error of |l_i|² above 10⁻⁹, e.g. those of an earlier pose) are refused; the
/// other root of a leg's IK closes it too, so angles from anything but `ik` are the caller's risk.
///
/// Errors: as [`implicit_friction`] and [`crate::rk4_step_with_env`];
/// [`CoreError::InvalidParameter`] for angles that do not close the legs.
pub fn rk4_step_implicit_friction(
    kp: &KinematicParams,
    dp: &DynamicParams,
    state: &ModelState,
    tau_a: &Vec6,
    dt: f64,
    env: &Environment,
    theta: Option<&Vec6>,
) -> Result<(ModelState, FrictionStep)> {
    rk4_step_implicit_friction_observed(kp, dp, state, tau_a, dt, env, theta, |_, _, _, _| {})
}

/// [`rk4_step_implicit_friction`], calling `stage(χ, χ̇, θ, χ̈)` with each RK4 stage's state, its
/// joint angles θ = IK(χ) and its acceleration, in order (four calls when the step succeeds; all
/// four stages are under τ_a − τ_f, the step's [`FrictionStep::torque`] taken from τ_a, on the
/// friction-free model): what a caller needs to evaluate the same stages again, e.g. with their
/// derivatives ([`crate::JacobianRequest::theta`], [`crate::JacobianRequest::pose_ddot`]). χ̈ is
/// [`crate::forward_dynamics_with_env`]'s at (χ, χ̇, τ_a − τ_f) bit for bit, and the step is bit
/// for bit [`rk4_step_implicit_friction`]'s.
///
/// Errors: as [`rk4_step_implicit_friction`].
#[allow(clippy::too_many_arguments)]
pub fn rk4_step_implicit_friction_observed<F: FnMut(&Vec6, &Vec6, &Vec6, &Vec6)>(
    kp: &KinematicParams,
    dp: &DynamicParams,
    state: &ModelState,
    tau_a: &Vec6,
    dt: f64,
    env: &Environment,
    theta: Option<&Vec6>,
    mut stage: F,
) -> Result<(ModelState, FrictionStep)> {
    env.check()?;
    let geom = LegGeometry::at_pose_from(kp, &state.pose, theta)?;
    let (f, td, chol) = implicit_friction_at(&geom, dp, &state.pose_dot, tau_a, env, dt)?;
    let mut dp_nf = *dp;
    dp_nf.coulomb = [0.0; LEGS];
    dp_nf.viscous = [0.0; LEGS];
    let net = tau_a - f.torque;
    check_state(&state.pose_dot, &net)?;
    let first = accel_from(&geom, &td, &chol, &dp_nf, &state.pose_dot, &net)?.chi_ddot;
    // rk4_step_by evaluates its stages in order: the first is the one computed above; the others
    // are `forward_dynamics_with_env`'s steps (its checks, IK, `chi_ddot_at`), θ kept.
    let mut k = 0u8;
    let next = rk4_step_by(state, dt, |p, v| {
        k = k.saturating_add(1);
        if k == 1 {
            stage(p, v, &geom.theta, &first);
            Ok(first)
        } else {
            check_state(v, &net)?;
            let g = LegGeometry::at_pose(kp, p)?;
            let a = chi_ddot_at(&g, &dp_nf, v, &net, env)?;
            stage(p, v, &g.theta, &a);
            Ok(a)
        }
    })?;
    Ok((next, f))
}

fn check_dt(dt: f64) -> Result<()> {
    if dt > 0.0 && dt.is_finite() {
        Ok(())
    } else {
        Err(CoreError::InvalidParameter(
            "dt must be positive and finite",
        ))
    }
}

/// One joint's friction torque given r, its rate if its own friction were zero.
fn coordinate(kii: f64, r: f64, fc: f64, fv: f64) -> (f64, bool) {
    if fc > 0.0 && r.abs() <= kii * fc {
        (r / kii, true)
    } else {
        // Slip: τ = s f_c + f_v w with w = r − K_ii τ.
        let s = if r > 0.0 {
            1.0
        } else if r < 0.0 {
            -1.0
        } else {
            0.0
        };
        ((fv * r + s * fc) / (1.0 + fv * kii), false)
    }
}

/// Solves the friction conditions for K, w₀ (see the module docs).
fn solve(k: &Mat6, w0: &Vec6, fc: &Vec6, fv: &Vec6) -> FrictionStep {
    let mut tau = Vec6::zeros();
    let mut stuck = [false; LEGS];
    let mut sweeps = 0;
    let mut exact = false;
    let positive = (0..LEGS).all(|i| k[(i, i)] > 0.0);
    if positive {
        while sweeps < MAX_SWEEPS {
            for i in 0..LEGS {
                let r = w0[i] - (k.row(i) * tau)[0] + k[(i, i)] * tau[i];
                (tau[i], stuck[i]) = coordinate(k[(i, i)], r, fc[i], fv[i]);
            }
            sweeps += 1;
            if sweeps % POLISH_EVERY == 0 {
                if let Some(t) = polish(k, w0, fc, fv, &tau, &stuck) {
                    tau = t;
                    exact = true;
                    break;
                }
            }
        }
    }
    let rate = w0 - k * tau;
    FrictionStep {
        torque: tau,
        // Exactly zero where an exact solution sticks (rounding would leave ~1e-17).
        rate: if exact {
            Vec6::from_fn(|i, _| if stuck[i] { 0.0 } else { rate[i] })
        } else {
            rate
        },
        free_rate: *w0,
        compliance: *k,
        twist_change: Vec6::zeros(),
        stuck,
        sweeps,
        exact,
    }
}

/// The exact solution for the stick set and slip signs of `tau`, if it satisfies every condition.
fn polish(
    k: &Mat6,
    w0: &Vec6,
    fc: &Vec6,
    fv: &Vec6,
    tau: &Vec6,
    stuck: &[bool; LEGS],
) -> Option<Vec6> {
    let w = w0 - k * tau;
    let mut a = Mat6::zeros();
    let mut b = Vec6::zeros();
    let mut sign = [0.0; LEGS];
    for i in 0..LEGS {
        if stuck[i] {
            // (K τ)_i = w₀_i.
            a.set_row(i, &k.row(i));
            b[i] = w0[i];
        } else {
            // τ_i + f_v (K τ)_i = s f_c + f_v w₀_i.
            let s = if w[i] > 0.0 {
                1.0
            } else if w[i] < 0.0 {
                -1.0
            } else {
                0.0
            };
            sign[i] = s;
            a.set_row(i, &(k.row(i) * fv[i]));
            a[(i, i)] += 1.0;
            b[i] = s * fc[i] + fv[i] * w0[i];
        }
    }
    let t = solve6(a, b)?;
    let w = w0 - k * t;
    let scale = w0.amax().max((k * t).amax()).max(f64::MIN_POSITIVE);
    for i in 0..LEGS {
        if stuck[i] {
            if t[i].abs() > fc[i] * (1.0 + TOL) + TOL * scale / k[(i, i)] {
                return None;
            }
        } else if sign[i] * w[i] < -TOL * scale || (sign[i] == 0.0 && fc[i] > 0.0) {
            return None;
        }
    }
    check_finite(t.as_slice()).ok()?;
    Some(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fc_fv(fc: f64, fv: f64) -> (Vec6, Vec6) {
        (Vec6::from_element(fc), Vec6::from_element(fv))
    }

    #[test]
    fn single_joint_closed_form() {
        // Diagonal K: each joint on its own. Stick when |w0| ≤ K f_c; else slip.
        let k = Mat6::from_diagonal(&Vec6::from_element(0.5));
        let w0 = Vec6::new(0.1, -0.1, 1.0, -1.0, 0.0, 0.3);
        let (fc, fv) = fc_fv(0.4, 2.0);
        let s = solve(&k, &w0, &fc, &fv);
        assert!(s.exact);
        assert_eq!(s.stuck, [true, true, false, false, true, false]);
        assert_eq!(s.rate[0], 0.0);
        assert!((s.torque[0] - 0.2).abs() < 1e-15);
        // Slip: w = (w0 − K f_c)/(1 + f_v K) = (1 − 0.2)/2 = 0.4; τ = f_c + f_v w = 1.2.
        assert!((s.rate[2] - 0.4).abs() < 1e-14, "{}", s.rate[2]);
        assert!((s.torque[2] - 1.2).abs() < 1e-14);
        assert!((s.torque[3] + 1.2).abs() < 1e-14);
        // w0 = 0.3 > K f_c = 0.2: slips with w = 0.1/2.
        assert!((s.rate[5] - 0.05).abs() < 1e-14);
    }

    #[test]
    fn coupled_conditions_hold() {
        // A strongly coupled SPD K (off-diagonals 0.9 of the diagonal scale).
        let mut k = Mat6::from_element(0.45);
        for i in 0..LEGS {
            k[(i, i)] = 0.5 + 0.01 * i as f64;
        }
        let w0 = Vec6::new(0.3, -0.05, 0.8, 0.0, -0.6, 0.1);
        let (fc, fv) = fc_fv(0.3, 0.7);
        let s = solve(&k, &w0, &fc, &fv);
        assert!(s.exact, "sweeps {}", s.sweeps);
        let w = w0 - k * s.torque;
        for i in 0..LEGS {
            if s.stuck[i] {
                assert!(w[i].abs() < 1e-12 && s.torque[i].abs() <= 0.3 + 1e-12);
            } else {
                let expect = 0.3 * w[i].signum() + 0.7 * w[i];
                assert!((s.torque[i] - expect).abs() < 1e-12, "joint {i}");
            }
        }
    }

    #[test]
    fn no_friction_no_torque() {
        let k = Mat6::identity() * 0.3;
        let w0 = Vec6::new(1.0, -2.0, 0.0, 3.0, 0.5, -0.5);
        let s = solve(&k, &w0, &Vec6::zeros(), &Vec6::zeros());
        assert!(s.exact);
        assert_eq!(s.torque, Vec6::zeros());
        assert_eq!(s.rate, w0);
    }
}
