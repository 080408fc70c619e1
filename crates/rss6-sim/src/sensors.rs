//! Sensor models: the potentiometers (eq. 4.2, §4.5) and the optical CMM (§4.2.2), with the noise of
//! Table 4.1.
//!
//! # Optical CMM
//!
//! A C-Track-like stereo tracker: two pinhole cameras in the sensor frame ΣC look at n ≥ 4 reflectors
//! fixed on the platform (their coordinates are given in the target frame Σt, which sits at ᴱχ_t on
//! the end effector). Each frame: project every reflector into both cameras, add Gaussian pixel noise,
//! triangulate each reflector (midpoint of the two back-projected rays), then fit the rigid transform
//! from the reflector model to the triangulated points by SVD (Kabsch). The result is ᶜχ_t, the target
//! frame in the sensor frame, as the C-Track reports it.

use crate::error::{Result, SimError};
use nalgebra::{Isometry3, Matrix3, Point3, Translation3, UnitQuaternion};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rss6_core::{isometry_to_pose, pose_to_isometry, Vec3, Vec6};
use serde::{Deserialize, Serialize};

/// Potentiometer noise std of Table 4.1 (bit).
pub const POT_NOISE_BITS: f64 = rss6_core::thesis::KAPPA_NOISE_BITS;
/// Pose noise of Table 4.1: position std (m) per axis.
pub const CMM_POSITION_NOISE: f64 = rss6_core::thesis::POSE_POSITION_NOISE;
/// Pose noise of Table 4.1: angle std (rad) per axis (0.0261°).
pub const CMM_ANGLE_NOISE: f64 = rss6_core::thesis::POSE_ANGLE_NOISE;

/// One pinhole camera of the stereo head.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Camera pose in the sensor frame ΣC (χ convention; the camera looks along its +z, x right, y down).
    pub pose_in_sensor: [f64; 6],
    /// Focal length (px).
    pub focal: f64,
    /// Principal point (px).
    pub principal: [f64; 2],
    /// Image size (px); reflectors outside the image are an error.
    pub size: [f64; 2],
}

impl Camera {
    fn iso(&self) -> Isometry3<f64> {
        pose_to_isometry(&Vec6::from(self.pose_in_sensor))
    }

    /// Pixel coordinates of a point given in ΣC (None if behind the camera or outside the image).
    pub fn project(&self, p: &Vec3) -> Option<[f64; 2]> {
        let pc = self.iso().inverse_transform_point(&Point3::from(*p));
        if pc.z <= 0.0 {
            return None;
        }
        let u = self.focal * pc.x / pc.z + self.principal[0];
        let v = self.focal * pc.y / pc.z + self.principal[1];
        if u < 0.0 || v < 0.0 || u > self.size[0] || v > self.size[1] {
            return None;
        }
        Some([u, v])
    }

    /// The back-projected ray of a pixel: (origin, unit direction) in ΣC.
    pub fn ray(&self, px: &[f64; 2]) -> (Vec3, Vec3) {
        let iso = self.iso();
        let d = Vec3::new(
            (px[0] - self.principal[0]) / self.focal,
            (px[1] - self.principal[1]) / self.focal,
            1.0,
        );
        (iso.translation.vector, (iso.rotation * d).normalize())
    }
}

/// Configuration of the optical CMM.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CmmConfig {
    /// The two cameras.
    pub cameras: [Camera; 2],
    /// Reflector positions in the target frame Σt (m); at least 4, not collinear.
    pub reflectors: Vec<[f64; 3]>,
    /// Pixel noise std (px), independent per image coordinate.
    pub pixel_noise: f64,
    /// Frame period (s); 0.033 s ≈ 30.3 Hz.
    pub period: f64,
    /// Latency from exposure to the reading being available (s).
    pub latency: f64,
    /// Pose-space noise instead of the stereo model: `Some([σ_position (m), σ_angle (rad)])` adds
    /// independent Gaussian noise to each axis of the true ᶜχ_t (Table 4.1 per axis:
    /// [`CMM_POSITION_NOISE`], [`CMM_ANGLE_NOISE`]), with no projection, triangulation or dropped
    /// frames. `None` (default): the stereo tracker.
    #[serde(default)]
    pub pose_noise: Option<[f64; 2]>,
}

