//! The vector (Newton–Euler) path: body accelerations leg by leg, mapped back through the transposed
//! Jacobians (eq. 3.45–3.47) — [`inverse_dynamics`] and [`forward_dynamics`] without forming M̃ or C̃.

use super::lanes::Pair;
use super::leg_state::{add_leg_forces, Leg, LegColumns};
use super::load::{Environment, LoadAt};
use super::matrices::twist_mass_matrix;
use super::pose_tangent::{stepped_pose_columns, PoseTangents};
use super::rate_tangent::{twist_rate_directions, RateTangents};
use super::{check_finite, check_state, joint_friction, twist_and_rate};
use super::{platform_inertia, GRAVITY};
use crate::error::{CoreError, Result, SingularKind};
use crate::jacobian::LegGeometry;
use crate::params::{DynamicParams, KinematicParams};
use crate::pose::{twist_jacobian, twist_jacobian_dot, twist_jacobian_inverse, RateTrig};
use crate::types::{Mat6, Vec3, Vec6, LEGS};

/// Σ_k J_kᵀ (M_k v̇_k + gyroscopic − m_k g): the twist-space generalised force, i.e. J_adᵀ(τ_a − τ_f).
/// Also returns θ̇ and J_adᵀ (its columns are the rows J_ad,i).
pub(super) fn twist_force(
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
    add_leg_forces(geom, dp, (v, v_dot), g, &mut f, &mut theta_dot, &mut j_ad_t)?;
    Ok((f, theta_dot, j_ad_t))
}

/// Solves A x = b (6 × 6) by Gaussian elimination with partial pivoting on the stack; `None` if a pivot
/// is zero or not finite. (nalgebra's `lu().solve()` does the same with copies of A and b; this is
/// cheaper, and the solve is ~10 % of an inverse-dynamics call.)
pub(super) fn solve6(mut a: Mat6, mut b: Vec6) -> Option<Vec6> {
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
pub(super) fn solve_j_ad_t(j_ad_t: &Mat6, f: &Vec6) -> Result<Vec6> {
    let x = solve6(*j_ad_t, *f).ok_or(CoreError::Singular(SingularKind::TypeII))?;
    check_finite(x.as_slice()).map_err(|_| CoreError::Singular(SingularKind::TypeII))?;
    Ok(x)
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
    inverse_dynamics_with_env(
        kp,
        dp,
        pose,
        pose_dot,
        pose_ddot,
        &Environment::with_gravity(*g),
    )
}

/// [`inverse_dynamics`] in the environment `env`: its gravity and, if present, a load fixed to the
/// platform (the Newton–Euler force F_L of [`crate::PlatformLoad`], mapped to the actuators through
/// J_adᵀ like the platform's own). τ_a in N·m.
///
/// Errors: as [`inverse_dynamics`]; [`CoreError::NonFinite`] for a non-finite gravity or load.
pub fn inverse_dynamics_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    env: &Environment,
) -> Result<Vec6> {
    check_state(pose_dot, pose_ddot)?;
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let (tau, theta_dot) = rigid_torques(&geom, dp, pose, pose_dot, pose_ddot, env)?;
    Ok(tau + joint_friction(dp, &theta_dot))
}

/// The twist-space force of the rigid bodies (load included), θ̇ and J_adᵀ at a known geometry.
pub(super) fn rigid_forces(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    env: &Environment,
) -> Result<(Vec6, Vec6, Mat6)> {
    let (v, v_dot) = twist_and_rate(pose, pose_dot, pose_ddot);
    let (mut f, theta_dot, j_ad_t) = twist_force(geom, dp, &v, &v_dot, &env.gravity)?;
    if let Some(load) = &env.load {
        f += LoadAt::new(load, &geom.rot).force(&v, &v_dot, &env.gravity);
    }
    Ok((f, theta_dot, j_ad_t))
}

/// The actuator torques of the rigid bodies (friction not included) and θ̇, at a known geometry.
fn rigid_torques(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    env: &Environment,
) -> Result<(Vec6, Vec6)> {
    let (f, theta_dot, j_ad_t) = rigid_forces(geom, dp, pose, pose_dot, pose_ddot, env)?;
    Ok((solve_j_ad_t(&j_ad_t, &f)?, theta_dot))
}

