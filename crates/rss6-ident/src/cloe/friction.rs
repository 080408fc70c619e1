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
//! G_χ and G_χ̇ are central differences of g with τ_a − τ_f held (12 calls each; g is quadratic in
//! χ̇, so that difference is exact whatever the step). The derivative of a change of stick set is
//! ignored, as the sign law's derivative of sign(θ̇) is: both are events of measure zero in A.

use super::config::LoopConfig;
use crate::error::{IdentError, Result};
use nalgebra::{Dyn, OMatrix, U6};
use rss6_core::{
    forward_dynamics_with_env, implicit_friction, jacobian_theta, mass_matrix_with_env,
    regressor_with_gravity, DynamicParams, Mat6, Vec6, LEGS,
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
    /// ∂(τ_a − τ_f)/∂A when sensitivities are on.
    pub s_net: Option<Sens>,
    /// Whether the friction solve converged exactly ([`rss6_core::FrictionStep::exact`]).
    pub exact: bool,
    /// How many joints stick over the tick.
    pub stuck: usize,
}

/// The friction of one tick from (χ, χ̇) = (`p`, `v`) under the held drive torque `tau`, with `dp`
/// the full parameters (friction included) and `dp_nf` the same without friction.
#[allow(clippy::too_many_arguments)]
pub(super) fn step(
    cfg: &LoopConfig,
    dp: &DynamicParams,
    dp_nf: &DynamicParams,
    p: &Vec6,
    v: &Vec6,
    tau: &Vec6,
    sens: Option<StepSens<'_>>,
    t: f64,
) -> Result<Step> {
    let env = cfg.environment();
    let dt = cfg.dt;
    let f = implicit_friction(&cfg.kp, dp, p, v, tau, &env, dt).map_err(|e| sim_err(t, e))?;
    let net = tau - f.torque;
    let stuck = f.stuck.iter().filter(|&&b| b).count();
    let Some(s) = sens else {
        return Ok(Step {
            net,
            s_net: None,
            exact: f.exact,
            stuck,
        });
    };
    let n = s.columns.len();
    // g with τ_a − τ_f held: the free rates of a friction-free step.
    let g = |pp: &Vec6, vv: &Vec6| -> Result<Vec6> {
        Ok(implicit_friction(&cfg.kp, dp_nf, pp, vv, &net, &env, dt)
            .map_err(|e| sim_err(t, e))?
            .free_rate)
    };
    let mut dg = f.compliance * s.tau;
    let (gp, gv) = central_jacobians(g, p, v, 1e-2)?;
    dg += gp * s.p + gv * s.v;
    // The mass parameters act through the friction-free acceleration over the tick.
    if s.columns.iter().any(|&c| c < COULOMB) {
        let a = forward_dynamics_with_env(&cfg.kp, dp_nf, p, v, &net, &env)
            .map_err(|e| sim_err(t, e))?;
        let m = mass_matrix_with_env(&cfg.kp, dp, p, &env).map_err(|e| sim_err(t, e))?;
        let chol = m.cholesky().ok_or_else(|| IdentError::Simulation {
            time: t,
            message: "the mass matrix is not positive definite".into(),
        })?;
        let j = jacobian_theta(&cfg.kp, p).map_err(|e| sim_err(t, e))?;
        let jft = j * chol.solve(&j.transpose()) * dt;
        let gamma =
            regressor_with_gravity(&cfg.kp, p, v, &a, &cfg.gravity).map_err(|e| sim_err(t, e))?;
        for (c, &col) in s.columns.iter().enumerate() {
            if col < COULOMB {
                let d = -(jft * gamma.column(col));
                let mut dst = dg.column_mut(c);
                dst += d;
            }
        }
    }
    // The active-set system A dτ_f = R.
    let k = &f.compliance;
    let mut a = Mat6::zeros();
    let mut r = Sens::zeros(n);
    for i in 0..LEGS {
        if f.stuck[i] {
            a.set_row(i, &k.row(i));
            r.set_row(i, &dg.row(i));
        } else {
            let fv = dp.viscous[i].max(0.0);
            a.set_row(i, &(k.row(i) * fv));
            a[(i, i)] += 1.0;
            r.set_row(i, &(dg.row(i) * fv));
            let w = f.rate[i];
            let sign = sign0(w);
            for (c, &col) in s.columns.iter().enumerate() {
                if col == COULOMB + i && dp.coulomb[i] > 0.0 {
                    r[(i, c)] += sign;
                } else if col == VISCOUS + i && dp.viscous[i] > 0.0 {
                    r[(i, c)] += w;
                }
            }
        }
    }
    let lu = a.lu();
    let s_tf = lu.solve(&r).ok_or_else(|| IdentError::Simulation {
        time: t,
        message: "the implicit friction step's active-set system is singular".into(),
    })?;
    Ok(Step {
        net,
        s_net: Some(s.tau - s_tf),
        exact: f.exact,
        stuck,
    })
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
