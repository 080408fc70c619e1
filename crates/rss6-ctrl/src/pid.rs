//! The robot's built-in joint controller: an independent PID per joint (eq. 6.14 / 5.5), run at the
//! joint-loop rate (1 kHz) on the potentiometer angle.
//!
//! Units: the thesis's Table 5.2 gains (l_p = 10, l_i = 12, l_d = 0.1) are in the drive's own command
//! units, which the thesis does not state; with N·m/rad they would let the 24 kg platform sag by
//! ≈ 0.3 rad under gravity. rss6 works in SI, so [`PidGains::nominal`] is tuned for the Table 5.1 robot:
//! the reflected joint inertia at home is ≈ 0.03 kg·m², and l_p = 400 N·m/rad, l_d = 4 N·m·s/rad give a
//! ≈ 18 Hz, well-damped joint loop; l_i = 2000 N·m/(rad·s) removes the gravity sag in ≈ 0.2 s.

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
    /// The default SI gains for the nominal robot (see the module docs).
    pub const fn nominal() -> Self {
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
}

/// Discrete PID of eq. 6.14 for all six joints: τ = l_p e + l_i Σe·dt + l_d (e − e_prev)/dt,
/// with e = θ_d − θ. Backward-Euler derivative and rectangle-rule integral, exactly what
/// [`crate::pid::JointPid::step`] computes; the torque-to-position converter inverts this same law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPid {
    /// Gains.
    pub gains: PidGains,
    /// Sample time (s), 1e-3 at 1 kHz.
    pub dt: f64,
    /// Torque limit per joint (N·m); the output is clamped to ±limit (no anti-windup beyond holding the
    /// integral while saturated).
    pub torque_limit: f64,
    integral: [f64; LEGS],
    prev_error: [f64; LEGS],
    primed: bool,
}

impl JointPid {
    /// A PID at rest (zero integral, no previous error).
    pub const fn new(gains: PidGains, dt: f64, torque_limit: f64) -> Self {
        JointPid {
            gains,
            dt,
            torque_limit,
            integral: [0.0; LEGS],
            prev_error: [0.0; LEGS],
            primed: false,
        }
    }

    /// Clears the integral and derivative memory.
    pub fn reset(&mut self) {
        self.integral = [0.0; LEGS];
        self.prev_error = [0.0; LEGS];
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

    /// One tick: joint torques (N·m) from the commanded and measured angles (rad).
    pub fn step(&mut self, theta_cmd: &Vec6, theta_meas: &Vec6) -> Vec6 {
        let mut tau = Vec6::zeros();
        for i in 0..LEGS {
            let e = theta_cmd[i] - theta_meas[i];
            let de = if self.primed {
                (e - self.prev_error[i]) / self.dt
            } else {
                0.0
            };
            let integral = self.integral[i] + e * self.dt;
            let raw = self.gains.lp * e + self.gains.li * integral + self.gains.ld * de;
            let lim = self.torque_limit;
            let out = raw.clamp(-lim, lim);
            // Conditional integration: do not wind up while saturated.
            if raw == out {
                self.integral[i] = integral;
            }
            self.prev_error[i] = e;
            tau[i] = out;
        }
        self.primed = true;
        tau
    }
}
