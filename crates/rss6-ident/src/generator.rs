//! Fast analytic data generator for the simulation study of §4.4.3: a true robot drawn with the
//! Table 4.2 error sizes, true FK for the pose, the sensor pose composed as
//! ᶜχ_t = (ᴼχ_C)⁻¹ ∘ χ_E ∘ ᴱχ_t (eq. 4.12), and Table 4.1 noise averaged over a dwell.

use crate::closure::fk_reading;
use crate::data::{ConfigurationData, RobotSource};
use crate::error::{IdentError, Result};
use crate::model::{parameter_scale, SIGMA_EXT_ANGLE, SIGMA_EXT_POSITION};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rss6_core::{compose, home_pose, pose_inverse, KinematicParams, Vec6, N_KIN_ERRORS};

/// Nominal pose ᴼχ_C of the optical CMM in the robot base frame (m, rad): 1.2 m in front of the robot,
/// 0.8 m up, looking down at the platform. Its error is drawn with Table 4.2's external sizes.
pub const NOMINAL_SENSOR_IN_BASE: [f64; 6] = [0.0, -1.2, 0.8, -2.2, 0.0, 0.1];
/// Nominal pose ᴱχ_t of the reflector target frame in the end-effector frame (m, rad).
pub const NOMINAL_TARGET_IN_EFFECTOR: [f64; 6] = [0.02, -0.01, 0.03, 0.0, 0.0, 0.0];

/// Measurement noise (Table 4.1) and sampling rates (§4.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// σ of one potentiometer sample (bit); Table 4.1: 0.2233.
    pub kappa: f64,
    /// σ of one camera-frame position component (m); Table 4.1: 0.0096 mm.
    pub position: f64,
    /// σ of one camera-frame Euler angle (rad); Table 4.1: 0.0261°.
    pub angle: f64,
    /// Potentiometer sampling rate (Hz); thesis: 500.
    pub kappa_rate: f64,
    /// Camera frame rate (Hz); thesis: 29.
    pub camera_rate: f64,
}

impl Default for NoiseModel {
    /// Table 4.1 at 500 Hz / 29 Hz.
    fn default() -> Self {
        NoiseModel {
            kappa: rss6_core::thesis::KAPPA_NOISE_BITS,
            position: rss6_core::thesis::POSE_POSITION_NOISE,
            angle: rss6_core::thesis::POSE_ANGLE_NOISE,
            kappa_rate: 500.0,
            camera_rate: 29.0,
        }
    }
}

impl NoiseModel {
    /// No noise at all (for exactness tests).
    pub fn none() -> Self {
        NoiseModel {
            kappa: 0.0,
            position: 0.0,
            angle: 0.0,
            ..Self::default()
        }
    }
}

/// The "real" robot of a simulation: true kinematics and true external poses.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrueRobot {
    /// True kinematic parameters.
    pub kp: KinematicParams,
    /// True ᴼχ_C (m, rad).
    pub sensor_in_base: Vec6,
    /// True ᴱχ_t (m, rad).
    pub target_in_effector: Vec6,
}

fn normal(rng: &mut impl Rng) -> f64 {
    StandardNormal.sample(rng)
}

impl TrueRobot {
    /// Draws a true robot around `nominal`: b ~ N(0, Table 4.2) and the external poses around
    /// [`NOMINAL_SENSOR_IN_BASE`] / [`NOMINAL_TARGET_IN_EFFECTOR`] with Table 4.2's external sizes.
    pub fn draw(nominal: &KinematicParams, rng: &mut impl Rng) -> Self {
        let mut b = [0.0; N_KIN_ERRORS];
        for (j, v) in b.iter_mut().enumerate() {
            *v = parameter_scale(j) * normal(rng);
        }
        TrueRobot {
            kp: nominal.with_errors(&b),
            sensor_in_base: perturb_external(&Vec6::from(NOMINAL_SENSOR_IN_BASE), rng),
            target_in_effector: perturb_external(&Vec6::from(NOMINAL_TARGET_IN_EFFECTOR), rng),
        }
    }

    /// Target pose in the sensor frame for end-effector pose χ_E: (ᴼχ_C)⁻¹ ∘ χ_E ∘ ᴱχ_t.
    pub fn sensor_pose(&self, pose: &Vec6) -> Vec6 {
        compose(
            &compose(&pose_inverse(&self.sensor_in_base), pose),
            &self.target_in_effector,
        )
    }

