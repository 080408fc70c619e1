//! Collection checks of a calibration dwell: did the robot reach the command, and was it at rest while
//! the means were taken? A configuration that fails is kept in the data with its [`DwellFault`]; the
//! calibration solvers leave it out unless told otherwise.

use rss6_core::{KinematicParams, Vec6, LEGS};
use rss6_sim::{CMM_ANGLE_NOISE, CMM_POSITION_NOISE, POT_NOISE_BITS};
use serde::{Deserialize, Serialize};

/// The drive's joint convention (eq. 4.2 with the nominal parameters): the drive tracks the reading
/// κ_cmd = (θ_cmd − Δθ)/η.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveConvention {
    /// η (rad/bit) per joint.
    pub eta: [f64; LEGS],
    /// Δθ (rad) per joint.
    pub dtheta: [f64; LEGS],
}

impl DriveConvention {
    /// The convention of the parameters the drive was set up with (the nominal model).
    pub fn of(params: &KinematicParams) -> Self {
        DriveConvention {
            eta: params.eta,
            dtheta: params.dtheta,
        }
    }

    /// κ_cmd (bit) of a command θ_cmd (rad).
    pub fn reading(&self, theta_cmd: &[f64; LEGS]) -> [f64; LEGS] {
        core::array::from_fn(|i| (theta_cmd[i] - self.dtheta[i]) / self.eta[i])
    }
}

/// What the dwell runner checks per configuration (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DwellChecks {
    /// The drive's convention; `None` skips the reach check (the command cannot be turned into a
    /// reading).
    pub drive: Option<DriveConvention>,
    /// Largest accepted |κ̄ − κ_cmd| per joint (bit). Default 2 bit (0.09° with η = π/4096): twice the
    /// drive's 1-bit resolution. On the rapier plant a reached command ends within 0.05 bit of it after
    /// the default 0.5 s settle (96 dwells measured), while a joint held back by the geometry misses it
    /// by tens to hundreds of bits (docs/calibration.md).
    pub reach_tolerance: f64,
    /// Table 4.1 σ of one potentiometer sample (bit).
    pub sigma_kappa: f64,
    /// Table 4.1 σ of one camera position component (m).
    pub sigma_position: f64,
    /// Table 4.1 σ of one camera angle (rad).
    pub sigma_angle: f64,
    /// The robot is at rest if every scatter (sample standard deviation over the dwell) is at most
    /// `rest_factor` × its σ. Default 3. Measured at rest on the rapier plant (96 dwells of 2 s): the
    /// potentiometers scatter 1.15–1.5 σ_κ (the drive's PID jitters on the noisy reading), the stereo
    /// CMM 0.4–0.8 σ in x, y, 1.4–2.1 σ in z (depth) and 0.4–1.5 σ in the angles.
    pub rest_factor: f64,
    /// Abort with [`crate::ExpError::TargetLost`] when no camera frame arrived during a dwell
    /// (default `true`); `false` keeps such a configuration with `sensor_pose: None`.
    pub abort_on_lost_target: bool,
}

impl Default for DwellChecks {
    /// Table 4.1 noise, 2-bit reach tolerance, rest factor 3, no drive convention (reach unchecked).
    fn default() -> Self {
        DwellChecks {
            drive: None,
            reach_tolerance: 2.0,
            sigma_kappa: POT_NOISE_BITS,
            sigma_position: CMM_POSITION_NOISE,
            sigma_angle: CMM_ANGLE_NOISE,
            rest_factor: 3.0,
            abort_on_lost_target: true,
        }
    }
}

impl DwellChecks {
    /// The default checks with the reach check in the convention of `drive` (the nominal model).
    pub fn with_drive(drive: &KinematicParams) -> Self {
        DwellChecks {
            drive: Some(DriveConvention::of(drive)),
            ..Self::default()
        }
    }

