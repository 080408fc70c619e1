//! The visual servo of Fig. 6.2 on a [`Robot`]: the experiment rules in one place — which controller
//! commands in which joint convention, where the Kalman filter starts, which preset a tuning name
//! means — around rss6-ctrl's allocation-free [`rss6_ctrl::servo::run`].

use crate::error::{ExpError, Result};
use crate::observer::{Flow, Observer, Progress};
use crate::record::{Phase, Record};
use crate::robot::Robot;
use crate::view::{Convention, Externals, View};
use rss6_core::{fk, home_pose, DynamicParams, FkOptions, KinematicParams, Vec6};
use rss6_ctrl::servo::{run, TickRecord};
use rss6_ctrl::{
    CartesianPidGains, Dsmc, DsmcGains, FaultReason, JointSpaceGains, Kcsc, Kjsc, Scheme, Servo,
    ServoConfig, Trajectory,
};

/// The camera-rate controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Controller {
    /// DSMC (eq. 6.25) + torque-to-position converter.
    Dsmc,
    /// KCSC (eq. 6.40).
    Kcsc,
    /// KJSC (eq. 6.42).
    Kjsc,
}

impl Controller {
    /// Parses "dsmc", "kcsc" or "kjsc" (any case).
    pub fn parse(name: &str) -> Result<Self> {
        match name.to_ascii_lowercase().as_str() {
            "dsmc" => Ok(Controller::Dsmc),
            "kcsc" => Ok(Controller::Kcsc),
            "kjsc" => Ok(Controller::Kjsc),
            other => Err(ExpError::InvalidInput(format!(
                "controller must be 'dsmc', 'kcsc' or 'kjsc', got '{other}'"
            ))),
        }
    }

    /// "DSMC", "KCSC" or "KJSC".
    pub fn name(&self) -> &'static str {
        match self {
            Controller::Dsmc => "DSMC",
            Controller::Kcsc => "KCSC",
            Controller::Kjsc => "KJSC",
        }
    }

    /// The joint convention this controller commands in (see [`Convention`]): KJSC turns χ_d into
    /// joint angles by the model's IK, so it works in the model's convention; the DSMC's converter
    /// must mirror the drive's PID exactly and KCSC's increments come from J_θ, so both work in the
    /// drive's.
    pub fn convention(&self, kp_model: &KinematicParams) -> Convention {
        match self {
            Controller::Kjsc => Convention::Model(*kp_model),
            Controller::Dsmc | Controller::Kcsc => Convention::Drive,
        }
    }
}

/// A named set of presets for the servo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tuning {
    /// rss6's tuning used to reproduce Tables 6.1/6.2: the thesis's Kalman filter
    /// ([`ServoConfig::tuned`]), [`DsmcGains::tuned`] (the thesis gives no DSMC gains in SI for
    /// this robot), the thesis's KCSC/KJSC gains.
    Tuned,
    /// The low-noise DSMC servo: [`ServoConfig::low_noise`] + [`DsmcGains::low_noise`] (DSMC only).
    LowNoise,
}

impl Tuning {
    /// Parses "tuned" or "low_noise" (any case, '-' for '_').
    pub fn parse(name: &str) -> Result<Self> {
        match name.to_ascii_lowercase().replace('-', "_").as_str() {
            "tuned" => Ok(Tuning::Tuned),
            "low_noise" => Ok(Tuning::LowNoise),
            other => Err(ExpError::InvalidInput(format!(
                "tuning must be 'tuned' or 'low_noise', got '{other}'"
            ))),
        }
    }

    /// "tuned" or "low_noise".
    pub fn name(&self) -> &'static str {
        match self {
            Tuning::Tuned => "tuned",
            Tuning::LowNoise => "low_noise",
        }
    }
}

/// Everything that defines a servo experiment except the robot and the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoSpec {
    /// The controller.
    pub controller: Controller,
    /// The preset the servo configuration and gains were taken from.
    pub tuning: Tuning,
    /// The controller's kinematic model (nominal or calibrated).
    pub kp_model: KinematicParams,
    /// The controller's dynamic model (DSMC).
    pub dp_model: DynamicParams,
    /// The estimated ᴼχ_C and ᴱχ_t that turn camera frames into χ_E.
    pub externals: Externals,
    /// The drive's joint convention (the nominal kinematics).
    pub drive: KinematicParams,
    /// Rates, limits, Kalman tuning and the drive PID the converter inverts (from the tuning; fields
    /// may be overridden, `joint_dt` is set from the robot).
    pub config: ServoConfig,
    /// DSMC gains (from the tuning).
    pub dsmc: DsmcGains,
    /// Run length (s).
    pub duration: f64,
    /// Observer progress period (s of robot time).
    pub segment: f64,
}

