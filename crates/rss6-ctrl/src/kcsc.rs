//! Kinematic Cartesian-space controller KCSC (eq. 6.40) and the outer visual PID used for closed-loop
//! identification (eq. 5.4) — the same law:
//!
//! θ_d = θ_bias + J_θ(χ_m)·(k_p e + k_d ė + k_i ∫e dt),  e = χ_d − χ_m (eq. 6.39),
//!
//! with J_θ = J_ad J_s (eq. 5.3) of the *nominal* kinematics. The thesis writes it without θ_bias; its
//! robot sits at θ = 0 at home, so θ_bias = θ(home) = 0 reproduces eq. 6.40 exactly; a non-zero bias lets
//! the law start bumplessly from any resting configuration. The law is integral-dominated: the integral
//! holds the pose offset and k_p, k_d shape the transient.

use crate::error::{all_finite, CtrlError, FaultLatch, FaultReason, Result};
use crate::kalman::PoseEstimate;
use crate::trajectory::Reference;
use rss6_core::{jacobian_theta, thesis, KinematicParams, Vec6};

/// Diagonal gains of a Cartesian PID (eq. 5.4 / 6.40), per pose axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CartesianPidGains {
    /// k_p (dimensionless).
    pub kp: Vec6,
    /// k_i (1/s).
    pub ki: Vec6,
    /// k_d (s).
    pub kd: Vec6,
    /// Anti-windup bound on |∫e dt| per axis (m·s, rad·s).
    pub integral_limit: Vec6,
}

impl CartesianPidGains {
    /// The thesis's outer-loop gains (§5.6.2, [`rss6_core::thesis`]): k_p = 0.3, k_d = 0.001 s,
    /// k_i = 2.4 1/s on every axis. The anti-windup bound 0.1 (m·s, rad·s) is ours (the thesis has none).
    pub fn thesis() -> Self {
        CartesianPidGains {
            kp: Vec6::repeat(thesis::VISUAL_PID_KP),
            ki: Vec6::repeat(thesis::VISUAL_PID_KI),
            kd: Vec6::repeat(thesis::VISUAL_PID_KD),
            integral_limit: Vec6::repeat(0.1),
        }
    }

    /// Checks that every entry is finite and ≥ 0 (a negative anti-windup bound would make the clamp
    /// panic).
    ///
    /// Errors: [`CtrlError::NonFinite`], [`CtrlError::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        let all = [self.kp, self.ki, self.kd, self.integral_limit];
        if !all.iter().all(|v| all_finite(v.as_slice())) {
            return Err(CtrlError::NonFinite);
        }
        if all.iter().any(|v| v.iter().any(|&x| x < 0.0)) {
            return Err(CtrlError::InvalidParameter(
                "Cartesian PID gains and integral limit must be >= 0",
            ));
        }
        Ok(())
    }
}

/// Output of a kinematic controller: a joint position command (nominal convention, rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointCommand {
    /// θ_d (rad), before the command guard.
    pub theta_d: Vec6,
}

/// KCSC, eq. 6.40. Runs at the camera rate on the Kalman estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Kcsc {
    kp_model: KinematicParams,
    gains: CartesianPidGains,
    bias: Vec6,
    integral: Vec6,
    last: Vec6,
    fault: FaultLatch,
}

impl Kcsc {
    /// A KCSC on the nominal (or calibrated) kinematics `kp_model`, starting at command `bias`
    /// (θ(home) = 0 for the nominal robot).
    ///
    /// Errors: invalid kinematics as [`CtrlError::Core`], [`CartesianPidGains::validate`]'s errors,
    /// [`CtrlError::NonFinite`] for a NaN/∞ bias.
    pub fn new(kp_model: KinematicParams, gains: CartesianPidGains, bias: &Vec6) -> Result<Self> {
        kp_model.validate()?;
        gains.validate()?;
        if !all_finite(bias.as_slice()) {
            return Err(CtrlError::NonFinite);
        }
        Ok(Kcsc {
            kp_model,
            gains,
            bias: *bias,
            integral: Vec6::zeros(),
            last: *bias,
            fault: FaultLatch::default(),
        })
    }

    /// Gains.
    pub fn gains(&self) -> &CartesianPidGains {
        &self.gains
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultReason> {
        self.fault.get()
    }

    /// The last command produced (held while faulted).
    pub fn last_command(&self) -> Vec6 {
        self.last
    }

    /// Clears the integral and the fault; the command restarts from the bias.
    pub fn reset(&mut self) {
        self.integral = Vec6::zeros();
        self.last = self.bias;
        self.fault.clear();
    }

    /// One step `dt` (s) after the previous one.
    pub fn step(
        &mut self,
        reference: &Reference,
        estimate: &PoseEstimate,
        dt: f64,
    ) -> Result<JointCommand> {
        self.fault.admit_estimate(reference, estimate, dt)?;
        let j_theta = match jacobian_theta(&self.kp_model, &estimate.pose) {
            Ok(j) => j,
            Err(e) => return Err(self.fault.trip(FaultReason::Model(e))),
        };
        let e = reference.pose - estimate.pose;
        let e_dot = reference.pose_dot - estimate.pose_dot;
        let g = &self.gains;
        let mut integral = self.integral + e * dt;
        for i in 0..6 {
            // integral_limit ≥ 0 (validated in `new`): the clamp cannot panic.
            integral[i] = integral[i].clamp(-g.integral_limit[i], g.integral_limit[i]);
        }
        let u = g.kp.component_mul(&e) + g.kd.component_mul(&e_dot) + g.ki.component_mul(&integral);
        let theta_d = self.bias + j_theta * u;
        if !all_finite(theta_d.as_slice()) {
            return Err(self.fault.trip(FaultReason::NonFiniteCommand));
        }
        self.integral = integral;
        self.last = theta_d;
        Ok(JointCommand { theta_d })
    }
}

/// The outer visual-servoing PID of closed-loop identification (eq. 5.4): U_θ = J_θ[k_p e + k_d ė +
/// k_i ∫e], on the raw camera pose (or the simulated pose χ_s) instead of the Kalman estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct VisualPid {
    inner: Kcsc,
}

impl VisualPid {
    /// Same arguments as [`Kcsc::new`]; [`CartesianPidGains::thesis`] are the thesis's gains.
    pub fn new(kp_model: KinematicParams, gains: CartesianPidGains, bias: &Vec6) -> Result<Self> {
        Ok(VisualPid {
            inner: Kcsc::new(kp_model, gains, bias)?,
        })
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultReason> {
        self.inner.fault()
    }

    /// The last command U_θ (rad).
    pub fn last_command(&self) -> Vec6 {
        self.inner.last_command()
    }

    /// Clears integral and fault.
    pub fn reset(&mut self) {
        self.inner.reset();
    }

    /// One step: measured pose χ_m and its rate χ̇_m (m, rad, per s), `dt` (s) since the last step.
    pub fn step(
        &mut self,
        reference: &Reference,
        pose: &Vec6,
        pose_dot: &Vec6,
        dt: f64,
    ) -> Result<JointCommand> {
        let est = PoseEstimate {
            pose: *pose,
            pose_dot: *pose_dot,
            pose_ddot: Vec6::zeros(),
        };
        self.inner.step(reference, &est, dt)
    }
}
