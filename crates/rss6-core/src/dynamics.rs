//! Rigid-body dynamics of the 6-RSS robot by virtual work (§3.6, eq. 3.41–3.48) and its χ-coordinate
//! form (§6.2, eq. 6.1–6.4):
//!
//! ```text
//! J_sᵀ J_adᵀ τ_a = M̃(χ) χ̈ + C̃(χ, χ̇) χ̇ + G̃(χ) + τ̃_f(χ, χ̇)            (6.1, 6.3)
//! ```
//!
//! # Bodies and the inertias the model uses
//!
//! 13 moving bodies (Assumption 1: each symmetric, centre of mass at its geometric centre):
//!
//! * **platform**: centre of mass at E (origin of ΣE), inertia R·diag(I_x, I_y, I_z)·Rᵀ (ΣE principal
//!   axes); all three moments enter.
//! * **wrench i**: centre of mass at the midpoint of B_i T_i; it turns about the fixed axis ŝ = ẑ, so its
//!   angular velocity is always θ̇_i ŝ and only its moment **I_z** (about the axis through its centre of
//!   mass parallel to ŝ) enters; I_x, I_y never do (they would only matter for rotations about
//!   axes ⊥ ŝ, which the revolute joint forbids). The gyroscopic term ω × Iω vanishes.
//! * **link i**: centre of mass at the midpoint of T_i A_i; by Assumption 2 it does not spin about its
//!   axis, so ω_2,i ⊥ l_i and only its *transverse* moment enters. Table 5.1 lists I_x = I_y for the
//!   links (z is the link axis); the model uses I_t = (I_x + I_y)/2 (linear in Ξ, equal to I_x for the
//!   symmetric nominal body, and independent of how the link frame's x/y axes are turned about the
//!   link, which the spherical joints leave undefined). I_z (axial) never enters; ω × I_t ω = 0.
//!
//! Table 5.1's wrench and link inertias violate the triangle inequality (I_x + I_y < I_z), so they are
//! not the principal moments of any real body; they are kept as the thesis's nominal values. Because the
//! model uses only wrench I_z and link (I_x + I_y)/2, the inconsistency is invisible to it; a physics
//! engine that needs a full valid tensor must choose the unused entries itself.
//!
//! # Construction
//!
//! With the per-body twists v_k = J_k v_E (J_p = I, J_a,i, J_b,i of [`crate::leg_jacobians`]) and
//! v_E = J_s χ̇, the mass matrix in twist coordinates is M = Σ J_kᵀ M_k J_k and
//! M̃ = J_sᵀ M J_s (eq. 6.2). The Coriolis matrix is
//! C̃ = J_sᵀ M J̇_s + J_sᵀ (C_p + Σ J_kᵀ M_k J̇_k) J_s with C_p = [0 0; 0 [ω]× I_p]. This is eq. 6.2
//! with the term J_a,iᵀ M_w,i J_a,i J̇_s (and its link analogue) that eq. 6.2 leaves out for the legs:
//! d(J_a,i J_s)/dt = J̇_a,i J_s + J_a,i J̇_s. With this choice Ṁ̃ − 2C̃ is skew-symmetric (Property 2).
//! Wrench and link inertias enter through the constant effective moments above, so C_w = C_l = 0.
//!
//! [`inverse_dynamics`] does not form M̃ or C̃: it propagates body accelerations leg by leg
//! (Newton–Euler in vector form) and maps the body forces back through the transposed Jacobians,
//! which is the same virtual-work sum (eq. 3.45–3.47), only cheaper. The tests check that both paths
//! agree.
//!
//! # Friction
//!
//! Joint friction τ_f,i = f_c,i sign(θ̇_i) + f_v,i θ̇_i (eq. 3.48, 6.4) with sign(0) = 0, and
//! τ̃_f = J_θᵀ τ_f. A smooth alternative, [`joint_friction_smooth`], replaces sign by tanh(θ̇/ε); the model
//! functions use the thesis's sign.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::jacobian::LegGeometry;
use crate::leg_jacobians::{leg_kin, leg_m, leg_static, LegKin};
use crate::params::{Body, DynamicParams, KinematicParams};
use crate::pose::{
    euler_rate_jacobian, euler_rate_jacobian_dot, twist_jacobian, twist_jacobian_dot,
    twist_jacobian_inverse,
};
use crate::types::{Mat3, Mat6, Vec3, Vec6, LEGS};