impl ServoSpec {
    /// The spec of `controller` with the presets of `tuning`, nominal drive convention, 20 s, 1 s
    /// segments. Errors for the low-noise tuning on KCSC/KJSC.
    pub fn new(
        controller: Controller,
        tuning: Tuning,
        kp_model: KinematicParams,
        dp_model: DynamicParams,
        externals: Externals,
    ) -> Result<Self> {
        let (config, dsmc) = match tuning {
            Tuning::Tuned => (ServoConfig::tuned(), DsmcGains::tuned()),
            Tuning::LowNoise => {
                if controller != Controller::Dsmc {
                    return Err(ExpError::InvalidInput(format!(
                        "tuning 'low_noise' is for the DSMC only (controller '{}')",
                        controller.name()
                    )));
                }
                (ServoConfig::low_noise(), DsmcGains::low_noise())
            }
        };
        Ok(ServoSpec {
            controller,
            tuning,
            kp_model,
            dp_model,
            externals,
            drive: KinematicParams::nominal(),
            config,
            dsmc,
            duration: 20.0,
            segment: 1.0,
        })
    }
}

/// What a servo run reports besides its records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoOutcome {
    /// Ticks run.
    pub ticks: u32,
    /// Camera frames the servo consumed.
    pub frames: u32,
    /// Time since the start of the run (s) and reason of the first fault, if any.
    pub first_fault: Option<(f64, FaultReason)>,
}

/// The camera-rate controller `controller` on the model (`kp_model`, `dp_model`): the DSMC with
/// `dsmc` gains; KCSC and KJSC with the thesis's gains ([`CartesianPidGains::thesis`],
/// [`JointSpaceGains::from_visual_pid`]), starting from the joint command `theta0` (rad, the controller's
/// convention).
pub fn scheme(
    controller: Controller,
    kp_model: &KinematicParams,
    dp_model: &DynamicParams,
    dsmc: &DsmcGains,
    theta0: &Vec6,
) -> Result<Scheme> {
    Ok(match controller {
        Controller::Dsmc => Scheme::Dsmc(Dsmc::new(*kp_model, *dp_model, *dsmc)?),
        Controller::Kcsc => {
            Scheme::Kcsc(Kcsc::new(*kp_model, CartesianPidGains::thesis(), theta0)?)
        }
        Controller::Kjsc => Scheme::Kjsc(Kjsc::new(
            *kp_model,
            JointSpaceGains::from_visual_pid(),
            theta0,
        )?),
    })
}

/// The servo for `spec` on a robot now reading `kappa0` at time `t0`, with the Kalman filter starting
/// at the first camera frame if `frame` is pending, else at the model's FK of the readings.
fn build_servo(
    spec: &ServoSpec,
    view_conv: &Convention,
    kappa0: &Vec6,
    frame: Option<Vec6>,
    t0: f64,
) -> Result<Servo> {
    let kp_servo = match view_conv {
        Convention::Drive => spec.drive,
        Convention::Model(kp) => *kp,
    };
    let theta0 = kp_servo.theta_from_reading(kappa0);
    let start = match frame {
        Some(p) => p,
        None => {
            let kp = &spec.kp_model;
            fk(
                kp,
                &kp.theta_from_reading(kappa0),
                &home_pose(),
                &FkOptions::default(),
            )?
            .pose
        }
    };
    let scheme = scheme(
        spec.controller,
        &spec.kp_model,
        &spec.dp_model,
        &spec.dsmc,
        &theta0,
    )?;
    Ok(Servo::new(
        kp_servo,
        spec.config,
        scheme,
        &start,
        kappa0,
        t0,
    )?)
}

