//! Controller bindings (rss6-ctrl, thesis ch. 6): trajectories, the pose Kalman filter, DSMC, KCSC,
//! KJSC and the torque-to-position converter, each a class with `step`.
//!
//! A reference is a tuple (χ_d, χ̇_d, χ̈_d) and an estimate a tuple (χ_m, χ̇_m, χ̈_m) of (6,) arrays, exactly
//! what `Trajectory.sample` and `KalmanFilter.step` return, so the pieces compose in Python.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use rss6_core::Vec6;
use rss6_ctrl::{
    CartesianPidGains, CommandGuard, CommandLimits, CtrlError, Dsmc, DsmcGains, FaultReason,
    Fourier, JointSpaceGains, KalmanConfig, Kcsc, Kjsc, PidGains, PoseEstimate, PoseKalman,
    Reference, Sinusoid, TorqueToPosition, Trajectory,
};

use crate::convert::{array, out6, out_rows6, vec6};
use crate::errors::{core, invalid, make, non_finite, shape, Attr};
use crate::params::{PyDynamicParams, PyKinematicParams};

/// Maps a [`CtrlError`] onto its exception class.
pub(crate) fn ctrl_err(e: CtrlError) -> PyErr {
    match e {
        CtrlError::Faulted(r) => make(
            "ControllerFaultError",
            e.to_string(),
            vec![("reason", Attr::S(r.to_string()))],
        ),
        CtrlError::NonFinite => non_finite(e.to_string()),
        CtrlError::InvalidTimeStep(_) => invalid(e.to_string()),
        CtrlError::InvalidParameter(_) => make("InvalidParameterError", e.to_string(), vec![]),
        CtrlError::Core(c) => core(c),
        _ => make("Rss6Error", e.to_string(), vec![]),
    }
}

/// A fault reason as text for Python (`None` when healthy).
pub(crate) fn fault_text(f: Option<FaultReason>) -> Option<String> {
    f.map(|r| r.to_string())
}

fn opt6(obj: Option<&Bound<'_, PyAny>>, name: &str, default: Vec6) -> PyResult<Vec6> {
    match obj {
        Some(o) => vec6(o, name),
        None => Ok(default),
    }
}

/// Reads a (pose, pose_dot, pose_ddot) tuple (the third entry may be omitted: zeros).
fn triple(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec6, Vec6, Vec6)> {
    let t = obj.cast::<PyTuple>().map_err(|_| {
        invalid(format!(
            "{name} must be a tuple (pose, pose_dot[, pose_ddot]) of (6,) arrays"
        ))
    })?;
    if !(t.len() == 2 || t.len() == 3) {
        return Err(invalid(format!(
            "{name} must have 2 or 3 entries, got {}",
            t.len()
        )));
    }
    let p = vec6(&t.get_item(0)?, &format!("{name}[0]"))?;
    let v = vec6(&t.get_item(1)?, &format!("{name}[1]"))?;
    let a = if t.len() == 3 {
        vec6(&t.get_item(2)?, &format!("{name}[2]"))?
    } else {
        Vec6::zeros()
    };
    Ok((p, v, a))
}

fn reference(obj: &Bound<'_, PyAny>) -> PyResult<Reference> {
    let (pose, pose_dot, pose_ddot) = triple(obj, "reference")?;
    Ok(Reference {
        pose,
        pose_dot,
        pose_ddot,
    })
}

fn estimate(obj: &Bound<'_, PyAny>) -> PyResult<PoseEstimate> {
    let (pose, pose_dot, pose_ddot) = triple(obj, "estimate")?;
    Ok(PoseEstimate {
        pose,
        pose_dot,
        pose_ddot,
    })
}

/// Three (6,) arrays.
type Triple<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

fn out_triple<'py>(py: Python<'py>, p: &Vec6, v: &Vec6, a: &Vec6) -> Triple<'py> {
    (out6(py, p), out6(py, v), out6(py, a))
}

/// Three (N, 6) arrays.
type Triple2<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// Highest number of harmonics a Fourier trajectory may have.
const MAX_HARMONICS: usize = 10;

/// A reference trajectory with analytic derivatives.
#[derive(Debug, Clone)]
pub(crate) enum Traj {
    /// Sinusoid (Experiment 1).
    Sin(Sinusoid),
    /// Finite Fourier series (Experiment 2), zero-padded to [`MAX_HARMONICS`].
    Fourier(Box<Fourier<MAX_HARMONICS>>),
}

