//! The simulated closed loop of Fig. 5.1 as a function of the identification vector A (eq. 5.6), and
//! its forward sensitivities ∂χ_s/∂A.
//!
//! This is a lean copy of what `rss6_exp::ident::run` does on the model twin `rss6_sim::ModelSim`
//! (the same tick order, the same frame clock, the same held commands, the same arithmetic), kept
//! here because the sensitivities need the loop's internal state. `tests/cloe_loop.rs` checks that
//! both give the same χ_s. Per 1 kHz tick:
//!
//! 1. if a camera frame is pending, the visual PID (eq. 5.4) turns it and its backward-difference
//!    rate into U_θ, held until the next frame (sample-and-hold at the camera rate);
//! 2. the drive's PID (eq. 5.5) tracks U_θ on the held potentiometer angle (sampled every
//!    `pot_period`, drive convention), torques clamped at ±`torque_limit`;
//! 3. one RK4 step of the forward dynamics (eq. 6.1–6.4) with the torques held;
//! 4. the potentiometers and the camera clock advance (capture every `camera_period`, delivered
//!    `camera_latency` later).
//!
//! # Sensitivities
//!
//! Every state of the loop carries its derivative with respect to the active columns of A: the
//! model state (χ, χ̇), the held potentiometer angle, the drive PID's integral and previous error,
//! the held command, the visual PID's integral and last frame, and the frames waiting in the camera
//! queue. The recursion is the exact derivative of the discrete loop (RK4 included), so it matches
//! central differences of [`simulate`] up to their own error. At each RK4 stage
//!
//! ```text
//! dχ̈ = F_χ dχ + F_χ̇ dχ̇ + M̃⁻¹J_θᵀ dτ − M̃⁻¹J_θᵀ Γ(χ, χ̇, χ̈) dΞ
//! ```
//!
//! (the dynamics are linear in Ξ: τ_a = Γ Ξ, eq. 5.1). With the sign or the implicit friction law
//! one core call per stage gives all of it ([`rss6_core::forward_dynamics_jacobians_with_env`]:
//! F_χ, F_χ̇ from central differences of the inverse dynamics with the Coulomb signs held, exact in
//! χ̇, step 10⁻⁶ in χ; see `stages.rs`). With smoothed friction (`friction_smoothing` = ε > 0) the
//! Coulomb torque f_c tanh(θ̇/ε) is part of central differences of the forward dynamics, the χ̇
//! step 10⁻⁶ too. The state Jacobians are the dominant cost (`examples/cloe_cost.rs`); analytic
//! derivatives of the leg kinematics and the Newton–Euler pass in rss6-core
//! would remove it. Sign changes of θ̇ inside a step and torque saturation are treated as the
//! discrete loop treats them: the derivative of sign is 0, of a saturated torque 0.

use crate::error::{IdentError, Result};
use nalgebra::DMatrix;
use rss6_core::{ik, jacobian_theta, DynamicParams, ForwardJacobians, Mat6, Vec6, LEGS};
use rss6_ctrl::{PidGains, Trajectory};
use std::cell::RefCell;
use std::collections::VecDeque;
use std::sync::Arc;

use super::config::{LoopConfig, LoopParams, LoopRun, StateJacobians, N_A};
use super::friction::{self, sim_err, Sens, StepSens};
use super::sens_state::{drive_pid_sensitivity, mul_add, SensState};

mod ahead;
mod recording;
mod stages;
use ahead::{Ahead, StateJac};
pub use recording::Recording;
use recording::{FrictionModel, Recorder};
use stages::{Stage, StageModel};

/// Simulates the loop of `cfg` with parameters `a` following `reference` (sampled from t = 0).
/// `columns`: indices into A (0..67) whose sensitivities to propagate, or `None` for none.
///
/// Errors: [`IdentError::Simulation`] when the model leaves its workspace, a stage is singular or a
/// command is not finite (with the time); [`IdentError::InvalidInput`] for bad configurations or
/// column indices.
pub fn simulate<T: Trajectory + ?Sized>(
    cfg: &LoopConfig,
    a: &LoopParams,
    reference: &T,
    columns: Option<&[usize]>,
) -> Result<LoopRun> {
    simulate_recorded(cfg, a, reference, columns, None, false).map(|(run, _)| run)
}

