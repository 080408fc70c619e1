//! Calibration data (§4.4.3, §4.5): for every configuration l = 0..m (0 = the initial configuration)
//! the mean potentiometer readings κ^l and the mean sensor pose ᶜχ_t^l over a dwell, and the sources
//! that produce them. The data types and the dwell runner are the experiment layer's
//! ([`rss6_exp::dwell`]).

use crate::error::{IdentError, Result};
use rss6_core::Vec6;
use rss6_exp::dwell::DwellSession;
pub use rss6_exp::dwell::{CalibrationData, ConfigurationData};

/// Anything that can hold the robot at a commanded configuration and report mean readings: the rapier
/// plant (through the experiment layer's [`DwellSession`]), the analytic generator ([`crate::AnalyticRobot`]) or a log reader.
pub trait RobotSource {
    /// Moves to `theta_cmd` (rad, nominal joint convention), waits until at rest, then averages the
    /// potentiometers and the camera over `dwell` seconds.
    fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData>;
}

/// The experiment layer's dwell runner is a source: the robot is driven tick by tick (move, settle,
/// dwell) exactly as on the real robot.
impl<R: rss6_exp::Robot> RobotSource for DwellSession<R> {
    fn measure(&mut self, theta_cmd: &Vec6, dwell: f64) -> Result<ConfigurationData> {
        DwellSession::measure(self, theta_cmd, dwell).map_err(|e| match e {
            rss6_exp::ExpError::InvalidInput(m) => IdentError::InvalidInput(m),
            other => IdentError::Source(other.to_string()),
        })
    }
}

/// Visits every configuration of `thetas` (rad, nominal convention; `thetas[0]` is the initial
/// configuration) and records the means over `dwell` seconds.
pub fn collect(
    source: &mut dyn RobotSource,
    thetas: &[Vec6],
    dwell: f64,
) -> Result<CalibrationData> {
    collect_with_progress(source, thetas, dwell, &mut |_, _| {})
}

/// [`collect`] with a progress callback `progress(done, total)` after each configuration.
pub fn collect_with_progress(
    source: &mut dyn RobotSource,
    thetas: &[Vec6],
    dwell: f64,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<CalibrationData> {
    let mut data = CalibrationData::default();
    for (k, th) in thetas.iter().enumerate() {
        data.configurations.push(source.measure(th, dwell)?);
        progress(k + 1, thetas.len());
    }
    Ok(data)
}