impl Traj {
    pub(crate) fn sample(&self, t: f64) -> Reference {
        match self {
            Traj::Sin(s) => s.sample(t),
            Traj::Fourier(f) => f.sample(t),
        }
    }
}

impl Trajectory for Traj {
    fn sample(&self, t: f64) -> Reference {
        Traj::sample(self, t)
    }
}

fn pad_fourier(f: &Fourier<5>) -> Fourier<MAX_HARMONICS> {
    let mut s = [[0.0; MAX_HARMONICS]; 6];
    let mut c = [[0.0; MAX_HARMONICS]; 6];
    for i in 0..6 {
        s[i][..5].copy_from_slice(&f.s[i]);
        c[i][..5].copy_from_slice(&f.c[i]);
    }
    Fourier {
        s,
        c,
        offset: f.offset,
        omega0: f.omega0,
    }
}

/// Reference trajectory χ_d(t) with analytic χ̇_d, χ̈_d (thesis §6.5: Experiments 1 and 2).
#[pyclass(name = "Trajectory", module = "rss6._rss6", frozen)]
#[derive(Debug, Clone)]
pub(crate) struct PyTrajectory {
    pub(crate) inner: Traj,
    name: String,
}

#[pymethods]
impl PyTrajectory {
    /// Experiment 1: sinusoid with an initial step, ω = 0.5 rad/s.
    #[staticmethod]
    fn experiment1() -> Self {
        PyTrajectory {
            inner: Traj::Sin(Sinusoid::experiment1()),
            name: "exp1".into(),
        }
    }

    /// Experiment 2: finite Fourier series (eq. 6.43), n = 5, ω0 = 0.15 rad/s.
    #[staticmethod]
    fn experiment2() -> Self {
        PyTrajectory {
            inner: Traj::Fourier(Box::new(pad_fourier(&Fourier::experiment2()))),
            name: "exp2".into(),
        }
    }

    /// χ_d,i = center_i + amplitude_i·sin(ω t + phase_i); all (6,), ω in rad/s.
    #[staticmethod]
    fn sinusoid(
        center: &Bound<'_, PyAny>,
        amplitude: &Bound<'_, PyAny>,
        phase: &Bound<'_, PyAny>,
        omega: f64,
    ) -> PyResult<Self> {
        if !omega.is_finite() {
            return Err(non_finite("omega must be finite"));
        }
        Ok(PyTrajectory {
            inner: Traj::Sin(Sinusoid {
                center: vec6(center, "center")?,
                amplitude: vec6(amplitude, "amplitude")?,
                phase: vec6(phase, "phase")?,
                omega,
            }),
            name: "sinusoid".into(),
        })
    }

    /// Finite Fourier series of eq. 5.11/6.43: s, c of shape (6, n) (m/s, rad/s), n ≤ 10 harmonics,
    /// offset χ0 (6,), fundamental ω0 (rad/s).
    #[staticmethod]
    fn fourier(
        s: &Bound<'_, PyAny>,
        c: &Bound<'_, PyAny>,
        offset: &Bound<'_, PyAny>,
        omega0: f64,
    ) -> PyResult<Self> {
        if !(omega0.is_finite() && omega0 > 0.0) {
            return Err(invalid(format!(
                "omega0 must be finite and > 0, got {omega0}"
            )));
        }
        let read =
            |o: &Bound<'_, PyAny>, name: &str| -> PyResult<(usize, [[f64; MAX_HARMONICS]; 6])> {
                let (dims, data) = array(o, name)?;
                if dims.len() != 2 || dims[0] != 6 || dims[1] == 0 || dims[1] > MAX_HARMONICS {
                    return Err(shape(format!(
                    "{name} must have shape (6, n) with 1 <= n <= {MAX_HARMONICS}, got {dims:?}"
                )));
                }
                crate::convert::check_finite(&data, &dims, name)?;
                let n = dims[1];
                let mut out = [[0.0; MAX_HARMONICS]; 6];
                for i in 0..6 {
                    out[i][..n].copy_from_slice(&data[i * n..(i + 1) * n]);
                }
                Ok((n, out))
            };
        let (ns, s) = read(s, "s")?;
        let (nc, c) = read(c, "c")?;
        if ns != nc {
            return Err(shape(format!(
                "s and c must have the same shape, got (6, {ns}) and (6, {nc})"
            )));
        }
        Ok(PyTrajectory {
            inner: Traj::Fourier(Box::new(Fourier {
                s,
                c,
                offset: vec6(offset, "offset")?,
                omega0,
            })),
            name: "fourier".into(),
        })
    }

    /// (χ_d, χ̇_d, χ̈_d) at time t (s), each (6,).
    fn sample<'py>(&self, py: Python<'py>, t: f64) -> PyResult<Triple<'py>> {
        if !t.is_finite() {
            return Err(non_finite("t must be finite"));
        }
        let r = self.inner.sample(t);
        Ok(out_triple(py, &r.pose, &r.pose_dot, &r.pose_ddot))
    }

    /// Samples at every time in `times` (N,): three (N, 6) arrays.
    fn sample_many<'py>(
        &self,
        py: Python<'py>,
        times: &Bound<'py, PyAny>,
    ) -> PyResult<Triple2<'py>> {
        let (dims, ts) = array(times, "times")?;
        if dims.len() != 1 {
            return Err(shape(format!("times must be 1-D, got shape {dims:?}")));
        }
        crate::convert::check_finite(&ts, &dims, "times")?;
        let rs: Vec<Reference> = ts.iter().map(|&t| self.inner.sample(t)).collect();
        let p: Vec<Vec6> = rs.iter().map(|r| r.pose).collect();
        let v: Vec<Vec6> = rs.iter().map(|r| r.pose_dot).collect();
        let a: Vec<Vec6> = rs.iter().map(|r| r.pose_ddot).collect();
        Ok((out_rows6(py, &p), out_rows6(py, &v), out_rows6(py, &a)))
    }

    /// "exp1", "exp2", "sinusoid" or "fourier".
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    fn __repr__(&self) -> String {
        format!("Trajectory({})", self.name)
    }
}