/// Standard gravity in the base frame, g = [0, 0, −9.81] m/s² (the base's z axis points up).
pub const GRAVITY: Vec3 = Vec3::new(0.0, 0.0, -9.81);

/// The moment of a wrench that the model uses: I_z about its centre of mass, parallel to ŝ (kg·m²).
#[inline]
pub fn wrench_axial_inertia(b: &Body) -> f64 {
    b.inertia[2]
}

/// The moment of a link that the model uses: the transverse moment (I_x + I_y)/2 (kg·m²).
#[inline]
pub fn link_transverse_inertia(b: &Body) -> f64 {
    0.5 * (b.inertia[0] + b.inertia[1])
}

/// Platform inertia tensor in the base frame, R·diag(I_x, I_y, I_z)·Rᵀ (kg·m²).
#[inline]
pub fn platform_inertia(rot: &Mat3, b: &Body) -> Mat3 {
    rot * Mat3::from_diagonal(&b.inertia) * rot.transpose()
}

#[inline]
fn sign0(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Joint friction τ_f,i = f_c,i sign(θ̇_i) + f_v,i θ̇_i (N·m, eq. 3.48), sign(0) = 0. θ̇ in rad/s.
pub fn joint_friction(dp: &DynamicParams, theta_dot: &Vec6) -> Vec6 {
    Vec6::from_fn(|i, _| dp.coulomb[i] * sign0(theta_dot[i]) + dp.viscous[i] * theta_dot[i])
}

/// Smooth joint friction f_c,i tanh(θ̇_i/ε) + f_v,i θ̇_i (N·m); ε (rad/s) > 0 is the velocity scale of
/// the Coulomb transition. Not used by the model functions (they follow the thesis's sign); offered
/// for integrators that dislike the discontinuity.
pub fn joint_friction_smooth(dp: &DynamicParams, theta_dot: &Vec6, eps: f64) -> Vec6 {
    Vec6::from_fn(|i, _| {
        dp.coulomb[i] * libm::tanh(theta_dot[i] / eps) + dp.viscous[i] * theta_dot[i]
    })
}

/// ŝ × u for ŝ = ẑ: [−u_y, u_x, 0].
#[inline(always)]
fn z_cross(u: &Vec3) -> Vec3 {
    Vec3::new(-u[1], u[0], 0.0)
}

/// ŝ·(u × v) for ŝ = ẑ: u_x v_y − u_y v_x.
#[inline(always)]
fn z_triple(u: &Vec3, v: &Vec3) -> f64 {
    u[0] * v[1] - u[1] * v[0]
}

// ---------------------------------------------------------------------------------------------
// Vector (Newton–Euler) path: body accelerations of one leg.

/// Accelerations of one leg's bodies for twist v and twist rate v̇.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegAcc {
    /// Row i of J_ad.
    pub(crate) r: Vec6,
    pub(crate) theta_dot: f64,
    pub(crate) theta_ddot: f64,
    pub(crate) w: Vec3,
    pub(crate) l: Vec3,
    pub(crate) a: Vec3,
    pub(crate) inv_l2: f64,
    /// ŝ × c_w (c_w = w/2).
    pub(crate) s_cw: Vec3,
    /// c̈_w (wrench centre-of-mass acceleration).
    pub(crate) cw_acc: Vec3,
    /// c̈_l (link centre-of-mass acceleration).
    pub(crate) cl_acc: Vec3,
    /// ω̇_2.
    pub(crate) omega2_dot: Vec3,
}

impl LegAcc {
    /// J_bd,iᵀ u for a 3-vector u (no matrix formed).
    #[inline]
    pub(crate) fn jbd_t(&self, u: &Vec3) -> Vec6 {
        let p = u.cross(&self.l);
        let ap = self.a.cross(&p);
        let k = z_triple(&p, &self.w);
        (Vec6::new(p[0], p[1], p[2], ap[0], ap[1], ap[2]) + self.r * k) * self.inv_l2
    }

