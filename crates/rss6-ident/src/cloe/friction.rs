//! The implicit friction law in the CLOE loop (`LoopConfig::implicit_friction`) and its forward
//! sensitivities.
//!
//! Per tick the friction torque τ_f is [`rss6_core::implicit_friction`] of the state (χ, χ̇) and
//! the held drive torque τ_a, exactly as the model twin steps it; the tick is then integrated on
//! the friction-free model with τ_a − τ_f held. τ_f solves, with w the predicted end-of-tick joint
//! rates, w = g(χ, χ̇, τ_a − τ_f, Ξ) = w₀ − K τ_f:
//!
//! ```text
//! stuck joint i:  w_i = 0                       slipping joint i:  τ_f,i = s_i f_c,i + f_v,i w_i
//! ```
//!
//! On a fixed stick set and slip signs both are smooth, so differentiating them gives a 6 × 6
//! linear system for dτ_f (the implicit-function theorem on the active set):
//!
//! ```text
//! stuck:  (K dτ_f)_i = dg_i                  slipping:  dτ_f,i + f_v,i (K dτ_f)_i = f_v,i dg_i + s_i df_c,i + w_i df_v,i
//! dg = G_χ dχ + G_χ̇ dχ̇ + K dτ_a + dt J_θ ∂χ̈/∂Ξ dΞ      (∂χ̈/∂Ξ = −M̃⁻¹J_θᵀΓ, friction-free)
//! ```
//!
//! G_χ and G_χ̇ come from the tick's first RK4 stage (same state, same held τ_a − τ_f): its state
//! Jacobians F_χ, F_χ̇ and ∂χ̈/∂Ξ, plus the kinematic part of g by central differences (see
//! [`sensitivity`]). The derivative of a change of stick set is ignored, as the sign law's
//! derivative of sign(θ̇) is: both are events of measure zero in A.

use super::config::LoopConfig;
use crate::error::{IdentError, Result};
use nalgebra::{Dyn, OMatrix, U6};
use rss6_core::{
    implicit_friction, twist_jacobian, twist_jacobian_dot, twist_jacobian_inverse, DynamicParams,
    FrictionStep, Mat6, Vec6, LEGS,
};

/// A 6 × p block of sensitivities (rows: a 6-vector's components, columns: active parameters).
pub(super) type Sens = OMatrix<f64, U6, Dyn>;

/// Index of f_c,1 in Ξ (after the 13 bodies' [m, I_x, I_y, I_z]); f_v,1 follows the six f_c.
pub(super) const COULOMB: usize = 4 * (1 + 2 * LEGS);
const VISCOUS: usize = COULOMB + LEGS;

/// The tick's state and its sensitivities (to the active columns).
pub(super) struct StepSens<'s> {
    pub columns: &'s [usize],
    pub p: &'s Sens,
    pub v: &'s Sens,
    pub tau: &'s Sens,
}

/// What one implicit friction step gives the loop.
pub(super) struct Step {
    /// τ_a − τ_f, held over the tick on the friction-free model.
    pub net: Vec6,
    /// The core's solution (stick set, rates, compliance K).
    pub solved: FrictionStep,
    /// Whether the friction solve converged exactly ([`rss6_core::FrictionStep::exact`]).
    pub exact: bool,
    /// How many joints stick over the tick.
    pub stuck: usize,
}

/// The friction of one tick from (χ, χ̇) = (`p`, `v`) under the held drive torque `tau` (the
/// values only; [`sensitivity`] adds the derivatives once the tick's first RK4 stage is known).
pub(super) fn solve(
    cfg: &LoopConfig,
    dp: &DynamicParams,
    p: &Vec6,
    v: &Vec6,
    tau: &Vec6,
    t: f64,
) -> Result<Step> {
    let env = cfg.environment();
    let f = implicit_friction(&cfg.kp, dp, p, v, tau, &env, cfg.dt).map_err(|e| sim_err(t, e))?;
    Ok(Step::new(tau, f))
}

