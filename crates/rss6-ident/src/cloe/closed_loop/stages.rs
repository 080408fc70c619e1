//! One RK4 stage of the loop's model with its derivatives (see the parent module's docs).

use super::super::config::{LoopConfig, StateJacobians};
use super::super::friction::{central_jacobians, sim_err, Sens, COULOMB};
use super::super::sens_state::SensState;
use super::recording::StageKnown;
use crate::error::{IdentError, Result};
use nalgebra::{SMatrix, SVector};
use rss6_core::{
    forward_dynamics_by_joint_rates, forward_dynamics_jacobians_with_env,
    forward_dynamics_with_env, jacobian_theta, mass_matrix_with_env, regressor_with_gravity,
    DynamicParams, ForwardJacobians, JacobianRequest, Mat6, Vec6, LEGS, N_DYN,
};

/// Pose step (m, rad) of the one-sided state Jacobians of [`StateJacobians::PerTick`].
const PER_TICK_H_POSE: f64 = 1e-7;

/// What a stage needs of the loop: the configuration, the parameters and the active columns. It
/// holds no loop state, so the threads that evaluate stages ahead (`ahead.rs`) share it.
pub(super) struct StageModel<'a> {
    pub(super) cfg: &'a LoopConfig,
    pub(super) dp: DynamicParams,
    /// `dp` without Coulomb friction (the smoothed law's friction-free model).
    pub(super) dp_nc: DynamicParams,
    /// `dp` without any friction (the implicit law's friction-free step).
    pub(super) dp_nf: DynamicParams,
    /// The active columns of A (`None`: no sensitivities).
    pub(super) columns: Option<Vec<usize>>,
    /// The columns of ∂χ̈/∂Ξ a stage needs (bit k for column k of Ξ).
    param_mask: u64,
}

/// One RK4 stage's acceleration and (optionally) its derivatives (boxed: ≈ 1.5 KB that the
/// stages evaluated ahead would otherwise copy at every move).
pub(super) struct Stage {
    pub(super) a: Vec6,
    pub(super) jac: Option<Box<StageJac>>,
}

/// A stage's derivatives.
pub(super) struct StageJac {
    /// F_χ = ∂χ̈/∂χ, F_χ̇ = ∂χ̈/∂χ̇.
    pub(super) fp: Mat6,
    pub(super) fv: Mat6,
    /// M̃⁻¹J_θᵀ = ∂χ̈/∂τ.
    pub(super) ft: Mat6,
    /// −M̃⁻¹J_θᵀΓ restricted to the active Ξ columns.
    pub(super) fxi: Sens,
    pub(super) j_theta: Mat6,
    /// ∂(J_ad ν)/∂χ of the free rates (the implicit law's first stage only).
    pub(super) d_rates: Option<Mat6>,
}

/// A stage asked for its own state Jacobians always gets them.
fn unreachable_state(t: f64) -> Result<(Mat6, Mat6)> {
    Err(IdentError::Simulation {
        time: t,
        message: "the dynamics returned no state Jacobians".into(),
    })
}

impl<'a> StageModel<'a> {
    pub(super) fn new(
        cfg: &'a LoopConfig,
        dp: &DynamicParams,
        columns: Option<Vec<usize>>,
    ) -> Self {
        let mut dp_nc = *dp;
        dp_nc.coulomb = [0.0; LEGS];
        let mut dp_nf = dp_nc;
        dp_nf.viscous = [0.0; LEGS];
        let param_mask = columns.iter().flatten().fold(0u64, |m, &col| {
            if Self::uses_params_column(cfg, col) {
                m | 1 << col
            } else {
                m
            }
        });
        StageModel {
            cfg,
            dp: *dp,
            dp_nc,
            dp_nf,
            columns,
            param_mask,
        }
    }

    /// Whether column `col` of A takes its sensitivity from ∂χ̈/∂Ξ: the dynamic parameters, and
    /// the friction unless the implicit law applies it through τ_f (its sensitivity is then in
    /// the held torque's).
    fn uses_params_column(cfg: &LoopConfig, col: usize) -> bool {
        col < N_DYN && !(cfg.implicit_friction && col >= COULOMB)
    }

