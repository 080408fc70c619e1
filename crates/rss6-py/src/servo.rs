//! `rss6._rss6.run_servo`: a thin binding over rss6-exp's servo runner ([`rss6_exp::servo::track`]).
//! The arguments become a [`ServoSpec`]; an observer collects the arrays `rss6.servo.track` needs,
//! hands the rows of each segment to `on_segment`, stops the run when a callback raised or Ctrl-C was
//! pressed, and (with `mcap`) a [`LogObserver`] logs the run as it goes.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::{compose, pose_inverse, Vec6};
use rss6_ctrl::{PidGains, Reference, Trajectory};
use rss6_exp::servo::{track, Controller, ServoSpec, Tuning};
use rss6_exp::{Externals, Flow, Observer, Progress, Record, Tabulated};

use crate::convert::{out1, out_rows6, rows6, vec6};
use crate::ctrl::{PyTrajectory, Traj};
use crate::errors::{invalid, make, shape};
use crate::exp::{create_log, exp_err, finish_log, Interrupt};
use crate::params::{PyDynamicParams, PyKinematicParams};
use crate::plant::with_robot;

/// A built-in trajectory or one tabulated from Python.
enum AnyTraj {
    Builtin(Traj),
    Table(Tabulated),
}

impl Trajectory for AnyTraj {
    fn sample(&self, t: f64) -> Reference {
        match self {
            AnyTraj::Builtin(b) => b.sample(t),
            AnyTraj::Table(tb) => tb.sample(t),
        }
    }
}

/// The arrays of a servo run: per tick and per camera frame (see `rss6.servo.TrackingResult`).
#[derive(Default)]
struct Arrays {
    t: Vec<f64>,
    desired: Vec<Vec6>,
    truth: Vec<Vec6>,
    theta_cmd: Vec<Vec6>,
    torque: Vec<Vec6>,
    frame_t: Vec<f64>,
    frame_desired: Vec<Vec6>,
    frame_truth: Vec<Vec6>,
    measured: Vec<Vec6>,
    estimate: Vec<Vec6>,
    estimate_dot: Vec<Vec6>,
    sliding: Vec<Vec6>,
}

impl Arrays {
    fn push(&mut self, r: &Record) {
        let nan = Vec6::repeat(f64::NAN);
        let desired = r.reference.map_or(nan, |x| x.pose);
        let truth = r.truth.map_or(nan, |s| s.pose);
        self.t.push(r.t);
        self.desired.push(desired);
        self.truth.push(truth);
        self.theta_cmd.push(r.theta_cmd);
        self.torque.push(r.torque.unwrap_or(nan));
        if let Some(z) = r.camera {
            self.frame_t.push(r.t);
            self.frame_desired.push(desired);
            self.frame_truth.push(truth);
            self.measured.push(z);
            self.estimate.push(r.estimate.map_or(nan, |e| e.pose));
            self.estimate_dot
                .push(r.estimate.map_or(nan, |e| e.pose_dot));
            self.sliding.push(r.dsmc.map_or(nan, |(_, f)| f));
        }
    }

    /// The rows from tick `from.0` and camera frame `from.1` on, as a dict (keys of the result).
    fn dict<'py>(&self, py: Python<'py>, from: (usize, usize)) -> PyResult<Bound<'py, PyDict>> {
        let (a, f) = from;
        let d = PyDict::new(py);
        d.set_item("t", out1(py, self.t.get(a..).unwrap_or_default()))?;
        for (key, v) in [
            ("desired", &self.desired),
            ("true", &self.truth),
            ("theta_cmd", &self.theta_cmd),
            ("torque", &self.torque),
        ] {
            d.set_item(key, out_rows6(py, v.get(a..).unwrap_or_default()))?;
        }
        d.set_item(
            "frame_t",
            out1(py, self.frame_t.get(f..).unwrap_or_default()),
        )?;
        for (key, v) in [
            ("frame_desired", &self.frame_desired),
            ("frame_true", &self.frame_truth),
            ("measured", &self.measured),
            ("estimate", &self.estimate),
            ("estimate_dot", &self.estimate_dot),
            ("sliding", &self.sliding),
        ] {
            d.set_item(key, out_rows6(py, v.get(f..).unwrap_or_default()))?;
        }
        Ok(d)
    }
}

/// Collects the arrays; at each progress: Ctrl-C check and `on_segment(rows since the last call)`.
struct Collector {
    arrays: Arrays,
    on_segment: Option<Py<PyAny>>,
    sent: (usize, usize),
    interrupt: Interrupt,
}

