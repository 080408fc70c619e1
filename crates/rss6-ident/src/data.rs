//! Calibration data (§4.4.3, §4.5): for every configuration l = 0..m (0 = the initial configuration)
//! the mean potentiometer readings κ^l and the mean sensor pose ᶜχ_t^l over a dwell, and the sources
//! that produce them.

use crate::error::{IdentError, Result};
use rss6_core::{Vec6, LEGS};
use serde::{Deserialize, Serialize};

/// One calibration configuration: the means over a dwell at rest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConfigurationData {
    /// Commanded joint angles θ_cmd in the nominal joint convention (rad); informational.
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

/// Anything that can hold the robot at a commanded configuration and report mean readings: the rapier
/// plant (through [`Stepped`]), the analytic generator ([`crate::AnalyticRobot`]) or a log reader.
pub trait RobotSource {
    /// Moves to `theta_cmd` (rad, nominal joint convention), waits until at rest, then averages the
    /// potentiometers and the camera over `dwell` seconds.
    fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData>;
}

/// A robot driven tick by tick, as the rapier plant is (`rss6_sim::Plant`): one joint command per
/// tick of `dt()` seconds, potentiometers readable at any tick, camera frames at ~29 Hz.
pub trait SteppedRobot {
    /// Tick length (s), e.g. 1e-3 for the 1 kHz joint loop.
    fn dt(&self) -> f64;
    /// Applies one tick with the joint command θ_cmd (rad, nominal convention).
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()>;
    /// ᶜχ_t if a camera frame completed on the last tick, else `None`.
    fn camera(&mut self) -> Option<Vec6>;
    /// Current potentiometer readings κ (bits).
    fn potentiometers(&mut self) -> Vec6;
}

/// Adapter turning a [`SteppedRobot`] into a [`RobotSource`]: a smooth move, a settling wait, then a
/// dwell during which the potentiometers are sampled at `kappa_rate` and every camera frame is kept.
#[derive(Debug)]
pub struct Stepped<R> {
    /// The driven robot.
    pub robot: R,
    /// Duration of the cosine-blended move between configurations (s).
    pub move_time: f64,
    /// Wait at the target before averaging starts (s).
    pub settle_time: f64,
    /// Potentiometer sampling rate during the dwell (Hz); thesis: 500 Hz.
    pub kappa_rate: f64,
    last_cmd: Vec6,
}

impl<R: SteppedRobot> Stepped<R> {
    /// Wraps `robot`, assumed at rest at the command `start` (rad). Defaults: 1 s move, 0.5 s settle,
    /// 500 Hz potentiometer sampling.
    pub fn new(robot: R, start: Vec6) -> Self {
        Stepped {
            robot,
            move_time: 1.0,
            settle_time: 0.5,
            kappa_rate: 500.0,
            last_cmd: start,
        }
    }
}

/// Running mean of poses; angles are unwrapped against the first sample so ±π causes no jump.
#[derive(Debug, Default)]
pub(crate) struct PoseMean {
    first: Option<Vec6>,
    sum: Vec6,
    n: u32,
}

impl PoseMean {
    pub(crate) fn add(&mut self, p: &Vec6) {
        let first = *self.first.get_or_insert(*p);
        let mut d = p - first;
        for k in 3..6 {
            d[k] = rss6_core::wrap_angle(d[k]);
        }
        self.sum += d;
        self.n += 1;
    }

    pub(crate) fn mean(&self) -> Option<Vec6> {
        let first = self.first?;
        let mut m = first + self.sum / f64::from(self.n);
        for k in 3..6 {
            m[k] = rss6_core::wrap_angle(m[k]);
        }
        Some(m)
    }
}

impl<R: SteppedRobot> RobotSource for Stepped<R> {
    fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData> {
        if dwell.is_nan() || dwell <= 0.0 || theta_cmd.iter().any(|t| !t.is_finite()) {
            return Err(IdentError::InvalidInput(format!(
                "dwell must be > 0 and the command finite (dwell {dwell}, command {theta_cmd:?})"
            )));
        }
        let dt = self.robot.dt();
        let ticks = |t: f64| (t / dt).round().max(0.0) as usize;
        let from = self.last_cmd;
        let n_move = ticks(self.move_time).max(1);
        for k in 1..=n_move {
            let s = 0.5 - 0.5 * (std::f64::consts::PI * k as f64 / n_move as f64).cos();
            self.robot
                .step_joint_command(&(from + (theta_cmd - from) * s))?;
        }
        self.last_cmd = *theta_cmd;
        for _ in 0..ticks(self.settle_time) {
            self.robot.step_joint_command(theta_cmd)?;
        }
        let every = ((1.0 / (self.kappa_rate * dt)).round() as usize).max(1);
        let mut kappa = Vec6::zeros();
        let mut kappa_samples = 0u32;
        let mut poses = PoseMean::default();
        for k in 0..ticks(dwell).max(1) {
            self.robot.step_joint_command(theta_cmd)?;
            if k % every == 0 {
                kappa += self.robot.potentiometers();
                kappa_samples += 1;
            }
            if let Some(p) = self.robot.camera() {
                if p.iter().all(|v| v.is_finite()) {
                    poses.add(&p);
                }
            }
        }
        let kappa = kappa / f64::from(kappa_samples.max(1));
        Ok(ConfigurationData {
            theta_cmd: (*theta_cmd).into(),
            kappa: kappa.into(),
            sensor_pose: poses.mean().map(Into::into),
            kappa_samples,
            camera_frames: poses.n,
        })
    }
}

/// Visits every configuration of `thetas` (rad, nominal convention; `thetas[0]` is the initial
/// configuration) and records the means over `dwell` seconds.
pub fn collect(
    source: &mut dyn RobotSource,
    thetas: &[Vec6],
    dwell: f64,
) -> Result<CalibrationData> {
    collect_with_progress(source, thetas, dwell, &mut |_, _| {})
}

/// [`collect`] with a progress callback `progress(done, total)` after each configuration.
pub fn collect_with_progress(
    source: &mut dyn RobotSource,
    thetas: &[Vec6],
    dwell: f64,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<CalibrationData> {
    let mut data = CalibrationData::default();
    for (k, th) in thetas.iter().enumerate() {
        data.configurations.push(source.measure(th, dwell)?);
        progress(k + 1, thetas.len());
    }
    Ok(data)
}