/// State derivatives of the inverse dynamics, (∂τ_a/∂χ, ∂τ_a/∂χ̇) at (χ, χ̇, χ̈) in `env`,
/// Coulomb friction's sign held at the given state's θ̇ (the derivative of the smooth part). Both
/// are exact (analytic tangents, no finite differences): per pose direction one product-rule pass
/// of the leg recursion through the leg geometry's own tangent (θ along J_θ, the platform turned by
/// J_e δφ), per χ̇ direction one pass at the fixed pose (τ_a is quadratic in χ̇ there, plus the
/// viscous term), and one LU of J_adᵀ maps every column.
///
/// With them the forward dynamics' state Jacobians follow from the implicit function theorem:
/// ∂χ̈/∂χ = −M̃⁻¹J_θᵀ ∂τ_a/∂χ and ∂χ̈/∂χ̇ = −M̃⁻¹J_θᵀ ∂τ_a/∂χ̇ (∂τ_a/∂χ̈ = J_θ⁻ᵀM̃).
///
/// Errors: as [`inverse_dynamics_with_env`].
pub fn inverse_dynamics_derivatives_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    env: &Environment,
) -> Result<(Mat6, Mat6)> {
    check_state(pose_dot, pose_ddot)?;
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    let j_theta = geom.j_theta()?;
    // The rigid torque at the state: one Newton–Euler pass and a solve.
    let (f0, _, j0) = rigid_forces(&geom, dp, pose, pose_dot, pose_ddot, env)?;
    let lu = j0.lu();
    let singular = || CoreError::Singular(SingularKind::TypeII);
    let tau0 = lu.solve(&f0).ok_or_else(singular)?;
    let (v, v_dot) = twist_and_rate(pose, pose_dot, pose_ddot);
    let rates = (&v, &v_dot);
    let t = derivatives_at(
        kp, &geom, &j_theta, dp, pose_dot, pose_ddot, rates, env, &tau0, None, None, None,
    )?;
    // τ_a = J_adᵀ⁻¹ f + f_c sign(θ̇) + f_v θ̇ (Coulomb's sign held at θ̇).
    let mut d_pose = lu.solve(&t.pose).ok_or_else(singular)?;
    let mut d_vel = lu.solve(&t.vel).ok_or_else(singular)?;
    for i in 0..LEGS {
        let fv = dp.viscous[i];
        for k in 0..6 {
            d_pose[(i, k)] += fv * t.rate_pose[(i, k)];
            d_vel[(i, k)] += fv * j_theta[(i, k)];
        }
    }
    check_finite(d_pose.as_slice())?;
    check_finite(d_vel.as_slice())?;
    Ok((d_pose, d_vel))
}

/// The state derivatives of the rigid bodies' twist-space force balance f = J_adᵀ τ_rigid at one
/// state, before any map to torques: ∂τ_rigid/∂χ = J_adᵀ⁻¹ `pose`, ∂τ_rigid/∂χ̇ = J_adᵀ⁻¹ `vel`.
pub(super) struct ForceTangents {
    /// ∂f − ∂J_adᵀ τ_rigid along each pose direction.
    pub pose: Mat6,
    /// ∂f/∂χ̇ (J_adᵀ does not depend on χ̇).
    pub vel: Mat6,
    /// ∂θ̇/∂χ at χ̇ held (for the viscous term).
    pub rate_pose: Mat6,
    /// ∂(J_ad ν)/∂χ at ν held, if asked for.
    pub rates: Option<Mat6>,
}