    /// Generalised force of a force f at the link's centre of mass: J_buᵀ f.
    #[inline]
    pub(crate) fn jbu_t(&self, f: &Vec3) -> Vec6 {
        let cl = self.l * 0.5;
        self.r * z_triple(&self.w, f) + self.jbd_t(&cl.cross(f))
    }
}

#[inline(always)]
pub(crate) fn leg_acc(geom: &LegGeometry, i: usize, v: &Vec6, v_dot: &Vec6) -> Result<LegAcc> {
    let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
    let e_dot = Vec3::new(v[0], v[1], v[2]);
    let omega = Vec3::new(v[3], v[4], v[5]);
    let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
    let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
    let m = leg_m(&w, &l)?;
    let inv_m = 1.0 / m;
    let al = a.cross(&l);
    let r = Vec6::new(l[0], l[1], l[2], al[0], al[1], al[2]) * inv_m;
    let theta_dot = r.dot(v);
    let s_w = z_cross(&w);
    let w_dot = s_w * theta_dot;
    let a_dot = omega.cross(&a);
    let l_dot = e_dot + a_dot - w_dot;
    let m_dot = w_dot[0] * l[1] - w_dot[1] * l[0] + w[0] * l_dot[1] - w[1] * l_dot[0];
    let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
    // θ̈ = J_ad,i v̇_E + J̇_ad,i v_E with J̇_ad,i = ([l̇; ȧ × l + a × l̇] − ṁ J_ad,i)/m
    let theta_ddot =
        r.dot(v_dot) + (l_dot.dot(&e_dot) + al_dot.dot(&omega) - m_dot * theta_dot) * inv_m;
    // T̈ = θ̈ ŝ × w + θ̇ ŝ × ẇ
    let t_acc = s_w * theta_ddot + z_cross(&w_dot) * theta_dot;
    let l_acc = e_ddot + omega_dot.cross(&a) + omega.cross(&a_dot) - t_acc;
    let inv_l2 = 1.0 / l.norm_squared();
    // ω_2 = l × l̇ / ‖l‖²  ⇒  ω̇_2 = l × l̈ / ‖l‖² − 2 (l·l̇)/‖l‖² ω_2
    let omega2 = l.cross(&l_dot) * inv_l2;
    let omega2_dot = l.cross(&l_acc) * inv_l2 - omega2 * (2.0 * l.dot(&l_dot) * inv_l2);
    Ok(LegAcc {
        r,
        theta_dot,
        theta_ddot,
        w,
        l,
        a,
        inv_l2,
        s_cw: s_w * 0.5,
        cw_acc: t_acc * 0.5,
        cl_acc: t_acc + l_acc * 0.5,
        omega2_dot,
    })
}

/// Σ_k J_kᵀ (M_k v̇_k + gyroscopic − m_k g): the twist-space generalised force, i.e. J_adᵀ(τ_a − τ_f).
/// Also returns θ̇ and J_adᵀ (its columns are the rows J_ad,i).
fn twist_force(
    geom: &LegGeometry,
    dp: &DynamicParams,
    v: &Vec6,
    v_dot: &Vec6,
    g: &Vec3,
) -> Result<(Vec6, Vec6, Mat6)> {
    let omega = Vec3::new(v[3], v[4], v[5]);
    let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
    let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let f_lin = (e_ddot - g) * dp.platform.mass;
    let f_ang = ip * omega_dot + omega.cross(&(ip * omega));
    let mut f = Vec6::new(f_lin[0], f_lin[1], f_lin[2], f_ang[0], f_ang[1], f_ang[2]);
    let mut theta_dot = Vec6::zeros();
    let mut j_ad_t = Mat6::zeros();
    for i in 0..LEGS {
        let k = leg_acc(geom, i, v, v_dot)?;
        theta_dot[i] = k.theta_dot;
        j_ad_t.set_column(i, &k.r);
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let q_w = wb.mass * k.s_cw.dot(&(k.cw_acc - g)) + wrench_axial_inertia(wb) * k.theta_ddot;
        let f_l = (k.cl_acc - g) * lb.mass;
        let n_l = k.omega2_dot * link_transverse_inertia(lb);
        let cl = k.l * 0.5;
        f += k.r * (q_w + z_triple(&k.w, &f_l)) + k.jbd_t(&(cl.cross(&f_l) + n_l));
    }
    Ok((f, theta_dot, j_ad_t))
}

