//! The dynamic regressor (eq. 5.1): the model is linear in Ξ (64, docs/architecture.md order: [m, I_x, I_y, I_z]
//! for the platform, wrenches 1..6, links 1..6, then f_c,1..6, f_v,1..6), so
//!
//! ```text
//! τ_a = Γ(χ, χ̇, χ̈) Ξ                 (actuator-torque form, [`regressor`])
//! J_adᵀ τ_a = τ_g = Γ_g(χ, v_E, v̇_E) Ξ  (the thesis's τ_g form of eq. 5.1, [`regressor_tau_g`])
//! ```
//!
//! Columns that the model does not use are identically zero: wrench I_x, I_y and link I_z (see
//! [`crate::dynamics`] module docs); the link's I_x and I_y columns are equal (the model uses
//! (I_x + I_y)/2). The Coulomb columns carry sign(θ̇_i) with sign(0) = 0, exactly as
//! [`crate::inverse_dynamics`] does.

use crate::dynamics::{leg_acc, GRAVITY};
use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::jacobian::LegGeometry;
use crate::params::{KinematicParams, N_DYN};
use crate::pose::{twist_jacobian, twist_jacobian_dot};
use crate::types::{Mat3, Mat6, Vec3, Vec6, LEGS};
use nalgebra::SMatrix;

/// A 6 × 64 regressor Γ (eq. 5.1): rows are joints (or twist components), columns follow Ξ.
pub type Regressor = SMatrix<f64, 6, N_DYN>;

#[inline]
fn put(gamma: &mut Regressor, col: usize, x: &Vec6) {
    gamma.fixed_view_mut::<6, 1>(0, col).copy_from(x);
}

/// The body columns of Γ_g (twist-space generalised force per unit parameter) and θ̇.
fn body_columns(
    kp: &KinematicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    g: &Vec3,
) -> Result<(LegGeometry, Regressor, Vec6)> {
    check_finite(pose_dot.as_slice())?;
    check_finite(pose_ddot.as_slice())?;
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let mut gamma = Regressor::zeros();
    let theta_dot = body_columns_at(&geom, pose_dot, pose_ddot, g, &mut gamma)?;
    Ok((geom, gamma, theta_dot))
}

/// [`body_columns`] at a known geometry (inputs already checked), written into `gamma` (its
/// friction columns are left as they are); returns θ̇.
fn body_columns_at(
    geom: &LegGeometry,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    g: &Vec3,
    gamma: &mut Regressor,
) -> Result<Vec6> {
    let pose = &geom.pose;
    let js = twist_jacobian(pose);
    let v = js * pose_dot;
    let v_dot = js * pose_ddot + twist_jacobian_dot(pose, pose_dot) * pose_dot;
    gamma.columns_mut(0, 4 * (1 + 2 * LEGS)).fill(0.0);
    for (k, c) in platform_columns(&geom.rot, &v, &v_dot, g)
        .iter()
        .enumerate()
    {
        put(gamma, k, c);
    }
    let mut theta_dot = Vec6::zeros();
    for i in 0..LEGS {
        let k = leg_acc(geom, i, &v, &v_dot)?;
        theta_dot[i] = k.theta_dot;
        let cw = 4 * (1 + i);
        put(gamma, cw, &(k.r * k.s_cw.dot(&(k.cw_acc - g))));
        put(gamma, cw + 3, &(k.r * k.theta_ddot));
        let cl = 4 * (7 + i);
        put(gamma, cl, &k.jbu_t(&(k.cl_acc - g)));
        let half = k.jbd_t(&k.omega2_dot) * 0.5;
        put(gamma, cl + 1, &half);
        put(gamma, cl + 2, &half);
    }
    Ok(theta_dot)
}

/// The platform's columns of Γ_g at the twist v, its rate v̇ and gravity g (R the platform's
/// rotation): m → [Ë − g; 0]; I_k → [0; r_k (r_k·ω̇) + (ω × r_k)(r_k·ω)], r_k = column k of R.
pub(crate) fn platform_columns(rot: &Mat3, v: &Vec6, v_dot: &Vec6, g: &Vec3) -> [Vec6; 4] {
    let omega = Vec3::new(v[3], v[4], v[5]);
    let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
    let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
    let lin = e_ddot - g;
    let mut c = [Vec6::new(lin[0], lin[1], lin[2], 0.0, 0.0, 0.0); 4];
    for k in 0..3 {
        let rk: Vec3 = rot.column(k).into_owned();
        let n = rk * rk.dot(&omega_dot) + omega.cross(&rk) * rk.dot(&omega);
        c[1 + k] = Vec6::new(0.0, 0.0, 0.0, n[0], n[1], n[2]);
    }
    c
}