/// The pose Kalman filter (eq. 6.15–6.18, exact discrete form at a variable sample time).
#[pyclass(name = "KalmanFilter", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyKalmanFilter {
    inner: PoseKalman,
}

#[pymethods]
impl PyKalmanFilter {
    /// A filter at `initial_pose` (6,). Defaults: Table 4.1 camera noise `r` (variances, m², rad²), the
    /// thesis jerk density `q_jerk`; `steady_state=True` uses the precomputed gain at `nominal_dt`.
    #[new]
    #[pyo3(signature = (initial_pose, *, r=None, q_jerk=None, q_vel=None, nominal_dt=0.033, steady_state=false))]
    fn py_new(
        initial_pose: &Bound<'_, PyAny>,
        r: Option<&Bound<'_, PyAny>>,
        q_jerk: Option<&Bound<'_, PyAny>>,
        q_vel: Option<&Bound<'_, PyAny>>,
        nominal_dt: f64,
        steady_state: bool,
    ) -> PyResult<Self> {
        let d = KalmanConfig::tuned();
        let cfg = KalmanConfig {
            r: opt6(r, "r", d.r)?,
            q_jerk: opt6(q_jerk, "q_jerk", d.q_jerk)?,
            q_vel: opt6(q_vel, "q_vel", d.q_vel)?,
            nominal_dt,
            steady_state,
            ..d
        };
        cfg.validate().map_err(ctrl_err)?;
        let p = vec6(initial_pose, "initial_pose")?;
        Ok(PyKalmanFilter {
            inner: PoseKalman::new(cfg, &p).map_err(ctrl_err)?,
        })
    }

    /// Advances by dt (s) and fuses `measurement` (6,) if given (None: predict only, a missing frame).
    /// Returns (χ_m, χ̇_m, χ̈_m).
    #[pyo3(signature = (dt, measurement=None))]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        dt: f64,
        measurement: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Triple<'py>> {
        let z = match measurement {
            Some(m) => Some(vec6(m, "measurement")?),
            None => None,
        };
        let e = self.inner.step(dt, z.as_ref()).map_err(ctrl_err)?;
        Ok(out_triple(py, &e.pose, &e.pose_dot, &e.pose_ddot))
    }

    /// The current estimate (χ_m, χ̇_m, χ̈_m).
    fn estimate<'py>(&self, py: Python<'py>) -> Triple<'py> {
        let e = self.inner.estimate();
        out_triple(py, &e.pose, &e.pose_dot, &e.pose_ddot)
    }

    /// Restarts at `pose` with the initial covariance.
    fn reset(&mut self, pose: &Bound<'_, PyAny>) -> PyResult<()> {
        let p = vec6(pose, "pose")?;
        self.inner.reset(&p);
        Ok(())
    }

    /// Variance of the pose estimate (6,) (m², rad²).
    fn pose_variance<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.inner.pose_variance())
    }
}

