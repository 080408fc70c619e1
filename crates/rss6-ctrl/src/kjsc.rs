//! Kinematic joint-space controller KJSC (eq. 6.41–6.42): the reference pose is mapped to joint angles by
//! the nominal inverse kinematics, θ_r = IK(χ_d), and a PID on e_j = θ_r − θ (potentiometers) gives
//!
//! θ_d = θ_bias + k_p e_j + k_d ė_j + k_i ∫e_j dt.
//!
//! As with KCSC the thesis's form has no θ_bias (θ(home) = 0 on its robot). ė_j uses the analytic
//! θ̇_r = J_θ(χ_d) χ̇_d and a backward difference of θ. KJSC never sees the camera, so kinematic errors
//! of the robot go straight into the Cartesian error — the point of the comparison in Tables 6.1/6.2.

use crate::error::{all_finite, CtrlError, FaultLatch, FaultReason, Result};
use crate::kcsc::JointCommand;
use crate::trajectory::Reference;
use rss6_core::{ik, jacobian_theta, thesis, KinematicParams, Vec6};

/// Diagonal joint-space PID gains of eq. 6.42 (same for every joint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpaceGains {
    /// k_p (dimensionless).
    pub kp: f64,
    /// k_i (1/s).
    pub ki: f64,
    /// k_d (s).
    pub kd: f64,
    /// Anti-windup bound on |∫e_j dt| (rad·s).
    pub integral_limit: f64,
}

impl JointSpaceGains {
    /// The thesis prints no KJSC gains (§6.5); rss6 uses the outer visual PID's numbers of §5.6.2
    /// ([`rss6_core::thesis::VISUAL_PID_KP`] …: k_p = 0.3, k_i = 2.4 1/s, k_d = 0.001 s) per joint, with
    /// our anti-windup bound 1 rad·s.
    pub fn from_visual_pid() -> Self {
        JointSpaceGains {
            kp: thesis::VISUAL_PID_KP,
            ki: thesis::VISUAL_PID_KI,
            kd: thesis::VISUAL_PID_KD,
            integral_limit: 1.0,
        }
    }

    /// Checks that every entry is finite and ≥ 0 (a negative anti-windup bound would make the clamp
    /// panic).
    ///
    /// Errors: [`CtrlError::NonFinite`], [`CtrlError::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        let all = [self.kp, self.ki, self.kd, self.integral_limit];
        if !all_finite(&all) {
            return Err(CtrlError::NonFinite);
        }
        if all.iter().any(|&x| x < 0.0) {
            return Err(CtrlError::InvalidParameter(
                "joint-space PID gains and integral limit must be >= 0",
            ));
        }
        Ok(())
    }
}

/// KJSC, eq. 6.42.
#[derive(Debug, Clone, PartialEq)]
pub struct Kjsc {
    kp_model: KinematicParams,
    gains: JointSpaceGains,
    bias: Vec6,
    integral: Vec6,
    prev_theta: Option<Vec6>,
    last: Vec6,
    fault: FaultLatch,
}

impl Kjsc {
    /// A KJSC on kinematics `kp_model`, starting at command `bias` (rad).
    ///
    /// Errors: invalid kinematics as [`CtrlError::Core`], [`JointSpaceGains::validate`]'s errors,
    /// [`CtrlError::NonFinite`] for a NaN/∞ bias.
    pub fn new(kp_model: KinematicParams, gains: JointSpaceGains, bias: &Vec6) -> Result<Self> {
        kp_model.validate()?;
        gains.validate()?;
        if !all_finite(bias.as_slice()) {
            return Err(CtrlError::NonFinite);
        }
        Ok(Kjsc {
            kp_model,
            gains,
            bias: *bias,
            integral: Vec6::zeros(),
            prev_theta: None,
            last: *bias,
            fault: FaultLatch::default(),
        })
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultReason> {
        self.fault.get()
    }

    /// The last command produced (held while faulted).
    pub fn last_command(&self) -> Vec6 {
        self.last
    }

    /// Clears integral, derivative memory and the fault.
    pub fn reset(&mut self) {
        self.integral = Vec6::zeros();
        self.prev_theta = None;
        self.last = self.bias;
        self.fault.clear();
    }

    /// One step `dt` (s) after the previous one, with the potentiometer angles `theta` (nominal
    /// convention, rad).
    pub fn step(&mut self, reference: &Reference, theta: &Vec6, dt: f64) -> Result<JointCommand> {
        self.fault.admit(reference, dt)?;
        if !all_finite(theta.as_slice()) {
            return Err(self.fault.trip(FaultReason::NonFiniteJoint));
        }
        let theta_r = match ik(&self.kp_model, &reference.pose) {
            Ok(t) => t,
            Err(e) => return Err(self.fault.trip(FaultReason::Model(e))),
        };
        let theta_r_dot = match jacobian_theta(&self.kp_model, &reference.pose) {
            Ok(j) => j * reference.pose_dot,
            Err(e) => return Err(self.fault.trip(FaultReason::Model(e))),
        };
        let theta_dot = match self.prev_theta {
            Some(p) => (theta - p) / dt,
            None => Vec6::zeros(),
        };
        let g = &self.gains;
        let e = theta_r - theta;
        let e_dot = theta_r_dot - theta_dot;
        // lim ≥ 0 (validated in `new`): the clamp cannot panic.
        let lim = g.integral_limit;
        let integral = (self.integral + e * dt).map(|x| x.clamp(-lim, lim));
        let theta_d = self.bias + e * g.kp + e_dot * g.kd + integral * g.ki;
        if !all_finite(theta_d.as_slice()) {
            return Err(self.fault.trip(FaultReason::NonFiniteCommand));
        }
        self.integral = integral;
        self.prev_theta = Some(*theta);
        self.last = theta_d;
        Ok(JointCommand { theta_d })
    }
}
