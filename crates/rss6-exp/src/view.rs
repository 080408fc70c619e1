//! What a controller sees of a robot: camera frames in the base frame through the *estimated* external
//! parameters, commands converted between the model's and the drive's joint conventions.

use crate::error::ExpError;
use crate::robot::Robot;
use rss6_core::{compose, pose_inverse, KinematicParams, Vec6};

/// The external parameters the experimenter uses (estimates, e.g. from calibration).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Externals {
    /// ᴼχ_C: the sensor (camera) frame in the base frame (m, rad).
    pub sensor_in_base: Vec6,
    /// ᴱχ_t: the target frame in the end-effector frame (m, rad).
    pub target_in_effector: Vec6,
}

impl Externals {
    /// χ_E = ᴼχ_C ∘ ᶜχ_t ∘ (ᴱχ_t)⁻¹: the end-effector pose in the base frame from a camera frame.
    pub fn effector_pose(&self, sensor_pose: &Vec6) -> Vec6 {
        compose(
            &compose(&self.sensor_in_base, sensor_pose),
            &pose_inverse(&self.target_in_effector),
        )
    }

    /// ᶜχ_t = (ᴼχ_C)⁻¹ ∘ χ_E ∘ ᴱχ_t: the camera frame of an end-effector pose.
    pub fn sensor_pose(&self, effector_pose: &Vec6) -> Vec6 {
        compose(
            &pose_inverse(&self.sensor_in_base),
            &compose(effector_pose, &self.target_in_effector),
        )
    }
}

/// The joint convention a controller commands in.
// Built once per run and read every tick: keep the parameters inline rather than boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Convention {
    /// The drive's (nominal η, Δθ): commands go to the drive unchanged. DSMC (its converter mirrors
    /// the drive's PID) and KCSC (joint increments from J_θ) work here.
    Drive,
    /// The model's physical convention (calibrated η, Δθ): commands are converted to the drive's
    /// through the reading they mean, κ = (θ − Δθ_model)/η_model. KJSC (θ_d from the model's IK)
    /// works here.
    Model(KinematicParams),
}

/// A [`Robot`] as a controller sees it; implements [`rss6_ctrl::Plant`].
///
/// `stop` is set by a runner when its observer asks to stop: the next command is refused with
/// [`ExpError::Stopped`], which ends rss6-ctrl's runner.
#[derive(Debug)]
pub struct View<R> {
    /// The robot.
    pub robot: R,
    /// The external parameters used to turn frames into χ_E.
    pub externals: Externals,
    /// The drive's joint convention (nominal kinematics).
    pub drive: KinematicParams,
    /// The convention the controller's commands are in.
    pub convention: Convention,
    pub(crate) stop: bool,
    pub(crate) last_sensor_pose: Option<Vec6>,
}

impl<R: Robot> View<R> {
    /// A view of `robot` through `externals`, with the drive's convention `drive` (the nominal
    /// kinematics) and commands in `convention`.
    pub fn new(
        robot: R,
        externals: Externals,
        drive: KinematicParams,
        convention: Convention,
    ) -> Self {
        View {
            robot,
            externals,
            drive,
            convention,
            stop: false,
            last_sensor_pose: None,
        }
    }

    /// The drive-convention command for a command in the controller's convention.
    pub fn to_drive(&self, theta_cmd: &Vec6) -> Vec6 {
        match &self.convention {
            Convention::Drive => *theta_cmd,
            Convention::Model(kp) => self
                .drive
                .theta_from_reading(&kp.reading_from_theta(theta_cmd)),
        }
    }

    /// Joint angles (controller convention) of potentiometer readings κ.
    pub fn theta_from_reading(&self, kappa: &Vec6) -> Vec6 {
        match &self.convention {
            Convention::Drive => self.drive.theta_from_reading(kappa),
            Convention::Model(kp) => kp.theta_from_reading(kappa),
        }
    }

    /// The raw frame ᶜχ_t behind the last [`rss6_ctrl::Plant::camera`] result.
    pub fn last_sensor_pose(&self) -> Option<Vec6> {
        self.last_sensor_pose
    }
}

impl<R: Robot> rss6_ctrl::Plant for View<R> {
    type Error = ExpError;

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<(), ExpError> {
        if self.stop {
            return Err(ExpError::Stopped {
                time: self.robot.time(),
            });
        }
        let cmd = self.to_drive(theta_cmd);
        self.robot.step_joint_command(&cmd)
    }

    fn camera(&mut self) -> Option<Vec6> {
        self.last_sensor_pose = self.robot.camera();
        self.last_sensor_pose
            .map(|z| self.externals.effector_pose(&z))
    }

    fn potentiometers(&self) -> Vec6 {
        self.robot.potentiometers()
    }

    fn time(&self) -> f64 {
        self.robot.time()
    }
}
