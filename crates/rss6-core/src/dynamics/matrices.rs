//! The matrix path: M, C, G, τ_f in twist coordinates (eq. 3.41, 3.47) and in χ coordinates (eq. 6.2,
//! 6.4), all terms in one pass ([`dynamics_terms`]), and the energies used by the tests.

use super::lanes::{cross_matrix, Lanes, Pair};
use super::load::{Environment, LoadAt};
use super::newton_euler::twist_force;
use super::{check_finite, joint_friction, link_transverse_inertia, platform_inertia};
use super::{wrench_axial_inertia, GRAVITY};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::leg_jacobians::{leg_kin, leg_m, LegKin};
use crate::params::{DynamicParams, KinematicParams};
use crate::pose::{twist_jacobian, twist_jacobian_dot};
use crate::types::{Mat3, Mat6, Vec3, Vec6, LEGS};
use nalgebra::{Matrix3, Vector3};
use num_traits::Zero;

// ---------------------------------------------------------------------------------------------
// Matrix path: M, C, G in twist coordinates.

#[derive(Debug, Clone, Copy)]
pub(super) struct TwistTerms {
    pub(super) m: Mat6,
    pub(super) c: Mat6,
    pub(super) g: Vec6,
    pub(super) theta_dot: Vec6,
}

/// Twist-coordinate mass matrix M = M_p + Σ (J_a,iᵀ M_w,i J_a,i + J_b,iᵀ M_l,i J_b,i) (eq. 3.47).
///
/// Every leg Jacobian is a 3 × 3 block times P_i = [I, −[a_i]×], the map from the twist to the
/// velocity of platform joint i: J_ad,i = lᵀP/m, J_b,d = D P with D = ([l]× + q lᵀ/m)/|l|²
/// (q = l × (w × ŝ)), J_b,u = U P with U = −(w × ŝ) lᵀ/m − [l/2]× D. So a leg adds P_iᵀ N_i P_i with
/// the 3 × 3 N_i = (I_w/m²) l lᵀ + m_l UᵀU + I_l DᵀD, whose blocks are N, N A, Aᵀ N A (A = −[a]×):
/// the same matrix as the products of the 3 × 6 blocks, at a third of their cost.
pub(super) fn twist_mass_matrix(geom: &LegGeometry, dp: &DynamicParams) -> Result<Mat6> {
    let mut tl = Mat3::from_diagonal_element(dp.platform.mass);
    let mut tr = Mat3::zeros();
    let mut br = platform_inertia(&geom.rot, &dp.platform);
    // Two legs at a time ([`Pair`] lanes); the blocks still sum the legs in order 0..6.
    for k in 0..LEGS / 2 {
        let (i, j) = (2 * k, 2 * k + 1);
        // A leg's vectors, then 1/m, 1/‖l‖², the wrench's mass and axial inertia, the link's mass.
        let leg = |i: usize| -> Result<([Vec3; 3], [f64; 5])> {
            let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
            let inv_m = 1.0 / leg_m(&w, &l)?;
            let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
            let (mw, iz) = (wb.mass, wrench_axial_inertia(wb));
            Ok(([w, l, a], [inv_m, 1.0 / l.norm_squared(), mw, iz, lb.mass]))
        };
        let (vi, si) = leg(i)?;
        let (vj, sj) = leg(j)?;
        let [w, l, a]: [Vector3<Pair>; 3] = core::array::from_fn(|k| Lanes::zip(&vi[k], &vj[k]));
        let [inv_m, inv_l2, mass_w, iz, mass_l] = core::array::from_fn(|k| Pair::new(si[k], sj[k]));
        let it = Pair::new(
            link_transverse_inertia(&dp.links[i]),
            link_transverse_inertia(&dp.links[j]),
        );
        let ws = Vector3::new(w[1], -w[0], Pair::zero()); // w × ŝ
        let q = l.cross(&ws);
        let lx = cross_matrix(&l);
        let d = (lx + q * (l.transpose() * inv_m)) * inv_l2;
        let u = ws * (l.transpose() * -inv_m) - lx * d * Pair::from(0.5);
        // |ŝ × c_w|² with c_w = w/2.
        let s_cw2 = Pair::from(0.25) * (w[0] * w[0] + w[1] * w[1]);
        let iw = (mass_w * s_cw2 + iz) * inv_m * inv_m;
        let n = l * l.transpose() * iw + u.tr_mul(&u) * mass_l + d.tr_mul(&d) * it;
        let ax = cross_matrix(&a);
        let b = -(n * ax);
        let ab = ax * b;
        for lane in 0..2 {
            let at = |m: &Matrix3<Pair>| m.map(|p| p.get(lane));
            tl += at(&n);
            tr += at(&b);
            br += at(&ab);
        }
    }
    let mut m = Mat6::zeros();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&tl);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&tr);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&tr.transpose());
    // The lower-right block is symmetric in exact arithmetic; keep M exactly so.
    for r in 0..3 {
        for c in 0..3 {
            m[(3 + r, 3 + c)] = if c >= r { br[(r, c)] } else { br[(c, r)] };
        }
    }
    Ok(m)
}

