//! [`run`]: drives any [`Plant`] with a [`Servo`] for a fixed number of ticks.

use super::{Servo, ServoTick};
use crate::error::FaultReason;
use crate::trajectory::{Reference, Trajectory};
use rss6_core::Vec6;

/// A robot (real or simulated) as the servo sees it. Joint commands are in the nominal joint convention.
pub trait Plant {
    /// The plant's own error type (bus error, simulation failure …).
    type Error;
    /// Sends one joint command and advances one joint-loop tick (1 kHz).
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> core::result::Result<(), Self::Error>;
    /// The camera pose χ̄_E of the end-effector in the base frame (m, rad) if a frame arrived since the
    /// last call, else `None`. (A plant whose camera reports ᶜχ_t converts with ᴼχ_C and ᴱχ_t first.)
    fn camera(&mut self) -> Option<Vec6>;
    /// The latest potentiometer readings κ (bits).
    fn potentiometers(&self) -> Vec6;
    /// Plant time (s).
    fn time(&self) -> f64;
}

/// What [`run`] shows the observer after every tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TickRecord {
    /// Time at the start of the tick (s).
    pub t: f64,
    /// The reference used.
    pub reference: Reference,
    /// The camera frame consumed this tick, if any.
    pub camera: Option<Vec6>,
    /// The command sent (rad).
    pub theta_cmd: Vec6,
    /// The servo's output, or `None` while faulted.
    pub tick: Option<ServoTick>,
    /// The servo's latched fault, if any.
    pub fault: Option<FaultReason>,
}

/// Summary of a [`run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// Ticks executed.
    pub ticks: u32,
    /// Camera frames consumed.
    pub frames: u32,
    /// Time and reason of the first fault, if any.
    pub first_fault: Option<(f64, FaultReason)>,
}

/// Runs `servo` on `plant` for `ticks` joint-loop ticks following `trajectory` (sampled at plant time
/// minus `t0`). While the servo is faulted the held command keeps being sent. `observe` sees every tick
/// and the plant after the command was applied. Stops early only on a plant error.
pub fn run<P, T, F>(
    plant: &mut P,
    servo: &mut Servo,
    trajectory: &T,
    t0: f64,
    ticks: u32,
    mut observe: F,
) -> core::result::Result<RunSummary, P::Error>
where
    P: Plant,
    T: Trajectory + ?Sized,
    F: FnMut(&TickRecord, &P),
{
    let mut summary = RunSummary {
        ticks: 0,
        frames: 0,
        first_fault: None,
    };
    for _ in 0..ticks {
        let t = plant.time();
        let reference = trajectory.sample(t - t0);
        let camera = plant.camera();
        let kappa = plant.potentiometers();
        let result = servo.tick(t, &reference, camera.as_ref(), &kappa);
        let (theta_cmd, tick) = match result {
            Ok(o) => (o.theta_cmd, Some(o)),
            Err(_) => (servo.held_command(), None),
        };
        if camera.is_some() && tick.is_some() {
            summary.frames += 1;
        }
        let fault = servo.fault();
        if summary.first_fault.is_none() {
            if let Some(r) = fault {
                summary.first_fault = Some((t, r));
            }
        }
        plant.step_joint_command(&theta_cmd)?;
        summary.ticks += 1;
        observe(
            &TickRecord {
                t,
                reference,
                camera,
                theta_cmd,
                tick,
                fault,
            },
            plant,
        );
    }
    Ok(summary)
}