impl CmmConfig {
    /// Default stereo head: baseline 0.8 m, f = 4000 px, 2048 × 2048 images, both cameras toed in to
    /// converge at 2.05 m (where the robot is, see [`crate::default_sensor_in_base`]); 6 reflectors on
    /// a 2.3 cm-radius target (±1 cm in depth); pixel noise chosen so the pose noise matches Table 4.1 (see `docs/sim.md`).
    pub fn c_track() -> Self {
        let (b, d): (f64, f64) = (0.8, 2.05);
        let toe = (0.5 * b / d).atan();
        let cam = |x: f64, yaw: f64| Camera {
            pose_in_sensor: [x, 0.0, 0.0, 0.0, yaw, 0.0],
            focal: 4000.0,
            principal: [1024.0, 1024.0],
            size: [2048.0, 2048.0],
        };
        let r = TARGET_RADIUS;
        let reflectors = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::PI / 3.0;
                let h = if k % 2 == 0 { 0.01 } else { -0.01 };
                [r * a.cos(), r * a.sin(), h]
            })
            .collect();
        CmmConfig {
            cameras: [cam(-0.5 * b, toe), cam(0.5 * b, -toe)],
            reflectors,
            pixel_noise: DEFAULT_PIXEL_NOISE,
            period: rss6_core::thesis::CONTROL_PERIOD,
            latency: 0.0,
            pose_noise: None,
        }
    }

    /// The stereo head's timing with Table 4.1's pose noise applied per axis of ᶜχ_t (see
    /// [`CmmConfig::pose_noise`]): the thesis's noise model, isotropic where the stereo model is not.
    pub fn table_4_1() -> Self {
        CmmConfig {
            pose_noise: Some([CMM_POSITION_NOISE, CMM_ANGLE_NOISE]),
            ..Self::c_track()
        }
    }

    /// Checks the configuration.
    pub fn validate(&self) -> Result<()> {
        if self.reflectors.len() < 4 {
            return Err(SimError::InvalidConfig(
                "the CMM needs at least 4 reflectors".into(),
            ));
        }
        if let Some([p, a]) = self.pose_noise {
            if !(p.is_finite() && p >= 0.0 && a.is_finite() && a >= 0.0) {
                return Err(SimError::InvalidConfig(
                    "CMM pose noise must be finite and >= 0".into(),
                ));
            }
        }
        if !(self.period > 0.0 && self.latency >= 0.0 && self.pixel_noise >= 0.0) {
            return Err(SimError::InvalidConfig(
                "CMM period must be > 0, latency and pixel noise >= 0".into(),
            ));
        }
        Ok(())
    }
}

/// Radius of the default reflector target (m).
pub const TARGET_RADIUS: f64 = 0.023;
/// Default pixel noise (px), tuned so the pose noise matches Table 4.1.
pub const DEFAULT_PIXEL_NOISE: f64 = 0.021;

/// Closest-approach midpoint of two rays (o + s d).
fn triangulate(o1: &Vec3, d1: &Vec3, o2: &Vec3, d2: &Vec3) -> Option<Vec3> {
    let w = o1 - o2;
    let (a, b, c) = (d1.dot(d1), d1.dot(d2), d2.dot(d2));
    let (d, e) = (d1.dot(&w), d2.dot(&w));
    let den = a * c - b * b;
    if den.abs() < 1e-12 {
        return None;
    }
    let s = (b * e - c * d) / den;
    let t = (a * e - b * d) / den;
    Some(0.5 * ((o1 + d1 * s) + (o2 + d2 * t)))
}

/// Rigid transform T with `measured ≈ T·model` by SVD (Kabsch), least squares over all points.
pub fn kabsch(model: &[Vec3], measured: &[Vec3]) -> Result<Isometry3<f64>> {
    if model.len() != measured.len() || model.len() < 3 {
        return Err(SimError::Cmm("Kabsch needs >= 3 matched points".into()));
    }
    let n = model.len() as f64;
    let cm = model.iter().sum::<Vec3>() / n;
    let cs = measured.iter().sum::<Vec3>() / n;
    let mut h = Matrix3::zeros();
    for (p, q) in model.iter().zip(measured) {
        h += (p - cm) * (q - cs).transpose();
    }
    let svd = h.svd(true, true);
    let (u, vt) = match (svd.u, svd.v_t) {
        (Some(u), Some(vt)) => (u, vt),
        _ => return Err(SimError::Cmm("SVD failed".into())),
    };
    if svd.singular_values[1] < 1e-12 * svd.singular_values[0].max(1e-300) {
        return Err(SimError::Cmm("reflectors are collinear".into()));
    }
    let v = vt.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vec3::new(1.0, 1.0, d)) * u.transpose();
    let rot = UnitQuaternion::from_matrix(&r);
    let t = cs - rot * cm;
    Ok(Isometry3::from_parts(Translation3::from(t), rot))
}

