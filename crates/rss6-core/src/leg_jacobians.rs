//! Per-leg body Jacobians of the 6-RSS robot (§3.5, eq. 3.31–3.40) and their time derivatives
//! (appendix A.1–A.6).
//!
//! For leg i, with the leg vectors of [`LegGeometry`] (w_i = T_i − B_i, l_i = A_i − T_i,
//! a_i = R·A'_i) and the end-effector twist v_E = [Ė; ω] = J_s χ̇ (eq. 3.23):
//!
//! * `J_ad,i = [l_iᵀ, (a_i × l_i)ᵀ] / m_i`, m_i = (w_i × l_i)·ŝ — row i of J_ad (eq. 3.30), θ̇_i = J_ad,i v_E;
//! * wrench (eq. 3.31–3.33): centre of mass at c_w,i = w_i/2 from B_i,
//!   `J_a,i = [(ŝ × c_w,i) J_ad,i ; ŝ J_ad,i]` maps v_E to [ċ_w,i; ω_1,i];
//! * link (eq. 3.36–3.40): centre of mass at c_l,i = l_i/2 from T_i, angular velocity ω_2,i ⊥ l_i
//!   (Assumption 2), `J_bd,i = ([[l]×, −[l]×[a]×] + [l]×[w]× ŝ J_ad,i)/‖l‖²`,
//!   `J_bu,i = −[w]× ŝ J_ad,i − [c_l]× J_bd,i`, `J_b,i = [J_bu,i; J_bd,i]` maps v_E to [ċ_l,i; ω_2,i].
//!
//! **Time derivatives.** J̇_a,i and J̇_b,i are obtained by exact (product-rule) differentiation of the
//! closed forms above along the motion, with ẇ = ω_1 × w, ȧ = ω × a, l̇ = Ė + ȧ − ẇ, ṁ = (ẇ × l + w × l̇)·ŝ.
//! This is the appendix's result (A.2–A.6) written with l̇ where the appendix writes ω_2 × l (equal,
//! since ‖l_i‖ is constant) and with ċ_l = l̇/2 in A.6. The term −2(l·l̇)/‖l‖⁴ of d(1/‖l‖²)/dt is kept
//! although it vanishes on the constraint manifold. The tests check every J̇ against finite
//! differences of J along trajectories.

use crate::error::{CoreError, Result, SingularKind};
use crate::jacobian::{LegGeometry, TYPE_I_TOLERANCE};
use crate::params::KinematicParams;
use crate::pose::twist_jacobian;
use crate::types::{LegJacobian, Mat3x6, Vec3, Vec6, LEGS};

/// Revolute axis ŝ = ẑ of every wrench.
pub(crate) const S_HAT: Vec3 = Vec3::new(0.0, 0.0, 1.0);

/// Velocity-level kinematics of one leg at one state: the compact blocks the dynamics uses.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegKin {
    /// Row i of J_ad (as a column vector).
    pub(crate) r: Vec6,
    /// Its time derivative.
    pub(crate) r_dot: Vec6,
    /// θ̇_i (rad/s).
    pub(crate) theta_dot: f64,
    /// J_au,i (eq. 3.32) and its derivative.
    pub(crate) jau: Mat3x6,
    pub(crate) jau_dot: Mat3x6,
    /// J_bu,i, J_bd,i (eq. 3.39, 3.37) and their derivatives.
    pub(crate) jbu: Mat3x6,
    pub(crate) jbu_dot: Mat3x6,
    pub(crate) jbd: Mat3x6,
    pub(crate) jbd_dot: Mat3x6,
    /// ω_1,i and ω_2,i (rad/s).
    pub(crate) omega1: Vec3,
    pub(crate) omega2: Vec3,
}

/// m_i = (w_i × l_i)·ŝ, the diagonal entry of J_a1 (eq. 3.29), checked against type-I singularity.
#[inline]
pub(crate) fn leg_m(w: &Vec3, l: &Vec3) -> Result<f64> {
    let m = w[0] * l[1] - w[1] * l[0];
    if m.abs() < TYPE_I_TOLERANCE || !m.is_finite() {
        return Err(CoreError::Singular(SingularKind::TypeI));
    }
    Ok(m)
}