    /// True end-effector pose reached from potentiometer readings κ (bits), warm-started at `guess`.
    pub fn pose_from_reading(&self, kappa: &Vec6, guess: &Vec6) -> Result<Vec6> {
        fk_reading(&self.kp, kappa, guess).map_err(|e| {
            IdentError::Source(format!("true robot has no forward-kinematic solution: {e}"))
        })
    }
}

/// An external pose perturbed with Table 4.2's sizes (0.5 mm, 0.017 rad per component).
pub fn perturb_external(pose: &Vec6, rng: &mut impl Rng) -> Vec6 {
    Vec6::from_fn(|k, _| {
        let s = if k < 3 {
            SIGMA_EXT_POSITION
        } else {
            SIGMA_EXT_ANGLE
        };
        pose[k] + s * normal(rng)
    })
}

/// Analytic stand-in for the plant: the robot is commanded in the nominal joint convention
/// (κ_cmd = (θ_cmd − Δθ_nom)/η_nom, as the plant's joint servo does), reaches the true FK pose of those
/// readings, and each dwell returns means whose noise is Table 4.1's σ/√(samples).
#[derive(Debug, Clone)]
pub struct AnalyticRobot {
    /// The true robot.
    pub truth: TrueRobot,
    /// The nominal parameters that define the joint convention of the commands.
    pub nominal: KinematicParams,
    /// Noise and rates.
    pub noise: NoiseModel,
    rng: ChaCha8Rng,
    last_pose: Vec6,
}

impl AnalyticRobot {
    /// A generator for `truth`, commanded in the convention of `nominal`, with its own noise seed.
    pub fn new(truth: TrueRobot, nominal: KinematicParams, noise: NoiseModel, seed: u64) -> Self {
        AnalyticRobot {
            truth,
            nominal,
            noise,
            rng: ChaCha8Rng::seed_from_u64(seed),
            last_pose: home_pose(),
        }
    }
}

impl RobotSource for AnalyticRobot {
    fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData> {
        if dwell.is_nan() || dwell < 0.0 || theta_cmd.iter().any(|t| !t.is_finite()) {
            return Err(IdentError::InvalidInput(format!(
                "dwell must be >= 0 and the command finite (dwell {dwell}, command {theta_cmd:?})"
            )));
        }
        let kappa = self.nominal.reading_from_theta(theta_cmd);
        // warm start at the nominal pose of the command (close to the true one)
        let guess = fk_reading(&self.nominal, &kappa, &home_pose()).unwrap_or(self.last_pose);
        let pose = self.truth.pose_from_reading(&kappa, &guess)?;
        self.last_pose = pose;
        let n_k = (dwell * self.noise.kappa_rate).floor().max(1.0);
        let n_c = (dwell * self.noise.camera_rate).floor().max(1.0);
        let sk = self.noise.kappa / n_k.sqrt();
        let (sp, sa) = (
            self.noise.position / n_c.sqrt(),
            self.noise.angle / n_c.sqrt(),
        );
        let rng = &mut self.rng;
        let kappa_meas = kappa.map(|k| k + sk * normal(rng));
        let mut cam = self.truth.sensor_pose(&pose);
        for k in 0..6 {
            cam[k] += if k < 3 { sp } else { sa } * normal(rng);
        }
        Ok(ConfigurationData {
            theta_cmd: (*theta_cmd).into(),
            kappa: kappa_meas.into(),
            sensor_pose: Some(cam.into()),
            kappa_samples: n_k as u32,
            camera_frames: n_c as u32,
            // the scatter a robot at rest shows: one sample's noise
            kappa_std: Some([self.noise.kappa; 6]),
            sensor_pose_std: Some(core::array::from_fn(|k| {
                if k < 3 {
                    self.noise.position
                } else {
                    self.noise.angle
                }
            })),
            // independent components (the analytic generator's noise is per axis)
            sensor_pose_cov: Some(core::array::from_fn(|r| {
                core::array::from_fn(|c| {
                    let s = if r < 3 {
                        self.noise.position
                    } else {
                        self.noise.angle
                    };
                    if r == c {
                        s * s
                    } else {
                        0.0
                    }
                })
            })),
            fault: None,
        })
    }
}
