//! What defines a simulation of the identification loop besides the reference: its configuration
//! ([`LoopConfig`]), the identification vector A ([`LoopParams`], eq. 5.6) and what a run returns
//! ([`LoopRun`]).

use crate::error::{IdentError, Result};
use nalgebra::DMatrix;
use rss6_core::{
    jacobian_theta, mass_matrix_with_env, DynamicParams, Environment, KinematicParams, Mat6,
    PlatformLoad, Vec3, Vec6, GRAVITY, LEGS, N_DYN,
};
use rss6_ctrl::{CartesianPidGains, PidGains};

/// Largest λ·dt of the friction's linearisation M_θ⁻¹ diag(f_c/ε + f_v) that RK4 (stable on the
/// real axis up to 2.785) is allowed at the start pose: 2.0 leaves room for the drive's damping.
const MAX_FRICTION_STIFFNESS: f64 = 2.0;

/// Length of the identification vector A = [Ξ (64); l_p, l_i, l_d] (eq. 5.6).
pub const N_A: usize = N_DYN + 3;

/// Everything about the loop except A: the model's kinematics, the drive's convention, the outer
/// loop's gains and the timing. Mirrors `rss6_exp::IdentSpec` plus the twin's `SimConfig`.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopConfig {
    /// The model's (calibrated) kinematics: dynamics model, potentiometers and the visual PID's J_θ.
    pub kp: KinematicParams,
    /// The drive's joint convention (nominal η, Δθ).
    pub drive: KinematicParams,
    /// The outer visual PID's gains (thesis: k_p = 0.3, k_i = 2.4, k_d = 0.001).
    pub gains: CartesianPidGains,
    /// Joint-loop period (s), 1e-3.
    pub dt: f64,
    /// Drive torque limit (N·m).
    pub torque_limit: f64,
    /// Time constant T_f (s) of the drive's derivative filter (`JointPid::with_derivative_filter`);
    /// 0 = unfiltered (eq. 5.5 as printed).
    pub derivative_filter: f64,
    /// Velocity scale ε (rad/s) of the model's Coulomb friction f_c tanh(θ̇/ε); 0 = f_c sign(θ̇)
    /// (eq. 3.48 as printed).
    pub friction_smoothing: f64,
    /// Coulomb + viscous friction stepped implicitly per tick ([`rss6_core::implicit_friction`]:
    /// stick–slip, held over the tick; the law of the twin and the plant with
    /// `SimConfig::implicit_friction`). Exclusive with `friction_smoothing` > 0; stable for any
    /// friction, so the stiffness check does not apply.
    pub implicit_friction: bool,
    /// Potentiometer sampling period (s), 2e-3.
    pub pot_period: f64,
    /// Camera frame period (s), 0.033.
    pub camera_period: f64,
    /// Camera latency (s), 0 unless measured.
    pub camera_latency: f64,
    /// Gravity in the base frame (m/s²).
    pub gravity: Vec3,
    /// A load fixed to the platform (payload: mass, centre-of-mass offset in ΣE, inertia), outside Ξ.
    pub load: Option<PlatformLoad>,
    /// Drift rate of each potentiometer offset (rad/s): the reading of joint i uses Δθ_i + rate_i·t
    /// (t from the start of the run), as the `joint_offset_drift` effect of rss6-sim.
    pub offset_drift: Vec6,
    /// The pose the robot rests at when the run starts (m, rad).
    pub start: Vec6,
    /// Run length (s).
    pub duration: f64,
    /// Where the sensitivities evaluate the state Jacobians F_χ, F_χ̇.
    pub state_jacobians: StateJacobians,
    /// Use the other rayon threads (when there are any and the caller is not one of them): with
    /// sensitivities, a primal run records the stage calls (or CLOE passes the accepted trial's)
    /// and every RK4 stage's derivatives are evaluated in parallel blocks ahead of the sensitivity
    /// recursion; CLOE evaluates its trial step at 10λ beside the one at λ, used if that is
    /// rejected. Bit for bit the sequential results (docs/identification.md, "Forward
    /// sensitivities"). `false`: one thread, in turn.
    pub parallel_stages: bool,
    /// The robot's own joint commands U_θ (drive convention, rad), one per camera frame the visual
    /// PID consumed, in order: the simulated loop holds these instead of closing the outer loop on
    /// its own frames (`None`: the thesis's loop, eq. 5.4 on χ_s). With stick–slip friction the
    /// camera noise fed back through the visual PID moves the robot by more than the noise itself
    /// (docs/identification.md); with the recorded commands that motion is in the input.
    pub recorded_commands: Option<Vec<Vec6>>,
    /// Potentiometer noise to replay (drive convention, rad), one row per joint-loop tick: at each
    /// sampling tick k the simulated reading is the noise-free angle plus row k. The robot's drive
    /// reacts to its noisy potentiometers, and with stick–slip that dither breaks sticking joints
    /// free earlier than a clean replay does (docs/identification.md, "Replaying the
    /// potentiometer noise"). `None`: noise-free readings. Its sensitivity is 0 (data).
    pub pot_dither: Option<Vec<Vec6>>,
    /// Record [`LoopRun::pot_angles`] (default off: CLOE's trial and sensitivity runs never read it).
    pub record_pot_angles: bool,
}

