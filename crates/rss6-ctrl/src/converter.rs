//! Torque-to-position converter (§6.4.3, eq. 6.37–6.38): turns the DSMC torque τ_a into the joint
//! position command θ_d that makes the robot's built-in PID (eq. 6.14) apply exactly τ_a.
//!
//! The thesis writes the inverse with the differential operator p: θ_d = τ_a/(l_p + l_d p + l_i p⁻¹) + θ.
//! rss6 inverts the *discrete* PID that [`crate::JointPid`] implements (and that the robot runs at the
//! joint rate): with e_k = θ_d,k − θ_k, I_k = I_{k−1} + e_k Δt,
//!
//! τ_k = l_p e_k + l_i I_k + l_d (e_k − e_{k−1})/Δt
//! ⇒ e_k = (τ_k − l_i I_{k−1} + l_d e_{k−1}/Δt) / (l_p + l_i Δt + l_d/Δt),  θ_d,k = θ_k + e_k,
//!
//! and with a filtered derivative (T_f > 0, D_k = (T_f D_{k−1} + l_d (e_k − e_{k−1}))/(T_f + Δt))
//!
//! e_k = (τ_k − l_i I_{k−1} − (T_f D_{k−1} − l_d e_{k−1})/(T_f + Δt)) / (l_p + l_i Δt + l_d/(T_f + Δt)),
//!
//! using the latest potentiometer θ_k (the same reading the drive uses). The converter keeps a shadow copy
//! of the drive's PID state and advances it with the command actually sent (after the stroke clamp and the
//! rate limit), so the shadow never drifts from the drive even when a command is limited. The request is
//! clamped to ±`torque_limit` first so the inverse never asks for a saturated PID.

use crate::error::{all_finite, CtrlError, FaultReason, Result};
use crate::pid::{JointPid, PidGains};
use crate::safety::{CommandGuard, Guarded};
use rss6_core::{Vec6, LEGS};

/// One converter tick's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConverterOutput {
    /// Joint command θ_cmd to send to the drive (nominal joint convention, rad), already guarded.
    pub theta_cmd: Vec6,
    /// Torque the drive's PID will produce with `theta_cmd` (N·m), from the shadow PID.
    pub tau_expected: Vec6,
    /// Some joint hit its stroke limit.
    pub stroke_limited: bool,
    /// Some joint hit the rate limit.
    pub rate_limited: bool,
}

/// The converter of eq. 6.37–6.38 as the exact discrete inverse of [`JointPid`].
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueToPosition {
    shadow: JointPid,
}

impl TorqueToPosition {
    /// A converter for a drive PID with these gains, period `dt` (s) and torque limit (N·m); the drive's
    /// PID must start from rest at the same time (zero integral, not primed).
    ///
    /// Errors: those of [`JointPid::new`], and [`CtrlError::InvalidParameter`] if l_p + l_d = 0 (the
    /// inverse would divide by l_i Δt alone).
    pub fn new(gains: PidGains, dt: f64, torque_limit: f64) -> Result<Self> {
        Self::mirroring(&JointPid::new(gains, dt, torque_limit)?)
    }

    /// A converter mirroring an existing drive PID, including its current integral and derivative memory.
    ///
    /// Errors: [`CtrlError::InvalidParameter`] if the PID has l_p + l_d = 0.
    pub fn mirroring(pid: &JointPid) -> Result<Self> {
        let g = pid.gains();
        if g.lp + g.ld <= 0.0 {
            return Err(CtrlError::InvalidParameter(
                "PID gains must have l_p + l_d > 0 to be inverted",
            ));
        }
        Ok(TorqueToPosition {
            shadow: pid.clone(),
        })
    }

    /// The shadow copy of the drive's PID.
    pub fn shadow(&self) -> &JointPid {
        &self.shadow
    }

    /// Clears the shadow PID (call together with a reset of the drive's PID).
    pub fn reset(&mut self) {
        self.shadow.reset();
    }

    /// The joint-angle error e_k (rad) that makes the shadow PID output `tau` (N·m) this tick.
    pub fn error_for_torque(&self, tau: &Vec6) -> Vec6 {
        let g = *self.shadow.gains();
        let dt = self.shadow.dt();
        let lim = self.shadow.torque_limit();
        let integral = self.shadow.integral();
        let prev = self.shadow.prev_error();
        let prev_d = self.shadow.prev_derivative();
        let t_f = self.shadow.derivative_filter();
        let primed = self.shadow.is_primed();
        let mut e = Vec6::zeros();
        for i in 0..LEGS {
            // Stay a hair inside the limit so the drive never saturates on an exact request. `lim` > 0
            // (checked by `JointPid::new`), so the clamp cannot panic; the denominators are > 0.
            let t = tau[i].clamp(-lim, lim) * (1.0 - 1e-12);
            let (num, den) = if primed && t_f > 0.0 {
                let h = t_f + dt;
                (
                    t - g.li * integral[i] - (t_f * prev_d[i] - g.ld * prev[i]) / h,
                    g.lp + g.li * dt + g.ld / h,
                )
            } else if primed {
                (
                    t - g.li * integral[i] + g.ld * prev[i] / dt,
                    g.lp + g.li * dt + g.ld / dt,
                )
            } else {
                (t - g.li * integral[i], g.lp + g.li * dt)
            };
            e[i] = num / den;
        }
        e
    }

    /// One joint-rate tick: command for torque `tau_a` (N·m) given the latest potentiometer angles
    /// `theta` (nominal convention, rad), passed through `guard` (stroke clamp, rate limit) with period
    /// `dt` of the shadow PID. Advances the shadow PID with the command actually sent.
    ///
    /// Errors: `Faulted(NonFiniteJoint)` / `Faulted(NonFiniteCommand)` for NaN/∞ inputs (nothing sent,
    /// shadow untouched).
    pub fn step(
        &mut self,
        tau_a: &Vec6,
        theta: &Vec6,
        guard: &mut CommandGuard,
    ) -> Result<ConverterOutput> {
        if !all_finite(theta.as_slice()) {
            return Err(CtrlError::Faulted(FaultReason::NonFiniteJoint));
        }
        if !all_finite(tau_a.as_slice()) {
            return Err(CtrlError::Faulted(FaultReason::NonFiniteCommand));
        }
        let request = theta + self.error_for_torque(tau_a);
        let Guarded {
            command,
            stroke_limited,
            rate_limited,
        } = guard.apply(&request, self.shadow.dt())?;
        let tau_expected = self.shadow.step(&command, theta);
        Ok(ConverterOutput {
            theta_cmd: command,
            tau_expected,
            stroke_limited,
            rate_limited,
        })
    }

    /// Advances the shadow PID with a command sent by someone else (e.g. a held command in a fault, or a
    /// kinematic controller), so the converter can take over later without a bump.
    pub fn observe(&mut self, theta_cmd: &Vec6, theta: &Vec6) -> Vec6 {
        self.shadow.step(theta_cmd, theta)
    }
}
