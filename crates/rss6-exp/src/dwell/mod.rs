//! Calibration dwells (§4.4.3, §4.5): move to each configuration, wait, then average the potentiometers
//! and the camera at rest. The one dwell segmentation and mean of the project: a dwell is the ticks of
//! [`Phase::Dwell`]; κ is averaged over the samples taken at `kappa_rate` from its first tick, ᶜχ_t over
//! every finite frame of it with [`crate::PoseMean`]. Logged collections carry these means
//! ([`crate::log`]), so a log and a live run give the same numbers.

mod check;

pub use check::{DriveConvention, DwellChecks, DwellFault, RestChannel, Scatter};

use crate::error::{ExpError, Result};
use crate::observer::{Flow, Observer, Progress};
use crate::pose_mean::PoseMean;
use crate::record::{Phase, Record};
use crate::robot::Robot;
use rss6_core::{KinematicParams, Vec6, LEGS};
use serde::{Deserialize, Serialize};

/// One calibration configuration: the means over a dwell at rest.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ConfigurationData {
    /// Commanded joint angles θ_cmd in the drive's (nominal) joint convention (rad).
    pub theta_cmd: [f64; LEGS],
    /// Mean potentiometer readings κ (bits, eq. 4.2).
    pub kappa: [f64; LEGS],
    /// Mean sensor pose ᶜχ_t of the target frame in the sensor frame (m, rad; eq. 4.7);
    /// `None` when no camera frame arrived during the dwell.
    pub sensor_pose: Option<[f64; 6]>,
    /// Number of potentiometer samples averaged.
    pub kappa_samples: u32,
    /// Number of camera frames averaged.
    pub camera_frames: u32,
    /// Sample standard deviation of each potentiometer over the dwell (bit); `None` if not recorded.
    #[serde(default)]
    pub kappa_std: Option<[f64; LEGS]>,
    /// Sample standard deviation of each component of ᶜχ_t over the dwell (m, rad); `None` if not
    /// recorded or fewer than 2 frames.
    #[serde(default)]
    pub sensor_pose_std: Option<[f64; 6]>,
    /// Sample covariance of ᶜχ_t's components over the dwell, one frame's (m², m·rad, rad²; not
    /// divided by the frame count); `None` if not recorded or fewer than 2 frames. Pooled over a
    /// collection it is the camera's pose noise with its correlations (calibration's
    /// `noise_from_dwells`).
    #[serde(default)]
    pub sensor_pose_cov: Option<[[f64; 6]; 6]>,
    /// The collection check this configuration failed ([`DwellChecks`]), or `None` (passed, or not
    /// checked). Such a configuration is kept in the data and left out of calibrations by default.
    #[serde(default)]
    pub fault: Option<DwellFault>,
}

impl ConfigurationData {
    /// κ as a vector.
    pub fn kappa_vec(&self) -> Vec6 {
        Vec6::from_column_slice(&self.kappa)
    }

    /// ᶜχ_t as a vector, if present.
    pub fn sensor_pose_vec(&self) -> Option<Vec6> {
        self.sensor_pose.map(|p| Vec6::from_column_slice(&p))
    }

    /// Why this configuration cannot be used (NaN/∞ values, missing camera frames), or `None`.
    pub fn defect(&self) -> Option<String> {
        if self.kappa.iter().any(|k| !k.is_finite()) {
            return Some("non-finite potentiometer reading".into());
        }
        match &self.sensor_pose {
            None => Some("no camera frame during the dwell".into()),
            Some(p) if p.iter().any(|v| !v.is_finite()) => Some("non-finite sensor pose".into()),
            Some(_) => None,
        }
    }

    /// Why this configuration is left out of a calibration by default: its [`Self::defect`], or the
    /// collection check it failed ([`Self::fault`]); `None` if it is usable.
    pub fn exclusion(&self) -> Option<String> {
        self.defect()
            .or_else(|| self.fault.as_ref().map(ToString::to_string))
    }
}

/// The data of one calibration experiment. Configuration 0 is the initial (reference) configuration.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CalibrationData {
    /// Configurations in the order they were visited; index 0 is the reference.
    pub configurations: Vec<ConfigurationData>,
}

impl CalibrationData {
    /// Number of configurations (including configuration 0).
    pub fn len(&self) -> usize {
        self.configurations.len()
    }

    /// `true` if there are no configurations.
    pub fn is_empty(&self) -> bool {
        self.configurations.is_empty()
    }
}

