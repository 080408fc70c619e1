//! The servo's configuration: rates, limits, filter tuning, the drive's PID, and the presets
//! [`ServoConfig::tuned`] and [`ServoConfig::low_noise`].

use crate::kalman::KalmanConfig;
use crate::pid::PidGains;
use crate::safety::CommandLimits;
use rss6_core::Vec6;

/// Time constant (s) of the average of θ_pot − IK(χ_m) used by [`ServoConfig::hold_compensation`].
pub const HOLD_OFFSET_TIME: f64 = 0.3;

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
    /// known input ([`crate::PoseKalman::set_input`]); ignored for KCSC/KJSC, which do not compute one.
    pub kalman_model_input: bool,
    /// DSMC only: every joint tick send τ_a + H (θ − θ̂) instead of the held τ_a, with θ the latest
    /// potentiometer angles, H the model's joint-space hold stiffness at the start pose
    /// ([`crate::Dsmc::hold_stiffness`]) and θ̂ the potentiometer angles the robot would read at the estimate χ_m
    /// the DSMC was evaluated at (IK(χ_m) plus the average of θ − IK(raw frame) over
    /// [`HOLD_OFFSET_TIME`]). On the 6-RSS a held τ_a does not hold the generalized force: under gravity
    /// the platform tilts away at ≈ 14/s between frames, and the model evaluated at a noisy χ_m turns
    /// camera noise into torque noise through the same stiffness. The compensation takes the pose
    /// dependence from the potentiometers instead (docs/control.md, "Held torque between frames").
    pub hold_compensation: bool,
    /// Also feed the filter the pose rate the potentiometers measured over each camera frame: the
    /// least-squares slope of the joint angles since the previous frame, mapped by J_θ⁻¹ at the estimate
    /// ([`crate::PoseKalman::update_rate`]). `None` = camera only (the thesis filter); `Some(σ)` with σ the 1σ
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
    /// rss6's tuned servo, used with [`crate::DsmcGains::tuned`]: 1 kHz joint loop, the thesis's 30 Hz
    /// camera (§6.5) without latency, stale after 0.2 s, nominal limits, [`KalmanConfig::tuned`], the
    /// [`PidGains::tuned`] drive PID with a 30 N·m limit.
    pub fn tuned() -> Self {
        ServoConfig {
            joint_dt: 1e-3,
            frame_period: rss6_core::thesis::CONTROL_PERIOD,
            stale_after: 0.2,
            camera_latency: 0.0,
            limits: CommandLimits::nominal(),
            kalman: KalmanConfig::tuned(),
            kalman_model_input: false,
            potentiometer_rate: None,
            potentiometer_rate_scale_error: Vec6::repeat(0.2),
            hold_compensation: false,
            pid: PidGains::tuned(),
            torque_limit: 30.0,
        }
    }
}

impl ServoConfig {
    /// The low-noise DSMC servo (docs/control.md, "Kalman filter in the loop"): [`Self::tuned`] with
    /// [`KalmanConfig::low_noise`], the DSMC's model acceleration as the filter's known input
    /// (`kalman_model_input`), the joint-rate hold compensation (`hold_compensation`) and the
    /// potentiometer rate as a second filter measurement (`potentiometer_rate` = Table 4.1's 0.2233 bit ×
    /// π/4096 rad/bit, scale error 0.2 for x, y, z and 0.12 for α, β, γ). Use with [`crate::DsmcGains::low_noise`]. KCSC and KJSC
    /// ignore the DSMC-only options but would get the smoother filter: keep them on [`Self::tuned`].
    pub fn low_noise() -> Self {
        ServoConfig {
            kalman: KalmanConfig::low_noise(),
            kalman_model_input: true,
            hold_compensation: true,
            potentiometer_rate: Some(POTENTIOMETER_SIGMA_RAD),
            potentiometer_rate_scale_error: Vec6::new(0.2, 0.2, 0.2, 0.12, 0.12, 0.12),
            ..Self::tuned()
        }
    }
}

/// Table 4.1 potentiometer noise in rad: 0.2233 bit × η = π/4096 rad/bit.
pub const POTENTIOMETER_SIGMA_RAD: f64 =
    rss6_core::thesis::KAPPA_NOISE_BITS * rss6_core::ETA_NOMINAL;