/// Runs the servo of `spec` on `robot` from its current state for `spec.duration` s following
/// `trajectory` (sampled from t = 0 at the start of the run). Every tick becomes a [`Record`] (phase
/// [`Phase::Servo`], times from the start of the run) shown to `observer`, which also sees the progress
/// every `spec.segment` s and may stop the run ([`ExpError::Stopped`]).
///
/// A controller fault does not end the run: the servo keeps sending its held command (the drive's
/// PID holds the robot) and the outcome reports the first fault.
pub fn track<R: Robot, T: Trajectory + ?Sized>(
    robot: R,
    spec: &ServoSpec,
    trajectory: &T,
    observer: &mut dyn Observer,
) -> Result<ServoOutcome> {
    if !(spec.duration.is_finite() && spec.duration > 0.0) {
        return Err(ExpError::InvalidInput(format!(
            "duration must be finite and > 0 s, got {}",
            spec.duration
        )));
    }
    if !(spec.segment.is_finite() && spec.segment > 0.0) {
        return Err(ExpError::InvalidInput(format!(
            "segment must be finite and > 0 s, got {}",
            spec.segment
        )));
    }
    let convention = spec.controller.convention(&spec.kp_model);
    let mut view = View::new(robot, spec.externals, spec.drive, convention);
    let dt = view.robot.dt();
    let mut spec_dt = spec.clone();
    spec_dt.config.joint_dt = dt;
    let t0 = view.robot.time();
    let kappa0 = view.robot.potentiometers();
    let frame = rss6_ctrl::Plant::camera(&mut view);
    // A frame taken for the filter's start is the tick's frame: hand it to the servo too.
    let mut servo = build_servo(&spec_dt, &convention, &kappa0, frame, t0)?;
    let ticks = (spec.duration / dt).round() as u32;
    let segment_ticks = ((spec.segment / dt).round() as u32).max(1);
    let mut prev_truth = view.robot.true_state();
    let mut prev_kappa = kappa0;
    let pending = frame.map(|z| (z, view.last_sensor_pose()));
    let mut done = 0u32;
    let mut plant = FirstFrame {
        view: &mut view,
        pending,
        stop: std::cell::Cell::new(false),
    };
    let result = run(
        &mut plant,
        &mut servo,
        trajectory,
        t0,
        ticks,
        |rec: &TickRecord, p: &FirstFrame<'_, R>| {
            let mut r = Record::new(rec.t - t0, Phase::Servo, prev_kappa, rec.theta_cmd);
            r.theta_cmd = p.view.to_drive(&rec.theta_cmd);
            r.reference = Some(rec.reference);
            r.camera = rec.camera;
            r.sensor_pose = rec.camera.and(p.consumed_sensor_pose());
            r.estimate = rec.tick.and_then(|k| k.estimate);
            r.dsmc = rec.tick.and_then(|k| k.dsmc);
            r.fault = rec.fault;
            r.truth = prev_truth;
            let now = p.view.robot.true_state();
            r.torque = now.map(|s| s.torque);
            prev_truth = now;
            prev_kappa = p.view.robot.potentiometers();
            done += 1;
            let mut stopped = observer.record(&r) == Flow::Stop;
            if done % segment_ticks == 0 || done == ticks {
                let pr = Progress {
                    done: f64::from(done) * dt,
                    total: f64::from(ticks) * dt,
                    time: p.view.robot.time(),
                    finished: done == ticks,
                };
                if observer.progress(&pr) == Flow::Stop {
                    stopped = true;
                }
            }
            if stopped {
                p.request_stop();
            }
        },
    );
    // A stop asked on a tick refuses the next command, so rss6-ctrl's runner ends with
    // `ExpError::Stopped`; a stop on the last tick changes nothing.
    let s = result?;
    Ok(ServoOutcome {
        ticks: s.ticks,
        frames: s.frames,
        first_fault: s.first_fault.map(|(t, r)| (t - t0, r)),
    })
}

/// The view with the frame taken at the start (for the filter's start pose) handed back to the servo
/// on its first tick, and a stop flag settable from the observer.
struct FirstFrame<'a, R> {
    view: &'a mut View<R>,
    pending: Option<(Vec6, Option<Vec6>)>,
    stop: std::cell::Cell<bool>,
}

impl<R: Robot> FirstFrame<'_, R> {
    fn consumed_sensor_pose(&self) -> Option<Vec6> {
        self.view.last_sensor_pose()
    }
    fn request_stop(&self) {
        self.stop.set(true);
    }
}

impl<R: Robot> rss6_ctrl::Plant for FirstFrame<'_, R> {
    type Error = ExpError;

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()> {
        if self.stop.get() {
            self.view.stop = true;
        }
        rss6_ctrl::Plant::step_joint_command(self.view, theta_cmd)
    }

    fn camera(&mut self) -> Option<Vec6> {
        if let Some((z, raw)) = self.pending.take() {
            self.view.last_sensor_pose = raw;
            return Some(z);
        }
        rss6_ctrl::Plant::camera(self.view)
    }

    fn potentiometers(&self) -> Vec6 {
        self.view.robot.potentiometers()
    }

    fn time(&self) -> f64 {
        self.view.robot.time()
    }
}
