//! Model validation like the thesis's Fig. 5.5–5.6: the plant and the model twin, same nominal
//! parameters, same PID, same exciting trajectory; the pose difference over time.

use crate::error::Result;
use crate::sim::{Physics, Robot, RobotSim};
use rss6_core::{home_pose, ik, pose_rotation, KinematicParams, Vec6};
use std::f64::consts::PI;

/// A smooth multi-sine platform trajectory around the home pose, started from rest by a
/// (1 − cos) ramp of its amplitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExcitingTrajectory {
    /// Amplitudes per pose coordinate (m, rad).
    pub amplitude: Vec6,
    /// Frequencies per pose coordinate (Hz).
    pub frequency: Vec6,
    /// Duration of the amplitude ramp (s).
    pub ramp: f64,
}

impl Default for ExcitingTrajectory {
    /// ±12 mm, ±10 mm in z, ±0.03–0.04 rad at 0.4–0.9 Hz (non-commensurate), 0.5 s ramp.
    fn default() -> Self {
        ExcitingTrajectory {
            amplitude: Vec6::new(0.012, 0.012, 0.010, 0.03, 0.03, 0.04),
            frequency: Vec6::new(0.5, 0.7, 0.9, 0.6, 0.8, 0.4),
            ramp: 0.5,
        }
    }
}

impl ExcitingTrajectory {
    /// Desired pose χ_d(t).
    pub fn pose(&self, t: f64) -> Vec6 {
        let s = if t >= self.ramp {
            1.0
        } else {
            0.5 * (1.0 - (PI * t.max(0.0) / self.ramp).cos())
        };
        home_pose()
            + Vec6::from_fn(|i, _| s * self.amplitude[i] * (2.0 * PI * self.frequency[i] * t).sin())
    }

    /// Joint command at time t in the nominal convention: IK of the nominal robot.
    pub fn joint_command(&self, nominal: &KinematicParams, t: f64) -> Result<Vec6> {
        Ok(ik(nominal, &self.pose(t))?)
    }
}

/// One sample of the plant–twin comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiffSample {
    /// Time (s).
    pub time: f64,
    /// |E_plant − E_twin| (m).
    pub position: f64,
    /// Rotation angle of R_plantᵀ R_twin (rad).
    pub angle: f64,
    /// Plant loop-closure gap (m).
    pub loop_closure: f64,
    /// Largest gap the constraint solvers left before the post-step projection (m).
    pub solver_gap: f64,
    /// Distance of robot `a`'s platform from the home position (m): shows the motion is real.
    pub excursion: f64,
}

/// Position and orientation distance between two poses (m, rad).
pub fn pose_distance(a: &Vec6, b: &Vec6) -> (f64, f64) {
    let dp = (a.fixed_rows::<3>(0) - b.fixed_rows::<3>(0)).norm();
    let r = pose_rotation(a).transpose() * pose_rotation(b);
    let c = ((r.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
    (dp, c.acos())
}

/// Runs two robots on the same trajectory from the home pose for `duration` s and records their
/// pose difference every `every` ticks.
pub fn compare<P: Physics, Q: Physics>(
    a: &mut Robot<P>,
    b: &mut Robot<Q>,
    traj: &ExcitingTrajectory,
    nominal: &KinematicParams,
    duration: f64,
    every: usize,
) -> Result<Vec<DiffSample>> {
    a.reset(&home_pose())?;
    b.reset(&home_pose())?;
    let dt = a.config().dt;
    let n = (duration / dt).round() as usize;
    let mut out = Vec::with_capacity(n / every.max(1) + 1);
    for k in 0..n {
        let cmd = traj.joint_command(nominal, k as f64 * dt)?;
        a.step_joint_command(&cmd)?;
        b.step_joint_command(&cmd)?;
        if (k + 1) % every.max(1) == 0 {
            let (position, angle) = pose_distance(&a.true_pose(), &b.true_pose());
            out.push(DiffSample {
                time: a.time(),
                position,
                angle,
                loop_closure: a.loop_closure_error().max(b.loop_closure_error()),
                solver_gap: a.solver_gap().max(b.solver_gap()),
                excursion: pose_distance(&a.true_pose(), &home_pose()).0,
            });
        }
    }
    Ok(out)
}
