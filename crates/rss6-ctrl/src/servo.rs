//! The visual-servo loop of Fig. 6.2 as one allocation-free object, plus a plant-agnostic runner.
//!
//! [`Servo::tick`] is called at the joint rate (1 kHz). When a camera frame arrives it runs the Kalman
//! filter and the camera-rate controller (DSMC, KCSC or KJSC); every tick it produces a guarded joint
//! command: DSMC through the torque-to-position converter (with the latest potentiometer angles),
//! KCSC/KJSC by holding their latest θ_d. If no frame arrives for 1.5 camera periods the filter predicts
//! and the controller runs on the prediction; after `stale_after` seconds without a frame, or on any
//! NaN/∞ input, the servo latches a fault, returns [`CtrlError::Faulted`] and [`Servo::held_command`] is
//! the last command sent (the drive's PID then holds the robot there).
//!
//! [`run`] drives any [`Plant`] (the analytic model in the tests, the rapier plant, or a real robot behind
//! a bus) with a [`Trajectory`] for a fixed number of ticks, sending the held command while faulted.

use crate::converter::TorqueToPosition;
use crate::dsmc::Dsmc;
use crate::error::{all_finite, check_dt, CtrlError, FaultLatch, FaultReason, Result};
use crate::kalman::{KalmanConfig, PoseEstimate, PoseKalman};
use crate::kcsc::Kcsc;
use crate::kjsc::Kjsc;
use crate::pid::PidGains;
use crate::safety::{CommandGuard, CommandLimits};
use crate::trajectory::{Reference, Trajectory};
use rss6_core::{ik, jacobian_theta, KinematicParams, Mat6, Vec6};

/// Running sums of a least-squares line θ(t) = a + b t per joint (t relative to the last frame).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct RateFit {
    n: f64,
    st: f64,
    stt: f64,
    sy: Vec6,
    sty: Vec6,
    last: Vec6,
}

impl RateFit {
    /// Adds a sample if the reading changed (the potentiometers update every other joint tick).
    fn add(&mut self, t: f64, theta: &Vec6) {
        if self.n > 0.0 && *theta == self.last {
            return;
        }
        self.last = *theta;
        self.n += 1.0;
        self.st += t;
        self.stt += t * t;
        self.sy += theta;
        self.sty += theta * t;
    }

    /// Slope b per joint (rad/s) and Σ(t − t̄)² (s²), if at least 3 samples spread in time.
    fn slope(&self) -> Option<(Vec6, f64)> {
        let sxx = self.stt - self.st * self.st / self.n.max(1.0);
        if self.n < 3.0 || sxx <= 0.0 {
            return None;
        }
        let b = (self.sty - self.sy * (self.st / self.n)) / sxx;
        Some((b, sxx))
    }

    fn clear(&mut self) {
        let last = self.last;
        *self = RateFit::default();
        self.last = last;
    }
}

/// Time constant (s) of the average of θ_pot − IK(χ_m) used by [`ServoConfig::hold_compensation`].
pub const HOLD_OFFSET_TIME: f64 = 0.3;

/// The camera-rate controller inside a [`Servo`].
#[derive(Debug, Clone, Copy, PartialEq)]
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