/// Actuator-torque regressor Γ (6 × 64) with τ_a = Γ(χ, χ̇, χ̈)·Ξ, g = [`GRAVITY`]. χ in m and rad,
/// its derivatives per s and s². Agrees with [`crate::inverse_dynamics`] for every Ξ.
///
/// ```
/// use rss6_core::*;
/// let kp = KinematicParams::nominal();
/// let mut dp = DynamicParams::nominal();
/// dp.coulomb = [0.2; 6];
/// dp.viscous = [0.05; 6];
/// let pose = Vec6::new(0.01, 0.0, 0.12, 0.0, 0.03, 0.0);
/// let (pd, pdd) = (Vec6::new(0.0, 0.1, 0.0, 0.3, 0.0, 0.0), Vec6::new(1.0, 0.0, 0.0, 0.0, 0.0, 2.0));
/// let gamma = regressor(&kp, &pose, &pd, &pdd).unwrap();
/// let xi = nalgebra::SVector::<f64, 64>::from_column_slice(&dp.to_vector());
/// let tau = inverse_dynamics(&kp, &dp, &pose, &pd, &pdd).unwrap();
/// assert!((gamma * xi - tau).amax() < 1e-12 * tau.amax());
/// ```
pub fn regressor(
    kp: &KinematicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
) -> Result<Regressor> {
    regressor_with_gravity(kp, pose, pose_dot, pose_ddot, &GRAVITY)
}

/// [`regressor`] with an arbitrary gravity vector `g` (m/s², base frame).
pub fn regressor_with_gravity(
    kp: &KinematicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    g: &Vec3,
) -> Result<Regressor> {
    let (geom, cols, theta_dot) = body_columns(kp, pose, pose_dot, pose_ddot, g)?;
    let j_ad = geom.j_ad()?;
    let mut gamma = j_ad
        .transpose()
        .lu()
        .solve(&cols)
        .ok_or(CoreError::Singular(SingularKind::TypeII))?;
    check_finite(gamma.as_slice()).map_err(|_| CoreError::Singular(SingularKind::TypeII))?;
    for i in 0..LEGS {
        let td = theta_dot[i];
        gamma[(i, 52 + i)] = if td > 0.0 {
            1.0
        } else if td < 0.0 {
            -1.0
        } else {
            0.0
        };
        gamma[(i, 58 + i)] = td;
    }
    Ok(gamma)
}

/// Generalised-force regressor Γ_g (6 × 64, eq. 5.1 as printed): τ_g = J_adᵀ τ_a = Γ_g·Ξ, rows are the
/// twist components [force (N); moment (N·m)], g = [`GRAVITY`].
pub fn regressor_tau_g(
    kp: &KinematicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
) -> Result<Regressor> {
    let (geom, gamma, theta_dot) = body_columns(kp, pose, pose_dot, pose_ddot, &GRAVITY)?;
    Ok(with_twist_friction_columns(
        gamma,
        &geom.j_ad()?,
        &theta_dot,
    ))
}

/// Γ_g's friction columns: J_adᵀ e_i sign(θ̇_i) and J_adᵀ e_i θ̇_i.
fn with_twist_friction_columns(mut gamma: Regressor, j_ad: &Mat6, theta_dot: &Vec6) -> Regressor {
    twist_friction_columns(&mut gamma, j_ad, theta_dot);
    gamma
}

fn twist_friction_columns(gamma: &mut Regressor, j_ad: &Mat6, theta_dot: &Vec6) {
    for i in 0..LEGS {
        let td = theta_dot[i];
        let s = if td > 0.0 {
            1.0
        } else if td < 0.0 {
            -1.0
        } else {
            0.0
        };
        let row: Vec6 = j_ad.row(i).transpose();
        put(gamma, 52 + i, &(row * s));
        put(gamma, 58 + i, &(row * td));
    }
}