/// The dynamic sliding-mode controller (eq. 6.19–6.28) on a model (kp_model, dp_model).
#[pyclass(name = "Dsmc", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyDsmc {
    inner: Dsmc,
}

controller_methods!(
    PyDsmc,
    "Clears the integral, the held output and the fault.",
    {
        /// Gains default to the tuned set of rss6-ctrl; any may be overridden with a (6,) array.
        #[new]
        #[pyo3(signature = (kp_model, dp_model, *, lambda_=None, kp=None, ki=None, kr=None, epsilon=None, integral_limit=None))]
        #[allow(clippy::too_many_arguments)]
        fn py_new(
            kp_model: &PyKinematicParams,
            dp_model: &PyDynamicParams,
            lambda_: Option<&Bound<'_, PyAny>>,
            kp: Option<&Bound<'_, PyAny>>,
            ki: Option<&Bound<'_, PyAny>>,
            kr: Option<&Bound<'_, PyAny>>,
            epsilon: Option<&Bound<'_, PyAny>>,
            integral_limit: Option<&Bound<'_, PyAny>>,
        ) -> PyResult<Self> {
            let d = DsmcGains::tuned();
            let g = DsmcGains {
                lambda: opt6(lambda_, "lambda_", d.lambda)?,
                kp: opt6(kp, "kp", d.kp)?,
                ki: opt6(ki, "ki", d.ki)?,
                kr: opt6(kr, "kr", d.kr)?,
                epsilon: opt6(epsilon, "epsilon", d.epsilon)?,
                integral_limit: opt6(integral_limit, "integral_limit", d.integral_limit)?,
            };
            Ok(PyDsmc {
                inner: Dsmc::new(kp_model.inner, dp_model.inner, g).map_err(ctrl_err)?,
            })
        }

        /// One camera-rate step of dt (s): returns dict tau_a (actuator torques, N·m), sliding (F),
        /// generalized (τ in χ coordinates), tau_model (model part), in_boundary_layer (bool).
        fn step<'py>(
            &mut self,
            py: Python<'py>,
            reference: &Bound<'py, PyAny>,
            estimate: &Bound<'py, PyAny>,
            dt: f64,
        ) -> PyResult<Bound<'py, PyDict>> {
            let r = self::reference(reference)?;
            let e = self::estimate(estimate)?;
            let o = self.inner.step(&r, &e, dt).map_err(ctrl_err)?;
            let d = PyDict::new(py);
            d.set_item("tau_a", out6(py, &o.tau_a))?;
            d.set_item("sliding", out6(py, &o.sliding))?;
            d.set_item("generalized", out6(py, &o.generalized))?;
            d.set_item("tau_model", out6(py, &o.tau_model))?;
            d.set_item("in_boundary_layer", o.in_boundary_layer)?;
            Ok(d)
        }

        /// ∫F dt (6,).
        fn integral<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
            out6(py, &self.inner.integral())
        }
    }
);

/// The kinematic Cartesian-space controller KCSC (eq. 6.40).
#[pyclass(name = "Kcsc", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyKcsc {
    inner: Kcsc,
}

controller_methods!(PyKcsc, "Clears the integral and the fault.", {
    /// KCSC on `kp_model`, starting at command `bias` (6,) rad (default zeros); gains default to the
    /// thesis's k_p = 0.3, k_i = 2.4, k_d = 0.001 on every axis.
    #[new]
    #[pyo3(signature = (kp_model, *, bias=None, kp=None, ki=None, kd=None))]
    fn py_new(
        kp_model: &PyKinematicParams,
        bias: Option<&Bound<'_, PyAny>>,
        kp: Option<&Bound<'_, PyAny>>,
        ki: Option<&Bound<'_, PyAny>>,
        kd: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let d = CartesianPidGains::thesis();
        let g = CartesianPidGains {
            kp: opt6(kp, "kp", d.kp)?,
            ki: opt6(ki, "ki", d.ki)?,
            kd: opt6(kd, "kd", d.kd)?,
            ..d
        };
        let b = opt6(bias, "bias", Vec6::zeros())?;
        Ok(PyKcsc {
            inner: Kcsc::new(kp_model.inner, g, &b).map_err(ctrl_err)?,
        })
    }

    /// One camera-rate step: joint command θ_d (6,) rad from the reference and the Kalman estimate.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        reference: &Bound<'py, PyAny>,
        estimate: &Bound<'py, PyAny>,
        dt: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let r = self::reference(reference)?;
        let e = self::estimate(estimate)?;
        Ok(out6(
            py,
            &self.inner.step(&r, &e, dt).map_err(ctrl_err)?.theta_d,
        ))
    }
});