#[inline]
fn stack(top: &Vec3, bottom: &Vec3) -> Vec6 {
    Vec6::new(top[0], top[1], top[2], bottom[0], bottom[1], bottom[2])
}

/// [[u]×, −[u]×[a]×] as a 3 × 6 block.
#[inline]
fn cross_block(left: &nalgebra::Matrix3<f64>, right: &nalgebra::Matrix3<f64>) -> Mat3x6 {
    let mut j = Mat3x6::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(left);
    j.fixed_view_mut::<3, 3>(0, 3).copy_from(right);
    j
}

/// Leg `i` kinematics for the twist `v` (v_E = [Ė; ω]).
pub(crate) fn leg_kin(geom: &LegGeometry, i: usize, v: &Vec6) -> Result<LegKin> {
    let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
    let e_dot = Vec3::new(v[0], v[1], v[2]);
    let omega = Vec3::new(v[3], v[4], v[5]);
    let m = leg_m(&w, &l)?;
    let inv_m = 1.0 / m;
    let r = stack(&l, &a.cross(&l)) * inv_m;
    let theta_dot = r.dot(v);
    let omega1 = S_HAT * theta_dot;
    let w_dot = omega1.cross(&w);
    let a_dot = omega.cross(&a);
    let l_dot = e_dot + a_dot - w_dot;
    let m_dot = w_dot[0] * l[1] - w_dot[1] * l[0] + w[0] * l_dot[1] - w[1] * l_dot[0];
    let r_dot = (stack(&l_dot, &(a_dot.cross(&l) + a.cross(&l_dot))) - r * m_dot) * inv_m;

    // Wrench, eq. 3.32 and A.3 (c_w = w/2).
    let cw = w * 0.5;
    let cw_dot = w_dot * 0.5;
    let s_cw = S_HAT.cross(&cw);
    let jau = s_cw * r.transpose();
    let jau_dot = S_HAT.cross(&cw_dot) * r.transpose() + s_cw * r_dot.transpose();

    // Link, eq. 3.37, 3.39 and A.5, A.6 (c_l = l/2).
    let l2 = l.norm_squared();
    let inv_l2 = 1.0 / l2;
    let (lx, ax) = (l.cross_matrix(), a.cross_matrix());
    let (lx_dot, ax_dot) = (l_dot.cross_matrix(), a_dot.cross_matrix());
    let ws = w.cross(&S_HAT);
    let ws_dot = w_dot.cross(&S_HAT);
    let q = l.cross(&ws); // [l]×[w]× ŝ
    let q_dot = l_dot.cross(&ws) + l.cross(&ws_dot);
    let jbd = (cross_block(&lx, &(-lx * ax)) + q * r.transpose()) * inv_l2;
    let d_inv_l2 = -2.0 * l.dot(&l_dot) * inv_l2;
    let jbd_dot = (cross_block(&lx_dot, &(-(lx_dot * ax) - lx * ax_dot))
        + q_dot * r.transpose()
        + q * r_dot.transpose())
        * inv_l2
        + jbd * d_inv_l2;
    let cl = l * 0.5;
    let cl_dot = l_dot * 0.5;
    let jbu = -(ws * r.transpose()) - cl.cross_matrix() * jbd;
    let jbu_dot = -(ws_dot * r.transpose())
        - ws * r_dot.transpose()
        - cl_dot.cross_matrix() * jbd
        - cl.cross_matrix() * jbd_dot;
    let omega2 = jbd * v;
    Ok(LegKin {
        r,
        r_dot,
        theta_dot,
        jau,
        jau_dot,
        jbu,
        jbu_dot,
        jbd,
        jbd_dot,
        omega1,
        omega2,
    })
}