/// How each configuration is visited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DwellSpec {
    /// Duration of the cosine-blended move between configurations (s).
    pub move_time: f64,
    /// Wait at the target before averaging starts (s).
    pub settle_time: f64,
    /// Potentiometer sampling rate during the dwell (Hz); thesis §4.5: 500 Hz.
    pub kappa_rate: f64,
    /// Collection checks of every dwell; `None` records the means unchecked.
    pub checks: Option<DwellChecks>,
}

impl Default for DwellSpec {
    /// 1 s move, 0.5 s settle, 500 Hz potentiometer sampling, the default [`DwellChecks`] (at rest,
    /// target seen; the reach check needs the drive's convention, see [`DwellSpec::checked`]).
    fn default() -> Self {
        DwellSpec {
            move_time: 1.0,
            settle_time: 0.5,
            kappa_rate: 500.0,
            checks: Some(DwellChecks::default()),
        }
    }
}

impl DwellSpec {
    /// The default spec with every check, the reach check in the convention of `drive` (the
    /// nominal model the drive was set up with).
    pub fn checked(drive: &KinematicParams) -> Self {
        DwellSpec {
            checks: Some(DwellChecks::with_drive(drive)),
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<()> {
        let ok = self.move_time.is_finite()
            && self.move_time > 0.0
            && self.settle_time.is_finite()
            && self.settle_time >= 0.0
            && self.kappa_rate.is_finite()
            && self.kappa_rate > 0.0;
        if ok {
            Ok(())
        } else {
            Err(ExpError::InvalidInput(format!(
                "move_time must be > 0 s, settle_time >= 0 s and kappa_rate > 0 Hz, got {self:?}"
            )))
        }
    }
}

/// A robot visited configuration by configuration; remembers the last command so each move starts
/// where the previous one ended.
#[derive(Debug)]
pub struct DwellSession<R> {
    /// The robot.
    pub robot: R,
    /// How configurations are visited.
    pub spec: DwellSpec,
    last_cmd: Vec6,
    index: usize,
}

impl<R: Robot> DwellSession<R> {
    /// Wraps `robot`, at rest under the command `start` (rad, drive convention).
    pub fn new(robot: R, start: Vec6, spec: DwellSpec) -> Self {
        DwellSession {
            robot,
            spec,
            last_cmd: start,
            index: 0,
        }
    }

    /// Moves to `theta_cmd` (rad, drive convention), settles, and averages over `dwell` seconds.
    pub fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData> {
        self.measure_observed(theta_cmd, dwell, &mut ())
            .map(|(d, _)| d)
    }

    /// [`Self::measure`] with every tick shown to `observer` (phases Move, Settle, Dwell of this
    /// configuration, times as the robot's), then its [`Observer::dwell`]. Returns the means and the
    /// dwell's window [first, last tick time] (s).
    pub fn measure_observed(
        &mut self,
        theta_cmd: &Vec6,
        dwell: f64,
        observer: &mut dyn Observer,
    ) -> Result<(ConfigurationData, [f64; 2])> {
        self.spec.validate()?;
        if !(dwell.is_finite() && dwell > 0.0) || theta_cmd.iter().any(|t| !t.is_finite()) {
            return Err(ExpError::InvalidInput(format!(
                "dwell must be finite and > 0 s and the command finite (dwell {dwell}, command {:?})",
                theta_cmd.as_slice()
            )));
        }
        let index = self.index;
        let dt = self.robot.dt();
        let ticks = |t: f64| (t / dt).round().max(0.0) as usize;
        let from = self.last_cmd;
        let n_move = ticks(self.spec.move_time).max(1);
        for k in 1..=n_move {
            let s = 0.5 - 0.5 * (std::f64::consts::PI * k as f64 / n_move as f64).cos();
            self.tick(
                &(from + (theta_cmd - from) * s),
                Phase::Move { index },
                observer,
            )?;
        }
        self.last_cmd = *theta_cmd;
        for _ in 0..ticks(self.spec.settle_time) {
            self.tick(theta_cmd, Phase::Settle { index }, observer)?;
        }
        let every = ((1.0 / (self.spec.kappa_rate * dt)).round() as usize).max(1);
        let mut kappa = Vec6::zeros();
        let mut kappa_samples = 0u32;
        let mut poses = PoseMean::default();
        let mut scatter = Scatter::default();
        let mut window = [f64::NAN; 2];
        for k in 0..ticks(dwell).max(1) {
            let t = self.robot.time();
            if k == 0 {
                window[0] = t;
            }
            window[1] = t;
            let (kappa_now, frame) = self.tick(theta_cmd, Phase::Dwell { index }, observer)?;
            if k % every == 0 {
                kappa += kappa_now;
                kappa_samples += 1;
                scatter.add_kappa(&kappa_now);
            }
            if let Some(p) = frame {
                poses.add(&p);
                scatter.add_pose(&p);
            }
        }
        let mut data = ConfigurationData {
            theta_cmd: (*theta_cmd).into(),
            kappa: (kappa / f64::from(kappa_samples.max(1))).into(),
            sensor_pose: poses.mean().map(Into::into),
            kappa_samples,
            camera_frames: poses.count(),
            kappa_std: Some(scatter.kappa_std()),
            sensor_pose_std: scatter.pose_std(),
            sensor_pose_cov: scatter.pose_cov(),
            fault: None,
        };
        if let Some(checks) = &self.spec.checks {
            if poses.count() == 0 && checks.abort_on_lost_target {
                return Err(ExpError::TargetLost {
                    index,
                    time: self.robot.time(),
                });
            }
            data.fault = checks.judge(&data.theta_cmd, &data.kappa, &scatter);
        }
        self.index += 1;
        if observer.dwell(index, window, &data) == Flow::Stop {
            return Err(ExpError::Stopped {
                time: self.robot.time(),
            });
        }
        Ok((data, window))
    }

    /// One tick: read κ (start of tick), send the command, read the frame that arrived. Returns the
    /// readings after the tick (what a sample at this tick sees) and the frame.
    fn tick(
        &mut self,
        cmd: &Vec6,
        phase: Phase,
        observer: &mut dyn Observer,
    ) -> Result<(Vec6, Option<Vec6>)> {
        let t = self.robot.time();
        let kappa = self.robot.potentiometers();
        let truth = self.robot.true_state();
        self.robot
            .step_joint_command(cmd)
            .map_err(|e| cannot_assemble(e, phase))?;
        let frame = self.robot.camera();
        let after = self.robot.potentiometers();
        let mut r = Record::new(t, phase, kappa, *cmd);
        r.sensor_pose = frame;
        r.truth = truth;
        r.torque = self.robot.true_state().map(|s| s.torque);
        if observer.record(&r) == Flow::Stop {
            return Err(ExpError::Stopped {
                time: self.robot.time(),
            });
        }
        Ok((after, frame.filter(|p| p.iter().all(|v| v.is_finite()))))
    }
}

/// A robot that fails mid-configuration (diverged, came apart, kinematics failed) could not assemble
/// at that configuration: say which.
fn cannot_assemble(e: ExpError, phase: Phase) -> ExpError {
    let index = match phase {
        Phase::Move { index } | Phase::Settle { index } | Phase::Dwell { index } => index,
        _ => return e,
    };
    match e {
        ExpError::Sim(rss6_sim::SimError::Diverged { .. } | rss6_sim::SimError::Core(_))
        | ExpError::Core(_) => ExpError::CannotAssemble {
            index,
            why: e.to_string(),
        },
        other => other,
    }
}

/// Visits every configuration of `thetas` (rad, drive convention; `thetas[0]` is the initial
/// configuration) on `robot`, at rest under the command `start`, and records the means over `dwell`
/// seconds. `observer` sees every tick, each dwell's means and the progress after each configuration.
pub fn collect<R: Robot>(
    robot: R,
    start: Vec6,
    thetas: &[Vec6],
    dwell: f64,
    spec: &DwellSpec,
    observer: &mut dyn Observer,
) -> Result<CalibrationData> {
    if thetas.is_empty() {
        return Err(ExpError::InvalidInput(
            "thetas must contain at least one configuration".into(),
        ));
    }
    let mut session = DwellSession::new(robot, start, *spec);
    let mut data = CalibrationData::default();
    for (k, th) in thetas.iter().enumerate() {
        let (c, _) = session.measure_observed(th, dwell, observer)?;
        data.configurations.push(c);
        let p = Progress {
            done: (k + 1) as f64,
            total: thetas.len() as f64,
            time: session.robot.time(),
            finished: k + 1 == thetas.len(),
        };
        if observer.progress(&p) == Flow::Stop {
            return Err(ExpError::Stopped {
                time: session.robot.time(),
            });
        }
    }
    Ok(data)
}
