//! The visual-servo loop of Fig. 6.2 as one allocation-free object, plus a plant-agnostic runner.
//!
//! [`Servo::tick`] is called at the joint rate (1 kHz). When a camera frame arrives it runs the Kalman
//! filter and the camera-rate controller (DSMC, KCSC or KJSC); every tick it produces a guarded joint
//! command: DSMC through the torque-to-position converter (with the latest potentiometer angles),
//! KCSC/KJSC by holding their latest θ_d. If no frame arrives for 1.5 camera periods the filter predicts
//! and the controller runs on the prediction; after `stale_after` seconds without a frame, or on any
//! NaN/∞ input, the servo latches a fault, returns [`CtrlError::Faulted`] and [`Servo::held_command`] is
//! the last command sent (the drive's PID then holds the robot there). A tick stamped before the
//! previous one latches [`FaultReason::TimeWentBackwards`]; equal stamps are allowed (a camera frame at
//! the same instant as the previous filter step is treated as 1 µs later).
//!
//! [`run`] drives any [`Plant`] (the analytic model in the tests, the rapier plant, or a real robot behind
//! a bus) with a [`crate::Trajectory`] for a fixed number of ticks, sending the held command while faulted.

mod config;
mod rate_fit;
mod runner;

pub use self::config::{ServoConfig, HOLD_OFFSET_TIME, POTENTIOMETER_SIGMA_RAD};
pub use self::runner::{run, Plant, RunSummary, TickRecord};

use self::rate_fit::RateFit;
use crate::converter::TorqueToPosition;
use crate::dsmc::Dsmc;
use crate::error::{all_finite, check_dt, CtrlError, FaultLatch, FaultReason, Result};
use crate::kalman::{PoseEstimate, PoseKalman};
use crate::kcsc::Kcsc;
use crate::kjsc::Kjsc;
use crate::safety::CommandGuard;
use crate::trajectory::Reference;
use rss6_core::{ik, jacobian_theta, KinematicParams, Mat6, Vec6};

/// The camera-rate controller inside a [`Servo`].
#[derive(Debug, Clone, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum Scheme {
    /// DSMC (eq. 6.25) + torque-to-position converter.
    Dsmc(Dsmc),
    /// KCSC (eq. 6.40).
    Kcsc(Kcsc),
    /// KJSC (eq. 6.42).
    Kjsc(Kjsc),
}

impl Scheme {
    /// Short name for reports: "DSMC", "KCSC" or "KJSC".
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::Dsmc(_) => "DSMC",
            Scheme::Kcsc(_) => "KCSC",
            Scheme::Kjsc(_) => "KJSC",
        }
    }
}

/// What one tick produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoTick {
    /// The joint command to send (nominal convention, rad).
    pub theta_cmd: Vec6,
    /// A camera frame was consumed this tick.
    pub frame: bool,
    /// The Kalman estimate if the camera-rate part ran this tick (frame or prediction).
    pub estimate: Option<PoseEstimate>,
    /// The DSMC's latest τ_a (N·m) and F (DSMC only).
    pub dsmc: Option<(Vec6, Vec6)>,
}

/// Kalman filter + camera-rate controller + converter + command guard (Fig. 6.2). `Clone`, not `Copy`:
/// `let s = servo;` moves the controller instead of silently forking it.
#[derive(Debug, Clone, PartialEq)]
pub struct Servo {
    kp_nominal: KinematicParams,
    config: ServoConfig,
    kalman: PoseKalman,
    scheme: Scheme,
    converter: TorqueToPosition,
    guard: CommandGuard,
    held_tau: Vec6,
    held_sliding: Vec6,
    held_theta_d: Vec6,
    hold_h: Mat6,
    theta_frame: Vec6,
    pot_offset: Vec6,
    ls: RateFit,
    last_frame_t: f64,
    last_kalman_t: f64,
    last_tick_t: f64,
    started: bool,
    fault: FaultLatch,
}