/// One leg's Jacobians at a state (χ, χ̇): the wrench Jacobian J_a,i (eq. 3.33), the link Jacobian
/// J_b,i (eq. 3.40), the row J_ad,i of J_ad (eq. 3.30), their time derivatives (appendix A.1–A.6),
/// and the body angular velocities. All map the twist v_E = [Ė; ω] = J_s χ̇ (m/s, rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegJacobians {
    /// Row i of J_ad (eq. 3.30) stored as a column: θ̇_i = j_adᵀ v_E. Units 1/m (first 3), 1 (last 3).
    pub j_ad: Vec6,
    /// d/dt of [`Self::j_ad`] (eq. A.2).
    pub j_ad_dot: Vec6,
    /// J_a,i (eq. 3.33): [ċ_w,i; ω_1,i] = J_a,i v_E, wrench centre of mass at the midpoint of B_i T_i.
    pub j_a: LegJacobian,
    /// J̇_a,i (eq. A.1, A.3).
    pub j_a_dot: LegJacobian,
    /// J_b,i (eq. 3.40): [ċ_l,i; ω_2,i] = J_b,i v_E, link centre of mass at the midpoint of T_i A_i.
    pub j_b: LegJacobian,
    /// J̇_b,i (eq. A.4–A.6).
    pub j_b_dot: LegJacobian,
    /// θ̇_i (rad/s).
    pub theta_dot: f64,
    /// Wrench angular velocity ω_1,i = θ̇_i ŝ (rad/s), base frame.
    pub omega1: Vec3,
    /// Link angular velocity ω_2,i ⊥ l_i (rad/s), base frame (eq. 3.36, Assumption 2).
    pub omega2: Vec3,
}

fn stack_rows(top: &Mat3x6, bottom: &Mat3x6) -> LegJacobian {
    let mut j = LegJacobian::zeros();
    j.fixed_view_mut::<3, 6>(0, 0).copy_from(top);
    j.fixed_view_mut::<3, 6>(3, 0).copy_from(bottom);
    j
}

impl LegJacobians {
    pub(crate) fn from_kin(k: &LegKin) -> Self {
        let s_r = S_HAT * k.r.transpose();
        let s_r_dot = S_HAT * k.r_dot.transpose();
        LegJacobians {
            j_ad: k.r,
            j_ad_dot: k.r_dot,
            j_a: stack_rows(&k.jau, &s_r),
            j_a_dot: stack_rows(&k.jau_dot, &s_r_dot),
            j_b: stack_rows(&k.jbu, &k.jbd),
            j_b_dot: stack_rows(&k.jbu_dot, &k.jbd_dot),
            theta_dot: k.theta_dot,
            omega1: k.omega1,
            omega2: k.omega2,
        }
    }
}

/// The six legs' Jacobians for a known geometry and end-effector twist `v_e` = [Ė; ω] (m/s, rad/s).
///
/// Errors: [`CoreError::Singular`]`(TypeI)` if a wrench and its link are collinear in the base plane.
pub fn leg_jacobians_from_geometry(geom: &LegGeometry, v_e: &Vec6) -> Result<[LegJacobians; LEGS]> {
    let mut out = [LegJacobians {
        j_ad: Vec6::zeros(),
        j_ad_dot: Vec6::zeros(),
        j_a: LegJacobian::zeros(),
        j_a_dot: LegJacobian::zeros(),
        j_b: LegJacobian::zeros(),
        j_b_dot: LegJacobian::zeros(),
        theta_dot: 0.0,
        omega1: Vec3::zeros(),
        omega2: Vec3::zeros(),
    }; LEGS];
    for (i, o) in out.iter_mut().enumerate() {
        *o = LegJacobians::from_kin(&leg_kin(geom, i, v_e)?);
    }
    Ok(out)
}

/// The six legs' Jacobians J_a,i, J_b,i and their derivatives at pose χ (m, rad) moving with χ̇
/// (m/s, rad/s). Runs one IK; the Jacobians map the twist v_E = J_s χ̇ (eq. 3.23).
///
/// Errors: IK errors for unreachable poses, [`CoreError::Singular`]`(TypeI)`, [`CoreError::NonFinite`].
pub fn leg_jacobians(
    kp: &KinematicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
) -> Result<[LegJacobians; LEGS]> {
    crate::error::check_finite(pose_dot.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    leg_jacobians_from_geometry(&geom, &(twist_jacobian(pose) * pose_dot))
}