/// Where the sensitivity recursion evaluates the state Jacobians F_χ, F_χ̇ of the forward dynamics
/// (and, for [`StateJacobians::FirstStage`], every other derivative of a stage).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StateJacobians {
    /// At every RK4 stage: the exact derivative of the discrete loop (24 forward-dynamics calls per
    /// stage).
    #[default]
    Exact,
    /// Once per tick, at the tick's start, for all four stages (4× fewer calls); an approximation
    /// of the derivative (error measured in `tests/cloe_loop.rs`), for LM iterations.
    PerTick,
    /// Every derivative of the tick's first stage — F_χ, F_χ̇, ∂χ̈/∂τ and ∂χ̈/∂Ξ — serves all four
    /// stages, which then need only their accelerations. Only with
    /// [`LoopConfig::implicit_friction`]: its tick integrates the friction-free model under a held
    /// torque, so the stages' derivatives differ little (≈ 10⁻³ relative error, as
    /// [`StateJacobians::PerTick`]); with the sign or smoothed law the joints' viscous friction
    /// makes the tick stiff, a stage's acceleration moves by tens of per cent within it, and so
    /// would the inertias' sensitivities (measured up to 0.8 relative): refused there.
    FirstStage,
}

impl LoopConfig {
    /// The thesis's loop on `kp` from rest at `start` for `duration` s: nominal drive convention,
    /// thesis outer gains, 1 kHz, 500 Hz potentiometers, 0.033 s frames without latency, 30 N·m,
    /// unfiltered derivative, sign Coulomb friction.
    pub fn new(kp: KinematicParams, start: Vec6, duration: f64) -> Self {
        LoopConfig {
            kp,
            drive: KinematicParams::nominal(),
            gains: CartesianPidGains::thesis(),
            dt: 1e-3,
            torque_limit: 30.0,
            derivative_filter: 0.0,
            friction_smoothing: 0.0,
            implicit_friction: false,
            pot_period: 2e-3,
            camera_period: 0.033,
            camera_latency: 0.0,
            gravity: GRAVITY,
            load: None,
            offset_drift: Vec6::zeros(),
            start,
            duration,
            state_jacobians: StateJacobians::Exact,
            parallel_stages: true,
            recorded_commands: None,
            pot_dither: None,
            record_pot_angles: false,
        }
    }