    /// The first failed check of a dwell, if any. `kappa` is the mean reading, `scatter` the dwell's
    /// scatter.
    pub fn judge(
        &self,
        theta_cmd: &[f64; LEGS],
        kappa: &[f64; LEGS],
        scatter: &Scatter,
    ) -> Option<DwellFault> {
        if let Some(drive) = &self.drive {
            let cmd = drive.reading(theta_cmd);
            let (joint, error) = (0..LEGS)
                .map(|i| (i, kappa[i] - cmd[i]))
                .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
            // NaN fails the check too
            if error.abs() > self.reach_tolerance || error.is_nan() {
                return Some(DwellFault::Unreached {
                    joint,
                    error_bits: error,
                    tolerance_bits: self.reach_tolerance,
                });
            }
        }
        let limits = [
            self.sigma_kappa,
            self.sigma_position,
            self.sigma_position,
            self.sigma_position,
            self.sigma_angle,
            self.sigma_angle,
            self.sigma_angle,
        ];
        let kappa_std = scatter.kappa_std();
        let pose_std = scatter.pose_std();
        let worst_kappa = kappa_std.iter().copied().fold(0.0, f64::max);
        let mut channels = vec![(RestChannel::Potentiometer, worst_kappa, limits[0])];
        if let Some(p) = pose_std {
            for (k, ch) in [
                RestChannel::X,
                RestChannel::Y,
                RestChannel::Z,
                RestChannel::Alpha,
                RestChannel::Beta,
                RestChannel::Gamma,
            ]
            .into_iter()
            .enumerate()
            {
                channels.push((ch, p[k], limits[k + 1]));
            }
        }
        channels
            .into_iter()
            .map(|(channel, s, sigma)| (channel, s, sigma, s / sigma))
            .filter(|(_, _, _, ratio)| *ratio > self.rest_factor || ratio.is_nan())
            .max_by(|a, b| a.3.total_cmp(&b.3))
            .map(|(channel, scatter, sigma, _)| DwellFault::Moving {
                channel,
                scatter,
                tolerance: self.rest_factor * sigma,
            })
    }
}

/// Which signal showed that the robot moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum RestChannel {
    /// A potentiometer (the worst joint).
    Potentiometer,
    /// Camera x.
    X,
    /// Camera y.
    Y,
    /// Camera z.
    Z,
    /// Camera α.
    Alpha,
    /// Camera β.
    Beta,
    /// Camera γ.
    Gamma,
}

/// Why a configuration failed the collection checks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[non_exhaustive]
pub enum DwellFault {
    /// The drive did not reach the command: the mean reading of `joint` is `error_bits` off the
    /// commanded reading (the robot is somewhere the data cannot say).
    Unreached {
        /// Joint (0-based).
        joint: usize,
        /// κ̄ − κ_cmd (bit).
        error_bits: f64,
        /// The tolerance (bit).
        tolerance_bits: f64,
    },
    /// The robot moved during the dwell: the scatter of `channel` exceeds the noise of Table 4.1.
    Moving {
        /// The signal.
        channel: RestChannel,
        /// Its sample standard deviation over the dwell (bit, m or rad).
        scatter: f64,
        /// The largest scatter accepted.
        tolerance: f64,
    },
}

impl core::fmt::Display for DwellFault {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DwellFault::Unreached {
                joint,
                error_bits,
                tolerance_bits,
            } => write!(
                f,
                "command not reached: joint {} reads {error_bits:+.2} bit off its command \
                 (tolerance {tolerance_bits} bit)",
                joint + 1
            ),
            DwellFault::Moving {
                channel,
                scatter,
                tolerance,
            } => write!(
                f,
                "not at rest during the dwell: {channel:?} scatter {scatter:.3e} > {tolerance:.3e}"
            ),
        }
    }
}

/// Running scatter of a dwell's potentiometer samples and camera frames (Welford's algorithm; camera
/// values relative to the first frame, angles wrapped, so ±π is harmless).
#[derive(Debug, Clone, Default)]
pub struct Scatter {
    kappa: Moments,
    pose: Moments,
    /// Co-moments Σ (x − x̄)(x − x̄)ᵀ of the camera components (Welford's update).
    pose_cross: [[f64; 6]; 6],
    first_pose: Option<Vec6>,
}

#[derive(Debug, Clone, Default)]
struct Moments {
    n: u32,
    mean: [f64; LEGS],
    m2: [f64; LEGS],
}

impl Moments {
    fn add(&mut self, v: &Vec6) {
        self.n += 1;
        let n = f64::from(self.n);
        for k in 0..LEGS {
            let d = v[k] - self.mean[k];
            self.mean[k] += d / n;
            self.m2[k] += d * (v[k] - self.mean[k]);
        }
    }

