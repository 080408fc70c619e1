//! Simulated robots as Python classes: `rss6.ModelSim` (the analytic-model twin: rss6-core forward
//! dynamics + the drive's joint PID + sensors) and, when rss6-sim provides it, `rss6.Plant` (rapier).
//! Both implement [`SimRobot`], which is what the servo and calibration runners drive.

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rss6_core::{
    compose, ik, pose_inverse, rk4_step, DynamicParams, KinematicParams, ModelState, Vec6,
};
use rss6_ctrl::{JointPid, PidGains};

use crate::convert::{out6, vec6};
use crate::errors::{core, invalid, make};
use crate::params::{PyDynamicParams, PyKinematicParams};

/// Table 4.1 camera noise (1σ): position (m), angle (rad).
pub(crate) const CAMERA_SIGMA: [f64; 2] = [0.0096e-3, 0.0261 * std::f64::consts::PI / 180.0];
/// Table 4.1 potentiometer noise (1σ, bits).
pub(crate) const POT_SIGMA: f64 = 0.2233;

/// The plant's hidden truth.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Truth {
    pub(crate) kp: KinematicParams,
    pub(crate) dp: DynamicParams,
    pub(crate) pid: PidGains,
    pub(crate) sensor_in_base: Vec6,
    pub(crate) target_in_effector: Vec6,
}

/// A robot driven tick by tick (joint commands in the nominal joint convention).
pub(crate) trait SimRobot: Send + Sync {
    /// Tick length (s).
    fn dt(&self) -> f64;
    /// Plant time (s).
    fn time(&self) -> f64;
    /// Places the robot at rest at `pose` (physical IK of the truth), drive PID at rest.
    fn reset(&mut self, pose: &Vec6) -> Result<(), String>;
    /// One tick with the joint command θ_cmd (rad, nominal convention).
    fn step(&mut self, theta_cmd: &Vec6) -> Result<(), String>;
    /// ᶜχ_t if a frame completed since the last call.
    fn camera(&mut self) -> Option<Vec6>;
    /// Latest potentiometer readings κ (bits).
    fn potentiometers(&self) -> Vec6;
    /// True end-effector pose χ_E (m, rad).
    fn true_pose(&self) -> Vec6;
    /// True physical joint angles (rad).
    fn true_theta(&self) -> Vec6;
    /// Last drive torques (N·m).
    fn torque(&self) -> Vec6;
    /// The hidden truth.
    fn truth(&self) -> Truth;
}

/// The analytic-model robot: RK4 of rss6-core forward dynamics at 1 kHz on the true kinematics and
/// dynamics, the drive's PID on its own (noisy, 500 Hz) potentiometer readings in the nominal joint
/// convention, and a camera at 1/0.033 s reporting ᶜχ_t = (ᴼχ_C)⁻¹ ∘ χ_E ∘ ᴱχ_t with Table 4.1 noise.
#[derive(Debug, Clone)]
pub(crate) struct ModelRobot {
    truth: Truth,
    kp_nominal: KinematicParams,
    pid: JointPid,
    torque_limit: f64,
    state: ModelState,
    tick: u64,
    dt: f64,
    camera_every: u64,
    pot_every: u64,
    camera_noise: bool,
    pot_noise: bool,
    kappa: Vec6,
    pending: Option<Vec6>,
    tau: Vec6,
    rng: ChaCha8Rng,
}

impl ModelRobot {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        truth: Truth,
        dt: f64,
        torque_limit: f64,
        camera_period: f64,
        camera_noise: bool,
        pot_noise: bool,
        seed: u64,
    ) -> Result<Self, String> {
        truth.kp.validate().map_err(|e| e.to_string())?;
        truth.dp.validate().map_err(|e| e.to_string())?;
        if !(dt.is_finite() && dt > 0.0 && dt <= 0.01) {
            return Err(format!("dt must be in (0, 0.01] s, got {dt}"));
        }
        let camera_every = (camera_period / dt).round().max(1.0) as u64;
        let pot_every = (0.002 / dt).round().max(1.0) as u64;
        let mut r = ModelRobot {
            truth,
            kp_nominal: KinematicParams::nominal(),
            pid: JointPid::new(truth.pid, dt, torque_limit),
            torque_limit,
            state: ModelState { pose: rss6_core::home_pose(), pose_dot: Vec6::zeros() },
            tick: 0,
            dt,
            camera_every,
            pot_every,
            camera_noise,
            pot_noise,
            kappa: Vec6::zeros(),
            pending: None,
            tau: Vec6::zeros(),
            rng: ChaCha8Rng::seed_from_u64(seed),
        };
        r.reset(&rss6_core::home_pose())?;
        Ok(r)
    }

    fn sample_potentiometers(&mut self) -> Result<(), String> {
        let theta = ik(&self.truth.kp, &self.state.pose).map_err(|e| format!("robot left its workspace: {e}"))?;
        let mut kappa = self.truth.kp.reading_from_theta(&theta);
        if self.pot_noise {
            let n = Normal::new(0.0, POT_SIGMA).map_err(|e| e.to_string())?;
            for k in kappa.iter_mut() {
                *k += n.sample(&mut self.rng);
            }
        }
        self.kappa = kappa;
        Ok(())
    }

    fn sample_camera(&mut self) -> Result<(), String> {
        let t = &self.truth;
        let mut z = compose(&compose(&pose_inverse(&t.sensor_in_base), &self.state.pose), &t.target_in_effector);
        if self.camera_noise {
            for (i, zi) in z.iter_mut().enumerate() {
                let n = Normal::new(0.0, CAMERA_SIGMA[i / 3]).map_err(|e| e.to_string())?;
                *zi += n.sample(&mut self.rng);
            }
        }
        self.pending = Some(z);
        Ok(())
    }
}

