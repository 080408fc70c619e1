//! `rss6._rss6.collect`: calibration data collected on a simulated robot with rss6-exp's dwell runner
//! ([`rss6_exp::dwell::collect`]), optionally logged as it goes.

use pyo3::prelude::*;
use rss6_core::KinematicParams;
use rss6_exp::dwell::{self, DwellSpec};
use rss6_exp::{Flow, Observer, Progress};

use crate::calib::PyCalibrationData;
use crate::convert::rows6;
use crate::errors::invalid;
use crate::exp::{create_log, finish_log, Interrupt};
use crate::plant::with_robot;

/// Progress of a collection: `progress(done, total)` after each configuration, Ctrl-C checks.
struct DwellProgress {
    callback: Option<Py<PyAny>>,
    interrupt: Interrupt,
}

impl Observer for DwellProgress {
    fn progress(&mut self, p: &Progress) -> Flow {
        let cb = &self.callback;
        self.interrupt.call(|py| {
            if let Some(cb) = cb {
                cb.call1(py, (p.done as usize, p.total as usize))?;
            }
            Ok(())
        })
    }
}

/// Visits every configuration of `thetas` (m, 6) rad (drive convention; row 0 = the initial
/// configuration) on `plant` (rss6.Plant or rss6.ModelSim) with rss6-exp's dwell runner: a
/// cosine-blended move over `move_time` s from the current command, `settle_time` s of wait, then κ
/// (sampled at `kappa_rate` Hz) and ᶜχ_t (every finite frame, rss6-exp's `mean_pose`) averaged over
/// `dwell` s. The plant should be at rest (e.g. just reset): the first move starts at the drive
/// angles of its current readings. `progress(done, total)` is called after each configuration; if
/// it raises (KeyboardInterrupt included) the collection stops and the exception propagates; Ctrl-C
/// is checked at the same points. `mcap`: log the collection there as it goes (every tick's samples,
/// each dwell's means; metadata kind "rss6.calibrate.collect", configurations, dwell, move_time,
/// settle_time, kappa_rate; at the end status "finished" or "failed: …"). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (plant, thetas, dwell=2.0, *, move_time=1.0, settle_time=0.5, kappa_rate=500.0, progress=None, mcap=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn collect(
    py: Python<'_>,
    plant: &Bound<'_, PyAny>,
    thetas: &Bound<'_, PyAny>,
    dwell: f64,
    move_time: f64,
    settle_time: f64,
    kappa_rate: f64,
    progress: Option<Py<PyAny>>,
    mcap: Option<std::path::PathBuf>,
) -> PyResult<PyCalibrationData> {
    let thetas = rows6(thetas, "thetas")?;
    if thetas.is_empty() {
        return Err(invalid("thetas must contain at least one configuration"));
    }
    if !(dwell.is_finite() && dwell > 0.0) {
        return Err(invalid(format!(
            "dwell must be finite and > 0 s, got {dwell}"
        )));
    }
    // Every dwell is checked (reached the command in the drive's nominal convention, at rest, target
    // seen); a failing configuration stays in the data with its reason and the solvers leave it out.
    let spec = DwellSpec {
        move_time,
        settle_time,
        kappa_rate,
        ..DwellSpec::checked(&KinematicParams::nominal())
    };
    if !(move_time.is_finite()
        && move_time > 0.0
        && settle_time.is_finite()
        && settle_time >= 0.0
        && kappa_rate.is_finite()
        && kappa_rate > 0.0)
    {
        return Err(invalid(
            "move_time must be > 0 s, settle_time >= 0 s and kappa_rate > 0 Hz",
        ));
    }
    let mut log = match &mcap {
        Some(path) => Some(create_log(
            path,
            &[
                ("kind", "rss6.calibrate.collect".to_string()),
                ("configurations", thetas.len().to_string()),
                ("dwell", format!("{dwell:?}")),
                ("move_time", format!("{move_time:?}")),
                ("settle_time", format!("{settle_time:?}")),
                ("kappa_rate", format!("{kappa_rate:?}")),
            ],
        )?),
        None => None,
    };
    let mut obs = DwellProgress {
        callback: progress,
        interrupt: Interrupt::default(),
    };
    let data = with_robot(plant, |robot| {
        // The robot is at rest at its current readings: start the first move from there.
        let start = KinematicParams::nominal().theta_from_reading(&robot.potentiometers());
        py.detach(|| match log.as_mut() {
            // The log first: a dwell is on disk before `progress` hears of it.
            Some(l) => dwell::collect(robot, start, &thetas, dwell, &spec, &mut (l, &mut obs)),
            None => dwell::collect(robot, start, &thetas, dwell, &spec, &mut obs),
        })
    })?;
    let data = finish_log(py, log, data, obs.interrupt.take(), &[])?;
    Ok(PyCalibrationData { inner: data })
}
