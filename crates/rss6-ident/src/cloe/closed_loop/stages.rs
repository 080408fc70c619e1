//! One RK4 stage of the loop's model with its derivatives (see the parent module's docs).

use super::super::config::LoopConfig;
use super::super::friction::{central_jacobians, sim_err, Sens, COULOMB};
use crate::error::{IdentError, Result};
use rss6_core::{
    forward_dynamics_jacobians_with_env, forward_dynamics_with_env, jacobian_theta,
    mass_matrix_with_env, regressor_with_gravity, DynamicParams, ForwardJacobians, JacobianRequest,
    Mat6, Vec6, LEGS, N_DYN,
};

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
}

/// One RK4 stage's acceleration and (optionally) its derivatives.
pub(super) struct Stage {
    pub(super) a: Vec6,
    pub(super) jac: Option<StageJac>,
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
        StageModel {
            cfg,
            dp: *dp,
            dp_nc,
            dp_nf,
            columns,
        }
    }

    /// One stage of the forward dynamics, with derivatives if sensitivities are on. With the
    /// implicit law `tau` is τ_a − τ_f and the model is friction-free. `frozen`: state Jacobians
    /// to use instead of computing them; `free_rates`: also the pose derivative of the joint
    /// rates one tick ahead (the implicit friction's first stage, see [`super::friction`]).
    /// `fj`: scratch space for the core call (≈ 4 KB, one per thread).
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
        let Some(columns) = self.columns.as_deref() else {
            let a = forward_dynamics_with_env(&cfg.kp, dp, p, v, tau, &env)
                .map_err(|e| sim_err(t, e))?;
            return Ok(Stage { a, jac: None });
        };
        let request = JacobianRequest {
            state: frozen.is_none(),
            rate_step: free_rates.then_some(cfg.dt),
            ..JacobianRequest::default()
        };
        forward_dynamics_jacobians_with_env(&cfg.kp, dp, p, v, tau, &env, &request, fj)
            .map_err(|e| sim_err(t, e))?;
        let (fp, fv) = match (frozen, fj.d_state) {
            (Some(j), _) | (None, Some(j)) => j,
            (None, None) => unreachable_state(t)?,
        };
        let mut fxi = Sens::zeros(columns.len());
        for (c, &col) in columns.iter().enumerate() {
            // With the implicit law friction acts through τ_f (its sensitivity is in the held
            // torque's).
            if col < N_DYN && !(implicit && col >= COULOMB) {
                fxi.set_column(c, &fj.d_params.column(col));
            }
        }
        Ok(Stage {
            a: fj.pose_ddot,
            jac: Some(StageJac {
                fp,
                fv,
                ft: fj.d_torque,
                fxi,
                j_theta: fj.j_theta,
                d_rates: fj.d_rates,
            }),
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
        let smooth_tau = |pp: &Vec6, vv: &Vec6| -> Result<Vec6> {
            let theta_dot = jacobian_theta(&cfg.kp, pp).map_err(|e| sim_err(t, e))? * vv;
            Ok(Vec6::from_fn(|i, _| {
                tau[i] - self.dp.coulomb[i] * (theta_dot[i] / eps).tanh()
            }))
        };
        let fd = |pp: &Vec6, vv: &Vec6| {
            forward_dynamics_with_env(&cfg.kp, &self.dp_nc, pp, vv, &smooth_tau(pp, vv)?, &env)
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
            jac: Some(StageJac {
                fp,
                fv,
                ft,
                fxi,
                j_theta,
                d_rates: None,
            }),
        })
    }
}