/// [`simulate`] without sensitivities that also records its stage calls when the loop would
/// evaluate them ahead on several threads (`cfg.parallel_stages`, more than one rayon thread, not
/// called from a rayon worker; otherwise `None`). CLOE records its trial runs so: the trial it
/// accepts serves the next sensitivity run, which then needs no primal run of its own.
///
/// Errors: as [`simulate`].
pub fn simulate_recording<T: Trajectory + ?Sized>(
    cfg: &LoopConfig,
    a: &LoopParams,
    reference: &T,
) -> Result<(LoopRun, Option<Recording>)> {
    simulate_recorded(cfg, a, reference, None, None, true)
}

/// [`simulate`] with sensitivities of `columns`, its stages' derivatives evaluated ahead from
/// `recording` (of [`simulate_recording`] with the same configuration but for
/// `state_jacobians`, the same parameters and reference; a call that differs is evaluated in
/// turn), or, with `None`, as [`simulate`] does. The result is bit for bit [`simulate`]'s.
///
/// Errors: as [`simulate`].
pub fn simulate_from<T: Trajectory + ?Sized>(
    cfg: &LoopConfig,
    a: &LoopParams,
    reference: &T,
    columns: &[usize],
    recording: Option<Recording>,
) -> Result<LoopRun> {
    simulate_recorded(cfg, a, reference, Some(columns), recording, false).map(|(run, _)| run)
}

/// [`simulate`], with the stages' derivatives evaluated ahead on all rayon threads when
/// `cfg.parallel_stages` allows it (not from inside a rayon worker: its pool may be busy with other
/// loops waiting on their own producers, which would then wait on each other). Without columns it
/// also returns the run's stage calls if `record`; with columns it takes them from `recording`
/// (which must come from the same configuration, parameters and reference: a call that differs is
/// evaluated in turn) or records them with a primal run first.
pub(crate) fn simulate_recorded<T: Trajectory + ?Sized>(
    cfg: &LoopConfig,
    a: &LoopParams,
    reference: &T,
    columns: Option<&[usize]>,
    recording: Option<Recording>,
    record: bool,
) -> Result<(LoopRun, Option<Recording>)> {
    cfg.validate()?;
    if let Some(c) = columns {
        if let Some(bad) = c.iter().find(|&&j| j >= N_A) {
            return Err(IdentError::InvalidInput(format!(
                "column {bad} is not an index into A (0..{N_A})"
            )));
        }
    }
    let cols = columns.map(<[usize]>::to_vec);
    let parallel = cfg.parallel_stages
        && rayon::current_thread_index().is_none()
        && rayon::current_num_threads() > 1;
    let primal = |record: bool| -> Result<(LoopRun, Option<Recording>)> {
        let mut sim = Lean::new(cfg, a, None)?;
        sim.record = record.then(|| RefCell::new(Recorder::for_run(cfg)));
        let run = sim.run(reference)?;
        let rec = sim.record.map(|r| {
            let r = r.into_inner();
            Recording {
                calls: r.calls.into(),
                known: r.known.into(),
                friction: r.friction.into(),
                model: FrictionModel::of(cfg, &a.dynamics),
            }
        });
        Ok((run, rec))
    };
    if !parallel {
        return Ok((Lean::new(cfg, a, cols)?.run(reference)?, None));
    }
    if cols.is_none() {
        return primal(record);
    }
    // If the primal run fails, the sensitivity run fails the same way in turn.
    let Some(Recording {
        calls,
        known,
        friction,
        model,
    }) = recording.or_else(|| primal(true).ok().and_then(|(_, r)| r))
    else {
        return Ok((Lean::new(cfg, a, cols)?.run(reference)?, None));
    };
    // The friction steps, angles and accelerations serve only the model they were computed with.
    let (friction, known) = if model == FrictionModel::of(cfg, &a.dynamics) {
        (friction, known)
    } else {
        (Arc::from([]), Arc::from([]))
    };
    let helper = StageModel::new(cfg, &a.dynamics, cols.clone());
    let shared = ahead::Shared::new(calls, known);
    let mut sim = Lean::new(cfg, a, cols)?;
    sim.ahead = Some(RefCell::new(Ahead::new(Arc::clone(&shared), friction)));
    // One helper per further core: the loop's own thread evaluates chunks too while it waits.
    let helpers = rayon::current_num_threads().saturating_sub(1).max(1);
    std::thread::scope(|scope| {
        for _ in 0..helpers {
            scope.spawn(|| ahead::help(&helper, &shared));
        }
        let out = sim.run(reference);
        // Stops the helpers at their next chunk (`Ahead`'s drop; on unwinding too).
        drop(sim);
        out.map(|run| (run, None))
    })
}

