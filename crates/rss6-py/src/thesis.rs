//! `thesis_tables()`: the thesis's published numbers from [`rss6_core::thesis`], so Python reads them
//! from the same place as Rust (`rss6.thesis` re-exports them as constants).

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::thesis as t;

fn norms<'py>(py: Python<'py>, n: &t::CalibrationNorms) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("param_error", n.param_error)?;
    d.set_item("residual", n.residual)?;
    d.set_item("configurations", n.configurations)?;
    d.set_item("iterations", n.iterations)?;
    Ok(d)
}

fn tracking<'py>(py: Python<'py>, table: &t::TrackingTable) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (key, rows) in [("rmse", &table.rmse), ("mae", &table.mae)] {
        let by_scheme = PyDict::new(py);
        for (name, row) in t::TRACKING_SCHEMES.iter().zip(rows.iter()) {
            by_scheme.set_item(*name, row.to_vec())?;
        }
        d.set_item(key, by_scheme)?;
    }
    Ok(d)
}

/// The thesis's tables as a dict of dicts (SI units except Tables 6.1/6.2: mm and 1e-3 rad, as
/// printed); pose-indexed lists in the order [x, y, z, α, β, γ].
#[pyfunction]
pub(crate) fn thesis_tables(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);

    let d = PyDict::new(py);
    d.set_item("kappa_bits", t::KAPPA_NOISE_BITS)?;
    d.set_item("position", t::POSE_POSITION_NOISE)?;
    d.set_item("angle", t::POSE_ANGLE_NOISE)?;
    d.set_item("angle_deg", t::POSE_ANGLE_NOISE_DEG)?;
    out.set_item("table_4_1", d)?;

    let d = PyDict::new(py);
    d.set_item("length", t::SIGMA_LENGTH)?;
    d.set_item("eta", t::SIGMA_ETA)?;
    d.set_item("dtheta", t::SIGMA_DTHETA)?;
    d.set_item("ext_position", t::SIGMA_EXT_POSITION)?;
    d.set_item("ext_angle", t::SIGMA_EXT_ANGLE)?;
    out.set_item("table_4_2", d)?;

    out.set_item("table_4_3", norms(py, &t::TABLE_4_3_IMPLICIT)?)?;
    out.set_item("table_4_4", norms(py, &t::TABLE_4_4_RPBA)?)?;

    let d = PyDict::new(py);
    d.set_item("uncalibrated", t::TABLE_4_5_UNCALIBRATED.to_vec())?;
    d.set_item("implicit", t::TABLE_4_5_IMPLICIT.to_vec())?;
    d.set_item("RPBA", t::TABLE_4_5_RPBA.to_vec())?;
    out.set_item("table_4_5", d)?;

    let d = PyDict::new(py);
    d.set_item("platform", t::TABLE_5_1_PLATFORM.to_vec())?;
    d.set_item("wrench", t::TABLE_5_1_WRENCH.to_vec())?;
    d.set_item("link", t::TABLE_5_1_LINK.to_vec())?;
    out.set_item("table_5_1", d)?;

    let d = PyDict::new(py);
    d.set_item("pid_initial", t::TABLE_5_2_PID_INITIAL.to_vec())?;
    d.set_item("pid_identified", t::TABLE_5_2_PID_IDENTIFIED.to_vec())?;
    d.set_item("coulomb", t::TABLE_5_2_COULOMB.to_vec())?;
    d.set_item("viscous", t::TABLE_5_2_VISCOUS.to_vec())?;
    out.set_item("table_5_2", d)?;

    let d = PyDict::new(py);
    d.set_item("platform", t::TABLE_5_2_PLATFORM.to_vec())?;
    let rows: Vec<Vec<f64>> = t::TABLE_5_2_WRENCHES.iter().map(|r| r.to_vec()).collect();
    d.set_item("wrenches", rows)?;
    let rows: Vec<Vec<f64>> = t::TABLE_5_2_LINKS.iter().map(|r| r.to_vec()).collect();
    d.set_item("links", rows)?;
    out.set_item("table_5_2_bodies", d)?;

    let d = PyDict::new(py);
    d.set_item("before", t::TABLE_5_3_BEFORE.to_vec())?;
    d.set_item("after", t::TABLE_5_3_AFTER.to_vec())?;
    out.set_item("table_5_3", d)?;

    let rows: Vec<Vec<f64>> = t::TABLE_5_4.iter().map(|r| r.to_vec()).collect();
    out.set_item("table_5_4", rows)?;

    let d = PyDict::new(py);
    for (name, v) in t::TABLE_5_5_PERCENT {
        d.set_item(name, v)?;
    }
    out.set_item("table_5_5_percent", d)?;

    let d = PyDict::new(py);
    d.set_item("kp", t::VISUAL_PID_KP)?;
    d.set_item("ki", t::VISUAL_PID_KI)?;
    d.set_item("kd", t::VISUAL_PID_KD)?;
    out.set_item("visual_pid", d)?;

    let d = PyDict::new(py);
    d.set_item("control_period", t::CONTROL_PERIOD)?;
    d.set_item("experiment1_omega", t::EXPERIMENT1_OMEGA)?;
    d.set_item("experiment2_omega0", t::EXPERIMENT2_OMEGA0)?;
    d.set_item("experiment2_harmonics", t::EXPERIMENT2_HARMONICS)?;
    out.set_item("section_6_5", d)?;

    out.set_item("table_6_1", tracking(py, &t::TABLE_6_1)?)?;
    out.set_item("table_6_2", tracking(py, &t::TABLE_6_2)?)?;
    Ok(out)
}
