//! The robot's built-in joint controller: an independent PID per joint (eq. 6.14 / 5.5), run at the
//! joint-loop rate (1 kHz) on the potentiometer angle.
//!
//! Units: the thesis's Table 5.2 gains (initial l_p = 10, l_i = 12, l_d = 0.1; identified 10.5, 11.4, 0.164) are in the drive's own command
//! units, which the thesis does not state; with N·m/rad they would let the 24 kg platform sag by
//! ≈ 0.3 rad under gravity. rss6 works in SI, so [`PidGains::tuned`] is tuned for the Table 5.1 robot:
//! the reflected joint inertia at home is ≈ 0.03 kg·m², and l_p = 400 N·m/rad, l_d = 4 N·m·s/rad give a
//! ≈ 18 Hz, well-damped joint loop; l_i = 2000 N·m/(rad·s) removes the gravity sag in ≈ 0.2 s.

use crate::error::{check_dt, CtrlError, Result};
use rss6_core::{Vec6, LEGS};

/// Gains of the built-in joint PID (eq. 6.14), the same for every joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PidGains {
    /// Proportional gain l_p (N·m/rad).
    pub lp: f64,
    /// Integral gain l_i (N·m/(rad·s)).
    pub li: f64,
    /// Derivative gain l_d (N·m·s/rad).
    pub ld: f64,
}

impl PidGains {
    /// rss6's SI gains, tuned for the Table 5.1 robot (see the module docs; the thesis's Table 5.2 values
    /// are in drive units, [`rss6_core::thesis::TABLE_5_2_PID_IDENTIFIED`]).
    pub const fn tuned() -> Self {
        PidGains {
            lp: 400.0,
            li: 2000.0,
            ld: 4.0,
        }
    }

    /// Gains as the thesis's (l_p, l_i, l_d) triple; the last three entries of the vector A (eq. 5.6).
    pub const fn to_array(&self) -> [f64; 3] {
        [self.lp, self.li, self.ld]
    }

    /// Checks that every gain is finite and ≥ 0.
    ///
    /// Errors: [`CtrlError::NonFinite`], [`CtrlError::InvalidParameter`].
    pub fn validate(&self) -> Result<()> {
        if !(self.lp.is_finite() && self.li.is_finite() && self.ld.is_finite()) {
            return Err(CtrlError::NonFinite);
        }
        if self.lp < 0.0 || self.li < 0.0 || self.ld < 0.0 {
            return Err(CtrlError::InvalidParameter("PID gains must be >= 0"));
        }
        Ok(())
    }
}

/// Discrete PID of eq. 6.14 for all six joints: τ = l_p e + l_i Σe·dt + D, with e = θ_d − θ,
/// rectangle-rule integral and derivative term D = l_d (e − e_prev)/dt (backward Euler, the thesis's
/// law and the default). A real drive low-passes its derivative: with a filter time constant T_f > 0
/// ([`JointPid::with_derivative_filter`]) D is the backward-Euler discretisation of l_d s/(T_f s + 1),
/// D_k = (T_f D_{k−1} + l_d (e_k − e_{k−1})) / (T_f + dt). The torque-to-position converter inverts
/// this same law.
///
/// The output is clamped to ±`torque_limit` (no anti-windup beyond holding the integral while saturated).
/// Gains, period and limit are fixed at construction ([`JointPid::new`] validates them).
#[derive(Debug, Clone, PartialEq)]
pub struct JointPid {
    gains: PidGains,
    dt: f64,
    torque_limit: f64,
    /// Derivative filter time constant T_f (s), 0 = unfiltered.
    filter: f64,
    integral: [f64; LEGS],
    prev_error: [f64; LEGS],
    /// The previous derivative term D_{k−1} (N·m).
    prev_derivative: [f64; LEGS],
    primed: bool,
}