impl SimRobot for ModelRobot {
    fn dt(&self) -> f64 {
        self.dt
    }

    fn time(&self) -> f64 {
        self.tick as f64 * self.dt
    }

    fn reset(&mut self, pose: &Vec6) -> Result<(), String> {
        ik(&self.truth.kp, pose).map_err(|e| format!("reset pose: {e}"))?;
        self.state = ModelState { pose: *pose, pose_dot: Vec6::zeros() };
        self.pid = JointPid::new(self.truth.pid, self.dt, self.torque_limit);
        self.tick = 0;
        self.tau = Vec6::zeros();
        self.sample_potentiometers()?;
        self.sample_camera()
    }

    fn step(&mut self, theta_cmd: &Vec6) -> Result<(), String> {
        if theta_cmd.iter().any(|x| !x.is_finite()) {
            return Err("joint command contains NaN or infinity".into());
        }
        let theta_meas = self.kp_nominal.theta_from_reading(&self.kappa);
        self.tau = self.pid.step(theta_cmd, &theta_meas);
        self.state = rk4_step(&self.truth.kp, &self.truth.dp, &self.state, &self.tau, self.dt)
            .map_err(|e| format!("model integration failed at t = {:.3} s: {e}", self.time()))?;
        self.tick += 1;
        if self.tick % self.pot_every == 0 {
            self.sample_potentiometers()?;
        }
        if self.tick % self.camera_every == 0 {
            self.sample_camera()?;
        }
        Ok(())
    }

    fn camera(&mut self) -> Option<Vec6> {
        self.pending.take()
    }

    fn potentiometers(&self) -> Vec6 {
        self.kappa
    }

    fn true_pose(&self) -> Vec6 {
        self.state.pose
    }

    fn true_theta(&self) -> Vec6 {
        ik(&self.truth.kp, &self.state.pose).unwrap_or_else(|_| Vec6::repeat(f64::NAN))
    }

    fn torque(&self) -> Vec6 {
        self.tau
    }

    fn truth(&self) -> Truth {
        self.truth
    }
}

/// `rss6.SimulationError` with `msg`.
pub(crate) fn sim_err(msg: impl Into<String>) -> PyErr {
    make("SimulationError", msg, vec![])
}

fn pid_gains(pid: (f64, f64, f64)) -> PyResult<PidGains> {
    let g = PidGains { lp: pid.0, li: pid.1, ld: pid.2 };
    if ![g.lp, g.li, g.ld].iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(invalid(format!("pid gains must be finite and >= 0, got {pid:?}")));
    }
    Ok(g)
}

fn opt6(obj: Option<&Bound<'_, PyAny>>, name: &str, default: Vec6) -> PyResult<Vec6> {
    match obj {
        Some(o) => vec6(o, name),
        None => Ok(default),
    }
}

/// Builds the `truth()` dict.
pub(crate) fn truth_dict<'py>(py: Python<'py>, t: &Truth, effects: &Bound<'py, PyDict>) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("kinematics", PyKinematicParams::wrap(t.kp))?;
    d.set_item("dynamics", PyDynamicParams { inner: t.dp })?;
    d.set_item("pid", (t.pid.lp, t.pid.li, t.pid.ld))?;
    d.set_item("sensor_in_base", out6(py, &t.sensor_in_base))?;
    d.set_item("target_in_effector", out6(py, &t.target_in_effector))?;
    d.set_item("effects", effects)?;
    Ok(d)
}

/// Default ᴼχ_C and ᴱχ_t of simulated robots (shared with rss6-ident's generator).
pub(crate) fn default_externals() -> (Vec6, Vec6) {
    (Vec6::from(rss6_ident::NOMINAL_SENSOR_IN_BASE), Vec6::from(rss6_ident::NOMINAL_TARGET_IN_EFFECTOR))
}

/// The analytic-model twin of the plant (thesis Fig. 5.1's "simulated model"): same call shape as
/// `rss6.Plant`, driven by rss6-core forward dynamics (RK4, 1 kHz), the built-in joint PID and the
/// same sensor models (camera ᶜχ_t at 1/0.033 s, potentiometers at 500 Hz, Table 4.1 noise).
#[pyclass(name = "ModelSim", module = "rss6._rss6")]
pub(crate) struct PyModelSim {
    pub(crate) robot: Box<dyn SimRobot>,
}