/// The optical CMM at run time: frame clock, latency queue and noise.
#[derive(Debug, Clone)]
pub(crate) struct OpticalCmm {
    cfg: CmmConfig,
    latency: f64,
    next_capture: f64,
    pending: std::collections::VecDeque<(f64, Vec6)>,
    out: Option<Vec6>,
    rng: ChaCha8Rng,
    dropped: u64,
}

impl OpticalCmm {
    pub(crate) fn new(cfg: CmmConfig, extra_latency: f64, rng: ChaCha8Rng) -> Self {
        let latency = cfg.latency + extra_latency;
        OpticalCmm {
            cfg,
            latency,
            next_capture: 0.0,
            pending: std::collections::VecDeque::with_capacity(16),
            out: None,
            rng,
            dropped: 0,
        }
    }

    pub(crate) fn reset(&mut self, time: f64) {
        self.next_capture = time;
        self.pending.clear();
        self.out = None;
    }

    /// One measurement of ᶜχ_t from the true ᶜχ_t (noise through pixels, triangulation, Kabsch).
    pub(crate) fn measure(&mut self, c_chi_t: &Vec6) -> Result<Vec6> {
        measure_with(&self.cfg, c_chi_t, &mut self.rng)
    }

    /// Advances the frame clock to `time` (s). `truth` gives the true ᶜχ_t now (called only when a
    /// frame is captured).
    pub(crate) fn tick(&mut self, time: f64, truth: impl FnOnce() -> Vec6) -> Result<()> {
        const EPS: f64 = 1e-9;
        if time + EPS >= self.next_capture {
            // A frame in which the target cannot be measured (a reflector outside an image,
            // degenerate geometry) is dropped, as a tracker drops occluded frames.
            match self.measure(&truth()) {
                Ok(m) => self
                    .pending
                    .push_back((self.next_capture + self.latency, m)),
                Err(SimError::Cmm(_)) => self.dropped += 1,
                Err(e) => return Err(e),
            }
            self.next_capture += self.cfg.period;
        }
        self.out = None;
        while let Some(&(t_avail, m)) = self.pending.front() {
            if t_avail <= time + EPS {
                self.out = Some(m);
                self.pending.pop_front();
            } else {
                break;
            }
        }
        Ok(())
    }

    pub(crate) fn output(&self) -> Option<Vec6> {
        self.out
    }

    /// Frames dropped since construction (target not measurable).
    pub(crate) fn dropped(&self) -> u64 {
        self.dropped
    }

    pub(crate) fn latency(&self) -> f64 {
        self.latency
    }
}

/// Simulates one CMM frame with the given configuration and RNG.
pub fn measure_with<R: Rng>(cfg: &CmmConfig, c_chi_t: &Vec6, rng: &mut R) -> Result<Vec6> {
    if let Some([sp, sa]) = cfg.pose_noise {
        let np = Normal::new(0.0, sp).map_err(|e| SimError::InvalidConfig(e.to_string()))?;
        let na = Normal::new(0.0, sa).map_err(|e| SimError::InvalidConfig(e.to_string()))?;
        return Ok(Vec6::from_fn(|i, _| {
            let n = if i < 3 { &np } else { &na };
            c_chi_t[i] + n.sample(rng)
        }));
    }
    let iso = pose_to_isometry(c_chi_t);
    let noise = Normal::new(0.0, cfg.pixel_noise.max(0.0))
        .map_err(|e| SimError::InvalidConfig(e.to_string()))?;
    let mut model = Vec::with_capacity(cfg.reflectors.len());
    let mut meas = Vec::with_capacity(cfg.reflectors.len());
    for r in &cfg.reflectors {
        let pt = Vec3::from(*r);
        let ps = (iso * Point3::from(pt)).coords;
        let mut rays = [(Vec3::zeros(), Vec3::zeros()); 2];
        for (ray, cam) in rays.iter_mut().zip(cfg.cameras.iter()) {
            let px = cam
                .project(&ps)
                .ok_or_else(|| SimError::Cmm("a reflector is outside a camera's view".into()))?;
            let noisy = [px[0] + noise.sample(rng), px[1] + noise.sample(rng)];
            *ray = cam.ray(&noisy);
        }
        let p = triangulate(&rays[0].0, &rays[0].1, &rays[1].0, &rays[1].1)
            .ok_or_else(|| SimError::Cmm("parallel rays".into()))?;
        model.push(pt);
        meas.push(p);
    }
    Ok(isometry_to_pose(&kabsch(&model, &meas)?))
}

