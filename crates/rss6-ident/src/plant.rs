//! Calibration data from the rapier plant (or its analytic twin): any `rss6_sim::RobotSim` drives the
//! [`Stepped`] adapter, so the plant's own PID, potentiometers (500 Hz) and stereo CMM (~29 Hz) produce
//! the data exactly as on the real robot.

use crate::data::{Stepped, SteppedRobot};
use crate::error::{IdentError, Result};
use crate::generator::{perturb_external, TrueRobot};
use rand::Rng;
use rss6_core::{KinematicParams, Vec6};
use rss6_sim::{
    default_sensor_in_base, default_target_in_effector, Plant, RobotSim, SimConfig, Truth,
};

/// A `RobotSim` seen as a [`SteppedRobot`].
#[derive(Debug)]
pub struct SimRobot<S>(pub S);

fn sim_error(e: rss6_sim::SimError) -> IdentError {
    IdentError::Source(e.to_string())
}

impl<S: RobotSim> SteppedRobot for SimRobot<S> {
    fn dt(&self) -> f64 {
        1e-3
    }

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()> {
        self.0.step_joint_command(theta_cmd).map_err(sim_error)
    }

    fn camera(&mut self) -> Option<Vec6> {
        self.0.camera()
    }

    fn potentiometers(&mut self) -> Vec6 {
        self.0.potentiometers()
    }
}

impl TrueRobot {
    /// The calibration-relevant part of a simulator's truth.
    pub fn from_sim_truth(truth: &Truth) -> Self {
        TrueRobot {
            kp: truth.kinematics,
            sensor_in_base: truth.sensor_in_base,
            target_in_effector: truth.target_in_effector,
        }
    }
}

/// Wraps `sim` for [`crate::collect`]: resets it at rest where the true robot sits under the
/// nominal-convention command θ = 0 (so the first configuration needs no jump), and returns the
/// adapter, which starts from that command.
pub fn sim_source<S: RobotSim>(
    mut sim: S,
    nominal: &KinematicParams,
) -> Result<Stepped<SimRobot<S>>> {
    let truth = TrueRobot::from_sim_truth(&sim.truth());
    let kappa0 = nominal.reading_from_theta(&Vec6::zeros());
    let pose0 = truth.pose_from_reading(&kappa0, &rss6_core::home_pose())?;
    sim.reset(&pose0).map_err(sim_error)?;
    Ok(Stepped::new(SimRobot(sim), Vec6::zeros()))
}

/// A rapier plant whose kinematics are drawn with Table 4.2 errors around `nominal` and whose external
/// poses are the simulator's defaults perturbed by Table 4.2's external sizes; nominal dynamics and PID.
/// Returns the plant (reset, wrapped for [`crate::collect`]) and its truth.
pub fn random_plant(
    nominal: &KinematicParams,
    rng: &mut impl Rng,
    seed: u64,
) -> Result<(Stepped<SimRobot<Plant>>, TrueRobot)> {
    let drawn = TrueRobot::draw(nominal, rng);
    let mut cfg = SimConfig::new(
        drawn.kp,
        rss6_core::DynamicParams::nominal(),
        rss6_ctrl::PidGains::tuned(),
    );
    cfg.nominal = *nominal;
    cfg.seed = seed;
    cfg.sensor_in_base = perturb_external(&default_sensor_in_base(), rng);
    cfg.target_in_effector = perturb_external(&default_target_in_effector(), rng);
    let plant = Plant::new(cfg).map_err(sim_error)?;
    let truth = TrueRobot::from_sim_truth(&plant.truth());
    Ok((sim_source(plant, nominal)?, truth))
}

/// The simulator's nominal ᴱχ_t (the starting guess for calibrations on the plant).
pub fn plant_nominal_target() -> Vec6 {
    default_target_in_effector()
}