impl JointPid {
    /// A PID at rest (zero integral, no previous error) with `gains`, sample time `dt` (s, 1e-3 at
    /// 1 kHz) and torque limit per joint `torque_limit` (N·m, > 0; +∞ = unlimited).
    ///
    /// Errors: [`CtrlError::InvalidTimeStep`] unless `dt` is finite and > 0; [`CtrlError::NonFinite`]
    /// or [`CtrlError::InvalidParameter`] for a NaN/∞ or negative gain; [`CtrlError::InvalidParameter`]
    /// for a NaN or non-positive torque limit.
    ///
    /// ```
    /// use rss6_ctrl::{JointPid, PidGains};
    /// assert!(JointPid::new(PidGains::tuned(), 1e-3, 30.0).is_ok());
    /// assert!(JointPid::new(PidGains::tuned(), 0.0, 30.0).is_err());
    /// assert!(JointPid::new(PidGains::tuned(), 1e-3, -1.0).is_err());
    /// ```
    pub fn new(gains: PidGains, dt: f64, torque_limit: f64) -> Result<Self> {
        check_dt(dt)?;
        gains.validate()?;
        if torque_limit.is_nan() || torque_limit <= 0.0 {
            return Err(CtrlError::InvalidParameter("torque limit must be > 0"));
        }
        Ok(JointPid {
            gains,
            dt,
            torque_limit,
            filter: 0.0,
            integral: [0.0; LEGS],
            prev_error: [0.0; LEGS],
            prev_derivative: [0.0; LEGS],
            primed: false,
        })
    }

    /// The same PID with its derivative term low-passed with time constant `t_f` (s, ≥ 0; 0 = the
    /// unfiltered law). See the type's docs.
    ///
    /// Errors: [`CtrlError::InvalidParameter`] unless `t_f` is finite and ≥ 0.
    ///
    /// ```
    /// use rss6_ctrl::{JointPid, PidGains};
    /// let pid = JointPid::new(PidGains::tuned(), 1e-3, 30.0).unwrap();
    /// assert!(pid.clone().with_derivative_filter(5e-3).is_ok());
    /// assert!(pid.with_derivative_filter(f64::NAN).is_err());
    /// ```
    pub fn with_derivative_filter(mut self, t_f: f64) -> Result<Self> {
        if !(t_f.is_finite() && t_f >= 0.0) {
            return Err(CtrlError::InvalidParameter(
                "derivative filter time constant must be finite and >= 0",
            ));
        }
        self.filter = t_f;
        Ok(self)
    }

    /// The derivative filter's time constant T_f (s); 0 = unfiltered.
    pub fn derivative_filter(&self) -> f64 {
        self.filter
    }

    /// The previous derivative term D_{k−1} (N·m) per joint.
    pub fn prev_derivative(&self) -> [f64; LEGS] {
        self.prev_derivative
    }

    /// The derivative term D_k for the error change `de` = e_k − e_{k−1} of joint `i` (a primed PID).
    pub(crate) fn derivative(&self, i: usize, de: f64) -> f64 {
        if self.filter > 0.0 {
            (self.filter * self.prev_derivative[i] + self.gains.ld * de) / (self.filter + self.dt)
        } else {
            self.gains.ld * (de / self.dt)
        }
    }

    /// The gains.
    pub fn gains(&self) -> &PidGains {
        &self.gains
    }

    /// The sample time (s).
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The torque limit per joint (N·m).
    pub fn torque_limit(&self) -> f64 {
        self.torque_limit
    }

    /// Clears the integral and derivative memory.
    pub fn reset(&mut self) {
        self.integral = [0.0; LEGS];
        self.prev_error = [0.0; LEGS];
        self.prev_derivative = [0.0; LEGS];
        self.primed = false;
    }

    /// The integral state Σe·dt (rad·s) per joint.
    pub fn integral(&self) -> [f64; LEGS] {
        self.integral
    }

    /// The previous error e_{k−1} = θ_d − θ (rad) per joint, used by the derivative term.
    pub fn prev_error(&self) -> [f64; LEGS] {
        self.prev_error
    }

    /// `false` until the first tick (the first tick has no derivative term).
    pub fn is_primed(&self) -> bool {
        self.primed
    }

    /// One tick: joint torques (N·m) from the commanded and measured angles (rad). NaN inputs give NaN
    /// torques (the caller checks its inputs); nothing here can panic.
    pub fn step(&mut self, theta_cmd: &Vec6, theta_meas: &Vec6) -> Vec6 {
        let mut tau = Vec6::zeros();
        let lim = self.torque_limit;
        for i in 0..LEGS {
            let e = theta_cmd[i] - theta_meas[i];
            let d = if self.primed {
                self.derivative(i, e - self.prev_error[i])
            } else {
                0.0
            };
            let integral = self.integral[i] + e * self.dt;
            let raw = self.gains.lp * e + self.gains.li * integral + d;
            // `lim` > 0 and not NaN (checked in `new`), so the clamp cannot panic.
            let out = raw.clamp(-lim, lim);
            // Conditional integration: do not wind up while saturated.
            if raw == out {
                self.integral[i] = integral;
            }
            self.prev_error[i] = e;
            self.prev_derivative[i] = d;
            tau[i] = out;
        }
        self.primed = true;
        tau
    }
}
