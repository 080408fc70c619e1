//! A robot driven tick by tick, seen the way the real one is.

use crate::error::Result;
use crate::record::TrueState;
use rss6_core::Vec6;
use rss6_sim::{Physics, RobotSim, Truth};

/// A 6-RSS robot driven at the joint-loop rate: one joint command per tick, potentiometers and camera
/// frames read between ticks. This is all a real robot offers; a simulated one also shows its truth.
///
/// Joint commands are in the **drive's** joint convention (the nominal η, Δθ of eq. 4.2): the drive
/// tracks the potentiometer reading κ_cmd = (θ_cmd − Δθ_nom)/η_nom.
pub trait Robot {
    /// Tick length (s): 1e-3 for the 1 kHz joint loop.
    fn dt(&self) -> f64;
    /// Robot time (s).
    fn time(&self) -> f64;
    /// Sends one joint command θ_cmd (rad, drive convention) and advances one tick.
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()>;
    /// ᶜχ_t (target in the sensor frame, m, rad) if a camera frame became available on the last tick.
    /// Call it once per tick.
    fn camera(&mut self) -> Option<Vec6>;
    /// The latest potentiometer readings κ (bit).
    fn potentiometers(&self) -> Vec6;
    /// A simulated robot's hidden truth; `None` for a real robot.
    fn truth(&self) -> Option<Truth> {
        None
    }
    /// A simulated robot's true state now; `None` for a real robot.
    fn true_state(&self) -> Option<TrueState> {
        None
    }
}

impl<P: Physics> Robot for rss6_sim::Robot<P> {
    fn dt(&self) -> f64 {
        self.config().dt
    }
    fn time(&self) -> f64 {
        RobotSim::time(self)
    }
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()> {
        Ok(RobotSim::step_joint_command(self, theta_cmd)?)
    }
    fn camera(&mut self) -> Option<Vec6> {
        RobotSim::camera(self)
    }
    fn potentiometers(&self) -> Vec6 {
        RobotSim::potentiometers(self)
    }
    fn truth(&self) -> Option<Truth> {
        Some(RobotSim::truth(self))
    }
    fn true_state(&self) -> Option<TrueState> {
        Some(TrueState {
            pose: self.true_pose(),
            theta: self.true_theta(),
            theta_dot: self.true_theta_dot(),
            torque: self.torques(),
        })
    }
}

/// A pointer to a robot is the robot.
macro_rules! forward_robot {
    ($($ptr:ty),*) => {$(
        impl<R: Robot + ?Sized> Robot for $ptr {
            fn dt(&self) -> f64 {
                (**self).dt()
            }
            fn time(&self) -> f64 {
                (**self).time()
            }
            fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()> {
                (**self).step_joint_command(theta_cmd)
            }
            fn camera(&mut self) -> Option<Vec6> {
                (**self).camera()
            }
            fn potentiometers(&self) -> Vec6 {
                (**self).potentiometers()
            }
            fn truth(&self) -> Option<Truth> {
                (**self).truth()
            }
            fn true_state(&self) -> Option<TrueState> {
                (**self).true_state()
            }
        }
    )*};
}

forward_robot!(&mut R, Box<R>);