impl Observer for Collector {
    fn record(&mut self, record: &Record) -> Flow {
        self.arrays.push(record);
        Flow::Continue
    }

    fn progress(&mut self, _progress: &Progress) -> Flow {
        let (arrays, sent, cb) = (&self.arrays, &mut self.sent, &self.on_segment);
        self.interrupt.call(|py| {
            if let Some(cb) = cb {
                cb.call1(py, (arrays.dict(py, *sent)?,))?;
            }
            *sent = (arrays.t.len(), arrays.frame_t.len());
            Ok(())
        })
    }
}

/// The reference: an rss6.Trajectory, or a tuple of three (N, 6) arrays tabulated every `dt`.
fn trajectory(obj: &Bound<'_, PyAny>, dt: f64) -> PyResult<(AnyTraj, String)> {
    if let Ok(t) = obj.cast::<PyTrajectory>() {
        let name: String = t.getattr("name")?.extract()?;
        return Ok((AnyTraj::Builtin(t.get().inner.clone()), name));
    }
    let Ok((p, v, a)) = obj.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>)>()
    else {
        return Err(invalid(
            "trajectory must be an rss6.Trajectory or a tuple of three (N, 6) arrays",
        ));
    };
    let (p, v, a) = (
        rows6(&p, "trajectory[0]")?,
        rows6(&v, "trajectory[1]")?,
        rows6(&a, "trajectory[2]")?,
    );
    if p.len() != v.len() || p.len() != a.len() || p.is_empty() {
        return Err(shape(
            "tabulated trajectory arrays must have the same non-zero length",
        ));
    }
    let rows = p
        .iter()
        .zip(v.iter().zip(a.iter()))
        .map(|(pose, (pose_dot, pose_ddot))| Reference {
            pose: *pose,
            pose_dot: *pose_dot,
            pose_ddot: *pose_ddot,
        })
        .collect();
    let table = Tabulated::new(dt, rows)
        .ok_or_else(|| invalid(format!("cannot tabulate the trajectory every {dt} s")))?;
    Ok((AnyTraj::Table(table), "table".into()))
}

/// The tuning name; "thesis" is refused with a pointer to "tuned".
fn tuning(name: &str) -> PyResult<Tuning> {
    if name.eq_ignore_ascii_case("thesis") {
        return Err(make(
            "InvalidParameterError",
            "tuning 'thesis' is no longer a tuning name: it selected rss6's own tuned DSMC gains \
             (the thesis gives none in SI for this robot); use 'tuned'",
            vec![],
        ));
    }
    Tuning::parse(name).map_err(exp_err)
}