    pub(super) fn validate(&self) -> Result<()> {
        let pos = [
            ("dt", self.dt),
            ("torque_limit", self.torque_limit),
            ("pot_period", self.pot_period),
            ("camera_period", self.camera_period),
            ("duration", self.duration),
        ];
        for (name, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return Err(IdentError::InvalidInput(format!(
                    "{name} must be finite and > 0, got {v}"
                )));
            }
        }
        let non_negative = [
            ("camera_latency", self.camera_latency),
            ("derivative_filter", self.derivative_filter),
            ("friction_smoothing", self.friction_smoothing),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(IdentError::InvalidInput(format!(
                    "{name} must be finite and >= 0, got {v}"
                )));
            }
        }
        if self.implicit_friction && self.friction_smoothing > 0.0 {
            return Err(IdentError::InvalidInput(
                "implicit_friction and friction_smoothing > 0 are two friction laws: choose one"
                    .into(),
            ));
        }
        if self.state_jacobians == StateJacobians::FirstStage && !self.implicit_friction {
            return Err(IdentError::InvalidInput(
                "state_jacobians = FirstStage needs implicit_friction: with the sign or smoothed \
                 friction law a tick is too stiff for one stage's derivatives to serve all four"
                    .into(),
            ));
        }
        if let Some(rec) = &self.recorded_commands {
            if let Some(k) = rec.iter().position(|c| !c.iter().all(|x| x.is_finite())) {
                return Err(IdentError::InvalidInput(format!(
                    "recorded command {k} is not finite"
                )));
            }
        }
        if let Some(d) = &self.pot_dither {
            if let Some(k) = d.iter().position(|c| !c.iter().all(|x| x.is_finite())) {
                return Err(IdentError::InvalidInput(format!(
                    "potentiometer dither row {k} is not finite"
                )));
            }
        }
        if !self.offset_drift.iter().all(|v| v.is_finite()) {
            return Err(IdentError::InvalidInput(
                "offset drift rates must be finite".into(),
            ));
        }
        if !self.gravity.iter().all(|v| v.is_finite()) {
            return Err(IdentError::InvalidInput("gravity must be finite".into()));
        }
        if let Some(load) = &self.load {
            load.validate()?;
        }
        self.kp.validate()?;
        self.drive.validate()?;
        Ok(())
    }

    /// With smoothed friction, f_c tanh(θ̇/ε) acts like a viscous f_c/ε near θ̇ = 0; integrated
    /// explicitly at `dt` it must stay inside RK4's stability region, or the loop chatters and χ_s
    /// stops being a smooth function of A (measured: ε = 0.1 rad/s with Table 5.2's friction, λ·dt ≈ 3,
    /// leaves LM stuck). The check is at the start pose, where the run rests.
    pub(super) fn check_friction_stiffness(&self, dp: &DynamicParams) -> Result<()> {
        let cfg = self;
        if cfg.implicit_friction {
            return Ok(());
        }
        let eps = cfg.friction_smoothing;
        let m = mass_matrix_with_env(&cfg.kp, dp, &cfg.start, &cfg.environment())?;
        let j = jacobian_theta(&cfg.kp, &cfg.start)?;
        let Some(m_inv) = m.try_inverse() else {
            return Err(IdentError::InvalidInput(
                "the mass matrix at the start pose is singular".into(),
            ));
        };
        // M_θ⁻¹ = J_θ M̃⁻¹ J_θᵀ; the eigenvalues of M_θ⁻¹ D are those of D^½ M_θ⁻¹ D^½ (symmetric).
        let d = Vec6::from_fn(|i, _| {
            let c = if eps > 0.0 { dp.coulomb[i] / eps } else { 0.0 };
            (c + dp.viscous[i]).max(0.0).sqrt()
        });
        let s = Mat6::from_diagonal(&d) * (j * m_inv * j.transpose()) * Mat6::from_diagonal(&d);
        let s = (s + s.transpose()) * 0.5;
        let lambda = s.symmetric_eigenvalues().max();
        let stiff = lambda * cfg.dt;
        if stiff.is_nan() || stiff > MAX_FRICTION_STIFFNESS {
            let need = if eps > 0.0 {
                format!(
                    "; with this friction ε must be at least ≈ {:.3} rad/s",
                    eps * stiff / MAX_FRICTION_STIFFNESS
                )
            } else {
                String::new()
            };
            return Err(IdentError::InvalidInput(format!(
                "joint friction too stiff for dt = {} s: λ·dt = {stiff:.2} > {MAX_FRICTION_STIFFNESS} \
                 (friction smoothing ε = {eps} rad/s){need}",
                cfg.dt
            )));
        }
        Ok(())
    }

    /// The drive-convention angle of the noise-free potentiometer reading of θ at time `t` (s from
    /// the start; eq. 4.2 twice, with the drifting offset Δθ_i + rate_i·t of `offset_drift`).
    pub(super) fn pot_angle(&self, theta: &Vec6, t: f64) -> Vec6 {
        let (m, d) = (&self.kp, &self.drive);
        Vec6::from_fn(|i, _| {
            let kappa = (theta[i] - (m.dtheta[i] + self.offset_drift[i] * t)) / m.eta[i] + 0.0;
            d.eta[i] * kappa + d.dtheta[i]
        })
    }

    /// Row `tick` of [`pot_dither`](Self::pot_dither) (0 without one); a list that ends before
    /// the run does is an [`IdentError::InvalidInput`].
    pub(super) fn dither(&self, tick: u64, t: f64) -> Result<Vec6> {
        match &self.pot_dither {
            None => Ok(Vec6::zeros()),
            Some(d) => d.get(tick as usize).copied().ok_or_else(|| {
                IdentError::InvalidInput(format!(
                    "the potentiometer dither ends at tick {} (t = {t:.4} s)",
                    d.len()
                ))
            }),
        }
    }

    /// Gravity and the platform load as the dynamics take them.
    pub fn environment(&self) -> Environment {
        Environment {
            gravity: self.gravity,
            load: self.load,
        }
    }
}

/// The identification vector A (eq. 5.6): the dynamic parameters Ξ and the drive PID's gains.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopParams {
    /// Ξ: masses, inertias, friction.
    pub dynamics: DynamicParams,
    /// l_p, l_i, l_d of the drive's PID (eq. 5.5).
    pub pid: PidGains,
}

