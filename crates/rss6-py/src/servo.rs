//! The whole visual-servo loop of Fig. 6.2 run in Rust (`rss6._rss6.run_servo`): rss6-ctrl's `Servo`
//! (Kalman filter + DSMC/KCSC/KJSC + converter + command guard) driving a simulated robot at 1 kHz,
//! recording every tick. `rss6.servo.track` wraps it.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::{compose, pose_inverse, KinematicParams, Vec6};
use rss6_ctrl::servo::{run, TickRecord};
use rss6_ctrl::{
    CartesianPidGains, Dsmc, DsmcGains, JointSpaceGains, Kcsc, Kjsc, PidGains, Plant, Reference,
    Scheme, Servo, ServoConfig, Trajectory,
};

use crate::convert::{out1, out_rows6, rows6, vec6};
use crate::ctrl::{ctrl_err, PyTrajectory, Traj};
use crate::errors::{core, invalid, shape};
use crate::params::{PyDynamicParams, PyKinematicParams};
use crate::plant::{sim_err, with_robot, SimRobot};

/// The servo's view of a simulated robot: camera frames converted to χ_E in the base frame with the
/// (estimated) external parameters, joint commands converted from the model's joint convention to the
/// drive's nominal one.
struct Adapter<'a> {
    robot: &'a mut dyn SimRobot,
    /// Set by the observer when an `on_segment` callback raised: the next step stops the run.
    stop: std::cell::Cell<bool>,
    sensor_in_base: Vec6,
    target_inv: Vec6,
    kp_model: KinematicParams,
    kp_nominal: KinematicParams,
    convert: bool,
}

impl Plant for Adapter<'_> {
    type Error = String;

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<(), String> {
        if self.stop.get() {
            return Err("run stopped: the on_segment callback raised".to_string());
        }
        if self.convert {
            let kappa = self.kp_model.reading_from_theta(theta_cmd);
            self.robot.step(&self.kp_nominal.theta_from_reading(&kappa))
        } else {
            self.robot.step(theta_cmd)
        }
    }

    fn camera(&mut self) -> Option<Vec6> {
        self.robot
            .camera()
            .map(|z| compose(&compose(&self.sensor_in_base, &z), &self.target_inv))
    }

    fn potentiometers(&self) -> Vec6 {
        self.robot.potentiometers()
    }

    fn time(&self) -> f64 {
        self.robot.time()
    }
}

/// A trajectory tabulated on the tick grid (for Python callables).
#[derive(Debug, Clone)]
struct Table {
    dt: f64,
    rows: Vec<Reference>,
}

impl Trajectory for Table {
    fn sample(&self, t: f64) -> Reference {
        let k = (t / self.dt).round().max(0.0) as usize;
        let k = k.min(self.rows.len().saturating_sub(1));
        self.rows
            .get(k)
            .copied()
            .unwrap_or(Reference::hold(&Vec6::repeat(f64::NAN)))
    }
}

enum AnyTraj {
    Builtin(Traj),
    Table(Table),
}

impl Trajectory for AnyTraj {
    fn sample(&self, t: f64) -> Reference {
        match self {
            AnyTraj::Builtin(b) => b.sample(t),
            AnyTraj::Table(tb) => tb.sample(t),
        }
    }
}

#[derive(Default)]
struct Log {
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
    fault: Option<(f64, String)>,
}

/// The rows of `log` from tick `from.0` and camera frame `from.1` on, as the dict passed to
/// `run_servo`'s `on_segment` callback (same keys and units as its result).
fn segment_dict<'py>(
    py: Python<'py>,
    log: &Log,
    from: (usize, usize),
) -> PyResult<Bound<'py, PyDict>> {
    let (a, f) = from;
    let d = PyDict::new(py);
    d.set_item("t", out1(py, log.t.get(a..).unwrap_or_default()))?;
    for (key, v) in [
        ("desired", &log.desired),
        ("true", &log.truth),
        ("theta_cmd", &log.theta_cmd),
        ("torque", &log.torque),
    ] {
        d.set_item(key, out_rows6(py, v.get(a..).unwrap_or_default()))?;
    }
    d.set_item(
        "frame_t",
        out1(py, log.frame_t.get(f..).unwrap_or_default()),
    )?;
    for (key, v) in [
        ("frame_desired", &log.frame_desired),
        ("frame_true", &log.frame_truth),
        ("measured", &log.measured),
        ("estimate", &log.estimate),
        ("estimate_dot", &log.estimate_dot),
        ("sliding", &log.sliding),
    ] {
        d.set_item(key, out_rows6(py, v.get(f..).unwrap_or_default()))?;
    }
    Ok(d)
}