/// Potentiometers: κ = (θ − Δθ(t))/η + noise (eq. 4.2), sampled every `period_ticks` joint-loop ticks.
/// Δθ(t) = Δθ + ṙ·t drifts linearly (the `joint_offset_drift` effect; ṙ = 0 without it), t the time
/// the sensors have run since the robot was built (a reset does not rewind it: the sensor keeps ageing).
#[derive(Debug, Clone)]
pub(crate) struct Potentiometers {
    eta: [f64; 6],
    dtheta: [f64; 6],
    /// Drift rate of Δθ per joint (rad/s).
    drift: [f64; 6],
    dt: f64,
    /// Joint-loop ticks run since construction (not reset).
    age_ticks: u64,
    noise: Normal<f64>,
    period_ticks: u64,
    last: Vec6,
    rng: ChaCha8Rng,
}

impl Potentiometers {
    pub(crate) fn new(
        eta: [f64; 6],
        dtheta: [f64; 6],
        sigma_bits: f64,
        period_ticks: u64,
        rng: ChaCha8Rng,
    ) -> Result<Self> {
        let noise = Normal::new(0.0, sigma_bits)
            .map_err(|e| SimError::InvalidConfig(format!("potentiometer noise: {e}")))?;
        Ok(Potentiometers {
            eta,
            dtheta,
            drift: [0.0; 6],
            dt: 0.0,
            age_ticks: 0,
            noise,
            period_ticks: period_ticks.max(1),
            last: Vec6::zeros(),
            rng,
        })
    }

    /// Lets Δθ drift at `rate` (rad/s per joint) with joint-loop period `dt` (s).
    pub(crate) fn with_drift(mut self, rate: [f64; 6], dt: f64) -> Self {
        self.drift = rate;
        self.dt = dt;
        self
    }

    /// Samples if `tick` is a sampling tick; returns the held reading (bit). `tick` > 0 is a
    /// joint-loop step (the sensors age by one tick); `tick` = 0 is a reset, which does not age them.
    pub(crate) fn tick(&mut self, tick: u64, theta: &Vec6) -> Vec6 {
        if tick > 0 {
            self.age_ticks += 1;
        }
        if tick % self.period_ticks == 0 {
            let age = self.age_ticks as f64 * self.dt;
            self.last = Vec6::from_fn(|i, _| {
                (theta[i] - (self.dtheta[i] + self.drift[i] * age)) / self.eta[i]
                    + self.noise.sample(&mut self.rng)
            });
        }
        self.last
    }

    pub(crate) fn reading(&self) -> Vec6 {
        self.last
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn kabsch_recovers_a_rigid_transform_exactly() {
        let iso = pose_to_isometry(&Vec6::new(0.3, -0.2, 2.0, 0.4, -0.3, 1.2));
        let model: Vec<Vec3> = CmmConfig::c_track()
            .reflectors
            .iter()
            .map(|r| Vec3::from(*r))
            .collect();
        let meas: Vec<Vec3> = model
            .iter()
            .map(|p| (iso * Point3::from(*p)).coords)
            .collect();
        let est = kabsch(&model, &meas).unwrap();
        assert!((est.to_homogeneous() - iso.to_homogeneous()).amax() < 1e-12);
    }

    #[test]
    fn noiseless_cmm_is_exact() {
        let mut cfg = CmmConfig::c_track();
        cfg.pixel_noise = 0.0;
        let truth = Vec6::new(0.01, -0.02, 2.05, 0.3, -0.2, 0.1);
        let m = measure_with(&cfg, &truth, &mut ChaCha8Rng::seed_from_u64(1)).unwrap();
        assert!((m - truth).amax() < 1e-9, "{m} vs {truth}");
    }
}
