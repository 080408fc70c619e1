//! Calibration data from the rapier plant (or its analytic twin): the experiment layer's dwell runner
//! ([`DwellSession`]) drives it, so the plant's own PID, potentiometers (500 Hz) and stereo CMM (~29 Hz)
//! produce the data exactly as on the real robot.

use crate::error::{IdentError, Result};
use rss6_exp::dwell::{DwellSession, DwellSpec};

fn sim_error(e: rss6_sim::SimError) -> IdentError {
    IdentError::Source(e.to_string())
}
use crate::generator::{perturb_external, TrueRobot};
use rand::Rng;
use rss6_core::{KinematicParams, Vec6};
use rss6_sim::{
    default_sensor_in_base, default_target_in_effector, Plant, RobotSim, SimConfig, Truth,
};

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
/// adapter, which starts from that command and checks every dwell ([`DwellSpec::checked`] in the
/// convention of `nominal`).
pub fn sim_source<S: RobotSim + rss6_exp::Robot>(
    mut sim: S,
    nominal: &KinematicParams,
) -> Result<DwellSession<S>> {
    let truth = TrueRobot::from_sim_truth(&RobotSim::truth(&sim));
    let kappa0 = nominal.reading_from_theta(&Vec6::zeros());
    let pose0 = truth.pose_from_reading(&kappa0, &rss6_core::home_pose())?;
    sim.reset(&pose0).map_err(sim_error)?;
    Ok(DwellSession::new(
        sim,
        Vec6::zeros(),
        DwellSpec::checked(nominal),
    ))
}

/// A rapier plant whose kinematics are drawn with Table 4.2 errors around `nominal` and whose external
/// poses are the simulator's defaults perturbed by Table 4.2's external sizes; nominal dynamics and PID.
/// Returns the plant (reset, wrapped for [`crate::collect`]) and its truth.
pub fn random_plant(
    nominal: &KinematicParams,
    rng: &mut impl Rng,
    seed: u64,
) -> Result<(DwellSession<Plant>, TrueRobot)> {
    let drawn = TrueRobot::draw(nominal, rng);
    plant_with_kinematics(nominal, &drawn.kp, rng, seed)
}

/// [`random_plant`] with given true kinematics `kp` (e.g. drawn by rejection sampling); the external
/// poses are drawn from `rng`.
pub fn plant_with_kinematics(
    nominal: &KinematicParams,
    kp: &KinematicParams,
    rng: &mut impl Rng,
    seed: u64,
) -> Result<(DwellSession<Plant>, TrueRobot)> {
    let mut cfg = SimConfig::new(
        *kp,
        rss6_core::DynamicParams::nominal(),
        rss6_ctrl::PidGains::tuned(),
    );
    cfg.nominal = *nominal;
    cfg.seed = seed;
    cfg.sensor_in_base = perturb_external(&default_sensor_in_base(), rng);
    cfg.target_in_effector = perturb_external(&default_target_in_effector(), rng);
    let plant = Plant::new(cfg).map_err(sim_error)?;
    let truth = TrueRobot::from_sim_truth(&RobotSim::truth(&plant));
    Ok((sim_source(plant, nominal)?, truth))
}

/// The simulator's nominal ᴱχ_t (the starting guess for calibrations on the plant).
pub fn plant_nominal_target() -> Vec6 {
    default_target_in_effector()
}