impl Servo {
    /// A servo starting at time `t0` (s) with the robot at `initial_pose` (m, rad; Kalman start) and the
    /// potentiometers reading `initial_kappa` (bits). `kp_nominal` converts readings to θ (eq. 4.2).
    /// The drive's PID must be at rest (zero integral) at `t0`.
    pub fn new(
        kp_nominal: KinematicParams,
        config: ServoConfig,
        scheme: Scheme,
        initial_pose: &Vec6,
        initial_kappa: &Vec6,
        t0: f64,
    ) -> Result<Self> {
        check_dt(config.joint_dt)?;
        check_dt(config.frame_period)?;
        check_dt(config.stale_after)?;
        if !(config.camera_latency >= 0.0 && config.camera_latency < config.stale_after) {
            return Err(CtrlError::InvalidParameter(
                "camera latency must be in [0, stale_after)",
            ));
        }
        if !t0.is_finite() {
            return Err(CtrlError::NonFinite);
        }
        if let Some(sigma) = config.potentiometer_rate {
            if !(sigma.is_finite() && sigma > 0.0) {
                return Err(CtrlError::InvalidParameter(
                    "potentiometer rate sigma must be finite and > 0",
                ));
            }
            if config.kalman.steady_state {
                return Err(CtrlError::InvalidParameter(
                    "potentiometer rate needs the propagated covariance (kalman.steady_state = false)",
                ));
            }
        }
        if !all_finite(config.potentiometer_rate_scale_error.as_slice())
            || config
                .potentiometer_rate_scale_error
                .iter()
                .any(|&x| x < 0.0)
        {
            return Err(CtrlError::InvalidParameter(
                "potentiometer rate scale error must be finite and >= 0",
            ));
        }
        let theta0 = kp_nominal.theta_from_reading(initial_kappa);
        let kalman = PoseKalman::new(config.kalman, initial_pose)?;
        let converter = TorqueToPosition::new(config.pid, config.joint_dt, config.torque_limit)?;
        let guard = CommandGuard::new(config.limits, &theta0)?;
        let hold_h = match (&scheme, config.hold_compensation) {
            (Scheme::Dsmc(d), true) => d.hold_stiffness(initial_pose)?,
            _ => Mat6::zeros(),
        };
        let pot_offset = if config.hold_compensation {
            theta0 - ik(&kp_nominal, initial_pose)?
        } else {
            Vec6::zeros()
        };
        let held_theta_d = guard.last_command();
        Ok(Servo {
            hold_h,
            theta_frame: theta0,
            pot_offset,
            ls: RateFit::default(),
            kp_nominal,
            config,
            kalman,
            scheme,
            converter,
            guard,
            held_tau: Vec6::zeros(),
            held_sliding: Vec6::zeros(),
            held_theta_d,
            last_frame_t: t0,
            last_kalman_t: t0 - config.camera_latency,
            last_tick_t: t0,
            started: false,
            fault: FaultLatch::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ServoConfig {
        &self.config
    }

    /// The camera-rate controller (read its gains, integral, fault).
    pub fn scheme(&self) -> &Scheme {
        &self.scheme
    }

    /// The Kalman filter.
    pub fn kalman(&self) -> &PoseKalman {
        &self.kalman
    }

    /// The converter (and its shadow of the drive PID).
    pub fn converter(&self) -> &TorqueToPosition {
        &self.converter
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultReason> {
        self.fault.get()
    }

    /// The last command let through the guard: what to keep sending while faulted.
    pub fn held_command(&self) -> Vec6 {
        self.guard.last_command()
    }

    /// Feeds the filter the pose rate the potentiometers measured since the previous frame: the
    /// least-squares slope of the joint angles, brought from the window's middle to the exposure time with
    /// the filter's acceleration and mapped to χ̇ by J_θ⁻¹ at the (just updated) estimate. Variance per axis:
    /// diag(J_θ⁻¹ J_θ⁻ᵀ) σ²/Σ(t − t̄)² + (scale_error · rate)².
    fn potentiometer_rate_update(
        &mut self,
        sigma: f64,
        t: f64,
    ) -> core::result::Result<(), FaultReason> {
        let fit = self.ls;
        self.ls.clear();
        let Some((slope, sxx)) = fit.slope() else {
            return Ok(());
        };
        let est = self.kalman.estimate();
        let j = jacobian_theta(&self.kp_nominal, &est.pose).map_err(FaultReason::Model)?;
        let Some(j_inv) = j.try_inverse() else {
            return Err(FaultReason::SingularJacobian);
        };
        // The slope is the mean rate over the window (middle at t − half); the filter's state is at the
        // exposure time t − L.
        let ahead = 0.5 * (t - self.last_frame_t) - self.config.camera_latency;
        let rate = j_inv * slope + est.pose_ddot * ahead;
        let var_joint = sigma * sigma / sxx;
        let rel = self.config.potentiometer_rate_scale_error;
        let var = Vec6::from_fn(|i, _| {
            let row = j_inv.row(i);
            let scale = rel[i] * rate[i];
            row.dot(&row) * var_joint + scale * scale
        });
        self.kalman
            .update_rate(&rate, &var)
            .map(|_| ())
            .map_err(|_| FaultReason::NonFiniteMeasurement)
    }

    fn trip(&mut self, r: FaultReason) -> CtrlError {
        self.fault.trip(r)
    }

    fn run_scheme(
        &mut self,
        reference: &Reference,
        est: &PoseEstimate,
        theta: &Vec6,
        dt: f64,
    ) -> Result<()> {
        match &mut self.scheme {
            Scheme::Dsmc(d) => {
                let out = d.step(reference, est, dt)?;
                if self.config.hold_compensation {
                    // θ̂ = the potentiometer angles at the pose the model was evaluated at (χ_m): IK plus
                    // the averaged offset between the readings and the IK of the raw frames.
                    let th_m = ik(&self.kp_nominal, &est.pose)?;
                    self.theta_frame = th_m + self.pot_offset;
                } else {
                    self.theta_frame = *theta;
                }
                if self.config.kalman_model_input {
                    self.kalman.set_input(&out.accel_model)?;
                }
                self.held_tau = out.tau_a;
                self.held_sliding = out.sliding;
            }
            Scheme::Kcsc(k) => self.held_theta_d = k.step(reference, est, dt)?.theta_d,
            Scheme::Kjsc(k) => self.held_theta_d = k.step(reference, theta, dt)?.theta_d,
        }
        Ok(())
    }

    /// One joint-rate tick at time `t` (s): `reference` at t, the camera pose χ̄_E in the base frame if a
    /// frame arrived (m, rad), and the potentiometer readings κ (bits). Fixed work: one Kalman step and one
    /// controller step at most, one converter/guard step always.
    ///
    /// On `Err` the caller sends [`Servo::held_command`]; the servo assumes it did and keeps the
    /// converter's shadow of the drive PID in step with it, so [`Servo::reset`] can restart bumplessly.
    pub fn tick(
        &mut self,
        t: f64,
        reference: &Reference,
        camera: Option<&Vec6>,
        kappa: &Vec6,
    ) -> Result<ServoTick> {
        let out = self.tick_inner(t, reference, camera, kappa);
        if out.is_err() {
            let theta = self.kp_nominal.theta_from_reading(kappa);
            if all_finite(theta.as_slice()) {
                let held = self.guard.last_command();
                self.converter.observe(&held, &theta);
            }
        }
        out
    }

    /// Clears every fault and restarts the filter at `pose` (m, rad) at time `t` (s); the command guard and
    /// the controllers' integrals restart from the held command. The drive's PID state is kept (the
    /// converter has been shadowing it throughout).
    pub fn reset(&mut self, t: f64, pose: &Vec6) -> Result<()> {
        if !(t.is_finite() && all_finite(pose.as_slice())) {
            return Err(CtrlError::NonFinite);
        }
        self.kalman.reset(pose);
        match &mut self.scheme {
            Scheme::Dsmc(d) => d.reset(),
            Scheme::Kcsc(k) => k.reset(),
            Scheme::Kjsc(k) => k.reset(),
        }
        self.held_theta_d = self.guard.last_command();
        self.held_tau = Vec6::zeros();
        self.held_sliding = Vec6::zeros();
        self.ls.clear();
        self.last_frame_t = t;
        self.last_kalman_t = t - self.config.camera_latency;
        self.last_tick_t = t;
        self.started = false;
        self.fault.clear();
        Ok(())
    }

    fn tick_inner(
        &mut self,
        t: f64,
        reference: &Reference,
        camera: Option<&Vec6>,
        kappa: &Vec6,
    ) -> Result<ServoTick> {
        self.fault.check()?;
        if !t.is_finite() {
            return Err(self.trip(FaultReason::NonFiniteReference));
        }
        if t < self.last_tick_t {
            let by = self.last_tick_t - t;
            return Err(self.trip(FaultReason::TimeWentBackwards { by }));
        }
        self.last_tick_t = t;
        let theta = self.kp_nominal.theta_from_reading(kappa);
        if !all_finite(theta.as_slice()) {
            return Err(self.trip(FaultReason::NonFiniteJoint));
        }
        if !reference.is_finite() {
            return Err(self.trip(FaultReason::NonFiniteReference));
        }
        let min_dt = 1e-6;
        if self.config.potentiometer_rate.is_some() {
            self.ls.add(t - self.last_frame_t, &theta);
        }
        let mut camera_step: Option<(PoseEstimate, f64)> = None;
        let mut frame = false;
        if let Some(z) = camera {
            if !all_finite(z.as_slice()) {
                return Err(self.trip(FaultReason::NonFiniteMeasurement));
            }
            let exposed = t - self.config.camera_latency;
            let dt = (exposed - self.last_kalman_t).max(min_dt);
            if self.kalman.step(dt, Some(z)).is_err() {
                return Err(self.trip(FaultReason::NonFiniteMeasurement));
            }
            if self.config.hold_compensation && matches!(self.scheme, Scheme::Dsmc(_)) {
                // Offset between the potentiometer angles and the IK of the *raw* frame (white noise,
                // unbiased), never of the filter's estimate: its error must not leak into the offset.
                match ik(&self.kp_nominal, z) {
                    Ok(th_z) => {
                        let w = dt / (dt + HOLD_OFFSET_TIME);
                        self.pot_offset += (theta - th_z - self.pot_offset) * w;
                    }
                    Err(e) => return Err(self.trip(FaultReason::Model(e))),
                }
            }
            if let Some(sigma) = self.config.potentiometer_rate {
                if let Err(r) = self.potentiometer_rate_update(sigma, t) {
                    return Err(self.trip(r));
                }
            }
            let est = self.kalman.predicted(self.config.camera_latency);
            self.last_frame_t = t;
            self.last_kalman_t = exposed;
            camera_step = Some((est, dt));
            frame = true;
        } else {
            let age = t - self.last_frame_t;
            if age > self.config.stale_after {
                return Err(self.trip(FaultReason::StaleCamera { age }));
            }
            let exposed = t - self.config.camera_latency;
            let since = exposed - self.last_kalman_t;
            if since >= 1.5 * self.config.frame_period {
                if self.kalman.step(since, None).is_err() {
                    return Err(self.trip(FaultReason::NonFiniteMeasurement));
                }
                self.last_kalman_t = exposed;
                camera_step = Some((self.kalman.predicted(self.config.camera_latency), since));
            } else if !self.started {
                camera_step = Some((
                    self.kalman.predicted(self.config.camera_latency),
                    self.config.frame_period,
                ));
            }
        }
        self.started = true;
        if let Some((est, dt)) = camera_step {
            if let Err(e) = self.run_scheme(reference, &est, &theta, dt) {
                let r = match e {
                    CtrlError::Faulted(r) => r,
                    CtrlError::Core(c) => FaultReason::Model(c),
                    CtrlError::SingularJacobian => FaultReason::SingularJacobian,
                    _ => FaultReason::NonFiniteCommand,
                };
                return Err(self.trip(r));
            }
        }
        let theta_cmd = match self.scheme {
            Scheme::Dsmc(_) => match self.converter.step(
                &(self.held_tau + self.hold_h * (theta - self.theta_frame)),
                &theta,
                &mut self.guard,
            ) {
                Ok(o) => o.theta_cmd,
                Err(CtrlError::Faulted(r)) => return Err(self.trip(r)),
                Err(_) => return Err(self.trip(FaultReason::NonFiniteCommand)),
            },
            _ => match self.guard.apply(&self.held_theta_d, self.config.joint_dt) {
                Ok(g) => {
                    self.converter.observe(&g.command, &theta);
                    g.command
                }
                Err(CtrlError::Faulted(r)) => return Err(self.trip(r)),
                Err(_) => return Err(self.trip(FaultReason::NonFiniteCommand)),
            },
        };
        let dsmc = match self.scheme {
            Scheme::Dsmc(_) => Some((self.held_tau, self.held_sliding)),
            _ => None,
        };
        Ok(ServoTick {
            theta_cmd,
            frame,
            estimate: camera_step.map(|(e, _)| e),
            dsmc,
        })
    }
}
