//! Python bindings of rss6 (module `rss6._rss6`, issue 7). The pure-Python package `rss6` re-exports
//! everything here; exceptions live in `rss6.errors` (mapped in `errors.rs`). Arrays cross as numpy float64;
//! every input is shape- and finiteness-checked before it reaches Rust, and long calls release the GIL.

use pyo3::prelude::*;

#[macro_use]
mod macros;

mod calib;
mod calib_data;
mod cloe;
mod convert;
mod ctrl;
mod dwell;
mod dynamics;
mod errors;
mod exp;
mod identify;
mod kinematics;
mod log;
mod params;
mod plant;
mod pyrobot;
mod servo;
mod thesis;

/// The compiled part of the `rss6` package.
#[pymodule]
fn _rss6(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // CLOE's default look-back of the settled stopping rule (`rss6_ident::SETTLE_STEPS`).
    m.add("SETTLE_STEPS", rss6_ident::SETTLE_STEPS)?;
    m.add_class::<params::PyKinematicParams>()?;
    m.add_class::<params::PyDynamicParams>()?;
    m.add_function(wrap_pyfunction!(kinematics::home_pose, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::ik, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::ik_batch, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::fk, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::fk_batch, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::jacobian_theta, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::jacobian_ad, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::mass_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::coriolis, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::gravity, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::friction, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::inverse_dynamics, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::forward_dynamics, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::regressor, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::dynamics_terms, m)?)?;
    m.add_function(wrap_pyfunction!(dynamics::rk4_step, m)?)?;
    m.add_class::<ctrl::PyTrajectory>()?;
    m.add_class::<ctrl::PyKalmanFilter>()?;
    m.add_class::<ctrl::PyDsmc>()?;
    m.add_class::<ctrl::PyKcsc>()?;
    m.add_class::<ctrl::PyKjsc>()?;
    m.add_class::<ctrl::PyTorqueToPosition>()?;
    m.add_class::<plant::PyModelSim>()?;
    m.add_class::<plant::PyPlant>()?;
    m.add_function(wrap_pyfunction!(servo::run_servo, m)?)?;
    m.add_function(wrap_pyfunction!(servo::compose_poses, m)?)?;
    m.add_function(wrap_pyfunction!(servo::invert_pose, m)?)?;
    m.add_class::<log::PyLogWriter>()?;
    m.add_function(wrap_pyfunction!(log::read_log, m)?)?;
    m.add_function(wrap_pyfunction!(log::mean_pose, m)?)?;
    m.add_class::<calib::PyCalibrationData>()?;
    m.add_class::<calib::PyCalibrationResult>()?;
    m.add_function(wrap_pyfunction!(calib::stroke, m)?)?;
    m.add_function(wrap_pyfunction!(calib::select_configurations, m)?)?;
    m.add_function(wrap_pyfunction!(dwell::collect, m)?)?;
    m.add_function(wrap_pyfunction!(calib::rpba, m)?)?;
    m.add_function(wrap_pyfunction!(calib::implicit, m)?)?;
    m.add_function(wrap_pyfunction!(calib::relative_pose_errors_raw, m)?)?;
    m.add_function(wrap_pyfunction!(calib::calibration_study, m)?)?;
    m.add_class::<identify::PyExcitationProblem>()?;
    m.add_function(wrap_pyfunction!(identify::excitation_at, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::identification_run, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::simulate_identification, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::cloe_identify, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::cloe_parameter_names, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::table_5_2_truth_params, m)?)?;
    m.add_function(wrap_pyfunction!(cloe::cloe_psi, m)?)?;
    m.add_function(wrap_pyfunction!(identify::loop_observability, m)?)?;
    m.add_function(wrap_pyfunction!(thesis::thesis_tables, m)?)?;
    Ok(())
}