/// M, C (twist coordinates) and G from the per-leg Jacobian blocks.
pub(super) fn twist_terms(
    geom: &LegGeometry,
    dp: &DynamicParams,
    v: &Vec6,
    env: &Environment,
) -> Result<TwistTerms> {
    let g = &env.gravity;
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
    if let Some(load) = &env.load {
        let l = LoadAt::new(load, &geom.rot);
        l.add_mass(&mut m);
        l.add_coriolis(&mut c, v);
        gv += l.gravity(g);
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
    mass_matrix_with_env(kp, dp, pose, &Environment::default())
}

/// [`mass_matrix`] with the load of `env`, if any (its gravity plays no part): M̃ = J_sᵀ (M + M_L) J_s
/// with M_L the load's twist-coordinate mass matrix ([`crate::PlatformLoad`]). Units as [`mass_matrix`].
///
/// Errors: as [`mass_matrix`]; [`CoreError::NonFinite`](crate::CoreError::NonFinite) for a non-finite
/// gravity or load.
pub fn mass_matrix_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    env: &Environment,
) -> Result<Mat6> {
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let mut m = twist_mass_matrix(&geom, dp)?;
    if let Some(load) = &env.load {
        LoadAt::new(load, &geom.rot).add_mass(&mut m);
    }
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
    let t = twist_terms(&geom, dp, &v, &Environment::default())?;
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
    gravity_with_env(kp, dp, pose, &Environment::with_gravity(*g))
}

/// G̃(χ) in the environment `env` (N, N·m): its gravity and, if present, the load's weight
/// [−m g; −m c × g] at its offset centre of mass, mapped by J_sᵀ.
pub fn gravity_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    env: &Environment,
) -> Result<Vec6> {
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let (mut f, _, _) = twist_force(&geom, dp, &Vec6::zeros(), &Vec6::zeros(), &env.gravity)?;
    if let Some(load) = &env.load {
        f += LoadAt::new(load, &geom.rot).gravity(&env.gravity);
    }
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
    Ok(twist_terms(
        &LegGeometry::at_pose(kp, pose)?,
        dp,
        v_e,
        &Environment::default(),
    )?
    .c)
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
    dynamics_terms_with_env(kp, dp, pose, pose_dot, &Environment::with_gravity(*g))
}

/// [`dynamics_terms`] in the environment `env`: M̃, C̃ and G̃ include the load, if any
/// ([`crate::PlatformLoad`]: M_L, C_L, G_L mapped by J_s like the platform's terms; Property 2 holds).
pub fn dynamics_terms_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    env: &Environment,
) -> Result<DynamicsTerms> {
    check_finite(pose_dot.as_slice())?;
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let j_s = twist_jacobian(pose);
    let v = j_s * pose_dot;
    let t = twist_terms(&geom, dp, &v, env)?;
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
    kinetic_energy_with_env(kp, dp, pose, pose_dot, &Environment::default())
}

/// [`kinetic_energy`] including the load of `env`, if any: ½ χ̇ᵀ M̃ χ̇ with [`mass_matrix_with_env`] (J).
pub fn kinetic_energy_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    env: &Environment,
) -> Result<f64> {
    check_finite(pose_dot.as_slice())?;
    Ok(0.5 * pose_dot.dot(&(mass_matrix_with_env(kp, dp, pose, env)? * pose_dot)))
}

/// Potential energy V = −Σ m_k gᵀ c_k of the 13 bodies (J), zero at the base plane for g = [`GRAVITY`].
/// Body centres of mass: E, the midpoints of B_i T_i and of T_i A_i. G̃ = ∂V/∂χ.
pub fn potential_energy_with_gravity(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    g: &Vec3,
) -> Result<f64> {
    potential_energy_with_env(kp, dp, pose, &Environment::with_gravity(*g))
}

/// [`potential_energy_with_gravity`] in the environment `env`, with the load's −m gᵀ(E + R c') if any
/// (J). G̃ of [`gravity_with_env`] is its gradient.
pub fn potential_energy_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    env: &Environment,
) -> Result<f64> {
    env.check()?;
    let g = &env.gravity;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let e = Vec3::new(pose[0], pose[1], pose[2]);
    let mut v = -dp.platform.mass * g.dot(&e);
    for i in 0..LEGS {
        let cw = (geom.b[i] + geom.t[i]) * 0.5;
        let cl = (geom.t[i] + geom.a[i]) * 0.5;
        v -= dp.wrenches[i].mass * g.dot(&cw) + dp.links[i].mass * g.dot(&cl);
    }
    if let Some(load) = &env.load {
        v += LoadAt::new(load, &geom.rot).potential(&e, g);
    }
    Ok(v)
}