/// Solves A x = b (6 × 6) by Gaussian elimination with partial pivoting on the stack; `None` if a pivot
/// is zero or not finite. (nalgebra's `lu().solve()` does the same with copies of A and b; this is
/// cheaper, and the solve is ~10 % of an inverse-dynamics call.)
fn solve6(mut a: Mat6, mut b: Vec6) -> Option<Vec6> {
    for k in 0..6 {
        let (mut p, mut max) = (k, a[(k, k)].abs());
        for r in k + 1..6 {
            let v = a[(r, k)].abs();
            if v > max {
                (p, max) = (r, v);
            }
        }
        if max == 0.0 || !max.is_finite() {
            return None;
        }
        if p != k {
            a.swap_rows(k, p);
            b.swap_rows(k, p);
        }
        let inv = 1.0 / a[(k, k)];
        for r in k + 1..6 {
            let f = a[(r, k)] * inv;
            for c in k + 1..6 {
                a[(r, c)] -= f * a[(k, c)];
            }
            b[r] -= f * b[k];
        }
    }
    let mut x = Vec6::zeros();
    for k in (0..6).rev() {
        let mut s = b[k];
        for c in k + 1..6 {
            s -= a[(k, c)] * x[c];
        }
        x[k] = s / a[(k, k)];
    }
    Some(x)
}

/// Solves J_adᵀ x = f (x = actuator torques that produce twist-space force f).
fn solve_j_ad_t(j_ad_t: &Mat6, f: &Vec6) -> Result<Vec6> {
    let x = solve6(*j_ad_t, *f).ok_or(CoreError::Singular(SingularKind::TypeII))?;
    check_finite(x.as_slice()).map_err(|_| CoreError::Singular(SingularKind::TypeII))?;
    Ok(x)
}

/// v_E = J_s χ̇ and v̇_E = J_s χ̈ + J̇_s χ̇ (eq. 3.23, 5.12) with 3 × 3 blocks only (J_s = diag(I, J_e)).
#[inline]
fn twist_and_rate(pose: &Vec6, pose_dot: &Vec6, pose_ddot: &Vec6) -> (Vec6, Vec6) {
    let je = euler_rate_jacobian(pose[3], pose[4]);
    let je_dot = euler_rate_jacobian_dot(pose[3], pose[4], pose_dot[3], pose_dot[4]);
    let phi_dot = Vec3::new(pose_dot[3], pose_dot[4], pose_dot[5]);
    let phi_ddot = Vec3::new(pose_ddot[3], pose_ddot[4], pose_ddot[5]);
    let w = je * phi_dot;
    let w_dot = je * phi_ddot + je_dot * phi_dot;
    (
        Vec6::new(pose_dot[0], pose_dot[1], pose_dot[2], w[0], w[1], w[2]),
        Vec6::new(
            pose_ddot[0],
            pose_ddot[1],
            pose_ddot[2],
            w_dot[0],
            w_dot[1],
            w_dot[2],
        ),
    )
}

fn check_state(pose_dot: &Vec6, more: &Vec6) -> Result<()> {
    check_finite(pose_dot.as_slice())?;
    check_finite(more.as_slice())
}

// ---------------------------------------------------------------------------------------------
// Matrix path: M, C, G in twist coordinates.

#[derive(Debug, Clone, Copy)]
struct TwistTerms {
    m: Mat6,
    c: Mat6,
    g: Vec6,
    theta_dot: Vec6,
}