/// Runs the closed loop for `duration` s on `plant` (rss6.Plant or rss6.ModelSim) and returns a dict
/// of arrays (see `rss6.servo.track`). `controller`: "dsmc", "kcsc" or "kjsc". `trajectory`: an
/// rss6.Trajectory, or a tuple of three (N, 6) arrays (χ_d, χ̇_d, χ̈_d) tabulated every plant tick.
/// `sensor_in_base` (ᴼχ_C) and `target_in_effector` (ᴱχ_t) convert camera frames to χ_E; default: the
/// plant's truth. `pid`: the drive's PID gains the converter inverts (default rss6-ctrl's nominal).
/// `on_segment`: called with a dict of the rows recorded since its previous call (same keys as the
/// result, without "controller" and "fault") every `segment` s of simulated time and once at the end,
/// so a caller can log the run as it goes; if it raises, the run stops and the error propagates.
#[pyfunction]
#[pyo3(signature = (plant, controller, trajectory, duration, kp_model, dp_model, *, sensor_in_base=None, target_in_effector=None, pid=None, torque_limit=30.0, steady_state_kalman=false, kalman_r=None, kalman_q_jerk=None, camera_latency=0.0, on_segment=None, segment=1.0, tuning="thesis"))]
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
    torque_limit: f64,
    steady_state_kalman: bool,
    kalman_r: Option<&Bound<'py, PyAny>>,
    kalman_q_jerk: Option<&Bound<'py, PyAny>>,
    camera_latency: f64,
    on_segment: Option<&Bound<'py, PyAny>>,
    segment: f64,
    tuning: &str,
) -> PyResult<Bound<'py, PyDict>> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(invalid(format!(
            "duration must be finite and > 0 s, got {duration}"
        )));
    }
    if !(segment.is_finite() && segment > 0.0) {
        return Err(invalid(format!(
            "segment must be finite and > 0 s, got {segment}"
        )));
    }
    let on_segment: Option<Py<PyAny>> = on_segment.map(|cb| cb.clone().unbind());
    let traj = if let Ok(t) = trajectory.cast::<PyTrajectory>() {
        AnyTraj::Builtin(t.get().inner.clone())
    } else if let Ok((p, v, a)) =
        trajectory.extract::<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyAny>)>()
    {
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
        let dt = with_robot(plant, |r| r.dt())?;
        let rows = p
            .iter()
            .zip(v.iter().zip(a.iter()))
            .map(|(pose, (pose_dot, pose_ddot))| Reference {
                pose: *pose,
                pose_dot: *pose_dot,
                pose_ddot: *pose_ddot,
            })
            .collect();
        AnyTraj::Table(Table { dt, rows })
    } else {
        return Err(invalid(
            "trajectory must be an rss6.Trajectory or a tuple of three (N, 6) arrays",
        ));
    };
    let kp_model = kp_model.inner;
    let dp_model = dp_model.inner;
    let truth = with_robot(plant, |r| r.truth())?;
    let sensor = match sensor_in_base {
        Some(s) => vec6(s, "sensor_in_base")?,
        None => truth.sensor_in_base,
    };
    let target = match target_in_effector {
        Some(s) => vec6(s, "target_in_effector")?,
        None => truth.target_in_effector,
    };
    let controller = controller.to_ascii_lowercase();
    let low_noise = match tuning.to_ascii_lowercase().replace('-', "_").as_str() {
        "thesis" => false,
        "low_noise" => true,
        other => {
            return Err(invalid(format!(
                "tuning must be 'thesis' or 'low_noise', got '{other}'"
            )))
        }
    };
    if low_noise && controller != "dsmc" {
        return Err(invalid(format!(
            "tuning 'low_noise' is for the DSMC only (controller '{controller}')"
        )));
    }
    let mut config = if low_noise {
        ServoConfig::low_noise()
    } else {
        ServoConfig::tuned()
    };
    if let Some((lp, li, ld)) = pid {
        config.pid = PidGains { lp, li, ld };
    }
    config.torque_limit = torque_limit;
    config.kalman.steady_state = steady_state_kalman;
    if let Some(r) = kalman_r {
        config.kalman.r = vec6(r, "kalman_r")?;
    }
    if let Some(q) = kalman_q_jerk {
        config.kalman.q_jerk = vec6(q, "kalman_q_jerk")?;
    }
    config.camera_latency = camera_latency;

    let result = with_robot(plant, |robot| -> PyResult<Log> {
        let dt = robot.dt();
        config.joint_dt = dt;
        // Joint conventions: KJSC turns χ_d into joint angles by the model's IK, so it works in the
        // model's (calibrated) physical convention and its commands are converted to the drive's nominal
        // one. DSMC's converter must mirror the drive's PID exactly, so DSMC (and KCSC, whose joint
        // increments come from J_θ) work in the drive's nominal convention.
        let convert = controller == "kjsc";
        let kp_nominal = KinematicParams::nominal();
        let kp_servo = if convert { kp_model } else { kp_nominal };
        let kappa0 = robot.potentiometers();
        let theta0 = kp_servo.theta_from_reading(&kappa0);
        let t0 = robot.time();
        let mut adapter = Adapter {
            robot,
            stop: std::cell::Cell::new(false),
            sensor_in_base: sensor,
            target_inv: pose_inverse(&target),
            kp_model,
            kp_nominal,
            convert,
        };
        // Kalman start: the first camera frame if one is pending, else the model's FK of the readings.
        let start = match adapter.camera() {
            Some(p) => p,
            None => {
                rss6_core::fk(
                    &kp_model,
                    &kp_model.theta_from_reading(&kappa0),
                    &rss6_core::home_pose(),
                    &rss6_core::FkOptions::default(),
                )
                .map_err(core)?
                .pose
            }
        };
        let scheme = match controller.as_str() {
            "dsmc" => {
                let gains = if low_noise {
                    DsmcGains::low_noise()
                } else {
                    DsmcGains::tuned()
                };
                Scheme::Dsmc(Dsmc::new(kp_model, dp_model, gains).map_err(ctrl_err)?)
            }
            "kcsc" => Scheme::Kcsc(
                Kcsc::new(kp_model, CartesianPidGains::thesis(), &theta0).map_err(ctrl_err)?,
            ),
            "kjsc" => Scheme::Kjsc(
                Kjsc::new(kp_model, JointSpaceGains::from_visual_pid(), &theta0)
                    .map_err(ctrl_err)?,
            ),
            other => {
                return Err(invalid(format!(
                    "controller must be 'dsmc', 'kcsc' or 'kjsc', got '{other}'"
                )))
            }
        };
        let mut servo =
            Servo::new(kp_servo, config, scheme, &start, &kappa0, t0).map_err(ctrl_err)?;
        let ticks = (duration / dt).round() as u32;
        let mut log = Log::default();
        // The observer sees the plant after the tick's step; record the true pose at the start of the
        // tick, when the reference was sampled and the consumed camera frame was taken.
        let mut start_pose = adapter.robot.true_pose();
        let segment_ticks = ((segment / dt).round() as usize).max(1);
        let mut sent = (0usize, 0usize);
        let mut callback_error: Option<PyErr> = None;
        let deliver = |log: &Log, sent: &mut (usize, usize)| -> PyResult<()> {
            if let Some(cb) = on_segment.as_ref() {
                Python::attach(|py| cb.call1(py, (segment_dict(py, log, *sent)?,)))?;
            }
            *sent = (log.t.len(), log.frame_t.len());
            Ok(())
        };
        let summary = py.detach(|| {
            run(
                &mut adapter,
                &mut servo,
                &traj,
                t0,
                ticks,
                |rec: &TickRecord, p: &Adapter<'_>| {
                    let t = rec.t - t0;
                    let true_pose = start_pose;
                    start_pose = p.robot.true_pose();
                    log.t.push(t);
                    log.desired.push(rec.reference.pose);
                    log.truth.push(true_pose);
                    log.theta_cmd.push(rec.theta_cmd);
                    log.torque.push(p.robot.torque());
                    if let Some(z) = rec.camera {
                        log.frame_t.push(t);
                        log.frame_desired.push(rec.reference.pose);
                        log.frame_truth.push(true_pose);
                        log.measured.push(z);
                        let est = rec.tick.and_then(|k| k.estimate);
                        log.estimate
                            .push(est.map(|e| e.pose).unwrap_or(Vec6::repeat(f64::NAN)));
                        log.estimate_dot
                            .push(est.map(|e| e.pose_dot).unwrap_or(Vec6::repeat(f64::NAN)));
                        let f = rec.tick.and_then(|k| k.dsmc).map(|(_, f)| f);
                        log.sliding.push(f.unwrap_or(Vec6::repeat(f64::NAN)));
                    }
                    if on_segment.is_some()
                        && callback_error.is_none()
                        && log.t.len() - sent.0 >= segment_ticks
                    {
                        if let Err(e) = deliver(&log, &mut sent) {
                            callback_error = Some(e);
                            p.stop.set(true);
                        }
                    }
                },
            )
        });
        if let Some(e) = callback_error {
            return Err(e);
        }
        let summary = summary.map_err(sim_err)?;
        if on_segment.is_some() && (log.t.len() > sent.0 || sent == (0, 0)) {
            deliver(&log, &mut sent)?;
        }
        log.fault = summary.first_fault.map(|(t, r)| (t - t0, r.to_string()));
        Ok(log)
    })??;

    let d = PyDict::new(py);
    d.set_item("t", out1(py, &result.t))?;
    d.set_item("desired", out_rows6(py, &result.desired))?;
    d.set_item("true", out_rows6(py, &result.truth))?;
    d.set_item("theta_cmd", out_rows6(py, &result.theta_cmd))?;
    d.set_item("torque", out_rows6(py, &result.torque))?;
    d.set_item("frame_t", out1(py, &result.frame_t))?;
    d.set_item("frame_desired", out_rows6(py, &result.frame_desired))?;
    d.set_item("frame_true", out_rows6(py, &result.frame_truth))?;
    d.set_item("measured", out_rows6(py, &result.measured))?;
    d.set_item("estimate", out_rows6(py, &result.estimate))?;
    d.set_item("estimate_dot", out_rows6(py, &result.estimate_dot))?;
    d.set_item("sliding", out_rows6(py, &result.sliding))?;
    d.set_item("controller", controller.to_ascii_uppercase())?;
    match result.fault {
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
