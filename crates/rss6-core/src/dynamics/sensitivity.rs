//! What the forward sensitivities of a simulated loop need of the dynamics at one state, from one
//! inverse kinematics: χ̈, J_θ, ∂χ̈/∂τ_a, ∂χ̈/∂Ξ and, on request, the state Jacobians ∂χ̈/∂χ,
//! ∂χ̈/∂χ̇ and the joint rates' pose derivative at a held twist.
//!
//! Separate calls ([`forward_dynamics_with_env`](super::forward_dynamics_with_env),
//! [`jacobian_theta`](crate::jacobian_theta), [`mass_matrix_with_env`](super::mass_matrix_with_env),
//! [`inverse_dynamics_derivatives_with_env`](super::inverse_dynamics_derivatives_with_env),
//! [`regressor_with_gravity`](crate::regressor_with_gravity)) solve the inverse kinematics five
//! times at the same pose and form the mass matrix twice. Here: ∂χ̈/∂τ_a = M̃⁻¹J_θᵀ = J_s⁻¹M⁻¹J_adᵀ
//! and ∂χ̈/∂Ξ = −M̃⁻¹J_θᵀΓ = −J_s⁻¹M⁻¹Γ_g (Γ_g = J_adᵀΓ, [`crate::regressor_tau_g`]) from the
//! Cholesky factor of the twist-space M the forward dynamics already has (through the 6 × 6
//! K = J_s⁻¹M⁻¹, one product per column of Ξ, and only for the columns requested).

use super::leg_state::{joint_rates, LegColumns};
use super::load::{Environment, LoadAt};
use super::matrices::twist_mass_matrix;
use super::newton_euler::{derivatives_at, forward_at};
use super::{check_finite, check_state, joint_friction, sign0, twist_and_rate_with};
use crate::error::{CoreError, Result, SingularKind};
use crate::jacobian::LegGeometry;
use crate::params::{DynamicParams, KinematicParams};
use crate::pose::RateTrig;
use crate::regressor::{platform_columns, Regressor};
use crate::types::{Mat6, Vec6, LEGS};

/// What [`forward_dynamics_jacobians_with_env`] computes beyond χ̈, J_θ, ∂χ̈/∂τ_a and ∂χ̈/∂Ξ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JacobianRequest {
    /// The state Jacobians ∂χ̈/∂χ, ∂χ̈/∂χ̇ (from the inverse dynamics' exact derivatives, as
    /// [`inverse_dynamics_derivatives_with_env`](super::inverse_dynamics_derivatives_with_env),
    /// or with forward differences in χ: `one_sided_step`).
    pub state: bool,
    /// With `state`: also ∂(J_ad(χ) ν)/∂χ at ν = v + `rate_step`·v̇ held (v = J_s χ̇ the twist, v̇
    /// its rate at this χ̈): the pose derivative of the joint rates one explicit step of
    /// `rate_step` s ahead, from the same pose tangents or steps (no extra inverse kinematics).
    pub rate_step: Option<f64>,
    /// Forward differences in χ with this step (m, rad) instead of the exact tangent: as cheap,
    /// with an O(h) error (the per-tick sensitivities, already approximate, use them). The χ̇
    /// columns are exact either way.
    pub one_sided_step: Option<f64>,
    /// The columns of ∂χ̈/∂Ξ wanted, bit k for column k (default: all); the others are zero.
    pub param_columns: u64,
    /// The joint angles θ = IK(χ) when already known ([`crate::ik`] at this pose, e.g. from the
    /// simulation step that visited the state): one inverse kinematics less. Angles that do not
    /// close the legs are refused, as by [`crate::rk4_step_implicit_friction`].
    pub theta: Option<Vec6>,
    /// χ̈ at this state when already known: [`forward_dynamics_with_env`](super::forward_dynamics_with_env)'s
    /// at the same inputs, bit for bit (e.g. the simulation step's stage acceleration). The forward
    /// dynamics' solve is then skipped (the mass matrix is still formed) and every output is the
    /// same, bit for bit, as without it. A χ̈ from other inputs gives derivatives at a state the
    /// dynamics do not have: the caller's risk.
    pub pose_ddot: Option<Vec6>,
}

