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
use crate::leg_jacobians::{leg_kin, leg_m, LegKin, S_HAT};
use crate::params::{Body, DynamicParams, KinematicParams};
use crate::pose::{twist_jacobian, twist_jacobian_dot, twist_jacobian_inverse};
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
        let k = S_HAT.dot(&p.cross(&self.w));
        (Vec6::new(p[0], p[1], p[2], ap[0], ap[1], ap[2]) + self.r * k) * self.inv_l2
    }

    /// Generalised force of a force f at the link's centre of mass: J_buᵀ f.
    #[inline]
    pub(crate) fn jbu_t(&self, f: &Vec3) -> Vec6 {
        let cl = self.l * 0.5;
        self.r * S_HAT.dot(&self.w.cross(f)) + self.jbd_t(&cl.cross(f))
    }
}

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
    let w_dot = S_HAT.cross(&w) * theta_dot;
    let a_dot = omega.cross(&a);
    let l_dot = e_dot + a_dot - w_dot;
    let m_dot = w_dot[0] * l[1] - w_dot[1] * l[0] + w[0] * l_dot[1] - w[1] * l_dot[0];
    let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
    let r_dot = (Vec6::new(
        l_dot[0], l_dot[1], l_dot[2], al_dot[0], al_dot[1], al_dot[2],
    ) - r * m_dot)
        * inv_m;
    let theta_ddot = r.dot(v_dot) + r_dot.dot(v);
    // T̈ = θ̈ ŝ × w + θ̇ ŝ × ẇ
    let t_acc = S_HAT.cross(&w) * theta_ddot + S_HAT.cross(&w_dot) * theta_dot;
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
        s_cw: S_HAT.cross(&(w * 0.5)),
        cw_acc: t_acc * 0.5,
        cl_acc: t_acc + l_acc * 0.5,
        omega2_dot,
    })
}

/// Σ_k J_kᵀ (M_k v̇_k + gyroscopic − m_k g): the twist-space generalised force, i.e. J_adᵀ(τ_a − τ_f).
/// Also returns θ̇.
fn twist_force(
    geom: &LegGeometry,
    dp: &DynamicParams,
    v: &Vec6,
    v_dot: &Vec6,
    g: &Vec3,
) -> Result<(Vec6, Vec6)> {
    let omega = Vec3::new(v[3], v[4], v[5]);
    let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
    let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let f_lin = (e_ddot - g) * dp.platform.mass;
    let f_ang = ip * omega_dot + omega.cross(&(ip * omega));
    let mut f = Vec6::new(f_lin[0], f_lin[1], f_lin[2], f_ang[0], f_ang[1], f_ang[2]);
    let mut theta_dot = Vec6::zeros();
    for i in 0..LEGS {
        let k = leg_acc(geom, i, v, v_dot)?;
        theta_dot[i] = k.theta_dot;
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let q_w = wb.mass * k.s_cw.dot(&(k.cw_acc - g)) + wrench_axial_inertia(wb) * k.theta_ddot;
        let f_l = (k.cl_acc - g) * lb.mass;
        let n_l = k.omega2_dot * link_transverse_inertia(lb);
        let cl = k.l * 0.5;
        f += k.r * (q_w + S_HAT.dot(&k.w.cross(&f_l))) + k.jbd_t(&(cl.cross(&f_l) + n_l));
    }
    Ok((f, theta_dot))
}