    /// One stage of the forward dynamics, with derivatives if sensitivities are on. With the
    /// implicit law `tau` is τ_a − τ_f and the model is friction-free. `frozen`: state Jacobians
    /// to use instead of computing them; `free_rates`: also the pose derivative of the joint
    /// rates one tick ahead (the implicit friction's first stage, see [`super::friction`]).
    /// `fj`: scratch space for the core call (≈ 4 KB, one per thread). `known`: the state's IK
    /// angles and acceleration as a primal run of the same model computed them (the derivatives
    /// then compute neither again; the results are the same bit for bit).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn stage(
        &self,
        fj: &mut ForwardJacobians,
        p: &Vec6,
        v: &Vec6,
        tau: &Vec6,
        t: f64,
        frozen: Option<(Mat6, Mat6)>,
        free_rates: bool,
        known: Option<&StageKnown>,
    ) -> Result<Stage> {
        let cfg = self.cfg;
        let env = cfg.environment();
        let eps = cfg.friction_smoothing;
        let implicit = cfg.implicit_friction;
        if eps > 0.0 && !implicit {
            return self.smoothed_stage(p, v, tau, t, frozen);
        }
        // Sign law (Coulomb's sign held) or implicit (friction-free model).
        let dp = if implicit { &self.dp_nf } else { &self.dp };
        let first_serves = frozen.is_some() && cfg.state_jacobians == StateJacobians::FirstStage;
        let Some(columns) = self.columns.as_deref().filter(|_| !first_serves) else {
            // No sensitivities, or the tick's first stage's derivatives serve this one: only χ̈,
            // which a recording of this model already holds (the same bits).
            let a = match known {
                Some(&(_, a)) => a,
                None => forward_dynamics_with_env(&cfg.kp, dp, p, v, tau, &env)
                    .map_err(|e| sim_err(t, e))?,
            };
            return Ok(Stage { a, jac: None });
        };
        // Per tick the state Jacobians are an approximation already (≈ 10⁻³): one-sided pose
        // differences halve their cost for an O(h) error far below that.
        let mut request = JacobianRequest {
            state: frozen.is_none(),
            rate_step: free_rates.then_some(cfg.dt),
            param_columns: self.param_mask,
            theta: known.map(|k| k.0),
            pose_ddot: known.map(|k| k.1),
            ..JacobianRequest::default()
        };
        if cfg.state_jacobians != StateJacobians::Exact {
            request.one_sided_step = Some(PER_TICK_H_POSE);
        }
        forward_dynamics_jacobians_with_env(&cfg.kp, dp, p, v, tau, &env, &request, fj)
            .map_err(|e| sim_err(t, e))?;
        let (fp, fv) = match (frozen, fj.d_state) {
            (Some(j), _) | (None, Some(j)) => j,
            (None, None) => unreachable_state(t)?,
        };
        let mut fxi = Sens::zeros(columns.len());
        for (c, &col) in columns.iter().enumerate() {
            if Self::uses_params_column(cfg, col) {
                fxi.set_column(c, &fj.d_params.column(col));
            }
        }
        Ok(Stage {
            a: fj.pose_ddot,
            jac: Some(Box::new(StageJac {
                fp,
                fv,
                ft: fj.d_torque,
                fxi,
                j_theta: fj.j_theta,
                d_rates: fj.d_rates,
            })),
        })
    }

    /// [`Self::stage`] with the Coulomb torque f_c tanh(θ̇/ε) (smoothed) as a known joint torque on
    /// the friction-free model, exactly as `rss6_sim::ModelSim` integrates it. Not quadratic in
    /// χ̇: central differences of the forward dynamics with a small step there too.
    fn smoothed_stage(
        &self,
        p: &Vec6,
        v: &Vec6,
        tau: &Vec6,
        t: f64,
        frozen: Option<(Mat6, Mat6)>,
    ) -> Result<Stage> {
        let cfg = self.cfg;
        let env = cfg.environment();
        let g = &cfg.gravity;
        let eps = cfg.friction_smoothing;
        // θ̇ and the dynamics from one IK (bit for bit θ̇ = J_θ(χ)χ̇ then the forward dynamics).
        let fd = |pp: &Vec6, vv: &Vec6| {
            forward_dynamics_by_joint_rates(&cfg.kp, &self.dp_nc, pp, vv, &env, |theta_dot| {
                Vec6::from_fn(|i, _| tau[i] - self.dp.coulomb[i] * (theta_dot[i] / eps).tanh())
            })
            .map_err(|e| sim_err(t, e))
        };
        let a = fd(p, v)?;
        let Some(columns) = self.columns.as_deref() else {
            return Ok(Stage { a, jac: None });
        };
        let j_theta = jacobian_theta(&cfg.kp, p).map_err(|e| sim_err(t, e))?;
        let theta_dot = j_theta * v;
        // With the load: ∂χ̈/∂Ξ = −M̃_tot⁻¹ J_θᵀ Γ, the load's inertia in M̃_tot.
        let m = mass_matrix_with_env(&cfg.kp, &self.dp, p, &env).map_err(|e| sim_err(t, e))?;
        let chol = m.cholesky().ok_or_else(|| IdentError::Simulation {
            time: t,
            message: "the mass matrix is not positive definite".into(),
        })?;
        let ft = chol.solve(&j_theta.transpose());
        let (fp, fv) = match frozen {
            Some(j) => j,
            None => central_jacobians(fd, p, v, 1e-6)?,
        };
        let gamma = regressor_with_gravity(&cfg.kp, p, v, &a, g).map_err(|e| sim_err(t, e))?;
        let mut fxi = Sens::zeros(columns.len());
        for (c, &col) in columns.iter().enumerate() {
            if (COULOMB..COULOMB + LEGS).contains(&col) {
                // ∂χ̈/∂f_c,i = −M̃⁻¹J_θᵀ e_i tanh(θ̇_i/ε).
                let i = col - COULOMB;
                fxi.set_column(c, &(-(ft.column(i) * (theta_dot[i] / eps).tanh())));
            } else if col < N_DYN {
                fxi.set_column(c, &(-(ft * gamma.column(col))));
            }
        }
        Ok(Stage {
            a,
            jac: Some(Box::new(StageJac {
                fp,
                fv,
                ft,
                fxi,
                j_theta,
                d_rates: None,
            })),
        })
    }
}