/// The kinematic joint-space controller KJSC (eq. 6.42).
#[pyclass(name = "Kjsc", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyKjsc {
    inner: Kjsc,
}

controller_methods!(PyKjsc, "Clears the integral and the fault.", {
    /// KJSC on `kp_model` (its IK turns χ_d into θ_d), starting at command `bias` (6,) rad.
    #[new]
    #[pyo3(signature = (kp_model, *, bias=None, kp=None, ki=None, kd=None))]
    fn py_new(
        kp_model: &PyKinematicParams,
        bias: Option<&Bound<'_, PyAny>>,
        kp: Option<f64>,
        ki: Option<f64>,
        kd: Option<f64>,
    ) -> PyResult<Self> {
        let d = JointSpaceGains::from_visual_pid();
        let g = JointSpaceGains {
            kp: kp.unwrap_or(d.kp),
            ki: ki.unwrap_or(d.ki),
            kd: kd.unwrap_or(d.kd),
            ..d
        };
        let b = opt6(bias, "bias", Vec6::zeros())?;
        Ok(PyKjsc {
            inner: Kjsc::new(kp_model.inner, g, &b).map_err(ctrl_err)?,
        })
    }

    /// One step: joint command θ_d (6,) rad from the reference and the measured joint angles θ (6,).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        reference: &Bound<'py, PyAny>,
        theta: &Bound<'py, PyAny>,
        dt: f64,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let r = self::reference(reference)?;
        let th = vec6(theta, "theta")?;
        Ok(out6(
            py,
            &self.inner.step(&r, &th, dt).map_err(ctrl_err)?.theta_d,
        ))
    }
});

/// The torque-to-position converter (eq. 6.37–6.38) with its command guard.
#[pyclass(name = "TorqueToPosition", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyTorqueToPosition {
    inner: TorqueToPosition,
    guard: CommandGuard,
}

#[pymethods]
impl PyTorqueToPosition {
    /// Inverts a drive PID with gains `pid` = (l_p, l_i, l_d) at period `dt` (s) and torque limit (N·m).
    /// Commands are clamped to `stroke` = (lo, hi) rad and rate-limited to `max_rate` rad/s, starting
    /// from `initial_command` (6,).
    #[new]
    #[pyo3(signature = (*, pid=(400.0, 2000.0, 4.0), dt=1e-3, torque_limit=30.0, stroke=None, max_rate=3.0, initial_command=None))]
    fn py_new(
        pid: (f64, f64, f64),
        dt: f64,
        torque_limit: f64,
        stroke: Option<(f64, f64)>,
        max_rate: f64,
        initial_command: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let mut limits = CommandLimits::nominal();
        if let Some((lo, hi)) = stroke {
            limits.min = Vec6::repeat(lo);
            limits.max = Vec6::repeat(hi);
        }
        limits.max_rate = max_rate;
        limits.validate().map_err(ctrl_err)?;
        let init = opt6(initial_command, "initial_command", Vec6::zeros())?;
        let inner = TorqueToPosition::new(
            PidGains {
                lp: pid.0,
                li: pid.1,
                ld: pid.2,
            },
            dt,
            torque_limit,
        )
        .map_err(ctrl_err)?;
        let guard = CommandGuard::new(limits, &init).map_err(ctrl_err)?;
        Ok(PyTorqueToPosition { inner, guard })
    }

    /// One joint-rate tick: θ_cmd (6,) that makes the drive PID produce tau_a (6,) N·m given the
    /// potentiometer angles θ (6,). Returns dict theta_cmd, tau_expected, stroke_limited, rate_limited.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        tau_a: &Bound<'py, PyAny>,
        theta: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let tau = vec6(tau_a, "tau_a")?;
        let th = vec6(theta, "theta")?;
        let o = self
            .inner
            .step(&tau, &th, &mut self.guard)
            .map_err(ctrl_err)?;
        let d = PyDict::new(py);
        d.set_item("theta_cmd", out6(py, &o.theta_cmd))?;
        d.set_item("tau_expected", out6(py, &o.tau_expected))?;
        d.set_item("stroke_limited", o.stroke_limited)?;
        d.set_item("rate_limited", o.rate_limited)?;
        Ok(d)
    }

    /// Clears the shadow PID.
    fn reset(&mut self) {
        self.inner.reset();
    }
}