/// Twist-coordinate mass matrix M = M_p + Σ (J_a,iᵀ M_w,i J_a,i + J_b,iᵀ M_l,i J_b,i) (eq. 3.47).
fn twist_mass_matrix(geom: &LegGeometry, dp: &DynamicParams) -> Result<Mat6> {
    let mut m = Mat6::zeros();
    for k in 0..3 {
        m[(k, k)] = dp.platform.mass;
    }
    m.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&platform_inertia(&geom.rot, &dp.platform));
    for i in 0..LEGS {
        let k = leg_static(geom, i)?;
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        // J_auᵀ J_au = |ŝ × c_w|² J_ad,iᵀ J_ad,i: the wrench is one rank-1 term.
        let iw = wb.mass * k.s_cw.norm_squared() + wrench_axial_inertia(wb);
        m += k.r * k.r.transpose() * iw
            + k.jbu.transpose() * k.jbu * lb.mass
            + k.jbd.transpose() * k.jbd * link_transverse_inertia(lb);
    }
    Ok(m)
}

/// M, C (twist coordinates) and G from the per-leg Jacobian blocks.
fn twist_terms(geom: &LegGeometry, dp: &DynamicParams, v: &Vec6, g: &Vec3) -> Result<TwistTerms> {
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let mut m = Mat6::zeros();
    let mut c = Mat6::zeros();
    for k in 0..3 {
        m[(k, k)] = dp.platform.mass;
    }
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&ip);
    let omega = Vec3::new(v[3], v[4], v[5]);
    c.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(omega.cross_matrix() * ip));
    let gp = -g * dp.platform.mass;
    let mut gv = Vec6::new(gp[0], gp[1], gp[2], 0.0, 0.0, 0.0);
    let mut theta_dot = Vec6::zeros();
    for i in 0..LEGS {
        let k: LegKin = leg_kin(geom, i, v)?;
        theta_dot[i] = k.theta_dot;
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let (mw, iw) = (wb.mass, wrench_axial_inertia(wb));
        let (ml, il) = (lb.mass, link_transverse_inertia(lb));
        m += k.jau.transpose() * k.jau * mw
            + k.r * k.r.transpose() * iw
            + k.jbu.transpose() * k.jbu * ml
            + k.jbd.transpose() * k.jbd * il;
        c += k.jau.transpose() * k.jau_dot * mw
            + k.r * k.r_dot.transpose() * iw
            + k.jbu.transpose() * k.jbu_dot * ml
            + k.jbd.transpose() * k.jbd_dot * il;
        gv -= k.jau.transpose() * g * mw + k.jbu.transpose() * g * ml;
    }
    Ok(TwistTerms {
        m,
        c,
        g: gv,
        theta_dot,
    })
}

/// Mass matrix M̃(χ) (eq. 6.2, χ coordinates), 6 × 6, symmetric positive definite in the workspace.
/// Units: kg (translation block), kg·m (coupling), kg·m² (rotation block).
///
/// Bodies (13): the platform (centre of mass E, inertia R·diag(I_x, I_y, I_z)·Rᵀ, [`platform_inertia`]);
/// wrench i (centre of mass at the midpoint of B_i T_i, only I_z about the axis through it parallel
/// to ŝ enters, [`wrench_axial_inertia`]); link i (centre of mass at the midpoint of T_i A_i, no spin
/// about its axis (Assumption 2), only the transverse moment (I_x + I_y)/2 enters,
/// [`link_transverse_inertia`]). M̃ = J_sᵀ M J_s with M = M_p + Σ (J_a,iᵀ M_w,i J_a,i + J_b,iᵀ M_l,i J_b,i)
/// (eq. 3.47); see `docs/dynamics.md`.
///
/// ```
/// use rss6_core::{mass_matrix, home_pose, DynamicParams, KinematicParams};
/// let m = mass_matrix(&KinematicParams::nominal(), &DynamicParams::nominal(), &home_pose()).unwrap();
/// assert!((m - m.transpose()).amax() < 1e-12);
/// assert!(m.cholesky().is_some());
/// ```
pub fn mass_matrix(kp: &KinematicParams, dp: &DynamicParams, pose: &Vec6) -> Result<Mat6> {
    let geom = LegGeometry::at_pose(kp, pose)?;
    let m = twist_mass_matrix(&geom, dp)?;
    let js = twist_jacobian(pose);
    Ok(js.transpose() * m * js)
}

