//! The identification loop of Fig. 5.1: reference → outer visual PID (eq. 5.4) on the camera pose →
//! the drive's built-in PID (eq. 5.5) → robot → camera. The same loop runs on the robot (its camera
//! frames) and on the model twin (CLOE's simulated output χ_s): both are [`Robot`]s.
//!
//! At each camera frame the visual PID takes χ_m (the frame through the estimated ᴼχ_C, ᴱχ_t) and its
//! rate (backward difference of the last two frames; zero at the first) and computes U_θ, which the
//! drive then tracks, held until the next frame (sample-and-hold at the camera rate). Before the first
//! frame the command holds the starting joint angles.

use crate::error::{ExpError, Result};
use crate::observer::{Flow, Observer, Progress};
use crate::record::{Phase, Record};
use crate::robot::Robot;
use crate::view::Externals;
use rss6_core::{KinematicParams, Vec6};
use rss6_ctrl::{CartesianPidGains, FaultReason, Trajectory, VisualPid};

/// Everything that defines an identification run except the robot and the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentSpec {
    /// The kinematic model of the visual PID's J_θ (nominal or calibrated).
    pub kp_model: KinematicParams,
    /// The estimated ᴼχ_C and ᴱχ_t.
    pub externals: Externals,
    /// The drive's joint convention (nominal kinematics).
    pub drive: KinematicParams,
    /// The outer loop's gains (thesis §5.6.2: k_p = 0.3, k_i = 2.4, k_d = 0.001).
    pub gains: CartesianPidGains,
    /// Run length (s).
    pub duration: f64,
    /// Observer progress period (s of robot time).
    pub segment: f64,
    /// Joint commands (drive convention) to send, one per tick, instead of the visual PID's: a
    /// recorded run replayed on the model with the robot's own inputs. Frames are still measured
    /// and recorded; the visual PID does not run (no faults). Must cover every tick.
    pub commands: Option<Vec<Vec6>>,
}

impl IdentSpec {
    /// The thesis's loop on `kp_model` with `externals`: nominal drive convention, thesis gains, 20 s,
    /// 1 s segments.
    pub fn new(kp_model: KinematicParams, externals: Externals) -> Self {
        IdentSpec {
            kp_model,
            externals,
            drive: KinematicParams::nominal(),
            gains: CartesianPidGains::thesis(),
            duration: 20.0,
            segment: 1.0,
            commands: None,
        }
    }
}

/// What an identification run reports besides its records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentOutcome {
    /// Ticks run.
    pub ticks: u32,
    /// Camera frames used by the visual PID.
    pub frames: u32,
    /// Time since the start (s) and reason of the first visual-PID fault (the command is then held).
    pub first_fault: Option<(f64, FaultReason)>,
}

/// Runs the loop of `spec` on `robot` from its current state (at rest) for `spec.duration` s following
/// `trajectory` (sampled from t = 0 at the start). Records have phase [`Phase::Identification`] and
/// times from the start of the run.
pub fn run<R: Robot, T: Trajectory + ?Sized>(
    mut robot: R,
    spec: &IdentSpec,
    trajectory: &T,
    observer: &mut dyn Observer,
) -> Result<IdentOutcome> {
    for (name, v) in [("duration", spec.duration), ("segment", spec.segment)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(ExpError::InvalidInput(format!(
                "{name} must be finite and > 0 s, got {v}"
            )));
        }
    }
    let dt = robot.dt();
    let t0 = robot.time();
    let theta0 = spec.drive.theta_from_reading(&robot.potentiometers());
    let mut pid = VisualPid::new(spec.kp_model, spec.gains, &theta0)?;
    let ticks = (spec.duration / dt).round() as u32;
    if let Some(c) = &spec.commands {
        if c.len() < ticks as usize {
            return Err(ExpError::InvalidInput(format!(
                "{} recorded commands for a run of {ticks} ticks",
                c.len()
            )));
        }
        if let Some(k) = c.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
            return Err(ExpError::InvalidInput(format!(
                "recorded command {k} is not finite"
            )));
        }
    }
    let segment_ticks = ((spec.segment / dt).round() as u32).max(1);
    let mut command = theta0;
    let mut last_frame: Option<(f64, Vec6)> = None;
    let mut outcome = IdentOutcome {
        ticks: 0,
        frames: 0,
        first_fault: None,
    };
    // A frame pending at the start belongs to the first tick.
    let mut frame = robot.camera();
    for done in 1..=ticks {
        let t = robot.time() - t0;
        let reference = trajectory.sample(t);
        let kappa = robot.potentiometers();
        let truth = robot.true_state();
        let measured = frame.map(|z| spec.externals.effector_pose(&z));
        if let Some(recorded) = &spec.commands {
            // Length checked above: every tick has one.
            command = recorded[(done - 1) as usize];
            outcome.frames += u32::from(measured.is_some());
        } else if let Some(chi) = measured {
            let (rate, h) = match last_frame {
                Some((tp, prev)) if t > tp => ((chi - prev) / (t - tp), t - tp),
                _ => (Vec6::zeros(), dt),
            };
            match pid.step(&reference, &chi, &rate, h) {
                Ok(c) => {
                    command = c.theta_d;
                    outcome.frames += 1;
                }
                Err(_) => {
                    if outcome.first_fault.is_none() {
                        outcome.first_fault =
                            Some((t, pid.fault().unwrap_or(FaultReason::NonFiniteCommand)));
                    }
                }
            }
            last_frame = Some((t, chi));
        }
        robot.step_joint_command(&command)?;
        let mut r = Record::new(t, Phase::Identification, kappa, command);
        r.reference = Some(reference);
        r.sensor_pose = frame;
        r.camera = measured;
        r.fault = pid.fault();
        r.truth = truth;
        r.torque = robot.true_state().map(|s| s.torque);
        outcome.ticks = done;
        let mut flow = observer.record(&r);
        if done % segment_ticks == 0 || done == ticks {
            let p = Progress {
                done: f64::from(done) * dt,
                total: f64::from(ticks) * dt,
                time: robot.time(),
                finished: done == ticks,
            };
            if observer.progress(&p) == Flow::Stop {
                flow = Flow::Stop;
            }
        }
        if flow == Flow::Stop && done < ticks {
            return Err(ExpError::Stopped { time: robot.time() });
        }
        frame = robot.camera();
    }
    Ok(outcome)
}
