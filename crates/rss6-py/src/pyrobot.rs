//! Any Python object that implements the `rss6.types.Robot` protocol (e.g. the CAN bridge's robot) as an
//! `rss6_exp::Robot`, so the compiled runners drive it tick by tick. Each call takes the GIL; an exception
//! raised by the object stops the run and is re-raised to the caller unchanged.

use std::sync::Mutex;

use pyo3::prelude::*;
use rss6_core::Vec6;
use rss6_exp::{ExpError, Robot, TrueState};
use rss6_sim::Truth;

use crate::convert::vec6;
use crate::params::{PyDynamicParams, PyKinematicParams};

/// A Python robot seen by the experiment layer.
pub(crate) struct PyRobot {
    obj: Py<PyAny>,
    dt: f64,
    /// The first exception the object raised (the run is stopped by it).
    error: Mutex<Option<PyErr>>,
    has_truth: bool,
}

impl PyRobot {
    /// Wraps `obj`; reads its `dt` once. A simulated robot behind it (one with `true_pose` and
    /// `truth`) also shows its true state and its truth dict (`kinematics`, `dynamics`, `pid`,
    /// `sensor_in_base`, `target_in_effector`; effects are not carried over).
    pub(crate) fn new(obj: &Bound<'_, PyAny>) -> PyResult<Self> {
        for name in [
            "step_joint_command",
            "camera",
            "potentiometers",
            "time",
            "dt",
        ] {
            if !obj.hasattr(name)? {
                return Err(crate::errors::invalid(format!(
                    "a robot must implement rss6.types.Robot: {} has no '{name}'",
                    obj.get_type().name()?
                )));
            }
        }
        let dt: f64 = obj.getattr("dt")?.extract()?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(crate::errors::invalid(format!(
                "robot.dt must be finite and > 0 s, got {dt}"
            )));
        }
        Ok(PyRobot {
            obj: obj.clone().unbind(),
            dt,
            error: Mutex::new(None),
            has_truth: obj.hasattr("true_pose")? && obj.hasattr("truth")?,
        })
    }

    /// The exception that stopped the run, if any.
    pub(crate) fn take_error(&self) -> Option<PyErr> {
        self.error.lock().ok().and_then(|mut e| e.take())
    }

    fn keep(&self, e: PyErr) -> ExpError {
        let msg = Python::attach(|py| e.value(py).to_string());
        if let Ok(mut slot) = self.error.lock() {
            if slot.is_none() {
                *slot = Some(e);
            }
        }
        ExpError::Robot(msg)
    }

    fn call_vec6(&self, name: &str) -> PyResult<Vec6> {
        Python::attach(|py| {
            let out = self.obj.bind(py).call_method0(name)?;
            vec6(&out, name)
        })
    }
}

impl Robot for PyRobot {
    fn dt(&self) -> f64 {
        self.dt
    }

    fn time(&self) -> f64 {
        Python::attach(|py| {
            self.obj
                .bind(py)
                .getattr("time")
                .and_then(|t| t.extract::<f64>())
                .unwrap_or(f64::NAN)
        })
    }

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> rss6_exp::Result<()> {
        let r = Python::attach(|py| -> PyResult<()> {
            let cmd = crate::convert::out6(py, theta_cmd);
            self.obj
                .bind(py)
                .call_method1("step_joint_command", (cmd,))?;
            // Ctrl-C between ticks stops the run like any exception.
            py.check_signals()
        });
        r.map_err(|e| self.keep(e))
    }

    fn camera(&mut self) -> Option<Vec6> {
        let r = Python::attach(|py| -> PyResult<Option<Vec6>> {
            let out = self.obj.bind(py).call_method0("camera")?;
            if out.is_none() {
                Ok(None)
            } else {
                vec6(&out, "camera()").map(Some)
            }
        });
        match r {
            Ok(z) => z,
            Err(e) => {
                self.keep(e);
                None
            }
        }
    }

    fn potentiometers(&self) -> Vec6 {
        match self.call_vec6("potentiometers") {
            Ok(k) => k,
            Err(e) => {
                self.keep(e);
                Vec6::repeat(f64::NAN)
            }
        }
    }

    fn truth(&self) -> Option<Truth> {
        if !self.has_truth {
            return None;
        }
        Python::attach(|py| -> PyResult<Truth> {
            let d = self.obj.bind(py).call_method0("truth")?;
            let kp = d
                .get_item("kinematics")?
                .extract::<PyRef<'_, PyKinematicParams>>()?
                .inner;
            let dp = d
                .get_item("dynamics")?
                .extract::<PyRef<'_, PyDynamicParams>>()?
                .inner;
            let (lp, li, ld): (f64, f64, f64) = d.get_item("pid")?.extract()?;
            Ok(Truth {
                kinematics: kp,
                dynamics: dp,
                pid: rss6_ctrl::PidGains { lp, li, ld },
                sensor_in_base: vec6(&d.get_item("sensor_in_base")?, "sensor_in_base")?,
                target_in_effector: vec6(&d.get_item("target_in_effector")?, "target_in_effector")?,
                effects: Vec::new(),
            })
        })
        .ok()
    }

    fn true_state(&self) -> Option<TrueState> {
        if !self.has_truth {
            return None;
        }
        let pose = self.call_vec6("true_pose").ok()?;
        let nan = Vec6::repeat(f64::NAN);
        let theta = self.call_vec6("true_theta").unwrap_or(nan);
        let torque = self.call_vec6("torque").unwrap_or(nan);
        Some(TrueState {
            pose,
            theta,
            theta_dot: nan,
            torque,
        })
    }
}