/// Coriolis and centrifugal matrix C̃(χ, χ̇) (eq. 6.2): the velocity force is C̃·χ̇, and
/// xᵀ(dM̃/dt − 2C̃)x = 0 (Property 2), indeed dM̃/dt = C̃ + C̃ᵀ.
///
/// C̃ = J_sᵀ M J̇_s + J_sᵀ (C_p + Σ J_kᵀ M_k J̇_k) J_s with C_p = `[0 0; 0 [ω]× I_p]`. Unlike eq. 6.2 as
/// printed, the legs' J_a,iᵀ M_w,i J_a,i J̇_s terms (and the links') are kept: d(J_a,i J_s)/dt needs
/// them, and without them Property 2 fails whenever the Euler angles move.
pub fn coriolis(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
) -> Result<Mat6> {
    check_finite(pose_dot.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let js = twist_jacobian(pose);
    let v = js * pose_dot;
    let t = twist_terms(&geom, dp, &v, &GRAVITY)?;
    Ok(js.transpose() * (t.m * twist_jacobian_dot(pose, pose_dot) + t.c * js))
}

/// Gravity vector G̃(χ) = ∂V/∂χ (eq. 6.2) for g = [`GRAVITY`]. N (first 3), N·m (last 3).
pub fn gravity(kp: &KinematicParams, dp: &DynamicParams, pose: &Vec6) -> Result<Vec6> {
    gravity_with(kp, dp, pose, &GRAVITY)
}

/// G̃(χ) for an arbitrary gravity vector `g` (m/s², base frame), e.g. a tilted base.
pub fn gravity_with(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    g: &Vec3,
) -> Result<Vec6> {
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let (f, _, _) = twist_force(&geom, dp, &Vec6::zeros(), &Vec6::zeros(), g)?;
    Ok(twist_jacobian(pose).transpose() * f)
}

/// Friction τ̃_f = J_sᵀ J_adᵀ [f_c,i sign(θ̇_i) + f_v,i θ̇_i] (eq. 6.4), θ̇ = J_θ χ̇.
pub fn friction(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
) -> Result<Vec6> {
    check_finite(pose_dot.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let j_theta = geom.j_theta()?;
    Ok(j_theta.transpose() * joint_friction(dp, &(j_theta * pose_dot)))
}

// ---------------------------------------------------------------------------------------------
// Twist-coordinate form (eq. 3.41, 3.47, 3.48): τ_g = J_adᵀ τ_a = M v̇_E + C v_E + G + τ_f.

/// Mass matrix M(χ) of eq. 3.41/3.47 in twist coordinates v_E = [Ė; ω]: M̃ = J_sᵀ M J_s.
pub fn mass_matrix_twist(kp: &KinematicParams, dp: &DynamicParams, pose: &Vec6) -> Result<Mat6> {
    twist_mass_matrix(&LegGeometry::at_pose(kp, pose)?, dp)
}

/// Coriolis matrix C(χ, v_E) of eq. 3.41/3.47 for the twist `v_e` = [Ė; ω] (m/s, rad/s):
/// C = C_p + Σ (J_a,iᵀ M_w,i J̇_a,i + J_b,iᵀ M_l,i J̇_b,i). dM/dt − 2C is skew-symmetric.
pub fn coriolis_twist(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    v_e: &Vec6,
) -> Result<Mat6> {
    check_finite(v_e.as_slice())?;
    Ok(twist_terms(&LegGeometry::at_pose(kp, pose)?, dp, v_e, &GRAVITY)?.c)
}

/// Gravity G(χ) of eq. 3.41/3.47 in twist coordinates (N, N·m) for gravity `g` (m/s²): G̃ = J_sᵀ G.
pub fn gravity_twist(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    g: &Vec3,
) -> Result<Vec6> {
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    Ok(twist_force(&geom, dp, &Vec6::zeros(), &Vec6::zeros(), g)?.0)
}

/// Friction τ_f = J_adᵀ [f_c,i sign(θ̇_i) + f_v,i θ̇_i] of eq. 3.48 for the twist `v_e` (θ̇ = J_ad v_E).
pub fn friction_twist(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    v_e: &Vec6,
) -> Result<Vec6> {
    check_finite(v_e.as_slice())?;
    let j_ad = LegGeometry::at_pose(kp, pose)?.j_ad()?;
    Ok(j_ad.transpose() * joint_friction(dp, &(j_ad * v_e)))
}

/// Actuator torques τ_a (N·m) for the motion (χ, χ̇, χ̈) (m, rad; /s; /s²), solving
/// J_sᵀ J_adᵀ τ_a = M̃χ̈ + C̃χ̇ + G̃ + τ̃_f (eq. 6.1, 6.3) with g = [`GRAVITY`].
///
/// Errors: IK errors, [`CoreError::Singular`] (type I or II), [`CoreError::NonFinite`].
///
/// ```
/// use rss6_core::*;
/// let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
/// let pose = Vec6::new(0.01, -0.01, 0.12, 0.02, 0.0, -0.03);
/// let (pd, pdd) = (Vec6::new(0.1, 0.0, 0.0, 0.0, 0.5, 0.0), Vec6::new(0.0, 0.0, 1.0, 2.0, 0.0, 0.0));
/// let tau = inverse_dynamics(&kp, &dp, &pose, &pd, &pdd).unwrap();
/// // the forward dynamics gives the acceleration back
/// let acc = forward_dynamics(&kp, &dp, &pose, &pd, &tau).unwrap();
/// assert!((acc - pdd).amax() < 1e-9);
/// // and J_θᵀ τ_a = M̃χ̈ + C̃χ̇ + G̃ + τ̃_f (eq. 6.1, 6.3)
/// let t = dynamics_terms(&kp, &dp, &pose, &pd).unwrap();
/// let rhs = t.m * pdd + t.c * pd + t.g + t.f;
/// assert!((t.j_theta.transpose() * tau - rhs).amax() < 1e-9 * rhs.amax());
/// ```
pub fn inverse_dynamics(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
) -> Result<Vec6> {
    inverse_dynamics_with_gravity(kp, dp, pose, pose_dot, pose_ddot, &GRAVITY)
}

/// [`inverse_dynamics`] with an arbitrary gravity vector `g` (m/s², base frame).
pub fn inverse_dynamics_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    g: &Vec3,
) -> Result<Vec6> {
    check_state(pose_dot, pose_ddot)?;
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let (v, v_dot) = twist_and_rate(pose, pose_dot, pose_ddot);
    let (f, theta_dot, j_ad_t) = twist_force(&geom, dp, &v, &v_dot, g)?;
    Ok(solve_j_ad_t(&j_ad_t, &f)? + joint_friction(dp, &theta_dot))
}

/// Forward dynamics (eq. 5.14 in χ form): χ̈ (m/s², rad/s²) from the state (χ, χ̇) and actuator
/// torques τ_a (N·m), with g = [`GRAVITY`]. Solves M̃χ̈ = J_θᵀ τ_a − C̃χ̇ − G̃ − τ̃_f by Cholesky.
///
/// Errors: IK errors, [`CoreError::Singular`] (type I; `Matrix` if M is not positive definite, which
/// only happens for non-physical Ξ; `Euler` at |β| = π/2), [`CoreError::NonFinite`].
pub fn forward_dynamics(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    tau_a: &Vec6,
) -> Result<Vec6> {
    forward_dynamics_with_gravity(kp, dp, pose, pose_dot, tau_a, &GRAVITY)
}

/// [`forward_dynamics`] with an arbitrary gravity vector `g` (m/s², base frame).
pub fn forward_dynamics_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    g: &Vec3,
) -> Result<Vec6> {
    check_state(pose_dot, tau_a)?;
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let js = twist_jacobian(pose);
    let v = js * pose_dot;
    let m = twist_mass_matrix(&geom, dp)?;
    // Velocity and gravity forces at zero twist acceleration.
    let (bias, theta_dot, j_ad_t) = twist_force(&geom, dp, &v, &Vec6::zeros(), g)?;
    let rhs = j_ad_t * (tau_a - joint_friction(dp, &theta_dot)) - bias;
    let v_dot = m
        .cholesky()
        .ok_or(CoreError::Singular(SingularKind::Matrix))?
        .solve(&rhs);
    let chi_ddot =
        twist_jacobian_inverse(pose)? * (v_dot - twist_jacobian_dot(pose, pose_dot) * pose_dot);
    check_finite(chi_ddot.as_slice())?;
    Ok(chi_ddot)
}

