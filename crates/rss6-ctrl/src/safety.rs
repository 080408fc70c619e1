//! The command guard: every joint command leaving rss6-ctrl is finite, inside the actuator stroke and
//! rate-limited. The guard remembers the last command it let through (the "last safe command").

use crate::error::{all_finite, check_dt, CtrlError, FaultReason, Result};
use rss6_core::Vec6;

/// Limits on joint commands θ_cmd (nominal joint convention, rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandLimits {
    /// Lower end of each actuator's stroke (rad).
    pub min: Vec6,
    /// Upper end of each actuator's stroke (rad).
    pub max: Vec6,
    /// Largest command rate |Δθ_cmd|/Δt per joint (rad/s).
    pub max_rate: f64,
}

impl CommandLimits {
    /// ±57.1° (the singularity-free wrench range of §5.4) and 3 rad/s.
    pub fn nominal() -> Self {
        let lim = 57.1_f64.to_radians();
        CommandLimits {
            min: Vec6::repeat(-lim),
            max: Vec6::repeat(lim),
            max_rate: 3.0,
        }
    }

    /// Checks finiteness, min < max and a positive rate.
    pub fn validate(&self) -> Result<()> {
        if !(all_finite(self.min.as_slice()) && all_finite(self.max.as_slice()))
            || self.max_rate.is_nan()
        {
            return Err(CtrlError::NonFinite);
        }
        if self.min.iter().zip(self.max.iter()).any(|(a, b)| a >= b) {
            return Err(CtrlError::InvalidParameter("stroke min must be < max"));
        }
        if self.max_rate <= 0.0 {
            return Err(CtrlError::InvalidParameter("max command rate must be > 0"));
        }
        Ok(())
    }
}

/// What the guard did to a request.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guarded {
    /// The command to send (rad).
    pub command: Vec6,
    /// Some joint was clamped to its stroke.
    pub stroke_limited: bool,
    /// Some joint was rate-limited.
    pub rate_limited: bool,
}

/// Clamps, rate-limits and remembers joint commands.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandGuard {
    limits: CommandLimits,
    last: Vec6,
}

impl CommandGuard {
    /// A guard whose rate limit starts from `initial` (e.g. the measured joint angles at start-up);
    /// `initial` is clamped into the stroke.
    pub fn new(limits: CommandLimits, initial: &Vec6) -> Result<Self> {
        limits.validate()?;
        if !all_finite(initial.as_slice()) {
            return Err(CtrlError::NonFinite);
        }
        let last = Vec6::from_fn(|i, _| initial[i].clamp(limits.min[i], limits.max[i]));
        Ok(CommandGuard { limits, last })
    }

    /// The limits.
    pub fn limits(&self) -> &CommandLimits {
        &self.limits
    }

    /// The last command let through (the command to hold in a fault).
    pub fn last_command(&self) -> Vec6 {
        self.last
    }

    /// Restarts the rate limiter from `command` (clamped into the stroke).
    pub fn reset(&mut self, command: &Vec6) {
        if all_finite(command.as_slice()) {
            self.last =
                Vec6::from_fn(|i, _| command[i].clamp(self.limits.min[i], self.limits.max[i]));
        }
    }

    /// Guards one request issued `dt` seconds after the previous command. A non-finite request is
    /// refused with `Faulted(NonFiniteCommand)` and the last command stays in force.
    pub fn apply(&mut self, request: &Vec6, dt: f64) -> Result<Guarded> {
        check_dt(dt)?;
        if !all_finite(request.as_slice()) {
            return Err(CtrlError::Faulted(FaultReason::NonFiniteCommand));
        }
        let step = self.limits.max_rate * dt;
        let mut out = Guarded {
            command: self.last,
            stroke_limited: false,
            rate_limited: false,
        };
        for i in 0..6 {
            let (lo, hi) = (self.limits.min[i], self.limits.max[i]);
            let mut c = request[i];
            if c < lo || c > hi {
                out.stroke_limited = true;
                c = c.clamp(lo, hi);
            }
            let prev = self.last[i];
            if (c - prev).abs() > step {
                out.rate_limited = true;
                c = c.clamp(prev - step, prev + step);
            }
            out.command[i] = c;
        }
        self.last = out.command;
        Ok(out)
    }
}
