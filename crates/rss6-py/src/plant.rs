//! Simulated robots as Python classes: `rss6.Plant` (rss6-sim's rapier plant, the "real robot") and
//! `rss6.ModelSim` (its analytic-model twin: rss6-core forward dynamics + the drive's joint PID + the
//! same sensors). The runners of rss6-exp drive them as [`rss6_exp::Robot`]s ([`with_robot`]).

use std::collections::BTreeMap;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::Vec6;
use rss6_ctrl::PidGains;
use rss6_sim::{EffectSpec, RobotSim, SimConfig, SimError, Truth};

use crate::convert::{out1, out6, out_rows6, rows6, vec6};
use crate::errors::{core, invalid, make};
use crate::params::{PyDynamicParams, PyKinematicParams};

/// Maps a [`SimError`] onto its exception class.
pub(crate) fn sim_error(e: SimError) -> PyErr {
    let msg = e.to_string();
    match e {
        SimError::Core(c) => core(c),
        SimError::InvalidConfig(_)
        | SimError::UnknownEffect { .. }
        | SimError::EffectParameter { .. } => make("InvalidParameterError", msg, vec![]),
        SimError::Io { .. } => make("LogError", msg, vec![]),
        _ => make("SimulationError", msg, vec![]),
    }
}

/// `rss6.SimulationError` with `msg`.
pub(crate) fn sim_err(msg: impl Into<String>) -> PyErr {
    make("SimulationError", msg, vec![])
}

fn pid_gains(pid: (f64, f64, f64)) -> PyResult<PidGains> {
    let g = PidGains {
        lp: pid.0,
        li: pid.1,
        ld: pid.2,
    };
    if ![g.lp, g.li, g.ld]
        .iter()
        .all(|x| x.is_finite() && *x >= 0.0)
    {
        return Err(invalid(format!(
            "pid gains must be finite and >= 0, got {pid:?}"
        )));
    }
    Ok(g)
}

/// Builds the `truth()` dict.
pub(crate) fn truth_dict<'py>(py: Python<'py>, t: &Truth) -> PyResult<Bound<'py, PyDict>> {
    let effects = PyDict::new(py);
    for e in &t.effects {
        let p = PyDict::new(py);
        for (k, v) in &e.params {
            p.set_item(k, v)?;
        }
        effects.set_item(&e.name, p)?;
    }
    let d = PyDict::new(py);
    d.set_item("kinematics", PyKinematicParams::wrap(t.kinematics))?;
    d.set_item("dynamics", PyDynamicParams { inner: t.dynamics })?;
    d.set_item("pid", (t.pid.lp, t.pid.li, t.pid.ld))?;
    d.set_item("sensor_in_base", out6(py, &t.sensor_in_base))?;
    d.set_item("target_in_effector", out6(py, &t.target_in_effector))?;
    d.set_item("effects", effects)?;
    Ok(d)
}