impl Step {
    /// The tick's step from the core's solution `f` under the held drive torque `tau`.
    pub(super) fn new(tau: &Vec6, f: FrictionStep) -> Self {
        Step {
            net: tau - f.torque,
            stuck: f.stuck.iter().filter(|&&b| b).count(),
            exact: f.exact,
            solved: f,
        }
    }
}

/// The tick's first RK4 stage at (χ, χ̇, τ_a − τ_f) on the friction-free model: χ̈, F_χ, F_χ̇,
/// M̃⁻¹J_θᵀ and −M̃⁻¹J_θᵀΓ on the active columns (zero for friction and gains).
pub(super) struct FirstStage<'s> {
    pub a: &'s Vec6,
    pub fp: &'s Mat6,
    pub fv: &'s Mat6,
    pub fxi: &'s Sens,
    /// J_θ at the state.
    pub j_theta: &'s Mat6,
    /// ∂(J_ad(χ) ν)/∂χ at ν = ξ + dt ξ̇ held ([`rss6_core::JacobianRequest::rate_step`]).
    pub d_rates: &'s Mat6,
}

/// ∂(τ_a − τ_f)/∂A of a solved tick. The free rates are w₀ = J_adᵀ(ξ + dt ξ̇) with ξ = J_s χ̇ and
/// ξ̇ = J_s χ̈ + J̇_s χ̇ (the twist), i.e. w₀ = J_θ(χ̇ + dt χ̈ + dt J_s⁻¹J̇_s χ̇): with χ̈ the first
/// stage's, ∂w₀/∂x = ∂w₀/∂x|_χ̈ + dt J_θ F_x and ∂w₀/∂Ξ = dt J_θ ∂χ̈/∂Ξ. The first term is
/// kinematics only (central differences of J_θ and J̇_s, 24 cheap calls) — the stage's state
/// Jacobians replace 24 dynamics calls per tick.
#[allow(clippy::too_many_arguments)]
pub(super) fn sensitivity(
    cfg: &LoopConfig,
    dp: &DynamicParams,
    step: &Step,
    p: &Vec6,
    v: &Vec6,
    s: StepSens<'_>,
    first: FirstStage<'_>,
    t: f64,
) -> Result<Sens> {
    let dt = cfg.dt;
    let f = &step.solved;
    let (gp, gv) = free_rate_jacobians(cfg, p, v, &first, t)?;
    // The active-set system A dτ_f = D dg + s: D = diag(1 stuck, f_v,i slipping), s the Coulomb
    // and viscous columns of a slipping joint. Solved once for A⁻¹ and W = A⁻¹D (6 × 6), so the
    // p columns take four 6 × 6 products: d(τ_a − τ_f) = (I − WK) dτ_a − W G_χ dχ − W G_χ̇ dχ̇
    // − W dt J_θ ∂χ̈/∂Ξ − A⁻¹ s.
    let k = &f.compliance;
    let mut a = Mat6::zeros();
    let mut d = Vec6::zeros();
    for i in 0..LEGS {
        if f.stuck[i] {
            a.set_row(i, &k.row(i));
            d[i] = 1.0;
        } else {
            d[i] = dp.viscous[i].max(0.0);
            a.set_row(i, &(k.row(i) * d[i]));
            a[(i, i)] += 1.0;
        }
    }
    let a_inv = a.lu().try_inverse().ok_or_else(|| IdentError::Simulation {
        time: t,
        message: "the implicit friction step's active-set system is singular".into(),
    })?;
    let w = a_inv * Mat6::from_diagonal(&d);
    let (m_tau, m_p, m_v) = (-(w * k), -(w * gp), -(w * gv));
    // The mass parameters act through the friction-free acceleration over the tick.
    let m_xi = -(w * (first.j_theta * dt));
    let mut out = s.tau.clone();
    // Column by column in one pass (the sums of four block products, in their order); the
    // friction and gain columns of ∂χ̈/∂Ξ are zero under this law (their product is skipped).
    for (c, &col) in s.columns.iter().enumerate() {
        let mut o: Vec6 = out.column(c).into_owned();
        o += m_tau * s.tau.column(c);
        o += m_p * s.p.column(c);
        o += m_v * s.v.column(c);
        if col < COULOMB {
            o += m_xi * first.fxi.column(c);
        }
        out.set_column(c, &o);
    }
    for i in (0..LEGS).filter(|&i| !f.stuck[i]) {
        let rate = f.rate[i];
        for (c, &col) in s.columns.iter().enumerate() {
            let source = if col == COULOMB + i && dp.coulomb[i] > 0.0 {
                sign0(rate)
            } else if col == VISCOUS + i && dp.viscous[i] > 0.0 {
                rate
            } else {
                continue;
            };
            let mut o = out.column_mut(c);
            o -= a_inv.column(i) * source;
        }
    }
    Ok(out)
}