/// Rates, limits and the drive's PID as seen by the servo.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoConfig {
    /// Joint-loop period (s), 1e-3.
    pub joint_dt: f64,
    /// Nominal camera period (s), 0.033.
    pub frame_period: f64,
    /// Fault if no frame for this long (s).
    pub stale_after: f64,
    /// Camera latency L (s, ≥ 0): a frame arriving at t was exposed at t − L. The filter runs on exposure
    /// times and the controllers get its estimate extrapolated by L (Φ(L), third-order model).
    pub camera_latency: f64,
    /// Stroke and rate limits of the joint commands.
    pub limits: CommandLimits,
    /// Kalman filter tuning.
    pub kalman: KalmanConfig,
    /// Feed the DSMC's model-predicted acceleration ([`crate::DsmcOutput::accel_model`]) to the filter as a
    /// known input ([`PoseKalman::set_input`]); ignored for KCSC/KJSC, which do not compute one.
    pub kalman_model_input: bool,
    /// DSMC only: every joint tick send τ_a + H (θ − θ̂) instead of the held τ_a, with θ the latest
    /// potentiometer angles, H the model's joint-space hold stiffness at the start pose
    /// ([`Dsmc::hold_stiffness`]) and θ̂ the potentiometer angles the robot would read at the estimate χ_m
    /// the DSMC was evaluated at (IK(χ_m) plus the average of θ − IK(raw frame) over
    /// [`HOLD_OFFSET_TIME`]). On the 6-RSS a held τ_a does not hold the generalized force: under gravity
    /// the platform tilts away at ≈ 14/s between frames, and the model evaluated at a noisy χ_m turns
    /// camera noise into torque noise through the same stiffness. The compensation takes the pose
    /// dependence from the potentiometers instead (docs/control.md, "Held torque between frames").
    pub hold_compensation: bool,
    /// Also feed the filter the pose rate the potentiometers measured over each camera frame: the
    /// least-squares slope of the joint angles since the previous frame, mapped by J_θ⁻¹ at the estimate
    /// ([`PoseKalman::update_rate`]). `None` = camera only (the thesis filter); `Some(σ)` with σ the 1σ
    /// noise of one potentiometer reading in rad (Table 4.1: 0.2233 bit × η ≈ 1.7e-4 rad). Needs
    /// `kalman.steady_state = false`.
    pub potentiometer_rate: Option<f64>,
    /// Relative error of the potentiometer rate per axis, added to its variance as (scale_error · rate)²:
    /// an uncalibrated scale η (Table 4.2: 5e-5 of π/4096 rad/bit ≈ 6.5 %) and geometry errors, plus a
    /// margin (default 0.2).
    pub potentiometer_rate_scale_error: Vec6,
    /// Gains of the drive's built-in PID (what the converter inverts).
    pub pid: PidGains,
    /// Torque limit of the drive's PID (N·m).
    pub torque_limit: f64,
}

impl ServoConfig {
    /// 1 kHz joint loop, 30 Hz camera without latency, stale after 0.2 s, nominal limits, thesis Kalman tuning, nominal
    /// drive PID with a 30 N·m limit.
    pub fn nominal() -> Self {
        ServoConfig {
            joint_dt: 1e-3,
            frame_period: 0.033,
            stale_after: 0.2,
            camera_latency: 0.0,
            limits: CommandLimits::nominal(),
            kalman: KalmanConfig::thesis(),
            kalman_model_input: false,
            potentiometer_rate: None,
            potentiometer_rate_scale_error: Vec6::repeat(0.2),
            hold_compensation: false,
            pid: PidGains::nominal(),
            torque_limit: 30.0,
        }
    }
}

impl ServoConfig {
    /// The low-noise DSMC servo (docs/control.md, "Kalman filter in the loop"): [`Self::nominal`] with
    /// [`KalmanConfig::low_noise`], the DSMC's model acceleration as the filter's known input
    /// (`kalman_model_input`), the joint-rate hold compensation (`hold_compensation`) and the
    /// potentiometer rate as a second filter measurement (`potentiometer_rate` = Table 4.1's 0.2233 bit ×
    /// π/4096 rad/bit, scale error 0.2 for x, y, z and 0.12 for α, β, γ). Use with [`crate::DsmcGains::low_noise`]. KCSC and KJSC
    /// ignore the DSMC-only options but would get the smoother filter: keep them on [`Self::nominal`].
    pub fn low_noise() -> Self {
        ServoConfig {
            kalman: KalmanConfig::low_noise(),
            kalman_model_input: true,
            hold_compensation: true,
            potentiometer_rate: Some(POTENTIOMETER_SIGMA_RAD),
            potentiometer_rate_scale_error: Vec6::new(0.2, 0.2, 0.2, 0.12, 0.12, 0.12),
            ..Self::nominal()
        }
    }
}

