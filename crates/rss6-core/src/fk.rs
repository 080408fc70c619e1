//! Forward kinematics χ = H_fwd(θ) (eq. 3.17).
//!
//! [`fk`] is the thesis's quasi-Stewart method (eq. 3.18–3.20, steps 1–4): the wrench tips T_i are fixed
//! by θ once (eq. 3.18), and Newton's method runs on the leg lengths of the equivalent Stewart platform
//! whose base points are T_i and whose legs must have the link lengths l_AT. The thesis adds the
//! rotational part of Δχ = J'⁻¹Δl directly to the Euler angles; J' (eq. 3.19) actually maps the twist
//! [Ė; ω], so we convert with J_e⁻¹ (eq. 3.22) — identical at zero tilt, and it keeps the quadratic
//! convergence of Newton's method away from it.
//!
//! [`fk_theta_newton`] is the "normal" method of Fig. 3.2: Newton on the joint angles, which needs an IK
//! (new T_i) and J_θ at every iterate.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::ik::{ik, wrench_tips};
use crate::jacobian::{jacobian_stewart, LegGeometry};
use crate::params::KinematicParams;
use crate::pose::euler_rate_jacobian;
use crate::types::{Vec3, Vec6};

/// Stopping rules of the iterative FK solvers (step 1 of §3.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkOptions {
    /// ε_c: stop when every leg-length residual |Δl_i| < ε_c (m).
    pub eps_c: f64,
    /// ε_p: stop when every component of the pose update |Δχ_j| < ε_p (m or rad).
    pub eps_p: f64,
    /// Hard bound on iterations; the solver never runs longer.
    pub max_iterations: u32,
}

impl Default for FkOptions {
    /// ε_c = 1e-13 m, ε_p = 1e-13, 30 iterations: round trips exact to ~1e-12.
    fn default() -> Self {
        FkOptions {
            eps_c: 1e-13,
            eps_p: 1e-13,
            max_iterations: 30,
        }
    }
}

/// A converged FK solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkSolution {
    /// The pose χ (m, rad).
    pub pose: Vec6,
    /// Newton iterations used (updates applied).
    pub iterations: u32,
    /// Largest leg-closure residual at `pose` (m).
    pub residual: f64,
}

fn check_inputs(theta: &Vec6, guess: &Vec6, opts: &FkOptions) -> Result<()> {
    check_finite(theta.as_slice())?;
    check_finite(guess.as_slice())?;
    if !(opts.eps_c >= 0.0 && opts.eps_p >= 0.0) {
        return Err(CoreError::InvalidParameter("FK tolerances must be >= 0"));
    }
    Ok(())
}

/// Converts a twist-space step [ΔE; Δω] into a pose step [ΔE; Δφ] (Δφ = J_e⁻¹ Δω).
fn twist_step_to_pose_step(pose: &Vec6, dv: &Vec6) -> Result<Vec6> {
    let je = euler_rate_jacobian(pose[3], pose[4]);
    let dphi = je
        .lu()
        .solve(&Vec3::new(dv[3], dv[4], dv[5]))
        .ok_or(CoreError::Singular(SingularKind::Euler))?;
    Ok(Vec6::new(dv[0], dv[1], dv[2], dphi[0], dphi[1], dphi[2]))
}

/// Quasi-Stewart forward kinematics (§3.4): pose χ from physical joint angles θ (rad), starting at
/// `guess` (e.g. the previous solution, or [`crate::home_pose`]).
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::Singular`] (J' lost rank),
/// [`CoreError::NotConverged`] after `opts.max_iterations`.
///
/// ```
/// use rss6_core::{fk, ik, home_pose, FkOptions, KinematicParams, Vec6};
/// let kp = KinematicParams::nominal();
/// let target = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03);
/// let sol = fk(&kp, &ik(&kp, &target).unwrap(), &home_pose(), &FkOptions::default()).unwrap();
/// assert!((sol.pose - target).amax() < 1e-10);
/// ```
pub fn fk(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    opts: &FkOptions,
) -> Result<FkSolution> {
    check_inputs(theta, guess, opts)?;
    let tips = wrench_tips(kp, theta);
    let target = Vec6::from_column_slice(&kp.link_lengths);
    let mut pose = *guess;
    let mut iterations = 0;
    loop {
        let (jp, len) = jacobian_stewart(kp, &pose, &tips)?;
        let dl = target - len;
        let residual = dl.amax();
        if !residual.is_finite() {
            return Err(CoreError::NonFinite);
        }
        if residual < opts.eps_c {
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
        if iterations >= opts.max_iterations {
            return Err(CoreError::NotConverged {
                iterations,
                residual,
            });
        }
        let dv = jp
            .lu()
            .solve(&dl)
            .ok_or(CoreError::Singular(SingularKind::StewartJacobian))?;
        let step = twist_step_to_pose_step(&pose, &dv)?;
        pose += step;
        iterations += 1;
        if step.amax() < opts.eps_p {
            let (_, len) = jacobian_stewart(kp, &pose, &tips)?;
            let residual = (target - len).amax();
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
    }
}

/// The "normal" FK of Fig. 3.2: Newton on θ, Δχ = J_θ⁻¹ (θ − θ(χ)) with an IK and J_θ per iterate.
/// Same stopping rules as [`fk`], with ε_c applied to the joint-angle residual (rad); the reported
/// `residual` is the joint-angle residual (rad).
pub fn fk_theta_newton(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    opts: &FkOptions,
) -> Result<FkSolution> {
    check_inputs(theta, guess, opts)?;
    let mut pose = *guess;
    let mut iterations = 0;
    loop {
        let geo = LegGeometry::at_pose(kp, &pose)?;
        let dth = theta - geo.theta;
        let residual = dth.amax();
        if residual < opts.eps_c {
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
        if iterations >= opts.max_iterations {
            return Err(CoreError::NotConverged {
                iterations,
                residual,
            });
        }
        let step = geo
            .j_theta()?
            .lu()
            .solve(&dth)
            .ok_or(CoreError::Singular(SingularKind::TypeII))?;
        pose += step;
        iterations += 1;
        if step.amax() < opts.eps_p {
            let residual = (theta - ik(kp, &pose)?).amax();
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
    }
}