/// (∂w₀/∂χ, ∂w₀/∂χ̇) of the free rates w₀ = J_ad(χ) ν, ν = J_s(χ)(χ̇ + dt χ̈) + dt J̇_s(χ, χ̇) χ̇,
/// at (`p`, `v`) with the first stage's χ̈ and its state Jacobians (see [`sensitivity`]). The pose
/// derivative of J_ad at ν held comes with the stage (from its own pose steps); the rest is the
/// Euler-angle kinematics J_s, J̇_s (no inverse kinematics): central differences, exact in χ̇
/// (J̇_s χ̇ is quadratic in χ̇).
pub(super) fn free_rate_jacobians(
    cfg: &LoopConfig,
    p: &Vec6,
    v: &Vec6,
    first: &FirstStage<'_>,
    t: f64,
) -> Result<(Mat6, Mat6)> {
    let dt = cfg.dt;
    let u = v + first.a * dt;
    // ν = J_s(χ) u + dt J̇_s(χ, χ̇) χ̇. J_s reads χ only through α, β and J̇_s χ̇ only through α, β,
    // α̇, β̇ (`euler_rate_jacobian`): along the other coordinates the differences of the two
    // matrices are exactly zero, so they are built once (the same bits as building them per step).
    let js = twist_jacobian(p);
    let jd = twist_jacobian_dot(p, v);
    let nu = |js: &Mat6, jd: &Mat6, vv: &Vec6, uu: &Vec6| -> Vec6 { js * uu + jd * vv * dt };
    let angle = |c: usize| c == 3 || c == 4;
    let (mut np, mut nv) = (Mat6::zeros(), Mat6::zeros());
    for c in 0..6 {
        if angle(c) {
            let (mut pp, mut pm) = (*p, *p);
            pp[c] += 1e-6;
            pm[c] -= 1e-6;
            let plus = nu(&twist_jacobian(&pp), &twist_jacobian_dot(&pp, v), v, &u);
            let minus = nu(&twist_jacobian(&pm), &twist_jacobian_dot(&pm, v), v, &u);
            np.set_column(c, &((plus - minus) / (pp[c] - pm[c])));
        }
        let (mut vp, mut vm) = (*v, *v);
        vp[c] += 1e-2;
        vm[c] -= 1e-2;
        let (up, um) = (vp + first.a * dt, vm + first.a * dt);
        let (jdp, jdm) = if angle(c) {
            (twist_jacobian_dot(p, &vp), twist_jacobian_dot(p, &vm))
        } else {
            (jd, jd)
        };
        nv.set_column(
            c,
            &((nu(&js, &jdp, &vp, &up) - nu(&js, &jdm, &vm, &um)) / (vp[c] - vm[c])),
        );
    }
    let j_ad = first.j_theta * twist_jacobian_inverse(p).map_err(|e| sim_err(t, e))?;
    let jdt = first.j_theta * dt;
    Ok((
        first.d_rates + j_ad * np + jdt * first.fp,
        j_ad * nv + jdt * first.fv,
    ))
}