/// The loop's state (and its sensitivities when `sens` is set).
struct Lean<'a> {
    cfg: &'a LoopConfig,
    dp: DynamicParams,
    /// What a stage needs (parameters, active columns), shared with the threads of `ahead`.
    model: StageModel<'a>,
    pid: PidGains,
    pot_ticks: u64,
    // Model state.
    pose: Vec6,
    pose_dot: Vec6,
    theta_meas: Vec6,
    // Drive PID.
    integral: [f64; LEGS],
    prev_error: [f64; LEGS],
    prev_derivative: [f64; LEGS],
    primed: bool,
    // Visual PID.
    bias: Vec6,
    v_integral: Vec6,
    command: Vec6,
    last_frame: Option<(f64, Vec6)>,
    // Camera.
    next_capture: f64,
    pending: VecDeque<(f64, Vec6, Option<Sens>)>,
    sens: Option<SensState>,
    /// The stage's derivatives, written in place (≈ 4 KB: not moved per stage).
    scratch: RefCell<ForwardJacobians>,
    /// The primal run: every stage call and friction step, in order.
    record: Option<RefCell<Recorder>>,
    /// The sensitivity run: stages evaluated ahead in parallel.
    ahead: Option<RefCell<Ahead>>,
}

const EPS_CLOCK: f64 = 1e-9;

impl<'a> Lean<'a> {
    fn new(cfg: &'a LoopConfig, a: &LoopParams, columns: Option<Vec<usize>>) -> Result<Self> {
        let theta = ik(&cfg.kp, &cfg.start)?;
        cfg.check_friction_stiffness(&a.dynamics)?;
        let pot_ticks = (cfg.pot_period / cfg.dt).round().max(1.0) as u64;
        let theta_meas = cfg.pot_angle(&theta, 0.0) + cfg.dither(0, 0.0)?;
        let pot_scale = Vec6::from_fn(|i, _| cfg.drive.eta[i] / cfg.kp.eta[i]);
        // The visual PID starts from the drive-convention angle of the first reading.
        let bias = theta_meas;
        let s = Lean {
            cfg,
            dp: a.dynamics,
            model: StageModel::new(cfg, &a.dynamics, columns.clone()),
            pid: a.pid,
            pot_ticks,
            pose: cfg.start,
            pose_dot: Vec6::zeros(),
            theta_meas,
            integral: [0.0; LEGS],
            prev_error: [0.0; LEGS],
            prev_derivative: [0.0; LEGS],
            primed: false,
            bias,
            v_integral: Vec6::zeros(),
            command: bias,
            last_frame: None,
            next_capture: 0.0,
            pending: VecDeque::new(),
            sens: columns.map(|c| SensState::zeros(c, pot_scale)),
            scratch: Default::default(),
            record: None,
            ahead: None,
        };
        // Nothing is captured yet: the frame of t = 0 is taken by the first `camera_tick(0.0)`.
        Ok(s)
    }

    fn time(&self, tick: u64) -> f64 {
        tick as f64 * self.cfg.dt
    }

    /// Advances the camera clock to `time`: captures, then returns the latest delivered frame.
    fn camera_tick(&mut self, time: f64) -> Option<(Vec6, Option<Sens>)> {
        if time + EPS_CLOCK >= self.next_capture {
            let s = self.sens.as_ref().map(|s| s.p.clone());
            self.pending
                .push_back((self.next_capture + self.cfg.camera_latency, self.pose, s));
            self.next_capture += self.cfg.camera_period;
        }
        let mut out = None;
        while let Some((t_avail, _, _)) = self.pending.front() {
            if *t_avail <= time + EPS_CLOCK {
                out = self.pending.pop_front().map(|(_, m, s)| (m, s));
            } else {
                break;
            }
        }
        out
    }