/// The RK4 step of the sensitivities (s_χ, s_χ̇) in `s`, in place: the same
/// arithmetic, in the same order, as the step of the state (χ̈'s sensitivity at a stage is
/// fxi + F_χ s_χ + F_χ̇ s_χ̇ + F_τ s_τ; a stage without derivatives takes the first stage's
/// ([`StateJacobians::FirstStage`]), zero when that has none either).
pub(super) fn propagate(s: &mut SensState, stages: [&Stage; 4], s_tau: &Sens, dt: f64) {
    if let (Some(j), true) = (
        &stages[0].jac,
        stages[1..].iter().all(|st| st.jac.is_none()),
    ) {
        return propagate_constant(s, j, s_tau, dt);
    }
    let first = stages[0].jac.as_deref();
    let jacs = stages.map(|st| st.jac.as_deref().or(first));
    let sixth = dt / 6.0;
    // The columns are independent: each column's four stages in registers, one pass over the
    // column instead of five over the whole block per stage.
    for c in 0..s.p.ncols() {
        let sp0: Vec6 = s.p.column(c).into_owned();
        let sv0: Vec6 = s.v.column(c).into_owned();
        let tau: Vec6 = s_tau.column(c).into_owned();
        let stage_da = |j: Option<&StageJac>, sp: &Vec6, sv: &Vec6| -> Vec6 {
            match j {
                Some(j) => {
                    let mut d: Vec6 = j.fxi.column(c).into_owned();
                    d += j.fp * sp;
                    d += j.fv * sv;
                    d += j.ft * tau;
                    d
                }
                None => Vec6::zeros(),
            }
        };
        let mut da = stage_da(jacs[0], &sp0, &sv0);
        let (mut acc_p, mut acc_v) = (sv0, da);
        // Stages 2 and 3 at half a step along the previous stage's rates, stage 4 at a full step.
        let mut sv = sv0;
        for (k, (h, w)) in [(0.5 * dt, 2.0), (0.5 * dt, 2.0), (dt, 1.0)]
            .into_iter()
            .enumerate()
        {
            let sp = sp0 + sv * h;
            sv = sv0 + da * h;
            acc_p += sv * w;
            da = stage_da(jacs[k + 1], &sp, &sv);
            acc_v += da * w;
        }
        s.p.set_column(c, &(sp0 + acc_p * sixth));
        s.v.set_column(c, &(sv0 + acc_v * sixth));
    }
}