/// Every term of eq. 6.1–6.4 at one state, computed in one pass (for model-based controllers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicsTerms {
    /// M̃(χ) (eq. 6.2).
    pub m: Mat6,
    /// C̃(χ, χ̇) (eq. 6.2), velocity force C̃χ̇.
    pub c: Mat6,
    /// G̃(χ) (eq. 6.2).
    pub g: Vec6,
    /// τ̃_f(χ, χ̇) (eq. 6.4).
    pub f: Vec6,
    /// J_ad (eq. 3.30): θ̇ = J_ad v_E.
    pub j_ad: Mat6,
    /// J_s (eq. 3.23): v_E = J_s χ̇.
    pub j_s: Mat6,
    /// J_θ = J_ad J_s (eq. 5.3): θ̇ = J_θ χ̇.
    pub j_theta: Mat6,
}

/// M̃, C̃, G̃, τ̃_f, J_ad, J_s, J_θ at (χ, χ̇) with g = [`GRAVITY`], one IK for all.
pub fn dynamics_terms(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
) -> Result<DynamicsTerms> {
    dynamics_terms_with_gravity(kp, dp, pose, pose_dot, &GRAVITY)
}

/// [`dynamics_terms`] with an arbitrary gravity vector `g` (m/s², base frame).
pub fn dynamics_terms_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    g: &Vec3,
) -> Result<DynamicsTerms> {
    check_finite(pose_dot.as_slice())?;
    check_finite(g.as_slice())?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let j_s = twist_jacobian(pose);
    let v = j_s * pose_dot;
    let t = twist_terms(&geom, dp, &v, g)?;
    let j_ad = geom.j_ad()?;
    let j_theta = j_ad * j_s;
    let js_t = j_s.transpose();
    Ok(DynamicsTerms {
        m: js_t * t.m * j_s,
        c: js_t * (t.m * twist_jacobian_dot(pose, pose_dot) + t.c * j_s),
        g: js_t * t.g,
        f: j_theta.transpose() * joint_friction(dp, &t.theta_dot),
        j_ad,
        j_s,
        j_theta,
    })
}