    fn run<T: Trajectory + ?Sized>(&mut self, reference: &T) -> Result<LoopRun> {
        let cfg = self.cfg;
        let ticks = (cfg.duration / cfg.dt).round() as u64;
        let mut out = LoopRun {
            t: Vec::new(),
            chi: Vec::new(),
            jacobian: None,
            columns: self
                .sens
                .as_ref()
                .map(|s| s.columns.clone())
                .unwrap_or_default(),
            saturated: 0,
            inexact_friction: 0,
            stuck_joint_ticks: 0,
            stages_ahead: 0,
            friction_ahead: 0,
            pot_angles: if cfg.record_pot_angles {
                vec![self.theta_meas - cfg.dither(0, 0.0)?]
            } else {
                Vec::new()
            },
        };
        let mut jac_rows: Vec<Sens> = Vec::new();
        let mut frame = self.camera_tick(0.0);
        // IK(χ) of the current pose when the last tick computed it (the potentiometers' ticks).
        let mut theta_at_pose: Option<Vec6> = None;
        for tick in 0..ticks {
            let t = self.time(tick);
            if let Some((chi, s_chi)) = frame.take() {
                match cfg.recorded_commands.as_deref() {
                    // The robot's own commands (their sensitivity stays 0).
                    Some(rec) => {
                        self.command = *rec.get(out.t.len()).ok_or_else(|| {
                            IdentError::InvalidInput(format!(
                                "the recorded commands end at frame {} (t = {t:.4} s)",
                                rec.len()
                            ))
                        })?;
                    }
                    None => self.visual_pid(t, reference, &chi, s_chi.as_ref())?,
                }
                out.t.push(t);
                out.chi.push(chi);
                if let Some(s) = s_chi {
                    jac_rows.push(s);
                }
            }
            let tau_sens = self.drive_pid();
            out.saturated += tau_sens
                .0
                .iter()
                .filter(|t| t.abs() >= cfg.torque_limit)
                .count();
            let ik_now = theta_at_pose.take();
            if cfg.implicit_friction && self.sens.is_none() {
                // A primal run (recording or not): core's one-call tick, whose first stage reuses
                // the friction step's dynamics (bit for bit the branch below; see `lean_tick`).
                self.lean_tick(&tau_sens.0, t, ik_now.as_ref(), &mut out)?;
            } else if cfg.implicit_friction {
                let (p0, v0) = (self.pose, self.pose_dot);
                // The recorded run's friction step at this state and torque, else solved.
                let recorded = self.ahead.as_ref().and_then(|a| {
                    a.borrow_mut()
                        .take_friction(&p0, &v0, &tau_sens.0)
                        .map(|f| friction::Step::new(&tau_sens.0, f))
                });
                let st = match recorded {
                    Some(st) => st,
                    None => friction::solve(cfg, &self.dp, &p0, &v0, &tau_sens.0, t)?,
                };
                out.count_friction(st.exact, st.stuck);
                // The first stage at (χ, χ̇, τ_a − τ_f) serves the friction's sensitivity too.
                let s1 = self.stage(&p0, &v0, &st.net, t, (true, StateJac::Compute), true)?;
                let s_net = self.friction_sensitivity(&st, &tau_sens.1, &s1, t)?;
                self.rk4(&(st.net, s_net), t, Some(s1))?;
            } else {
                self.rk4(&tau_sens, t, None)?;
            }
            let tick_new = tick + 1;
            if tick_new % self.pot_ticks == 0 {
                let theta = ik(&cfg.kp, &self.pose).map_err(|e| sim_err(t + cfg.dt, e))?;
                theta_at_pose = Some(theta);
                // The last reading of the run is never used: no dither row is needed for it.
                self.theta_meas = cfg.pot_angle(&theta, t + cfg.dt);
                if cfg.record_pot_angles {
                    out.pot_angles.push(self.theta_meas);
                }
                if tick_new < ticks {
                    self.theta_meas += cfg.dither(tick_new, t + cfg.dt)?;
                }
                if let Some(s) = self.sens.as_mut() {
                    let j =
                        jacobian_theta(&cfg.kp, &self.pose).map_err(|e| sim_err(t + cfg.dt, e))?;
                    let mut m = Sens::zeros(s.columns.len());
                    mul_add(&mut m, &j, &s.p);
                    for (i, mut row) in m.row_iter_mut().enumerate() {
                        row *= s.pot_scale[i];
                    }
                    s.theta_meas = m;
                }
            }
            frame = self.camera_tick(self.time(tick_new));
        }
        if self.sens.is_some() {
            let p = out.columns.len();
            let mut j = DMatrix::zeros(6 * jac_rows.len(), p);
            for (k, s) in jac_rows.iter().enumerate() {
                j.view_mut((6 * k, 0), (6, p)).copy_from(s);
            }
            out.jacobian = Some(j);
        }
        if let Some(ahead) = &self.ahead {
            out.stages_ahead = ahead.borrow().taken;
            out.friction_ahead = ahead.borrow().friction_taken;
        }
        Ok(out)
    }