/// Reads `effects`: None, a dict {name: {param: value}} or a list of (name, {param: value}).
fn effect_specs(effects: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<EffectSpec>> {
    let Some(e) = effects else {
        return Ok(Vec::new());
    };
    if e.is_none() {
        return Ok(Vec::new());
    }
    let pairs: Vec<(String, BTreeMap<String, f64>)> = if let Ok(d) = e.cast::<PyDict>() {
        d.iter()
            .map(|(k, v)| {
                Ok((
                    k.extract::<String>()?,
                    v.extract::<BTreeMap<String, f64>>()?,
                ))
            })
            .collect::<PyResult<_>>()
            .map_err(|err| {
                invalid(format!(
                    "effects must map names to {{parameter: value}} dicts ({err})"
                ))
            })?
    } else {
        e.extract().map_err(|err| {
            invalid(format!(
                "effects must be a dict or a list of (name, params) ({err})"
            ))
        })?
    };
    Ok(pairs
        .into_iter()
        .map(|(name, params)| EffectSpec { name, params })
        .collect())
}

#[allow(clippy::too_many_arguments)]
fn sim_config(
    kp: &PyKinematicParams,
    dp: &PyDynamicParams,
    pid: (f64, f64, f64),
    effects: Option<&Bound<'_, PyAny>>,
    seed: i128,
    dt: f64,
    sensor_in_base: Option<&Bound<'_, PyAny>>,
    target_in_effector: Option<&Bound<'_, PyAny>>,
    torque_limit: f64,
    camera_latency: f64,
    solver_iterations: Option<i64>,
    potentiometer_noise: Option<f64>,
    pixel_noise: Option<f64>,
    drive_derivative_filter: f64,
    friction_smoothing: f64,
    implicit_friction: bool,
    velocity_projection: bool,
) -> PyResult<SimConfig> {
    let solver_iterations = solver_iterations
        .map(|v| crate::convert::count::<usize>(v, "solver_iterations"))
        .transpose()?;
    let mut cfg = SimConfig::new(kp.inner, dp.inner, pid_gains(pid)?);
    cfg.drive_derivative_filter = drive_derivative_filter;
    cfg.friction_smoothing = friction_smoothing;
    cfg.implicit_friction = implicit_friction;
    cfg.solver.velocity_projection = velocity_projection;
    cfg.seed = crate::convert::seed(seed)?;
    cfg.dt = dt;
    cfg.torque_limit = torque_limit;
    cfg.cmm.latency = camera_latency;
    if let Some(s) = sensor_in_base {
        cfg.sensor_in_base = vec6(s, "sensor_in_base")?;
    }
    if let Some(t) = target_in_effector {
        cfg.target_in_effector = vec6(t, "target_in_effector")?;
    }
    if let Some(n) = solver_iterations {
        cfg.solver.iterations = n;
    }
    if let Some(n) = potentiometer_noise {
        cfg.pot_noise = n;
    }
    if let Some(n) = pixel_noise {
        cfg.cmm.pixel_noise = n;
    }
    cfg.effects = effect_specs(effects)?;
    cfg.validate().map_err(sim_error)?;
    Ok(cfg)
}

/// What `step_joint_commands` records: per tick, the state after it; camera frames as they arrive.
#[derive(Default)]
struct Ticks {
    time: Vec<f64>,
    pose: Vec<Vec6>,
    theta: Vec<Vec6>,
    kappa: Vec<Vec6>,
    torque: Vec<Vec6>,
    camera_time: Vec<f64>,
    camera: Vec<Vec6>,
}

/// Ticks between two checks for Ctrl-C in `step_joint_commands`.
const SIGNAL_CHECK_TICKS: usize = 1000;

/// Runs one tick per command on `robot`, recording what a caller stepping tick by tick would read.
/// Called with the GIL released; checks for Ctrl-C every [`SIGNAL_CHECK_TICKS`] ticks.
fn run_ticks<R: RobotSim>(robot: &mut R, commands: &[Vec6]) -> PyResult<Ticks> {
    let n = commands.len();
    let mut r = Ticks {
        time: Vec::with_capacity(n),
        pose: Vec::with_capacity(n),
        theta: Vec::with_capacity(n),
        kappa: Vec::with_capacity(n),
        torque: Vec::with_capacity(n),
        ..Ticks::default()
    };
    for (k, c) in commands.iter().enumerate() {
        if k % SIGNAL_CHECK_TICKS == SIGNAL_CHECK_TICKS - 1 {
            Python::attach(|py| py.check_signals())?;
        }
        robot
            .step_joint_command(c)
            .map_err(|e| sim_err(format!("tick {k}: {e}")))?;
        let t = robot.time();
        r.time.push(t);
        r.pose.push(robot.true_pose());
        r.theta.push(robot.true_theta());
        r.kappa.push(robot.potentiometers());
        r.torque.push(robot.torques());
        if let Some(z) = robot.camera() {
            r.camera_time.push(t);
            r.camera.push(z);
        }
    }
    Ok(r)
}

fn ticks_dict<'py>(py: Python<'py>, r: &Ticks) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time", out1(py, &r.time))?;
    d.set_item("true_pose", out_rows6(py, &r.pose))?;
    d.set_item("true_theta", out_rows6(py, &r.theta))?;
    d.set_item("kappa", out_rows6(py, &r.kappa))?;
    d.set_item("torque", out_rows6(py, &r.torque))?;
    d.set_item("camera_time", out1(py, &r.camera_time))?;
    d.set_item("camera", out_rows6(py, &r.camera))?;
    Ok(d)
}