/// The body of [`inverse_dynamics_derivatives_with_env`] at a known geometry and its J_θ (the state
/// already checked), `tau_rigid` = J_adᵀ⁻¹ f the rigid torque at the state. With `twist`: also
/// ∂(J_ad(χ) ν)/∂χ at ν = `twist` held (the joint rates' pose derivative). The pose columns are
/// the exact tangent of `pose_tangent`, or, with `one_sided_step` h, forward differences from the
/// state (as cheap as the tangent, with an O(h) error; the per-tick sensitivities use them). A
/// step does not solve the inverse kinematics: the stepped geometry takes the exact rotation and
/// platform joints of χ + h e_k with the joint angles θ + h J_θ e_k — the IK linearised along the
/// step, which has the IK's own derivative. The χ̇ columns are the exact tangent of
/// `rate_tangent`. The caller maps the columns (one LU of J_adᵀ, or the forward dynamics' own
/// factor). `rates`: (v, v̇) = [`twist_and_rate`] at the state. With `legs`: also the legs'
/// regressor columns from the same leg states.
#[allow(clippy::too_many_arguments)]
pub(super) fn derivatives_at(
    kp: &KinematicParams,
    geom: &LegGeometry,
    j_theta: &Mat6,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    rates: (&Vec6, &Vec6),
    env: &Environment,
    tau_rigid: &Vec6,
    one_sided_step: Option<f64>,
    twist: Option<&Vec6>,
    mut legs: Option<&mut LegColumns>,
) -> Result<ForceTangents> {
    let pose = &geom.pose;
    let load = env.load.as_ref().map(|l| LoadAt::new(l, &geom.rot));
    let (v, v_dot) = rates;
    // Columns of ∂f − ∂J_adᵀ τ_rigid (pose), with ∂θ̇ for the viscous term: the exact tangent
    // or forward differences from the state; the χ̇ columns are the force's exact tangent at this
    // geometry. The tangents take the legs two at a time.
    let g = &env.gravity;
    let trig = RateTrig::of(pose);
    let (dv, dvd) = twist_rate_directions(&trig, pose_dot);
    let mut vel = RateTangents::new(geom, dp, load.as_ref(), v, (&dv, &dvd));
    let mut each_pair = |k: usize, pair: &Leg<Pair>| {
        vel.add_pair(pair);
        if let Some(c) = legs.as_deref_mut() {
            c.add_pair(k, &pair.acc, g);
        }
    };
    // (The exact tangents built in place, not moved through an `Option`: ≈ 2.5 KB.)
    let (b_pose, d_rate_pose, d_rates) = match one_sided_step {
        None => {
            let state = (pose_dot, pose_ddot);
            let at = (v, v_dot, &trig);
            let mut t = PoseTangents::new(geom, dp, load.as_ref(), state, at, g, twist);
            for k in 0..LEGS / 2 {
                let pair = Leg::pair(geom, dp, k, (v, v_dot), g)?;
                t.add_pair(k, &pair, j_theta, tau_rigid);
                each_pair(k, &pair);
            }
            t.finish()
        }
        Some(h) => {
            for k in 0..LEGS / 2 {
                each_pair(k, &Leg::pair(geom, dp, k, (v, v_dot), g)?);
            }
            stepped_pose_columns(
                kp,
                geom,
                j_theta,
                dp,
                (pose_dot, pose_ddot),
                env,
                tau_rigid,
                twist,
                h,
            )?
        }
    };
    Ok(ForceTangents {
        pose: b_pose,
        vel: vel.out,
        rate_pose: d_rate_pose,
        rates: d_rates,
    })
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
    forward_dynamics_with_env(
        kp,
        dp,
        pose,
        pose_dot,
        tau_a,
        &Environment::with_gravity(*g),
    )
}

/// [`forward_dynamics`] in the environment `env`: its gravity and, if present, a load fixed to the
/// platform (its mass matrix M_L enters M, its velocity and gravity forces the bias). χ̈ in m/s²,
/// rad/s².
///
/// Errors: as [`forward_dynamics`]; [`CoreError::NonFinite`] for a non-finite gravity or load;
/// `Singular(Matrix)` if a load that is not positive semi-definite makes M indefinite.
pub fn forward_dynamics_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
) -> Result<Vec6> {
    check_state(pose_dot, tau_a)?;
    env.check()?;
    let geom = LegGeometry::at_pose(kp, pose)?;
    chi_ddot_at(&geom, dp, pose_dot, tau_a, env)
}

/// The forward dynamics at a known geometry, with what the sensitivities reuse.
pub(super) struct ForwardAt {
    pub chi_ddot: Vec6,
    pub j_ad_t: Mat6,
    pub js_inv: Mat6,
    pub chol: nalgebra::Cholesky<f64, nalgebra::U6>,
    /// The rigid bodies' torque τ_a − τ_f (friction at θ̇).
    pub tau_rigid: Vec6,
}

