//! Calibration bindings (rss6-ident, thesis ch. 4): configuration selection, stroke, the data type of
//! a collection (collected in `dwell.rs`), RPBA, implicit calibration, relative pose errors and the
//! §4.4.3 study.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rss6_core::KinematicParams;
use rss6_ident::{
    CalibrationOptions, CalibrationResult, IdentError, Method, SelectionOptions, StudyOptions,
    TrueRobot,
};

pub(crate) use crate::calib_data::PyCalibrationData;
use crate::convert::{out1, out6, out_rows6, rows6, vec6};
use crate::errors::{core, invalid, make, Attr};
use crate::params::PyKinematicParams;

/// Maps an [`IdentError`] onto its exception class.
pub(crate) fn ident_err(e: IdentError) -> PyErr {
    let msg = e.to_string();
    match e {
        IdentError::TooFewConfigurations { got, needed, .. } => make(
            "CalibrationError",
            msg,
            vec![
                ("got", Attr::I(got as i64)),
                ("needed", Attr::I(needed as i64)),
            ],
        ),
        IdentError::RankDeficient {
            rank,
            expected,
            unseen,
        } => make(
            "CalibrationError",
            msg,
            vec![
                ("rank", Attr::I(rank as i64)),
                ("expected", Attr::I(expected as i64)),
                ("unseen", Attr::S(unseen.join(", "))),
            ],
        ),
        IdentError::Fk { config, source } => {
            let err = crate::errors::core_at(source, Some(format!("configuration {config}")));
            Python::attach(|py| {
                let _ = err.value(py).setattr("config", config);
            });
            err
        }
        IdentError::Calibration {
            configurations,
            parameters,
            fit_statistic,
            ..
        } => make(
            "CalibrationError",
            msg,
            vec![
                (
                    "configurations",
                    Attr::IL(configurations.iter().map(|&c| c as i64).collect()),
                ),
                ("parameters", Attr::S(parameters.join(", "))),
                ("fit_statistic", Attr::F(fit_statistic)),
            ],
        ),
        IdentError::InvalidInput(_) => invalid(msg),
        IdentError::Core(c) => core(c),
        _ => make("CalibrationError", msg, vec![]),
    }
}

fn method(name: &str) -> PyResult<Method> {
    match name.to_ascii_lowercase().as_str() {
        "rpba" => Ok(Method::Rpba),
        "implicit" => Ok(Method::Implicit),
        other => Err(invalid(format!(
            "method must be 'rpba' or 'implicit', got '{other}'"
        ))),
    }
}

/// Outcome of RPBA or implicit calibration.
#[pyclass(name = "CalibrationResult", module = "rss6._rss6", frozen)]
#[derive(Debug, Clone)]
pub(crate) struct PyCalibrationResult {
    pub(crate) inner: CalibrationResult,
}