impl Default for JacobianRequest {
    /// No state Jacobians; exact tangents when requested; all columns.
    fn default() -> Self {
        JacobianRequest {
            state: false,
            rate_step: None,
            one_sided_step: None,
            param_columns: u64::MAX,
            theta: None,
            pose_ddot: None,
        }
    }
}

/// The dynamics' derivatives at one state, written by [`forward_dynamics_jacobians_with_env`]
/// (≈ 4 KB: keep one and reuse it; `Default` is all zeros).
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardJacobians {
    /// χ̈, equal to [`forward_dynamics_with_env`](super::forward_dynamics_with_env)'s bit for bit.
    pub pose_ddot: Vec6,
    /// J_θ (θ̇ = J_θ χ̇).
    pub j_theta: Mat6,
    /// ∂χ̈/∂τ_a = M̃⁻¹J_θᵀ.
    pub d_torque: Mat6,
    /// ∂χ̈/∂Ξ (6 × 64) = −M̃⁻¹J_θᵀΓ(χ, χ̇, χ̈), Coulomb's sign held at this θ̇.
    pub d_params: Regressor,
    /// (∂χ̈/∂χ, ∂χ̈/∂χ̇) if requested.
    pub d_state: Option<(Mat6, Mat6)>,
    /// ∂(J_ad ν)/∂χ if requested (see [`JacobianRequest::rate_step`]).
    pub d_rates: Option<Mat6>,
}

impl Default for ForwardJacobians {
    fn default() -> Self {
        ForwardJacobians {
            pose_ddot: Vec6::zeros(),
            j_theta: Mat6::zeros(),
            d_torque: Mat6::zeros(),
            d_params: Regressor::zeros(),
            d_state: None,
            d_rates: None,
        }
    }
}

