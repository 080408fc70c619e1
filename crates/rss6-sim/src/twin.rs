//! The model twin: the same call shape as the plant, driven by the analytic model of rss6-core
//! (forward dynamics eq. 6.1–6.4 integrated by RK4 in χ coordinates) with the same PID, drive train
//! and sensors: the "simulated model" of the thesis's Fig. 5.1.
//!
//! Joint angles are θ = IK(χ) and rates θ̇ = J_θ χ̇ (eq. 5.3). Effects the model can express act on it
//! too (gravity direction, friction, backlash, camera latency, and a payload: Ξ has no place for it,
//! so it enters the dynamics as a [`rss6_core::PlatformLoad`] — its mass, its centre-of-mass offset
//! in ΣE (the offset's gravity moment and inertial forces) and its inertia, through
//! [`rss6_core::rk4_step_with_env`] with [`EffectSetup::environment`]).

use crate::effects::EffectSetup;
use crate::error::Result;
use crate::sim::{total_friction, Physics, Robot, SimConfig};
use rss6_core::{
    forward_dynamics_by_joint_rates_from, ik, jacobian_theta, rk4_step_by,
    rk4_step_implicit_friction, rk4_step_with_env, DynamicParams, Environment, KinematicParams,
    LegGeometry, ModelState, Vec6, LEGS,
};

/// Analytic-model physics.
#[derive(Debug, Clone)]
pub struct ModelPhysics {
    kp: KinematicParams,
    dp: DynamicParams,
    /// ε of the smoothed Coulomb friction (rad/s); 0 = sign.
    smoothing: f64,
    /// Stick–slip friction stepped implicitly per tick ([`rss6_core::implicit_friction`]).
    implicit: bool,
    /// Gravity and the payload (a load fixed to the platform).
    env: Environment,
    dt: f64,
    state: ModelState,
    theta: Vec6,
    /// `theta` is IK(χ) of the current pose (set by a step; `place` takes its angles on trust).
    theta_is_ik: bool,
    /// θ̇ = J_θ(χ) χ̇ of the current state (NaN where J_θ fails), computed once per state: the
    /// experiment loop reads it twice a tick.
    theta_dot: Vec6,
    /// Implicit friction solves that hit their sweep bound.
    inexact: u64,
}

impl ModelPhysics {
    /// The model for `cfg` with effect hooks `setup`.
    pub fn new(cfg: &SimConfig, setup: &EffectSetup) -> Self {
        let mut dp = cfg.dynamics;
        let (fc, fv) = total_friction(&cfg.dynamics, setup);
        dp.coulomb = fc;
        dp.viscous = fv;
        ModelPhysics {
            kp: cfg.kinematics,
            dp,
            smoothing: cfg.friction_smoothing,
            implicit: cfg.implicit_friction,
            env: setup.environment(),
            dt: cfg.dt,
            state: ModelState {
                pose: rss6_core::home_pose(),
                pose_dot: Vec6::zeros(),
            },
            theta: Vec6::zeros(),
            theta_is_ik: false,
            theta_dot: Vec6::zeros(),
            inexact: 0,
        }
    }

    /// The model state (χ, χ̇).
    pub fn state(&self) -> ModelState {
        self.state
    }

    /// θ̇ = J_θ(χ) χ̇ (NaN where J_θ fails), J_θ from the angles of the last IK when known (the
    /// same geometry, without the IK).
    fn rates(&self) -> Vec6 {
        let (kp, pose) = (&self.kp, &self.state.pose);
        let j = if self.theta_is_ik {
            LegGeometry::from_pose_and_theta(kp, pose, &self.theta).j_theta()
        } else {
            jacobian_theta(kp, pose)
        };
        j.map(|j| j * self.state.pose_dot)
            .unwrap_or_else(|_| Vec6::from_element(f64::NAN))
    }
}

impl Physics for ModelPhysics {
    fn place(&mut self, pose: &Vec6, theta: &Vec6) -> Result<()> {
        self.state = ModelState {
            pose: *pose,
            pose_dot: Vec6::zeros(),
        };
        self.theta = *theta;
        self.theta_is_ik = false;
        self.theta_dot = self.rates();
        Ok(())
    }

    fn advance(&mut self, tau: &Vec6) -> Result<()> {
        self.state = if self.implicit {
            // Stick–slip friction stepped implicitly and held over the tick (the plant's law
            // with `implicit_friction`), then the friction-free model with τ − τ_f: one core call
            // that shares the first stage with the friction step, from the angles of the last IK.
            let (kp, env) = (&self.kp, &self.env);
            let theta = self.theta_is_ik.then_some(&self.theta);
            let (next, f) =
                rk4_step_implicit_friction(kp, &self.dp, &self.state, tau, self.dt, env, theta)?;
            self.inexact += u64::from(!f.exact);
            next
        } else if self.smoothing > 0.0 {
            // f_c tanh(θ̇/ε) at every stage: the Coulomb part as a known joint torque on the
            // friction-free model (the same arithmetic as rss6-ident's CLOE loop).
            let mut dp_nc = self.dp;
            dp_nc.coulomb = [0.0; LEGS];
            let (kp, dp, env, eps) = (&self.kp, &self.dp, &self.env, self.smoothing);
            // One IK a stage: θ̇ and the dynamics from the same geometry; the first stage (at
            // the tick's pose) from the angles of the last IK when known, so none there.
            let mut known = self.theta_is_ik.then_some(self.theta);
            rk4_step_by(&self.state, self.dt, |p, v| {
                let theta = known.take();
                forward_dynamics_by_joint_rates_from(kp, &dp_nc, p, v, env, theta.as_ref(), |td| {
                    Vec6::from_fn(|i, _| tau[i] - dp.coulomb[i] * (td[i] / eps).tanh())
                })
            })?
        } else {
            rk4_step_with_env(&self.kp, &self.dp, &self.state, tau, self.dt, &self.env)?
        };
        self.theta_is_ik = false;
        match ik(&self.kp, &self.state.pose) {
            Ok(theta) => {
                self.theta = theta;
                self.theta_is_ik = true;
                self.theta_dot = self.rates();
                Ok(())
            }
            Err(e) => {
                // J_θ fails where the IK does.
                self.theta_dot = Vec6::from_element(f64::NAN);
                Err(e.into())
            }
        }
    }

    fn pose(&self) -> Vec6 {
        self.state.pose
    }

    fn theta(&self) -> Vec6 {
        self.theta
    }

    fn theta_dot(&self) -> Vec6 {
        self.theta_dot
    }

    fn loop_closure_error(&self) -> f64 {
        0.0
    }

    fn inexact_friction_steps(&self) -> u64 {
        self.inexact
    }
}

/// The analytic-model twin of the plant.
pub type ModelSim = Robot<ModelPhysics>;

impl Robot<ModelPhysics> {
    /// Builds the twin from a full configuration, placed at the home pose.
    pub fn new(cfg: SimConfig) -> Result<Self> {
        let (effects, setup) = Self::prepare(&cfg)?;
        let physics = ModelPhysics::new(&cfg, &setup);
        Self::assemble(cfg, effects, setup, physics)
    }

    /// The model state (χ, χ̇).
    pub fn model_state(&self) -> ModelState {
        self.physics.state()
    }
}