#[pymethods]
impl PyCalibrationResult {
    /// "rpba" or "implicit".
    #[getter]
    fn method(&self) -> &'static str {
        match self.inner.method {
            Method::Rpba => "rpba",
            Method::Implicit => "implicit",
        }
    }

    /// Calibrated kinematic parameters.
    #[getter]
    fn params(&self) -> PyKinematicParams {
        PyKinematicParams::wrap(self.inner.params)
    }

    /// Calibrated error vector b (60,) relative to the starting parameters.
    #[getter]
    fn errors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.errors)
    }

    /// Calibrated ᴱχ_t (6,).
    #[getter]
    fn target_in_effector<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.inner.target_in_effector)
    }

    /// Calibrated ᴼχ_C (6,) (implicit only; None for RPBA).
    #[getter]
    fn sensor_in_base<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.sensor_in_base.map(|s| out6(py, &s))
    }

    /// Cost Σ‖W r‖² at the start and after each accepted step.
    #[getter]
    fn cost_history<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.cost_history)
    }

    /// Numerical rank of the scaled Jacobian at the solution.
    #[getter]
    fn rank(&self) -> usize {
        self.inner.rank
    }

    /// Number of parameters (66 RPBA, 72 implicit).
    #[getter]
    fn parameter_count(&self) -> usize {
        self.inner.parameter_count
    }

    /// Parameters not individually identifiable (gauge directions), by name.
    #[getter]
    fn unidentifiable(&self) -> Vec<String> {
        self.inner.unidentifiable.clone()
    }

    /// The gauge directions removed from the problem, described.
    #[getter]
    fn gauge_directions(&self) -> Vec<String> {
        self.inner.gauge_directions.clone()
    }

    /// Singular values of the scaled Jacobian, descending.
    #[getter]
    fn singular_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.singular_values)
    }

    /// Accepted LM steps.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }

    /// Dropped configurations as (index, reason).
    #[getter]
    fn dropped(&self) -> Vec<(usize, String)> {
        self.inner
            .dropped
            .iter()
            .map(|d| (d.index, d.reason.clone()))
            .collect()
    }

    /// Indices of the configurations used.
    #[getter]
    fn used(&self) -> Vec<usize> {
        self.inner.used.clone()
    }

    /// Gross outliers rejected by the solver as (index, normalised residual), in rejection order.
    #[getter]
    fn rejected(&self) -> Vec<(usize, f64)> {
        self.inner
            .rejected
            .iter()
            .map(|r| (r.index, r.normalized_residual))
            .collect()
    }

    /// Normalised residual r_lᵀΣ_ll⁻¹r_l/6 per used configuration as (index, value); ≈ 1 for noise.
    #[getter]
    fn normalized_residuals(&self) -> Vec<(usize, f64)> {
        self.inner.normalized_residuals.clone()
    }

    /// Fit statistic: weighted cost per degree of freedom (≈ 1 when the model explains the data).
    #[getter]
    fn fit_statistic(&self) -> f64 {
        self.inner.fit_statistic
    }

    /// Degrees of freedom of the fit statistic.
    #[getter]
    fn degrees_of_freedom(&self) -> usize {
        self.inner.degrees_of_freedom
    }

    /// How Levenberg–Marquardt ended: "cost_tolerance", "step_tolerance", "no_further_decrease" or
    /// "iteration_limit".
    #[getter]
    fn convergence(&self) -> &'static str {
        match self.inner.convergence {
            rss6_ident::Convergence::CostTolerance => "cost_tolerance",
            rss6_ident::Convergence::StepTolerance => "step_tolerance",
            rss6_ident::Convergence::NoFurtherDecrease => "no_further_decrease",
            _ => "iteration_limit",
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "CalibrationResult({}, {} iterations, rank {}/{}, fit statistic {:.3}, {} dropped, {} rejected)",
            self.method(),
            self.inner.iterations,
            self.inner.rank,
            self.inner.parameter_count,
            self.inner.fit_statistic,
            self.inner.dropped.len(),
            self.inner.rejected.len()
        )
    }
}

/// Actuator stroke (lo, hi) rad of §4.4.1 (eq. 4.24 with the type-I, type-II and homeomorphism
/// constraints). Releases the GIL.
#[pyfunction]
pub(crate) fn stroke(py: Python<'_>, kp: &PyKinematicParams) -> PyResult<(f64, f64)> {
    let k = kp.inner;
    py.detach(move || rss6_ident::stroke(&k)).map_err(ident_err)
}

/// Optimal calibration configurations (§4.4.2): (m, 6) rad, row 0 = the initial configuration.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (kp, method="rpba", seed=0, *, start=13, candidates=5000, stroke=None))]
pub(crate) fn select_configurations<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    method: &str,
    seed: i128,
    start: i64,
    candidates: i64,
    stroke: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let start: usize = crate::convert::count(start, "start")?;
    let candidates: usize = crate::convert::count(candidates, "candidates")?;
    let m = self::method(method)?;
    let seed = crate::convert::seed(seed)?;
    let k = kp.inner;
    let opts = SelectionOptions {
        start,
        candidates,
        stroke,
        ..SelectionOptions::default()
    };
    let rep = py
        .detach(move || rss6_ident::select_configurations_with(&k, m, seed, &opts))
        .map_err(ident_err)?;
    Ok(out_rows6(py, &rep.thetas))
}

/// The camera part of the noise model: "table" (Table 4.1, independent components), "dwells" (the
/// covariance pooled from the dwells' own frames) or a (6, 6) covariance of one frame's ᶜχ_t.
fn noise_option(o: &mut CalibrationOptions, noise: Option<&Bound<'_, PyAny>>) -> PyResult<()> {
    let Some(n) = noise else { return Ok(()) };
    if let Ok(s) = n.extract::<String>() {
        match s.as_str() {
            "table" => {}
            "dwells" => o.noise_from_dwells = true,
            other => {
                return Err(invalid(format!(
                    "noise must be \"table\", \"dwells\" or a (6, 6) covariance, got {other:?}"
                )))
            }
        }
        return Ok(());
    }
    let m = crate::convert::mat6_rows(n, "noise")?;
    let Some(m) = crate::convert::symmetrised6(&m) else {
        return Err(invalid(
            "the noise covariance must be symmetric (to 1e-12 relative) and positive definite",
        ));
    };
    let c = nalgebra::Matrix6::from_fn(|r, k| m[r][k]);
    if c.cholesky().is_none() {
        return Err(invalid("the noise covariance must be positive definite"));
    }
    if let Some(base) = &mut o.noise {
        base.pose_covariance = Some(c);
    }
    Ok(())
}