/// χ̈ of the forward dynamics at (χ, χ̇) under τ_a in `env`, with its derivatives, written into
/// `out` (see the module docs and [`JacobianRequest`]; `d_state` and `d_rates` are `None` unless
/// requested). The state Jacobians follow from the inverse dynamics by the implicit-function
/// theorem: ∂χ̈/∂x = −M̃⁻¹J_θᵀ ∂τ_a/∂x. On an error `out` holds no meaningful values.
///
/// Errors: as [`forward_dynamics_with_env`](super::forward_dynamics_with_env) and
/// [`inverse_dynamics_derivatives_with_env`](super::inverse_dynamics_derivatives_with_env)
/// (with `state`); [`CoreError::InvalidParameter`] for steps that are not finite and > 0 or a
/// non-finite `rate_step`.
///
/// ```
/// use rss6_core::*;
/// let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
/// let pose = Vec6::new(0.01, -0.01, 0.12, 0.02, 0.0, -0.03);
/// let (pd, tau) = (Vec6::new(0.1, 0.0, 0.0, 0.0, 0.5, 0.0), Vec6::new(1.0, -1.0, 0.5, 0.0, 2.0, 0.0));
/// let env = Environment::default();
/// let req = JacobianRequest { state: true, ..JacobianRequest::default() };
/// let mut fj = ForwardJacobians::default();
/// forward_dynamics_jacobians_with_env(&kp, &dp, &pose, &pd, &tau, &env, &req, &mut fj).unwrap();
/// assert_eq!(fj.pose_ddot, forward_dynamics_with_env(&kp, &dp, &pose, &pd, &tau, &env).unwrap());
/// // ∂χ̈/∂τ_a by a difference of the forward dynamics
/// let mut t2 = tau;
/// t2[2] += 1e-6;
/// let a2 = forward_dynamics_with_env(&kp, &dp, &pose, &pd, &t2, &env).unwrap();
/// assert!(((a2 - fj.pose_ddot) / 1e-6 - fj.d_torque.column(2)).amax() < 1e-6 * fj.d_torque.amax());
/// ```
#[allow(clippy::too_many_arguments)]
pub fn forward_dynamics_jacobians_with_env(
    kp: &KinematicParams,
    dp: &DynamicParams,
    pose: &Vec6,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
    request: &JacobianRequest,
    out: &mut ForwardJacobians,
) -> Result<()> {
    check_state(pose_dot, tau_a)?;
    env.check()?;
    let h_ok = |h: f64| h.is_finite() && h > 0.0;
    if request.state
        && !(request.one_sided_step.is_none_or(h_ok)
            && request.rate_step.is_none_or(f64::is_finite))
    {
        return Err(CoreError::InvalidParameter(
            "the finite-difference step must be finite and > 0, the rate step finite",
        ));
    }
    let geom = LegGeometry::at_pose_from(kp, pose, request.theta.as_ref())?;
    let trig = RateTrig::of(pose);
    let f = match &request.pose_ddot {
        None => {
            let f = forward_at(&geom, dp, pose_dot, tau_a, env)?;
            Known {
                chi_ddot: f.chi_ddot,
                j_ad_t: f.j_ad_t,
                js_inv: f.js_inv,
                chol: f.chol,
                tau_rigid: f.tau_rigid,
            }
        }
        Some(a) => known_acceleration(&geom, &trig, dp, pose_dot, tau_a, env, a)?,
    };
    let j_ad = f.j_ad_t.transpose();
    out.pose_ddot = f.chi_ddot;
    out.j_theta = j_ad * trig.js();
    // K = J_s⁻¹M⁻¹ once; then ∂χ̈/∂τ_a = K J_adᵀ and ∂χ̈/∂Ξ = −K Γ_g, column by column.
    let k = js_inv_m_inv(&f.js_inv, &f.chol);
    out.d_torque = k * f.j_ad_t;
    (out.d_state, out.d_rates) = (None, None);
    // The legs' regressor columns from the leg states the tangents form anyway (or on their own).
    let (v, v_dot) = twist_and_rate_with(&trig, pose_dot, &f.chi_ddot);
    let mut legs = LegColumns::zeros();
    if request.state {
        let nu = request.rate_step.map(|h| v + v_dot * h);
        // (Used in place: moved through an `Option` the ≈ 1.4 KB of tangents would be copied.)
        let t = derivatives_at(
            kp,
            &geom,
            &out.j_theta,
            dp,
            pose_dot,
            &f.chi_ddot,
            (&v, &v_dot),
            env,
            &f.tau_rigid,
            request.one_sided_step,
            nu.as_ref(),
            Some(&mut legs),
        )?;
        // ∂χ̈/∂x = −M̃⁻¹J_θᵀ ∂τ_a/∂x with ∂τ_a/∂x = J_adᵀ⁻¹ ∂f/∂x + f_v ∂θ̇/∂x: the force
        // columns through K = M̃⁻¹J_θᵀJ_adᵀ⁻¹ directly, no factor of J_adᵀ; the viscous ones
        // (if any) through M̃⁻¹J_θᵀ.
        let mut d_pose = -(k * t.pose);
        let mut d_vel = -(k * t.vel);
        if dp.viscous.iter().any(|&fv| fv != 0.0) {
            let fv = Mat6::from_diagonal(&Vec6::from(dp.viscous));
            d_pose -= out.d_torque * (fv * t.rate_pose);
            d_vel -= out.d_torque * (fv * out.j_theta);
        }
        check_finite(d_pose.as_slice())?;
        check_finite(d_vel.as_slice())?;
        if let Some(d) = &t.rates {
            check_finite(d.as_slice())?;
        }
        out.d_state = Some((d_pose, d_vel));
        out.d_rates = t.rates;
    } else {
        legs = LegColumns::at(&geom, (&v, &v_dot), &env.gravity)?;
    }
    let platform = platform_columns(&geom.rot, &v, &v_dot, &env.gravity);
    param_columns(
        &mut out.d_params,
        request.param_columns,
        (&k, &out.d_torque),
        &platform,
        &legs,
    );
    Ok(())
}