/// Central differences (∂f/∂χ, ∂f/∂χ̇) of a 6-vector function of the state at (`p`, `v`): steps
/// 10⁻⁶ in χ and `hv` in χ̇ (exact for any step when f is quadratic in χ̇). 24 calls of `f`.
pub(super) fn central_jacobians<F>(f: F, p: &Vec6, v: &Vec6, hv: f64) -> Result<(Mat6, Mat6)>
where
    F: Fn(&Vec6, &Vec6) -> Result<Vec6>,
{
    const HP: f64 = 1e-6;
    let mut fp = Mat6::zeros();
    let mut fv = Mat6::zeros();
    for k in 0..6 {
        let (mut pp, mut pm) = (*p, *p);
        pp[k] += HP;
        pm[k] -= HP;
        fp.set_column(k, &((f(&pp, v)? - f(&pm, v)?) / (pp[k] - pm[k])));
        let (mut vp, mut vm) = (*v, *v);
        vp[k] += hv;
        vm[k] -= hv;
        fv.set_column(k, &((f(p, &vp)? - f(p, &vm)?) / (vp[k] - vm[k])));
    }
    Ok((fp, fv))
}

/// sign(x) with sign(0) = 0.
pub(super) fn sign0(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x.signum()
    }
}

/// A core error met at `time` (s) while simulating the loop.
pub(super) fn sim_err(time: f64, e: rss6_core::CoreError) -> IdentError {
    IdentError::Simulation {
        time,
        message: e.to_string(),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::cloe::truth::table_5_2_truth;
    use rand::{Rng, SeedableRng};
    use rss6_core::{
        forward_dynamics_jacobians_with_env, forward_dynamics_with_env, home_pose,
        ForwardJacobians, JacobianRequest, KinematicParams,
    };

    /// The free rates' derivatives built from the first stage equal central differences of the
    /// core's own free-rate prediction ([`implicit_friction`]`.free_rate`, friction-free), at
    /// random states with up to 0.1 rad of rotation: the identity J_θ = J_adᵀJ_s the formula uses.
    #[test]
    fn free_rate_jacobians_match_the_cores_prediction() {
        let kp = KinematicParams::nominal();
        let cfg = LoopConfig::new(kp, home_pose(), 1.0);
        let mut dp = table_5_2_truth().dynamics;
        dp.coulomb = [0.0; LEGS];
        dp.viscous = [0.0; LEGS];
        let env = cfg.environment();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut worst: f64 = 0.0;
        for _ in 0..20 {
            let mut p = home_pose();
            for k in 0..6 {
                p[k] += if k < 3 { 0.01 } else { 0.1 } * rng.random_range(-1.0..1.0);
            }
            let v = Vec6::from_fn(|_, _| rng.random_range(-0.5..0.5));
            let tau = Vec6::from_fn(|_, _| rng.random_range(-5.0..5.0));
            let fd = |pp: &Vec6, vv: &Vec6| -> Result<Vec6> {
                forward_dynamics_with_env(&kp, &dp, pp, vv, &tau, &env).map_err(|e| sim_err(0.0, e))
            };
            let a = fd(&p, &v).unwrap();
            let (fp, fv) = central_jacobians(fd, &p, &v, 1e-6).unwrap();
            let fxi = Sens::zeros(0);
            let request = JacobianRequest {
                state: true,
                rate_step: Some(cfg.dt),
                ..JacobianRequest::default()
            };
            let mut fj = ForwardJacobians::default();
            forward_dynamics_jacobians_with_env(&kp, &dp, &p, &v, &tau, &env, &request, &mut fj)
                .unwrap();
            let first = FirstStage {
                a: &a,
                fp: &fp,
                fv: &fv,
                fxi: &fxi,
                j_theta: &fj.j_theta,
                d_rates: &fj.d_rates.unwrap(),
            };
            let (gp, gv) = free_rate_jacobians(&cfg, &p, &v, &first, 0.0).unwrap();
            let w0 = |pp: &Vec6, vv: &Vec6| -> Result<Vec6> {
                Ok(implicit_friction(&kp, &dp, pp, vv, &tau, &env, cfg.dt)
                    .map_err(|e| sim_err(0.0, e))?
                    .free_rate)
            };
            let (rp, rv) = central_jacobians(w0, &p, &v, 1e-2).unwrap();
            worst = worst
                .max((gp - rp).amax() / rp.amax())
                .max((gv - rv).amax() / rv.amax());
        }
        println!("worst relative difference {worst:.2e}");
        assert!(worst < 1e-6, "{worst}");
    }
}