/// [`forward_dynamics_with_env`] at a known geometry (the state and environment already checked).
#[inline]
pub(super) fn forward_at(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
) -> Result<ForwardAt> {
    let td = twist_dynamics_at(geom, dp, pose_dot, env)?;
    let chol = factor(&td)?;
    forward_from(geom, &td, chol, dp, pose_dot, tau_a)
}

/// [`forward_at`]'s χ̈ alone (nothing else built or copied).
#[inline]
pub(super) fn chi_ddot_at(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
) -> Result<Vec6> {
    let td = twist_dynamics_at(geom, dp, pose_dot, env)?;
    let chol = factor(&td)?;
    Ok(accel_from(geom, &td, &chol, dp, pose_dot, tau_a)?.chi_ddot)
}

/// The Cholesky factor of the twist-space mass matrix.
#[inline]
pub(super) fn factor(td: &TwistDynamics) -> Result<nalgebra::Cholesky<f64, nalgebra::U6>> {
    td.m.cholesky()
        .ok_or(CoreError::Singular(SingularKind::Matrix))
}

/// [`forward_at`] from the twist dynamics `td` at `geom` and the Cholesky factor of `td.m`.
#[inline]
pub(super) fn forward_from(
    geom: &LegGeometry,
    td: &TwistDynamics,
    chol: nalgebra::Cholesky<f64, nalgebra::U6>,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
) -> Result<ForwardAt> {
    let a = accel_from(geom, td, &chol, dp, pose_dot, tau_a)?;
    Ok(ForwardAt {
        chi_ddot: a.chi_ddot,
        j_ad_t: td.j_ad_t,
        js_inv: a.js_inv,
        chol,
        tau_rigid: a.tau_rigid,
    })
}

/// The acceleration of [`forward_from`] and what it derives on the way.
pub(super) struct Accel {
    pub chi_ddot: Vec6,
    pub js_inv: Mat6,
    pub tau_rigid: Vec6,
}

/// M v̇ = J_adᵀ(τ_a − τ_f) − b by the factor `chol` of `td.m`, then χ̈ = J_s⁻¹(v̇ − J̇_s χ̇).
#[inline]
pub(super) fn accel_from(
    geom: &LegGeometry,
    td: &TwistDynamics,
    chol: &nalgebra::Cholesky<f64, nalgebra::U6>,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
) -> Result<Accel> {
    let pose = &geom.pose;
    let tau_rigid = tau_a - joint_friction(dp, &td.theta_dot);
    let rhs = td.j_ad_t * tau_rigid - td.bias;
    let v_dot = chol.solve(&rhs);
    let js_inv = twist_jacobian_inverse(pose)?;
    let chi_ddot = js_inv * (v_dot - twist_jacobian_dot(pose, pose_dot) * pose_dot);
    check_finite(chi_ddot.as_slice())?;
    Ok(Accel {
        chi_ddot,
        js_inv,
        tau_rigid,
    })
}

/// The twist-space dynamics at (χ, χ̇): M (load included), the velocity and gravity forces at zero
/// twist acceleration, θ̇ and J_adᵀ (friction not included).
pub(super) struct TwistDynamics {
    pub m: Mat6,
    pub bias: Vec6,
    pub theta_dot: Vec6,
    pub j_ad_t: Mat6,
}

/// The [`TwistDynamics`] at a known geometry (the environment already checked).
#[inline]
pub(super) fn twist_dynamics_at(
    geom: &LegGeometry,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    env: &Environment,
) -> Result<TwistDynamics> {
    let v = twist_jacobian(&geom.pose) * pose_dot;
    let mut m = twist_mass_matrix(geom, dp)?;
    let (mut bias, theta_dot, j_ad_t) = twist_force(geom, dp, &v, &Vec6::zeros(), &env.gravity)?;
    if let Some(load) = &env.load {
        let l = LoadAt::new(load, &geom.rot);
        l.add_mass(&mut m);
        bias += l.force(&v, &Vec6::zeros(), &env.gravity);
    }
    Ok(TwistDynamics {
        m,
        bias,
        theta_dot,
        j_ad_t,
    })
}