macro_rules! sim_class {
    ($name:ident, $pyname:literal, $doc:literal, $ty:ty) => {
        #[doc = $doc]
        #[pyclass(name = $pyname, module = "rss6._rss6")]
        pub(crate) struct $name {
            pub(crate) robot: Mutex<$ty>,
        }

        impl $name {
            /// The robot. Never waits: a thread that waited here holding the GIL would deadlock a run
            /// on another thread that needs the GIL for its callbacks.
            pub(crate) fn lock(&self) -> PyResult<std::sync::MutexGuard<'_, $ty>> {
                self.robot.try_lock().map_err(|e| match e {
                    std::sync::TryLockError::WouldBlock => sim_err(
                        "the plant is busy: another thread is running an experiment on it",
                    ),
                    std::sync::TryLockError::Poisoned(_) => {
                        sim_err("the simulation panicked earlier and is unusable")
                    }
                })
            }
        }

        #[pymethods]
        impl $name {
            /// `kp`, `dp`: the true robot. `pid` = (l_p, l_i, l_d) of the drive (N·m/rad,
            /// N·m/(rad·s), N·m·s/rad). `effects`: hidden effects {name: {param: value}} (names:
            /// joint_friction, backlash, camera_latency, payload, base_tilt, joint_offset_drift).
            /// `sensor_in_base` (ᴼχ_C) and `target_in_effector` (ᴱχ_t) default to rss6-sim's
            /// placement; `camera_latency` (s), `potentiometer_noise` (bit, default Table 4.1's
            /// 0.2233) and `pixel_noise` (px) tune the sensors. `drive_derivative_filter`: time constant
            /// T_f (s) of the drive's derivative filter (0: eq. 5.5 as printed);
            /// `friction_smoothing`: ε (rad/s) of the twin's Coulomb friction f_c tanh(θ̇/ε) (0:
            /// sign; the rapier plant ignores it). `implicit_friction`: the friction law plant and
            /// twin share, stick–slip stepped implicitly per tick (rss6_core::implicit_friction; the
            /// plant follows the twin with `velocity_projection`, or with ≈ 48 `solver_iterations`).
            /// `velocity_projection`: the plant's mass-weighted velocity projection and symplectic
            /// position step (rss6_sim::SolverConfig::velocity_projection). Starts at home.
            #[new]
            #[pyo3(signature = (kp, dp, *, pid=(400.0, 2000.0, 4.0), effects=None, seed=0, dt=1e-3, sensor_in_base=None, target_in_effector=None, torque_limit=30.0, camera_latency=0.0, solver_iterations=None, potentiometer_noise=None, pixel_noise=None, drive_derivative_filter=0.0, friction_smoothing=0.0, implicit_friction=false, velocity_projection=false))]
            #[allow(clippy::too_many_arguments)]
            fn py_new(
                py: Python<'_>,
                kp: &PyKinematicParams,
                dp: &PyDynamicParams,
                pid: (f64, f64, f64),
                effects: Option<&Bound<'_, PyAny>>,
                seed: i128,
                dt: f64,
                sensor_in_base: Option<&Bound<'_, PyAny>>,
                target_in_effector: Option<&Bound<'_, PyAny>>,
                torque_limit: f64,
                camera_latency: f64,
                solver_iterations: Option<i64>,
                potentiometer_noise: Option<f64>,
                pixel_noise: Option<f64>,
                drive_derivative_filter: f64,
                friction_smoothing: f64,
                implicit_friction: bool,
                velocity_projection: bool,
            ) -> PyResult<Self> {
                let cfg = sim_config(kp, dp, pid, effects, seed, dt, sensor_in_base, target_in_effector, torque_limit, camera_latency, solver_iterations, potentiometer_noise, pixel_noise, drive_derivative_filter, friction_smoothing, implicit_friction, velocity_projection)?;
                let robot = py.detach(move || <$ty>::new(cfg)).map_err(sim_error)?;
                Ok($name { robot: Mutex::new(robot) })
            }

            /// Places the true robot at rest at `pose` (6,), drive PID at rest, time 0.
            fn reset(&self, pose: &Bound<'_, PyAny>) -> PyResult<()> {
                let p = vec6(pose, "pose")?;
                self.lock()?.reset(&p).map_err(sim_error)
            }

            /// One joint-loop tick with θ_cmd (6,) rad in the drive's (nominal) joint convention.
            fn step_joint_command(&self, theta_cmd: &Bound<'_, PyAny>) -> PyResult<()> {
                let c = vec6(theta_cmd, "theta_cmd")?;
                self.lock()?.step_joint_command(&c).map_err(sim_error)
            }

            /// N joint-loop ticks in one call, one per row of `commands` (N, 6) rad (drive convention),
            /// with the GIL released (Ctrl-C is checked every 1000 ticks). Returns what a caller would
            /// collect tick by tick after each step: time (N,) s, true_pose (N, 6), true_theta (N, 6),
            /// kappa (N, 6) bit, torque (N, 6) N·m, camera_time (M,) s and camera (M, 6) ᶜχ_t frames.
            fn step_joint_commands<'py>(
                &self,
                py: Python<'py>,
                commands: &Bound<'py, PyAny>,
            ) -> PyResult<Bound<'py, PyDict>> {
                let cmds = rows6(commands, "commands")?;
                let mut robot = self.lock()?;
                let robot: &mut $ty = &mut robot;
                let r = py.detach(|| run_ticks(robot, &cmds))?;
                ticks_dict(py, &r)
            }

            /// True pose χ_E (6,).
            fn true_pose<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
                Ok(out6(py, &self.lock()?.true_pose()))
            }

            /// True physical joint angles θ (6,).
            fn true_theta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
                Ok(out6(py, &self.lock()?.true_theta()))
            }

            /// Largest distance between joint anchors that should coincide, after the last tick (m);
            /// 0 for the model twin.
            fn loop_closure_error(&self) -> PyResult<f64> {
                Ok(RobotSim::loop_closure_error(&*self.lock()?))
            }

            /// Largest loop gap rapier's solver left in the last tick before the post-step
            /// projection (m); 0 for the model twin.
            fn solver_gap(&self) -> PyResult<f64> {
                Ok(RobotSim::solver_gap(&*self.lock()?))
            }

            /// Ticks whose implicit friction solve stopped at its sweep bound instead of
            /// converging exactly (0 expected; 0 without `implicit_friction`).
            fn inexact_friction_steps(&self) -> PyResult<u64> {
                Ok(RobotSim::inexact_friction_steps(&*self.lock()?))
            }

            /// Plant time (s).
            #[getter]
            fn time(&self) -> PyResult<f64> {
                Ok(RobotSim::time(&*self.lock()?))
            }

            /// Joint-loop tick length (s).
            #[getter]
            fn dt(&self) -> PyResult<f64> {
                Ok(self.lock()?.config().dt)
            }

            /// ᶜχ_t (6,) if a camera frame became available on the last tick, else None.
            fn camera<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
                Ok(RobotSim::camera(&*self.lock()?).map(|z| out6(py, &z)))
            }

            /// Latest potentiometer readings κ (6,) bits.
            fn potentiometers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
                Ok(out6(py, &RobotSim::potentiometers(&*self.lock()?)))
            }

            /// Drive torques of the last tick (6,) N·m.
            fn torque<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
                Ok(out6(py, &self.lock()?.torques()))
            }

            /// The hidden truth: kinematics, dynamics, pid, sensor_in_base (ᴼχ_C), target_in_effector
            /// (ᴱχ_t), effects.
            fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
                let t = RobotSim::truth(&*self.lock()?);
                truth_dict(py, &t)
            }

            fn __repr__(&self) -> PyResult<String> {
                Ok(format!("{}(t = {:.3} s)", $pyname, RobotSim::time(&*self.lock()?)))
            }
        }
    };
}