/// Solves J_adᵀ x = f (x = actuator torques that produce twist-space force f).
fn solve_j_ad_t(geom: &LegGeometry, f: &Vec6) -> Result<Vec6> {
    let j_ad = geom.j_ad()?;
    let x = j_ad
        .transpose()
        .lu()
        .solve(f)
        .ok_or(CoreError::Singular(SingularKind::TypeII))?;
    check_finite(x.as_slice()).map_err(|_| CoreError::Singular(SingularKind::TypeII))?;
    Ok(x)
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

/// M, C (twist coordinates) and G from the per-leg Jacobian blocks.
fn twist_terms(
    geom: &LegGeometry,
    dp: &DynamicParams,
    v: &Vec6,
    g: &Vec3,
    want_c: bool,
) -> Result<TwistTerms> {
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let mut m = Mat6::zeros();
    let mut c = Mat6::zeros();
    for k in 0..3 {
        m[(k, k)] = dp.platform.mass;
    }
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&ip);
    let omega = Vec3::new(v[3], v[4], v[5]);
    if want_c {
        c.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(omega.cross_matrix() * ip));
    }
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
        if want_c {
            c += k.jau.transpose() * k.jau_dot * mw
                + k.r * k.r_dot.transpose() * iw
                + k.jbu.transpose() * k.jbu_dot * ml
                + k.jbd.transpose() * k.jbd_dot * il;
        }
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
/// ```
/// use rss6_core::{mass_matrix, home_pose, DynamicParams, KinematicParams};
/// let m = mass_matrix(&KinematicParams::nominal(), &DynamicParams::nominal(), &home_pose()).unwrap();
/// assert!((m - m.transpose()).amax() < 1e-12);
/// assert!(m.cholesky().is_some());
/// ```
pub fn mass_matrix(kp: &KinematicParams, dp: &DynamicParams, pose: &Vec6) -> Result<Mat6> {
    let geom = LegGeometry::at_pose(kp, pose)?;
    let t = twist_terms(&geom, dp, &Vec6::zeros(), &GRAVITY, false)?;
    let js = twist_jacobian(pose);
    Ok(js.transpose() * t.m * js)
}

/// Coriolis and centrifugal matrix C̃(χ, χ̇) (eq. 6.2 with the J_a,i J̇_s terms, see module docs): the
/// velocity force is C̃·χ̇, and xᵀ(dM̃/dt − 2C̃)x = 0 (Property 2).
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
    let t = twist_terms(&geom, dp, &v, &GRAVITY, true)?;
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
    let (f, _) = twist_force(&geom, dp, &Vec6::zeros(), &Vec6::zeros(), g)?;
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

/// Actuator torques τ_a (N·m) for the motion (χ, χ̇, χ̈) (m, rad; /s; /s²), solving
/// J_sᵀ J_adᵀ τ_a = M̃χ̈ + C̃χ̇ + G̃ + τ̃_f (eq. 6.1, 6.3) with g = [`GRAVITY`].
///
/// Errors: IK errors, [`CoreError::Singular`] (type I or II), [`CoreError::NonFinite`].
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
    let js = twist_jacobian(pose);
    let v = js * pose_dot;
    let v_dot = js * pose_ddot + twist_jacobian_dot(pose, pose_dot) * pose_dot;
    let (f, theta_dot) = twist_force(&geom, dp, &v, &v_dot, g)?;
    Ok(solve_j_ad_t(&geom, &f)? + joint_friction(dp, &theta_dot))
}

/// Forward dynamics (eq. 5.14 in χ form): χ̈ (m/s², rad/s²) from the state (χ, χ̇) and actuator
/// torques τ_a (N·m), with g = [`GRAVITY`]. Solves M̃χ̈ = J_θᵀ τ_a − C̃χ̇ − G̃ − τ̃_f by Cholesky.
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
    let t = twist_terms(&geom, dp, &v, g, false)?;
    // Velocity and gravity forces at zero twist acceleration.
    let (bias, theta_dot) = twist_force(&geom, dp, &v, &Vec6::zeros(), g)?;
    let j_ad = geom.j_ad()?;
    let rhs = j_ad.transpose() * (tau_a - joint_friction(dp, &theta_dot)) - bias;
    let v_dot =
        t.m.cholesky()
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
    let t = twist_terms(&geom, dp, &v, g, true)?;
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

/// One classical fourth-order Runge–Kutta step of length `dt` (s) of the forward dynamics with the
/// actuator torques τ_a (N·m) held constant over the step, g = [`GRAVITY`].
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