    /// Eq. 5.4 at a frame: U_θ = θ_bias + J_θ(χ)[k_p e + k_d ė + k_i ∫e], exactly as
    /// `rss6_ctrl::VisualPid::step` computes it.
    fn visual_pid<T: Trajectory + ?Sized>(
        &mut self,
        t: f64,
        reference: &T,
        chi: &Vec6,
        s_chi: Option<&Sens>,
    ) -> Result<()> {
        let cfg = self.cfg;
        let r = reference.sample(t);
        let (rate, h, prev_t) = match self.last_frame {
            Some((tp, prev)) if t > tp => ((chi - prev) / (t - tp), t - tp, Some(tp)),
            _ => (Vec6::zeros(), cfg.dt, None),
        };
        let j = jacobian_theta(&cfg.kp, chi).map_err(|e| sim_err(t, e))?;
        let g = &cfg.gains;
        let e = r.pose - chi;
        let e_dot = r.pose_dot - rate;
        let raw = self.v_integral + e * h;
        let mut integral = raw;
        for i in 0..6 {
            integral[i] = integral[i].clamp(-g.integral_limit[i], g.integral_limit[i]);
        }
        let u = g.kp.component_mul(&e) + g.kd.component_mul(&e_dot) + g.ki.component_mul(&integral);
        let theta_d = self.bias + j * u;
        if !theta_d.iter().all(|x| x.is_finite()) {
            return Err(IdentError::Simulation {
                time: t,
                message: "the visual PID's command is not finite".into(),
            });
        }
        if let (Some(s), Some(s_chi)) = (self.sens.as_mut(), s_chi) {
            let s_rate = match (&s.last_frame, prev_t) {
                (Some(prev), Some(tp)) => (s_chi - prev) / (t - tp),
                _ => Sens::zeros(s.columns.len()),
            };
            let mut s_int = &s.v_integral - s_chi * h;
            for i in 0..6 {
                if integral[i] != raw[i] {
                    s_int.row_mut(i).fill(0.0);
                }
            }
            let mut s_u = Sens::zeros(s.columns.len());
            for i in 0..6 {
                let row =
                    -s_chi.row(i) * g.kp[i] - s_rate.row(i) * g.kd[i] + s_int.row(i) * g.ki[i];
                s_u.set_row(i, &row);
            }
            // ∂(J_θ(χ) u)/∂χ by central differences of J_θ (30 Hz only: cheap).
            let mut dj = Mat6::zeros();
            let step = 1e-6;
            for k in 0..6 {
                let mut cp = *chi;
                let mut cm = *chi;
                cp[k] += step;
                cm[k] -= step;
                let jp = jacobian_theta(&cfg.kp, &cp).map_err(|e| sim_err(t, e))?;
                let jm = jacobian_theta(&cfg.kp, &cm).map_err(|e| sim_err(t, e))?;
                dj.set_column(k, &((jp - jm) * u / (cp[k] - cm[k])));
            }
            s.command = j * s_u + dj * s_chi;
            s.v_integral = s_int;
            s.last_frame = Some(s_chi.clone());
        }
        self.v_integral = integral;
        self.command = theta_d;
        self.last_frame = Some((t, *chi));
        Ok(())
    }

    /// Eq. 5.5 on the held potentiometer angle, exactly as `rss6_ctrl::JointPid::step` (with its
    /// derivative filter when `derivative_filter` > 0). Returns the torque and its sensitivity.
    fn drive_pid(&mut self) -> (Vec6, Option<Sens>) {
        let dt = self.cfg.dt;
        let lim = self.cfg.torque_limit;
        let t_f = self.cfg.derivative_filter;
        let gains = self.pid;
        let mut tau = Vec6::zeros();
        let mut unclamped = [false; LEGS];
        // (e, ∂D/∂l_d, I) of each joint for the sensitivities.
        let mut terms = [(0.0, 0.0, 0.0); LEGS];
        for i in 0..LEGS {
            let e = self.command[i] - self.theta_meas[i];
            let de = e - self.prev_error[i];
            // D_k = l_d Δe/dt, or (T_f D_{k−1} + l_d Δe)/(T_f + dt) filtered; 0 on the first tick.
            let d = match (self.primed, t_f > 0.0) {
                (false, _) => 0.0,
                (true, false) => gains.ld * (de / dt),
                (true, true) => (t_f * self.prev_derivative[i] + gains.ld * de) / (t_f + dt),
            };
            let integral = self.integral[i] + e * dt;
            let raw = gains.lp * e + gains.li * integral + d;
            let out = raw.clamp(-lim, lim);
            if raw == out {
                self.integral[i] = integral;
            }
            unclamped[i] = raw == out;
            let dd_dld = if t_f > 0.0 { de / (t_f + dt) } else { de / dt };
            terms[i] = (e, if self.primed { dd_dld } else { 0.0 }, integral);
            self.prev_error[i] = e;
            self.prev_derivative[i] = d;
            tau[i] = out;
        }
        let s_tau = self
            .sens
            .as_mut()
            .map(|s| drive_pid_sensitivity(s, gains, self.primed, dt, t_f, &unclamped, &terms));
        self.primed = true;
        (tau, s_tau)
    }

