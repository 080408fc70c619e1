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
//! # A load on the platform
//!
//! A rigid body fixed to the platform with its centre of mass away from E and a full inertia tensor
//! ([`PlatformLoad`]) is not part of Ξ; it enters through an [`Environment`] (gravity + optional load)
//! passed to the `*_with_env` functions ([`inverse_dynamics_with_env`], [`forward_dynamics_with_env`],
//! [`mass_matrix_with_env`], [`dynamics_terms_with_env`], [`gravity_with_env`], [`rk4_step_with_env`],
//! and the energies). The plain and `*_with_gravity` functions are these with no load. The load's
//! terms (offset gravity moment m c × g, inertial wrench with m(Ë + ω̇ × c + ω × (ω × c)), the
//! parallel-axis inertia rotated to the base frame, the gyroscopic ω × I_c ω) are derived in the
//! `load` module's docs and in `docs/dynamics.md`.
//!
//! # Friction
//!
//! Joint friction τ_f,i = f_c,i sign(θ̇_i) + f_v,i θ̇_i (eq. 3.48, 6.4) with sign(0) = 0, and
//! τ̃_f = J_θᵀ τ_f. A smooth alternative, [`joint_friction_smooth`], replaces sign by tanh(θ̇/ε); the model
//! functions use the thesis's sign. The simulators step friction implicitly per tick with
//! [`implicit_friction`] (stick–slip, no smoothing; see its module).

mod friction_step;
mod integration;
mod joint_rates;
mod lanes;
mod leg_state;
mod load;
mod matrices;
mod newton_euler;
mod pose_tangent;
mod rate_tangent;
mod sensitivity;

pub use self::friction_step::{
    implicit_friction, rk4_step_implicit_friction, rk4_step_implicit_friction_observed,
    FrictionStep,
};
pub use self::integration::{
    rk4_step, rk4_step_by, rk4_step_with_env, rk4_step_with_gravity, ModelState,
};
pub use self::joint_rates::{
    forward_dynamics_by_joint_rates, forward_dynamics_by_joint_rates_from,
};
pub(crate) use self::leg_state::leg_acc;
pub use self::load::{Environment, PlatformLoad};
pub use self::matrices::{
    coriolis, coriolis_twist, dynamics_terms, dynamics_terms_with_env, dynamics_terms_with_gravity,
    friction, friction_twist, gravity, gravity_twist, gravity_with, gravity_with_env,
    kinetic_energy, kinetic_energy_with_env, mass_matrix, mass_matrix_twist, mass_matrix_with_env,
    potential_energy_with_env, potential_energy_with_gravity, DynamicsTerms,
};
pub use self::newton_euler::{
    forward_dynamics, forward_dynamics_with_env, forward_dynamics_with_gravity, inverse_dynamics,
    inverse_dynamics_derivatives_with_env, inverse_dynamics_with_env,
    inverse_dynamics_with_gravity,
};
pub use self::sensitivity::{
    forward_dynamics_jacobians_with_env, ForwardJacobians, JacobianRequest,
};

use crate::error::{check_finite, Result};
use crate::params::{Body, DynamicParams};
use crate::pose::RateTrig;
use crate::types::{Mat3, Vec3, Vec6};
use lanes::Lane;
use nalgebra::Vector3;

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
pub(super) fn sign0(x: f64) -> f64 {
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
/// for integrators that dislike the discontinuity. ε ≤ 0 gives the limit ε → 0⁺, [`joint_friction`]
/// (sign, sign(0) = 0), so finite input never yields NaN.
pub fn joint_friction_smooth(dp: &DynamicParams, theta_dot: &Vec6, eps: f64) -> Vec6 {
    if eps > 0.0 {
        // θ̇/ε is ±∞ at worst for finite θ̇, and tanh(±∞) = ±1.
        Vec6::from_fn(|i, _| {
            dp.coulomb[i] * libm::tanh(theta_dot[i] / eps) + dp.viscous[i] * theta_dot[i]
        })
    } else {
        joint_friction(dp, theta_dot)
    }
}

/// ŝ × u for ŝ = ẑ: [−u_y, u_x, 0].
#[inline(always)]
pub(super) fn z_cross<T: Lane>(u: &Vector3<T>) -> Vector3<T> {
    Vector3::new(-u[1], u[0], T::zero())
}

/// ŝ·(u × v) for ŝ = ẑ: u_x v_y − u_y v_x.
#[inline(always)]
pub(super) fn z_triple<T: Lane>(u: &Vector3<T>, v: &Vector3<T>) -> T {
    u[0] * v[1] - u[1] * v[0]
}

/// v_E = J_s χ̇ and v̇_E = J_s χ̈ + J̇_s χ̇ (eq. 3.23, 5.12) with 3 × 3 blocks only (J_s = diag(I, J_e)).
#[inline]
pub(super) fn twist_and_rate(pose: &Vec6, pose_dot: &Vec6, pose_ddot: &Vec6) -> (Vec6, Vec6) {
    twist_and_rate_with(&RateTrig::of(pose), pose_dot, pose_ddot)
}

/// [`twist_and_rate`] from the pose's [`RateTrig`].
#[inline]
pub(super) fn twist_and_rate_with(
    trig: &RateTrig,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
) -> (Vec6, Vec6) {
    let je = trig.je();
    let je_dot = trig.je_dot(pose_dot[3], pose_dot[4]);
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

pub(super) fn check_state(pose_dot: &Vec6, more: &Vec6) -> Result<()> {
    check_finite(pose_dot.as_slice())?;
    check_finite(more.as_slice())
}