/// K = J_s⁻¹M⁻¹ from the Cholesky factor L of M (M⁻¹ = L⁻ᵀL⁻¹, L⁻¹ by forward substitution:
/// ≈ 100 products where nalgebra's general `inverse` solves six columns twice) and J_s⁻¹ =
/// diag(I, J_e⁻¹) (only its lower block multiplies).
fn js_inv_m_inv(js_inv: &Mat6, chol: &nalgebra::Cholesky<f64, nalgebra::U6>) -> Mat6 {
    // Only L's lower triangle is read (`l_dirty` leaves the upper one as it was).
    let l = chol.l_dirty();
    let mut li = Mat6::zeros();
    for j in 0..6 {
        let d = 1.0 / l[(j, j)];
        li[(j, j)] = d;
        for i in j + 1..6 {
            let mut s = 0.0;
            for k in j..i {
                s += l[(i, k)] * li[(k, j)];
            }
            li[(i, j)] = -s / l[(i, i)];
        }
    }
    let mut m_inv = Mat6::zeros();
    for j in 0..6 {
        for i in j..6 {
            let mut s = 0.0;
            for k in i..6 {
                s += li[(k, i)] * li[(k, j)];
            }
            m_inv[(i, j)] = s;
            m_inv[(j, i)] = s;
        }
    }
    let je_inv = js_inv.fixed_view::<3, 3>(3, 3);
    let lower = je_inv * m_inv.fixed_rows::<3>(3);
    m_inv.fixed_rows_mut::<3>(3).copy_from(&lower);
    m_inv
}

/// ∂χ̈/∂Ξ = −K Γ_g on the columns of `mask` (the others zero), K = J_s⁻¹M⁻¹, from the platform's
/// columns of Γ_g and the legs' factors. A wrench's and a friction column of Γ_g is J_adᵀ e_i times
/// a scalar, so its K product is column i of K J_adᵀ = ∂χ̈/∂τ_a (`d_torque`) times that scalar; a
/// link's I_x and I_y columns are equal (one product).
fn param_columns(
    out: &mut Regressor,
    mask: u64,
    (k, d_torque): (&Mat6, &Mat6),
    platform: &[Vec6; 4],
    legs: &LegColumns,
) {
    let on = |c: usize| mask.checked_shr(c as u32).is_some_and(|m| m & 1 == 1);
    // A slice fill (one memset): nalgebra's element iterator costs ≈ 12 instructions an entry.
    out.as_mut_slice().fill(0.0);
    // Column c is written, and its product formed, only if the mask asks for it.
    macro_rules! put {
        ($c:expr, $x:expr) => {
            if on($c) {
                out.set_column($c, &$x);
            }
        };
    }
    for (c, col) in platform.iter().enumerate() {
        put!(c, -(k * col));
    }
    for i in 0..LEGS {
        let t = d_torque.column(i);
        let (cw, cl) = (4 * (1 + i), 4 * (7 + i));
        put!(cw, t * -legs.q[i]);
        put!(cw + 3, t * -legs.theta_ddot[i]);
        put!(cl, -(k * legs.f_cl.column(i)));
        if on(cl + 1) || on(cl + 2) {
            let h: Vec6 = -(k * legs.half.column(i));
            put!(cl + 1, h);
            put!(cl + 2, h);
        }
        let td = legs.theta_dot[i];
        put!(52 + i, t * -sign0(td));
        put!(58 + i, t * -td);
    }
}

/// What the derivatives need of the forward dynamics at the state.
struct Known {
    chi_ddot: Vec6,
    j_ad_t: Mat6,
    js_inv: Mat6,
    chol: nalgebra::Cholesky<f64, nalgebra::U6>,
    tau_rigid: Vec6,
}

/// [`Known`] from a known χ̈ (see [`JacobianRequest::pose_ddot`]): the mass matrix and its factor,
/// J_s⁻¹, J_adᵀ and the friction at θ̇ formed as the forward dynamics forms them (the same values,
/// bit for bit), no solve.
fn known_acceleration(
    geom: &LegGeometry,
    trig: &RateTrig,
    dp: &DynamicParams,
    pose_dot: &Vec6,
    tau_a: &Vec6,
    env: &Environment,
    chi_ddot: &Vec6,
) -> Result<Known> {
    check_finite(chi_ddot.as_slice())?;
    let v = trig.js() * pose_dot;
    let (j_ad_t, theta_dot) = joint_rates(geom, &v)?;
    let mut m = twist_mass_matrix(geom, dp)?;
    if let Some(load) = &env.load {
        LoadAt::new(load, &geom.rot).add_mass(&mut m);
    }
    Ok(Known {
        chi_ddot: *chi_ddot,
        j_ad_t,
        js_inv: trig.js_inv()?,
        chol: m
            .cholesky()
            .ok_or(CoreError::Singular(SingularKind::Matrix))?,
        tau_rigid: tau_a - joint_friction(dp, &theta_dot),
    })
}