/// Table 4.1 potentiometer noise in rad: 0.2233 bit × η = π/4096 rad/bit.
pub const POTENTIOMETER_SIGMA_RAD: f64 = 0.2233 * core::f64::consts::PI / 4096.0;

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

/// Kalman filter + camera-rate controller + converter + command guard (Fig. 6.2).
#[derive(Debug, Clone, Copy, PartialEq)]
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
            held_theta_d: guard.last_command(),
            last_frame_t: t0,
            last_kalman_t: t0 - config.camera_latency,
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
            return Err(FaultReason::NonFiniteCommand);
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

/// A robot (real or simulated) as the servo sees it. Joint commands are in the nominal joint convention.
pub trait Plant {
    /// The plant's own error type (bus error, simulation failure …).
    type Error;
    /// Sends one joint command and advances one joint-loop tick (1 kHz).
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> core::result::Result<(), Self::Error>;
    /// The camera pose χ̄_E of the end-effector in the base frame (m, rad) if a frame arrived since the
    /// last call, else `None`. (A plant whose camera reports ᶜχ_t converts with ᴼχ_C and ᴱχ_t first.)
    fn camera(&mut self) -> Option<Vec6>;
    /// The latest potentiometer readings κ (bits).
    fn potentiometers(&self) -> Vec6;
    /// Plant time (s).
    fn time(&self) -> f64;
}

/// What [`run`] shows the observer after every tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TickRecord {
    /// Time at the start of the tick (s).
    pub t: f64,
    /// The reference used.
    pub reference: Reference,
    /// The camera frame consumed this tick, if any.
    pub camera: Option<Vec6>,
    /// The command sent (rad).
    pub theta_cmd: Vec6,
    /// The servo's output, or `None` while faulted.
    pub tick: Option<ServoTick>,
    /// The servo's latched fault, if any.
    pub fault: Option<FaultReason>,
}

/// Summary of a [`run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// Ticks executed.
    pub ticks: u32,
    /// Camera frames consumed.
    pub frames: u32,
    /// Time and reason of the first fault, if any.
    pub first_fault: Option<(f64, FaultReason)>,
}

/// Runs `servo` on `plant` for `ticks` joint-loop ticks following `trajectory` (sampled at plant time
/// minus `t0`). While the servo is faulted the held command keeps being sent. `observe` sees every tick
/// and the plant after the command was applied. Stops early only on a plant error.
pub fn run<P, T, F>(
    plant: &mut P,
    servo: &mut Servo,
    trajectory: &T,
    t0: f64,
    ticks: u32,
    mut observe: F,
) -> core::result::Result<RunSummary, P::Error>
where
    P: Plant,
    T: Trajectory + ?Sized,
    F: FnMut(&TickRecord, &P),
{
    let mut summary = RunSummary {
        ticks: 0,
        frames: 0,
        first_fault: None,
    };
    for _ in 0..ticks {
        let t = plant.time();
        let reference = trajectory.sample(t - t0);
        let camera = plant.camera();
        let kappa = plant.potentiometers();
        let result = servo.tick(t, &reference, camera.as_ref(), &kappa);
        let (theta_cmd, tick) = match result {
            Ok(o) => (o.theta_cmd, Some(o)),
            Err(_) => (servo.held_command(), None),
        };
        if camera.is_some() && tick.is_some() {
            summary.frames += 1;
        }
        let fault = servo.fault();
        if summary.first_fault.is_none() {
            if let Some(r) = fault {
                summary.first_fault = Some((t, r));
            }
        }
        plant.step_joint_command(&theta_cmd)?;
        summary.ticks += 1;
        observe(
            &TickRecord {
                t,
                reference,
                camera,
                theta_cmd,
                tick,
                fault,
            },
            plant,
        );
    }
    Ok(summary)
}