    fn std(&self) -> Option<[f64; LEGS]> {
        (self.n >= 2).then(|| core::array::from_fn(|k| (self.m2[k] / f64::from(self.n - 1)).sqrt()))
    }
}

impl Scatter {
    /// Adds one potentiometer sample (bit).
    pub fn add_kappa(&mut self, kappa: &Vec6) {
        self.kappa.add(kappa);
    }

    /// Adds one finite camera frame ᶜχ_t (m, rad).
    pub fn add_pose(&mut self, pose: &Vec6) {
        let first = *self.first_pose.get_or_insert(*pose);
        let mut d = pose - first;
        for a in d.iter_mut().skip(3) {
            *a = (*a + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU)
                - core::f64::consts::PI;
        }
        let before: [f64; 6] = core::array::from_fn(|k| d[k] - self.pose.mean[k]);
        self.pose.add(&d);
        for (r, row) in self.pose_cross.iter_mut().enumerate() {
            for (c, v) in row.iter_mut().enumerate() {
                *v += before[r] * (d[c] - self.pose.mean[c]);
            }
        }
    }

    /// Sample standard deviation of each joint's reading (bit); zeros with fewer than 2 samples.
    pub fn kappa_std(&self) -> [f64; LEGS] {
        self.kappa.std().unwrap_or([0.0; LEGS])
    }

    /// Sample standard deviation of each camera component (m, rad); `None` with fewer than 2 frames.
    pub fn pose_std(&self) -> Option<[f64; 6]> {
        self.pose.std()
    }

    /// Sample covariance of the camera components [x, y, z, α, β, γ] (m², m·rad, rad²), symmetric;
    /// `None` with fewer than 2 frames. Its diagonal is the square of [`Self::pose_std`].
    pub fn pose_cov(&self) -> Option<[[f64; 6]; 6]> {
        let n = self.pose.n;
        (n >= 2).then(|| {
            let d = f64::from(n - 1);
            core::array::from_fn(|r| {
                core::array::from_fn(|c| 0.5 * (self.pose_cross[r][c] + self.pose_cross[c][r]) / d)
            })
        })
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_pose_covariance_is_the_two_pass_sample_covariance_across_pi() {
        // frames around γ = π (wrapping between +π and −π), with correlated x and β
        let frames: Vec<Vec6> = (0..7)
            .map(|k| {
                let u = f64::from(k) - 3.0 + 0.1 * f64::from(k * k % 5);
                let g = core::f64::consts::PI + 1e-4 * (f64::from(k % 3) - 1.0);
                Vec6::new(0.1 + 1e-5 * u, 0.2, 1.0 - 2e-6 * u * u, 0.0, -3e-4 * u, g)
            })
            .collect();
        let mut s = Scatter::default();
        for f in &frames {
            s.add_pose(f);
        }
        let cov = s.pose_cov().unwrap();
        // two passes on the unwrapped values
        let unwrapped: Vec<Vec6> = frames
            .iter()
            .map(|f| {
                let mut g = *f;
                g[5] = (g[5] - frames[0][5] + core::f64::consts::PI)
                    .rem_euclid(core::f64::consts::TAU)
                    - core::f64::consts::PI;
                g
            })
            .collect();
        let mean = unwrapped.iter().sum::<Vec6>() / 7.0;
        let std = s.pose_std().unwrap();
        for r in 0..6 {
            for c in 0..6 {
                let want = unwrapped
                    .iter()
                    .map(|f| (f[r] - mean[r]) * (f[c] - mean[c]))
                    .sum::<f64>()
                    / 6.0;
                let scale = (cov[r][r] * cov[c][c]).sqrt().max(1e-300);
                assert!(
                    (cov[r][c] - want).abs() <= 1e-9 * scale + 1e-30,
                    "{r} {c}: {} vs {want}",
                    cov[r][c]
                );
                assert_eq!(cov[r][c], cov[c][r]);
            }
            assert!((cov[r][r].sqrt() - std[r]).abs() <= 1e-12 * std[r].max(1e-300));
        }
        // x and β move together exactly: correlation −1
        assert!((cov[0][4] / (cov[0][0] * cov[4][4]).sqrt() + 1.0).abs() < 1e-9);
        assert!(Scatter::default().pose_cov().is_none());
    }
}
