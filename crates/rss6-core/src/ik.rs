//! Analytic inverse kinematics θ = H_inv(χ) (eq. 3.3–3.16), for the general case z_Bi ≠ 0 that the
//! error model needs (ΔB_i moves B_i out of the base plane).
//!
//! The thesis eliminates x_T (eq. 3.9) and solves a quadratic in y_T (eq. 3.11–3.15); that form divides
//! by x_A − x_B and loses accuracy near it. We solve the same two circle equations (3.5, 3.6) in polar
//! form instead: with d = A_i − B_i and the wrench w = l_TB·[cos φ, sin φ, 0],
//! |d − w|² = l_AT² gives d_x cos φ + d_y sin φ = K = (|d|² + l_TB² − l_AT²)/(2 l_TB), so
//! φ = atan2(d_y, d_x) ± acos(K/ρ) with ρ = √(d_x² + d_y²). The pose is reachable iff |K/ρ| ≤ 1
//! (the discriminant of eq. 3.12), and θ_i = φ − θ0_i (eq. 3.16).
//!
//! Branch: θ_i ∈ (−π/2, π/2] (remark after eq. 3.16). If both roots fall in that range the one whose
//! wrench/link sign (w_i × l_i)·ẑ matches the nominal working mode [+, −, +, −, +, −] is taken, so the
//! solution is continuous across the workspace.

use crate::error::{check_finite, CoreError, Result};
use crate::params::{leg_side, KinematicParams};
use crate::pose::pose_rotation;
use crate::types::{Mat3, Vec3, Vec6, LEGS};
use core::f64::consts::{FRAC_PI_2, PI};
use libm::{acos, atan2, sqrt};

/// Wraps an angle to (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    // Fast path: the IK's angles are almost always in range already (fmod is slow).
    if a > -PI && a <= PI {
        return a;
    }
    let mut x = a % (2.0 * PI);
    if x <= -PI {
        x += 2.0 * PI;
    } else if x > PI {
        x -= 2.0 * PI;
    }
    x
}

/// Platform joint centres A_i in the base frame for pose χ (eq. 3.4).
pub fn platform_joints_in_base(kp: &KinematicParams, pose: &Vec6) -> [Vec3; LEGS] {
    platform_joints_with_rotation(kp, &pose_rotation(pose), pose)
}

/// A_i = R A'_i + E for a rotation already computed from `pose`.
pub(crate) fn platform_joints_with_rotation(
    kp: &KinematicParams,
    r: &Mat3,
    pose: &Vec6,
) -> [Vec3; LEGS] {
    let e = Vec3::new(pose[0], pose[1], pose[2]);
    let mut a = [Vec3::zeros(); LEGS];
    for (ai, ap) in a.iter_mut().zip(kp.platform_joints.iter()) {
        *ai = r * ap + e;
    }
    a
}

/// Wrench tips T_i for joint angles θ (eq. 3.18, with B_i added).
pub fn wrench_tips(kp: &KinematicParams, theta: &Vec6) -> [Vec3; LEGS] {
    let mut t = [Vec3::zeros(); LEGS];
    for (i, ti) in t.iter_mut().enumerate() {
        let (s, c) = libm::sincos(theta[i] + kp.theta0[i]);
        *ti = kp.base_joints[i] + kp.wrench_lengths[i] * Vec3::new(c, s, 0.0);
    }
    t
}

/// IK of one leg given its platform joint A_i in the base frame.
pub fn ik_leg(kp: &KinematicParams, leg: usize, a: &Vec3) -> Result<f64> {
    let b = kp
        .base_joints
        .get(leg)
        .ok_or(CoreError::InvalidParameter("leg index >= 6"))?;
    let (r, l) = (kp.wrench_lengths[leg], kp.link_lengths[leg]);
    let d = a - b;
    let rho = sqrt(d[0] * d[0] + d[1] * d[1]);
    let k = (d.norm_squared() + r * r - l * l) / (2.0 * r);
    let leg_u8 = leg as u8;
    if rho.is_nan() || rho <= 0.0 || !k.is_finite() {
        return Err(CoreError::Unreachable {
            leg: leg_u8,
            excess: f64::INFINITY,
        });
    }
    let c = k / rho;
    if c.abs() > 1.0 {
        return Err(CoreError::Unreachable {
            leg: leg_u8,
            excess: c.abs() - 1.0,
        });
    }
    let psi = atan2(d[1], d[0]);
    let delta = acos(c);
    let th0 = kp.theta0[leg];
    // Root "−" gives (w × l)·ẑ = l_TB ρ sin(δ) ≥ 0, root "+" the opposite sign.
    let (preferred, other) = if leg_side(leg) > 0.0 {
        (wrap_angle(psi - delta - th0), wrap_angle(psi + delta - th0))
    } else {
        (wrap_angle(psi + delta - th0), wrap_angle(psi - delta - th0))
    };
    let in_branch = |t: f64| t > -FRAC_PI_2 && t <= FRAC_PI_2;
    if in_branch(preferred) {
        Ok(preferred)
    } else if in_branch(other) {
        Ok(other)
    } else {
        let theta = if preferred.abs() <= other.abs() {
            preferred
        } else {
            other
        };
        Err(CoreError::OutOfBranch { leg: leg_u8, theta })
    }
}

/// Inverse kinematics θ = H_inv(χ): physical joint angles (rad) for pose χ (m, rad).
///
/// Errors: [`CoreError::NonFinite`] for NaN/∞ input, [`CoreError::Unreachable`] naming the first leg
/// that cannot close, [`CoreError::OutOfBranch`] if no root lies in (−π/2, π/2].
///
/// ```
/// use rss6_core::{ik, home_pose, KinematicParams};
/// let theta = ik(&KinematicParams::nominal(), &home_pose()).unwrap();
/// assert!(theta.amax() < 1e-12); // home pose ↔ θ = 0
/// ```
pub fn ik(kp: &KinematicParams, pose: &Vec6) -> Result<Vec6> {
    check_finite(pose.as_slice())?;
    let a = platform_joints_in_base(kp, pose);
    let mut theta = Vec6::zeros();
    for (i, ai) in a.iter().enumerate() {
        theta[i] = ik_leg(kp, i, ai)?;
    }
    Ok(theta)
}

/// IK returning potentiometer readings κ (bits) instead of angles: κ = (θ − Δθ)/η (eq. 4.2).
pub fn ik_reading(kp: &KinematicParams, pose: &Vec6) -> Result<Vec6> {
    Ok(kp.reading_from_theta(&ik(kp, pose)?))
}