impl LoopParams {
    /// A as a 67-vector [Ξ; l_p, l_i, l_d].
    pub fn to_vector(&self) -> [f64; N_A] {
        let mut a = [0.0; N_A];
        a[..N_DYN].copy_from_slice(&self.dynamics.to_vector());
        a[N_DYN..].copy_from_slice(&self.pid.to_array());
        a
    }

    /// The inverse of [`Self::to_vector`].
    pub fn from_vector(a: &[f64; N_A]) -> Self {
        let mut xi = [0.0; N_DYN];
        xi.copy_from_slice(&a[..N_DYN]);
        LoopParams {
            dynamics: DynamicParams::from_vector(&xi),
            pid: PidGains {
                lp: a[N_DYN],
                li: a[N_DYN + 1],
                ld: a[N_DYN + 2],
            },
        }
    }
}

/// Names of the 67 entries of A, e.g. "platform.m", "wrench3.Iz", "link1.Ix", "fc2", "fv6", "lp".
pub fn parameter_names() -> Vec<String> {
    let mut names = Vec::with_capacity(N_A);
    let body = |names: &mut Vec<String>, b: &str| {
        for q in ["m", "Ix", "Iy", "Iz"] {
            names.push(format!("{b}.{q}"));
        }
    };
    body(&mut names, "platform");
    for i in 1..=LEGS {
        body(&mut names, &format!("wrench{i}"));
    }
    for i in 1..=LEGS {
        body(&mut names, &format!("link{i}"));
    }
    for i in 1..=LEGS {
        names.push(format!("fc{i}"));
    }
    for i in 1..=LEGS {
        names.push(format!("fv{i}"));
    }
    names.extend(["lp", "li", "ld"].map(String::from));
    names
}

/// What one simulation of the loop returns: the camera frames the visual PID consumed.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopRun {
    /// Time (s from the start) of the tick at which each frame was consumed.
    pub t: Vec<f64>,
    /// χ_s of each frame (m, rad): the model's pose at the frame's capture.
    pub chi: Vec<Vec6>,
    /// ∂χ_s/∂A of the requested columns: rows 6k..6k+6 belong to frame k; `None` without
    /// sensitivities.
    pub jacobian: Option<DMatrix<f64>>,
    /// The active columns of A the Jacobian's columns refer to.
    pub columns: Vec<usize>,
    /// Joint-ticks at which the drive's torque was clamped at ±`torque_limit` (the loop is not
    /// differentiable where the clamp switches).
    pub saturated: usize,
    /// Ticks whose implicit friction solve stopped at its sweep bound (not exact; 0 expected).
    pub inexact_friction: usize,
    /// Joint-ticks on which the implicit law held a joint stuck (0 for the other laws).
    pub stuck_joint_ticks: usize,
    /// RK4 stages whose derivatives were evaluated ahead in parallel
    /// ([`LoopConfig::parallel_stages`]; 0 when they were evaluated in turn).
    pub stages_ahead: usize,
    /// Ticks whose implicit friction step was taken from the recorded primal run (same state,
    /// torque, parameters and configuration) instead of solved again.
    pub friction_ahead: usize,
    /// The model's noise-free potentiometer angle (drive convention, rad) at each sampling tick —
    /// tick 0 and every `pot_period` after it — before any `pot_dither`: what a model-based
    /// estimate of the robot's potentiometer noise subtracts from the robot's readings. Empty
    /// unless [`LoopConfig::record_pot_angles`].
    pub pot_angles: Vec<Vec6>,
}

impl LoopRun {
    /// Counts one tick's implicit friction solve: inexact if it stopped at its sweep bound,
    /// `stuck` joints held.
    pub(crate) fn count_friction(&mut self, exact: bool, stuck: usize) {
        self.inexact_friction += usize::from(!exact);
        self.stuck_joint_ticks += stuck;
    }

    /// Index of the model frame at each time of `t` (within half a tick of `dt`), or an error
    /// naming the first time the model's loop has no frame at.
    pub(crate) fn frames_at(&self, t: &[f64], dt: f64) -> Result<Vec<usize>> {
        let mut idx = Vec::with_capacity(t.len());
        let mut s = 0usize;
        for &tk in t {
            while s < self.t.len() && self.t[s] < tk - 0.5 * dt {
                s += 1;
            }
            if s >= self.t.len() || (self.t[s] - tk).abs() > 0.5 * dt {
                return Err(IdentError::NoCameraFrames(format!(
                    "the model's loop has no frame at t = {tk:.4} s (camera timing differs?)"
                )));
            }
            idx.push(s);
        }
        Ok(idx)
    }
}