    /// The implicit friction of this tick under the drive torques (see [`super::friction`]).
    /// ∂(τ_a − τ_f)/∂A of the solved tick `st` (None without sensitivities), from the tick's
    /// first RK4 stage `s1`.
    fn friction_sensitivity(
        &self,
        st: &friction::Step,
        s_tau: &Option<Sens>,
        s1: &Stage,
        t: f64,
    ) -> Result<Option<Sens>> {
        let (Some(s), Some(s_tau), Some(jac)) = (&self.sens, s_tau, &s1.jac) else {
            return Ok(None);
        };
        let sens = StepSens {
            columns: &s.columns,
            p: &s.p,
            v: &s.v,
            tau: s_tau,
        };
        let d_rates = jac.d_rates.ok_or_else(|| IdentError::Simulation {
            time: t,
            message: "the first stage has no free-rate derivative".into(),
        })?;
        let first = friction::FirstStage {
            a: &s1.a,
            fp: &jac.fp,
            fv: &jac.fv,
            fxi: &jac.fxi,
            j_theta: &jac.j_theta,
            d_rates: &d_rates,
        };
        let (p, v) = (&self.pose, &self.pose_dot);
        friction::sensitivity(self.cfg, &self.dp, st, p, v, sens, first, t).map(Some)
    }

    /// Takes the state at the end of a tick (time `t_end`); a non-finite one ends the run.
    fn set_state(&mut self, pose: Vec6, pose_dot: Vec6, t_end: f64) -> Result<()> {
        self.pose = pose;
        self.pose_dot = pose_dot;
        if !(pose.iter().chain(pose_dot.iter())).all(|x| x.is_finite()) {
            return Err(IdentError::Simulation {
                time: t_end,
                message: "non-finite model state".into(),
            });
        }
        Ok(())
    }

    /// One RK4 step with the torques held (the same arithmetic as `rss6_core::rk4_step_with_gravity`).
    /// `first`: the first stage if already evaluated at the current state with `tau`.
    fn rk4(&mut self, tau: &(Vec6, Option<Sens>), t: f64, first: Option<Stage>) -> Result<()> {
        let dt = self.cfg.dt;
        let (tau, s_tau) = tau;
        let (p0, v0) = (self.pose, self.pose_dot);
        let s1 = match first {
            Some(s) => s,
            None => self.stage(&p0, &v0, tau, t, (true, StateJac::Compute), false)?,
        };
        // PerTick: the state Jacobians of stage 1 serve all four stages.
        let frozen = match self.cfg.state_jacobians {
            StateJacobians::PerTick | StateJacobians::FirstStage => {
                StateJac::Frozen(s1.jac.as_deref().map(|j| (j.fp, j.fv)))
            }
            StateJacobians::Exact => StateJac::Compute,
        };
        let a1 = s1.a;
        let (p2, v2) = (p0 + v0 * (0.5 * dt), v0 + a1 * (0.5 * dt));
        let s2 = self.stage(&p2, &v2, tau, t, (false, frozen), false)?;
        let a2 = s2.a;
        let (p3, v3) = (p0 + v2 * (0.5 * dt), v0 + a2 * (0.5 * dt));
        let s3 = self.stage(&p3, &v3, tau, t, (false, frozen), false)?;
        let a3 = s3.a;
        let (p4, v4) = (p0 + v3 * dt, v0 + a3 * dt);
        let s4 = self.stage(&p4, &v4, tau, t, (false, frozen), false)?;
        let a4 = s4.a;
        let pose = p0 + (v0 + v2 * 2.0 + v3 * 2.0 + v4) * (dt / 6.0);
        let pose_dot = v0 + (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (dt / 6.0);
        self.set_state(pose, pose_dot, t + dt)?;
        if let (Some(s), Some(s_tau)) = (self.sens.as_mut(), s_tau) {
            stages::propagate(s, [&s1, &s2, &s3, &s4], s_tau, dt);
        }
        Ok(())
    }
}