/// Runs the closed loop of Fig. 6.2 (rss6-exp's servo runner) for `duration` s on `plant`
/// (rss6.Plant or rss6.ModelSim) and returns a dict of arrays (see `rss6.servo.track`; `theta_cmd`
/// in the drive's joint convention). `controller`: "dsmc", "kcsc" or "kjsc"; `tuning`: "tuned" or
/// "low_noise" (DSMC only). `trajectory`: an rss6.Trajectory, or a tuple of three (N, 6) arrays
/// (χ_d, χ̇_d, χ̈_d) tabulated every plant tick. `sensor_in_base` (ᴼχ_C) and `target_in_effector`
/// (ᴱχ_t) convert camera frames to χ_E; default: the plant's truth. `pid`, `torque_limit`,
/// `steady_state_kalman`, `kalman_r`, `kalman_q_jerk`, `camera_latency` override the tuning's
/// servo configuration. `on_segment` is called with a dict of the rows recorded since its previous
/// call (same keys as the result, without "controller" and "fault") every `segment` s of simulated
/// time and at the end; if it raises (KeyboardInterrupt included), the run stops and the exception
/// propagates; Ctrl-C is checked at the same points. `mcap`: log the run to this file as it goes
/// (metadata controller, tuning, trajectory, duration; at the end status and fault). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (plant, controller, trajectory, duration, kp_model, dp_model, *, sensor_in_base=None, target_in_effector=None, pid=None, torque_limit=None, steady_state_kalman=None, kalman_r=None, kalman_q_jerk=None, camera_latency=None, on_segment=None, segment=1.0, tuning="tuned", mcap=None, trajectory_name=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_servo<'py>(
    py: Python<'py>,
    plant: &Bound<'py, PyAny>,
    controller: &str,
    trajectory: &Bound<'py, PyAny>,
    duration: f64,
    kp_model: &PyKinematicParams,
    dp_model: &PyDynamicParams,
    sensor_in_base: Option<&Bound<'py, PyAny>>,
    target_in_effector: Option<&Bound<'py, PyAny>>,
    pid: Option<(f64, f64, f64)>,
    torque_limit: Option<f64>,
    steady_state_kalman: Option<bool>,
    kalman_r: Option<&Bound<'py, PyAny>>,
    kalman_q_jerk: Option<&Bound<'py, PyAny>>,
    camera_latency: Option<f64>,
    on_segment: Option<Py<PyAny>>,
    segment: f64,
    tuning: &str,
    mcap: Option<std::path::PathBuf>,
    trajectory_name: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let controller = Controller::parse(controller).map_err(exp_err)?;
    let tuning = self::tuning(tuning)?;
    let (dt, truth) = with_robot(plant, |r| (r.dt(), r.truth()))?;
    let (traj, name) = self::trajectory(trajectory, dt)?;
    let name = trajectory_name.unwrap_or(name);
    let externals = Externals {
        sensor_in_base: match (sensor_in_base, &truth) {
            (Some(s), _) => vec6(s, "sensor_in_base")?,
            (None, Some(t)) => t.sensor_in_base,
            (None, None) => return Err(invalid("sensor_in_base is needed for this robot")),
        },
        target_in_effector: match (target_in_effector, &truth) {
            (Some(s), _) => vec6(s, "target_in_effector")?,
            (None, Some(t)) => t.target_in_effector,
            (None, None) => return Err(invalid("target_in_effector is needed for this robot")),
        },
    };
    let mut spec = ServoSpec::new(
        controller,
        tuning,
        kp_model.inner,
        dp_model.inner,
        externals,
    )
    .map_err(exp_err)?;
    spec.duration = duration;
    spec.segment = segment;
    let c = &mut spec.config;
    if let Some((lp, li, ld)) = pid {
        c.pid = PidGains { lp, li, ld };
    }
    if let Some(v) = torque_limit {
        c.torque_limit = v;
    }
    if let Some(v) = steady_state_kalman {
        c.kalman.steady_state = v;
    }
    if let Some(r) = kalman_r {
        c.kalman.r = vec6(r, "kalman_r")?;
    }
    if let Some(q) = kalman_q_jerk {
        c.kalman.q_jerk = vec6(q, "kalman_q_jerk")?;
    }
    if let Some(v) = camera_latency {
        c.camera_latency = v;
    }
    if !(duration.is_finite() && duration > 0.0) {
        return Err(invalid(format!(
            "duration must be finite and > 0 s, got {duration}"
        )));
    }
    let mut log = match &mcap {
        Some(path) => Some(create_log(
            path,
            &[
                ("controller", controller.name().to_string()),
                ("tuning", tuning.name().to_string()),
                ("trajectory", name),
                ("duration", format!("{duration:?}")),
            ],
        )?),
        None => None,
    };
    let mut coll = Collector {
        arrays: Arrays::default(),
        on_segment,
        sent: (0, 0),
        interrupt: Interrupt::default(),
    };
    let outcome = with_robot(plant, |robot| {
        py.detach(|| match log.as_mut() {
            // The log first: a segment is on disk before the caller hears of it.
            Some(l) => track(robot, &spec, &traj, &mut (l, &mut coll)),
            None => track(robot, &spec, &traj, &mut coll),
        })
    })?;
    let fault = outcome
        .as_ref()
        .ok()
        .and_then(|o| o.first_fault)
        .map(|(t, r)| (t, r.to_string()));
    let end: Vec<(&str, String)> = fault
        .iter()
        .map(|(t, r)| ("fault", format!("t = {t:.3} s: {r}")))
        .collect();
    finish_log(py, log, outcome, coll.interrupt.take(), &end)?;
    let a = &coll.arrays;
    let d = a.dict(py, (0, 0))?;
    d.set_item("controller", controller.name())?;
    match fault {
        Some((t, r)) => d.set_item("fault", (t, r))?,
        None => d.set_item("fault", py.None())?,
    }
    Ok(d)
}

/// Pose composition a ∘ b (6,) (4×4 transform product of eq. 3.2 poses).
#[pyfunction]
pub(crate) fn compose_poses<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let (a, b) = (vec6(a, "a")?, vec6(b, "b")?);
    Ok(crate::convert::out6(py, &compose(&a, &b)))
}

/// Inverse pose a⁻¹ (6,).
#[pyfunction]
pub(crate) fn invert_pose<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let a = vec6(a, "a")?;
    Ok(crate::convert::out6(py, &pose_inverse(&a)))
}