#[pymethods]
impl PyModelSim {
    /// `kp`, `dp`: the true robot. `pid` = (l_p, l_i, l_d) of the drive (N·m/rad, N·m/(rad·s),
    /// N·m·s/rad). `sensor_in_base` ᴼχ_C and `target_in_effector` ᴱχ_t default to rss6-ident's nominal
    /// placement. `effects` must be None (the analytic twin has no hidden effects). Starts at home.
    #[new]
    #[pyo3(signature = (kp, dp, *, pid=(400.0, 2000.0, 4.0), effects=None, seed=0, dt=1e-3, sensor_in_base=None, target_in_effector=None, camera_noise=true, potentiometer_noise=true, torque_limit=30.0, camera_period=0.033))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        kp: &PyKinematicParams,
        dp: &PyDynamicParams,
        pid: (f64, f64, f64),
        effects: Option<&Bound<'_, PyAny>>,
        seed: u64,
        dt: f64,
        sensor_in_base: Option<&Bound<'_, PyAny>>,
        target_in_effector: Option<&Bound<'_, PyAny>>,
        camera_noise: bool,
        potentiometer_noise: bool,
        torque_limit: f64,
        camera_period: f64,
    ) -> PyResult<Self> {
        if let Some(e) = effects {
            if !e.is_none() && e.len().map(|n| n > 0).unwrap_or(true) {
                return Err(invalid("ModelSim has no hidden effects; pass effects=None (use rss6.Plant)"));
            }
        }
        if !(torque_limit.is_finite() && torque_limit > 0.0) {
            return Err(invalid(format!("torque_limit must be > 0, got {torque_limit}")));
        }
        if !(camera_period.is_finite() && camera_period > 0.0) {
            return Err(invalid(format!("camera_period must be > 0, got {camera_period}")));
        }
        let (s0, t0) = default_externals();
        let truth = Truth {
            kp: kp.inner,
            dp: dp.inner,
            pid: pid_gains(pid)?,
            sensor_in_base: opt6(sensor_in_base, "sensor_in_base", s0)?,
            target_in_effector: opt6(target_in_effector, "target_in_effector", t0)?,
        };
        let r = ModelRobot::new(truth, dt, torque_limit, camera_period, camera_noise, potentiometer_noise, seed)
            .map_err(sim_err)?;
        Ok(PyModelSim { robot: Box::new(r) })
    }

    /// Places the true robot at rest at `pose` (6,), drive PID at rest, time 0.
    fn reset(&mut self, pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = vec6(pose, "pose")?;
        self.robot.reset(&p).map_err(sim_err)
    }

    /// One joint-loop tick with θ_cmd (6,) rad in the nominal joint convention.
    fn step_joint_command(&mut self, theta_cmd: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = vec6(theta_cmd, "theta_cmd")?;
        self.robot.step(&c).map_err(sim_err)
    }

    /// True pose χ_E (6,).
    fn true_pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.robot.true_pose())
    }

    /// True physical joint angles θ (6,).
    fn true_theta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.robot.true_theta())
    }

    /// Plant time (s).
    #[getter]
    fn time(&self) -> f64 {
        self.robot.time()
    }

    /// Joint-loop tick length (s).
    #[getter]
    fn dt(&self) -> f64 {
        self.robot.dt()
    }

    /// ᶜχ_t (6,) if a camera frame completed since the last call, else None.
    fn camera<'py>(&mut self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.robot.camera().map(|z| out6(py, &z))
    }

    /// Latest potentiometer readings κ (6,) bits.
    fn potentiometers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.robot.potentiometers())
    }

    /// Drive torques of the last tick (6,) N·m.
    fn torque<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.robot.torque())
    }

    /// The hidden truth: kinematics, dynamics, pid, sensor_in_base (ᴼχ_C), target_in_effector (ᴱχ_t),
    /// effects.
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        truth_dict(py, &self.robot.truth(), &PyDict::new(py))
    }

    fn __repr__(&self) -> String {
        format!("ModelSim(t = {:.3} s)", self.robot.time())
    }
}

/// Runs `f` on the robot behind a `rss6.Plant` or `rss6.ModelSim` object.
pub(crate) fn with_robot<R>(obj: &Bound<'_, PyAny>, f: impl FnOnce(&mut dyn SimRobot) -> R) -> PyResult<R> {
    if let Ok(m) = obj.cast::<PyModelSim>() {
        let mut m = m.try_borrow_mut()?;
        return Ok(f(m.robot.as_mut()));
    }
    Err(invalid(format!(
        "plant must be an rss6.Plant or rss6.ModelSim, got {}",
        obj.get_type().name()?
    )))
}

/// Checks that `pose` is finite and `kp` accepts it (used by callers that reset).
#[allow(dead_code)]
pub(crate) fn check_reachable(kp: &KinematicParams, pose: &Vec6) -> PyResult<()> {
    ik(kp, pose).map(|_| ()).map_err(core)
}