fn options(
    max_iterations: i64,
    target_guess: Option<&Bound<'_, PyAny>>,
    noise: Option<&Bound<'_, PyAny>>,
) -> PyResult<CalibrationOptions> {
    let max_iterations: usize = crate::convert::count(max_iterations, "max_iterations")?;
    let mut o = CalibrationOptions {
        max_iterations,
        ..CalibrationOptions::default()
    };
    noise_option(&mut o, noise)?;
    if let Some(t) = target_guess {
        o.target_guess = vec6(t, "target_guess")?.into();
    }
    Ok(o)
}

/// RPBA (eq. 4.16–4.21) from `data` starting at `kp`: 60 kinematic + 6 external (ᴱχ_t) parameters,
/// Levenberg–Marquardt with analytic Jacobians. `progress(iteration, cost)` per iteration; an
/// exception it raises (or Ctrl-C) is raised once the solve (milliseconds) has returned, and no further
/// callback is made.
#[pyfunction]
#[pyo3(signature = (data, kp, *, max_iterations=60, target_guess=None, progress=None, noise=None))]
pub(crate) fn rpba(
    py: Python<'_>,
    data: &PyCalibrationData,
    kp: &PyKinematicParams,
    max_iterations: i64,
    target_guess: Option<&Bound<'_, PyAny>>,
    progress: Option<Py<PyAny>>,
    noise: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyCalibrationResult> {
    let opts = options(max_iterations, target_guess, noise)?;
    let (d, k) = (&data.inner, kp.inner);
    let mut interrupt = crate::exp::Interrupt::default();
    let r = py.detach(|| {
        rss6_ident::rpba_with_progress(d, &k, &opts, &mut |p| {
            if let Some(cb) = &progress {
                interrupt.call(|py| cb.call1(py, (p.iteration, p.cost)).map(|_| ()));
            }
        })
    });
    if let Some(e) = interrupt.take() {
        return Err(e);
    }
    Ok(PyCalibrationResult {
        inner: r.map_err(ident_err)?,
    })
}

/// Implicit calibration (eq. 4.10–4.15) from `data` starting at `kp` and the rough sensor pose
/// `sensor_pose_guess` (ᴼχ_C): 60 kinematic + 12 external parameters.
#[pyfunction]
#[pyo3(signature = (data, kp, sensor_pose_guess, *, max_iterations=60, target_guess=None, noise=None))]
pub(crate) fn implicit(
    py: Python<'_>,
    data: &PyCalibrationData,
    kp: &PyKinematicParams,
    sensor_pose_guess: &Bound<'_, PyAny>,
    max_iterations: i64,
    target_guess: Option<&Bound<'_, PyAny>>,
    noise: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyCalibrationResult> {
    let opts = options(max_iterations, target_guess, noise)?;
    let s = vec6(sensor_pose_guess, "sensor_pose_guess")?;
    let (d, k) = (&data.inner, kp.inner);
    let r = py
        .detach(|| rss6_ident::implicit(d, &k, &s, &opts))
        .map_err(ident_err)?;
    Ok(PyCalibrationResult { inner: r })
}

/// RMS relative pose errors (Table 4.5 procedure) of the model (`params`, `target_in_effector`) on the
/// true robot (`true_kp`, `true_sensor_in_base`, `true_target_in_effector`) over `n` random test
/// configurations in `stroke`. Returns dict rms (6,), errors (n', 6), skipped.
#[pyfunction]
#[pyo3(signature = (params, target_in_effector, true_kp, true_sensor_in_base, true_target_in_effector, *, n=100, seed=0, stroke=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn relative_pose_errors_raw<'py>(
    py: Python<'py>,
    params: &PyKinematicParams,
    target_in_effector: &Bound<'py, PyAny>,
    true_kp: &PyKinematicParams,
    true_sensor_in_base: &Bound<'py, PyAny>,
    true_target_in_effector: &Bound<'py, PyAny>,
    n: i64,
    seed: i128,
    stroke: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let n: usize = crate::convert::count(n, "n")?;
    let truth = TrueRobot {
        kp: true_kp.inner,
        sensor_in_base: vec6(true_sensor_in_base, "true_sensor_in_base")?,
        target_in_effector: vec6(true_target_in_effector, "true_target_in_effector")?,
    };
    let target = vec6(target_in_effector, "target_in_effector")?;
    let seed = crate::convert::seed(seed)?;
    let nominal = KinematicParams::nominal();
    let stroke = match stroke {
        Some(s) => s,
        None => (-57.1f64.to_radians(), 57.1f64.to_radians()),
    };
    let p = params.inner;
    let r = py
        .detach(|| rss6_ident::relative_pose_errors(&p, &target, &truth, &nominal, n, seed, stroke))
        .map_err(ident_err)?;
    let d = PyDict::new(py);
    d.set_item("rms", out1(py, &r.rms))?;
    d.set_item("errors", out_rows6(py, &r.errors))?;
    d.set_item("skipped", r.skipped)?;
    Ok(d)
}

/// The simulation study of §4.4.3 over `robots` random true robots: list of dicts, one per robot,
/// with the Table 4.3–4.5 entries. Data from rss6-ident's analytic generator with Table 4.1 noise
/// (parallel), or with `plant=True` from the rapier plant, its PID and its stereo CMM (parallel).
/// `rpba_thetas` and `implicit_thetas` are the configuration sets (row 0 = initial). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (rpba_thetas, implicit_thetas, *, robots=20, seed=0, dwell=2.0, test_configurations=100, stroke=None, plant=false, noise=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn calibration_study<'py>(
    py: Python<'py>,
    rpba_thetas: &Bound<'py, PyAny>,
    implicit_thetas: &Bound<'py, PyAny>,
    robots: i64,
    seed: i128,
    dwell: f64,
    test_configurations: i64,
    stroke: Option<(f64, f64)>,
    plant: bool,
    noise: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let mut solver = CalibrationOptions::default();
    noise_option(&mut solver, noise)?;
    let robots: usize = crate::convert::count(robots, "robots")?;
    let test_configurations: usize =
        crate::convert::count(test_configurations, "test_configurations")?;
    let opts = StudyOptions {
        robots,
        seed: crate::convert::seed(seed)?,
        rpba_thetas: rows6(rpba_thetas, "rpba_thetas")?,
        implicit_thetas: rows6(implicit_thetas, "implicit_thetas")?,
        dwell,
        noise: rss6_ident::NoiseModel::default(),
        test_configurations,
        stroke: stroke.unwrap_or((-57.1f64.to_radians(), 57.1f64.to_radians())),
        solver,
        target_nominal: if plant {
            rss6_ident::plant_nominal_target().into()
        } else {
            rss6_ident::NOMINAL_TARGET_IN_EFFECTOR
        },
    };
    let nominal = KinematicParams::nominal();
    let rows = py.detach(|| {
        if plant {
            use rayon::prelude::*;
            (0..opts.robots)
                .into_par_iter()
                .map(|r| rss6_ident::run_plant_robot(&nominal, &opts, r))
                .collect::<Vec<_>>()
        } else {
            rss6_ident::run_study(&nominal, &opts)
        }
    });
    let out = PyList::empty(py);
    for r in rows {
        let r = r.map_err(ident_err)?;
        let d = PyDict::new(py);
        d.set_item("robot", r.robot)?;
        d.set_item("implicit_param_error", r.implicit_param_error)?;
        d.set_item("implicit_param_error_si", r.implicit_param_error_si)?;
        d.set_item("implicit_residual", r.implicit_residual)?;
        d.set_item("rpba_param_error", r.rpba_param_error)?;
        d.set_item("rpba_param_error_si", r.rpba_param_error_si)?;
        d.set_item("rpba_residual", r.rpba_residual)?;
        d.set_item("rms_uncalibrated", out1(py, &r.rms_uncalibrated))?;
        d.set_item("rms_implicit", out1(py, &r.rms_implicit))?;
        d.set_item("rms_rpba", out1(py, &r.rms_rpba))?;
        d.set_item(
            "rms_implicit_fixed_sensor",
            out1(py, &r.rms_implicit_fixed_sensor),
        )?;
        d.set_item("iterations", r.iterations)?;
        d.set_item("ranks", r.ranks)?;
        out.append(d)?;
    }
    Ok(out)
}