/// Kinetic energy T = ½ χ̇ᵀ M̃ χ̇ (J).
pub fn kinetic_energy(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
) -> Result<f64> {
    check_finite(pose_dot.as_slice())?;
    Ok(0.5 * pose_dot.dot(&(mass_matrix(kp, dp, pose)? * pose_dot)))
}

/// Potential energy V = −Σ m_k gᵀ c_k of the 13 bodies (J), zero at the base plane for g = [`GRAVITY`].
/// Body centres of mass: E, the midpoints of B_i T_i and of T_i A_i. G̃ = ∂V/∂χ.
pub fn potential_energy_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    g: &Vec3,
) -> Result<f64> {
    let geom = LegGeometry::at_pose(kp, pose)?;
    let e = Vec3::new(pose[0], pose[1], pose[2]);
    let mut v = -dp.platform.mass * g.dot(&e);
    for i in 0..LEGS {
        let cw = (geom.b[i] + geom.t[i]) * 0.5;
        let cl = (geom.t[i] + geom.a[i]) * 0.5;
        v -= dp.wrenches[i].mass * g.dot(&cw) + dp.links[i].mass * g.dot(&cl);
    }
    Ok(v)
}

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
/// [`forward_dynamics`] at any of the four stages (e.g. a stage state leaving the workspace).
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
    if !dt.is_finite() {
        return Err(CoreError::NonFinite);
    }
    let f = |p: &Vec6, pd: &Vec6| forward_dynamics_with_gravity(kp, dp, p, pd, tau_a, g);
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