/// [`propagate`] when one stage's derivatives serve all four ([`StateJacobians::FirstStage`]): the
/// sensitivities then follow y' = Z y/h + [0; b] with constant A = Z/h = [[0, I], [F_χ, F_χ̇]] and
/// b = ∂χ̈/∂Ξ + F_τ s_τ, and the RK4 step is y₁ = R(Z) y₀ + h P(Z) [0; b] with
/// R(Z) = I + Z + Z²/2 + Z³/6 + Z⁴/24 and P(Z) = I + Z/2 + Z²/6 + Z³/24 (RK4's stages, summed).
/// The 12 × 12 matrices are formed once per tick; each column then costs one 12 × 12 and one
/// 12 × 6 product instead of four stages' passes (the same step, other rounding).
fn propagate_constant(s: &mut SensState, j: &StageJac, s_tau: &Sens, dt: f64) {
    type M12 = SMatrix<f64, 12, 12>;
    let mut z = M12::zeros();
    z.fixed_view_mut::<6, 6>(0, 6).fill_diagonal(dt);
    z.fixed_view_mut::<6, 6>(6, 0).copy_from(&(j.fp * dt));
    z.fixed_view_mut::<6, 6>(6, 6).copy_from(&(j.fv * dt));
    let z2 = z * z;
    let z3 = z2 * z;
    let r = M12::identity() + z + z2 * 0.5 + z3 / 6.0 + z3 * z / 24.0;
    let p = (M12::identity() + z * 0.5 + z2 / 6.0 + z3 / 24.0) * dt;
    let pb: SMatrix<f64, 12, 6> = p.fixed_columns::<6>(6).into_owned();
    for c in 0..s.p.ncols() {
        let b = j.fxi.column(c) + j.ft * s_tau.column(c);
        let mut y = SVector::<f64, 12>::zeros();
        y.fixed_rows_mut::<6>(0).copy_from(&s.p.column(c));
        y.fixed_rows_mut::<6>(6).copy_from(&s.v.column(c));
        let y1 = r * y + pb * b;
        s.p.column_mut(c).copy_from(&y1.fixed_rows::<6>(0));
        s.v.column_mut(c).copy_from(&y1.fixed_rows::<6>(6));
    }
}

#[cfg(test)]
mod tests {
    use super::{propagate, SensState, Stage, StageJac};
    use crate::cloe::friction::Sens;
    use rss6_core::{Mat6, Vec6};

    #[test]
    fn one_stages_derivatives_for_all_four_give_the_stage_by_stage_step() {
        // Deterministic, well-scaled values like a tick's (F_χ ~ 10², F_χ̇ ~ 10, h = 1 ms).
        let f = |k: usize, scale: f64| ((k as f64 * 0.7361).sin() + 0.1) * scale;
        let jac = || StageJac {
            fp: Mat6::from_fn(|r, c| f(r * 6 + c, 300.0)),
            fv: Mat6::from_fn(|r, c| f(r * 7 + c + 40, 20.0)),
            ft: Mat6::from_fn(|r, c| f(r * 5 + c + 90, 3.0)),
            fxi: Sens::from_fn(9, |r, c| f(r * 9 + c + 130, 5.0)),
            j_theta: Mat6::identity(),
            d_rates: None,
        };
        let stage = |with: bool| Stage {
            a: Vec6::zeros(),
            jac: with.then(|| Box::new(jac())),
        };
        let s_tau = Sens::from_fn(9, |r, c| f(r * 11 + c + 200, 0.5));
        let state = || {
            let mut s = SensState::zeros((0..9).collect(), Vec6::repeat(1.0));
            s.p = Sens::from_fn(9, |r, c| f(r * 3 + c + 300, 1e-3));
            s.v = Sens::from_fn(9, |r, c| f(r * 13 + c + 400, 1e-2));
            s
        };
        let (first, same) = (stage(true), stage(true));
        let none = stage(false);
        let (mut each, mut constant) = (state(), state());
        propagate(&mut each, [&first, &same, &same, &same], &s_tau, 1e-3);
        propagate(&mut constant, [&first, &none, &none, &none], &s_tau, 1e-3);
        let start = state();
        let moved = (&each.v - &start.v).amax();
        let dp = (&constant.p - &each.p).amax() / each.p.amax();
        let dv = (&constant.v - &each.v).amax() / moved;
        println!("relative differences: s_χ {dp:.1e}, s_χ̇'s step {dv:.1e}");
        assert!(moved > 1e-4, "the step moved s_χ̇ by {moved:e}");
        // Rounding only (measured 3.9·10⁻¹⁶ and 5.6·10⁻¹⁶; bounds ≈ 3×).
        assert!(dp < 1.5e-15 && dv < 2e-15, "{dp:e} {dv:e}");
    }
}