sim_class!(
    PyPlant,
    "Plant",
    "The rapier plant (rss6-sim): the simulated \"real robot\" with its drive PID, potentiometers and optical CMM.",
    rss6_sim::Plant
);
sim_class!(
    PyModelSim,
    "ModelSim",
    "The analytic-model twin of the plant (thesis Fig. 5.1's simulated model): same call shape, rss6-core dynamics.",
    rss6_sim::ModelSim
);

/// A robot the experiment layer can drive from a thread without the GIL.
pub(crate) type SendRobot = dyn rss6_exp::Robot + Send;

/// Runs `f` on the robot behind a `rss6.Plant` or `rss6.ModelSim` object (locked for the call), or on
/// any Python object implementing `rss6.types.Robot`.
pub(crate) fn with_robot<R>(
    obj: &Bound<'_, PyAny>,
    f: impl FnOnce(&mut SendRobot) -> R,
) -> PyResult<R> {
    if let Ok(m) = obj.cast::<PyModelSim>() {
        let m = m.borrow();
        let mut g = m.lock()?;
        return Ok(f(&mut *g));
    }
    if let Ok(m) = obj.cast::<PyPlant>() {
        let m = m.borrow();
        let mut g = m.lock()?;
        return Ok(f(&mut *g));
    }
    // Any other object implementing the rss6.types.Robot protocol (e.g. rss6.can's robot): driven
    // tick by tick through Python; an exception it raised stops the run and is raised here.
    let mut r = crate::pyrobot::PyRobot::new(obj).map_err(|e| {
        invalid(format!(
            "plant must be an rss6.Plant, rss6.ModelSim or implement rss6.types.Robot ({e})"
        ))
    })?;
    let out = f(&mut r);
    match r.take_error() {
        Some(e) => Err(e),
        None => Ok(out),
    }
}
