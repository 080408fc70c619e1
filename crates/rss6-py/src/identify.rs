//! Bindings of dynamic identification (thesis ch. 5, rss6-ident): exciting trajectories and their
//! optimisation problem. `rss6.identify` wraps them.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use rss6_ident::{
    base_columns, output_observability, CloeOptions, Excitation, ExcitationLimits,
    ExcitationProblem, LoopParams,
};

use crate::cloe::{cloe_err, loop_config, pid_gains};
use crate::convert::{out1, out6, vec6};
use crate::errors::{invalid, shape};
use crate::params::{PyDynamicParams, PyKinematicParams};

fn coefficients(obj: &Bound<'_, PyAny>) -> PyResult<[Vec<f64>; 6]> {
    let (dims, data) = crate::convert::array(obj, "coefficients")?;
    if dims.len() != 2 || dims[0] != 6 || dims[1] < 3 || dims[1] % 2 == 0 {
        return Err(shape(format!(
            "coefficients must have shape (6, 2n + 1) with n >= 1, got {dims:?}"
        )));
    }
    crate::convert::check_finite(&data, &dims, "coefficients")?;
    let w = dims[1];
    Ok(std::array::from_fn(|i| data[i * w..(i + 1) * w].to_vec()))
}

pub(crate) fn excitation(f0: f64, coeffs: &Bound<'_, PyAny>) -> PyResult<Excitation> {
    Excitation::from_coefficients(f0, coefficients(coeffs)?).map_err(|e| invalid(e.to_string()))
}

/// The metadata of an identification run's log (`rss6.identify.collect(mcap=)`): everything
/// `IdentificationData.from_mcap` needs to rebuild the run — the reference's f0, harmonics and
/// coefficients (row per pose axis), the duration and the visual PID's gains when given.
pub(crate) fn collect_metadata(
    exc: &Excitation,
    f0: f64,
    duration: f64,
    outer_gains: Option<(f64, f64, f64)>,
) -> Vec<(&'static str, String)> {
    let coefficients = exc
        .coefficients()
        .iter()
        .flatten()
        .map(|c| format!("{c:?}"));
    let mut meta = vec![
        ("kind", "rss6.identify.collect".to_string()),
        ("f0", format!("{f0:?}")),
        ("harmonics", exc.harmonics().to_string()),
        ("duration", format!("{duration:?}")),
        ("coefficients", coefficients.collect::<Vec<_>>().join(", ")),
    ];
    if let Some((kp, ki, kd)) = outer_gains {
        meta.push(("outer_gains", format!("{kp:?}, {ki:?}, {kd:?}")));
    }
    meta
}

fn out_coefficients<'py>(py: Python<'py>, e: &Excitation) -> Bound<'py, PyArray2<f64>> {
    let rows: Vec<Vec<f64>> = e.coefficients().to_vec();
    PyArray2::from_vec2(py, &rows).unwrap_or_else(|_| PyArray2::zeros(py, [6, 0], false))
}

/// (χ, χ̇, χ̈) as three (6,) arrays.
type Sample<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<f64>>,
);

/// (χ, χ̇, χ̈) (each (6,)) of the Fourier trajectory (eq. 5.11) with fundamental `f0` (Hz) and
/// `coefficients` (6, 2n + 1) = per axis [s¹, c¹, …, sⁿ, cⁿ, χ0] at time `t` (s).
#[pyfunction]
pub(crate) fn excitation_at<'py>(
    py: Python<'py>,
    f0: f64,
    coefficients: &Bound<'py, PyAny>,
    t: f64,
) -> PyResult<Sample<'py>> {
    let r = excitation(f0, coefficients)?.at(t);
    Ok((
        out6(py, &r.pose),
        out6(py, &r.pose_dot),
        out6(py, &r.pose_ddot),
    ))
}

/// The problem of choosing an exciting trajectory: n harmonics of f0 starting and ending at rest at
/// `start`, feasible under the limits, maximising O_in (eq. 5.13) of the identifiable columns.
#[pyclass(name = "ExcitationProblem", module = "rss6._rss6")]
pub(crate) struct PyExcitationProblem {
    inner: ExcitationProblem,
}

#[pymethods]
impl PyExcitationProblem {
    /// `kp`: kinematic model; `harmonics` n ≥ 2; `f0` (Hz); `start` (6,) pose at rest at both ends;
    /// `stroke` (lo, hi) rad and `stroke_margin` rad; `max_joint_rate` rad/s; `samples` per period for
    /// the checks and the regressor. The identifiable columns are found by pivoted QR (relative
    /// threshold `rank_threshold`) on a mildly exciting reference trajectory.
    #[new]
    #[pyo3(signature = (kp, *, harmonics=5, f0=0.1, start=None, stroke=None, stroke_margin=0.15, max_joint_rate=1.5, samples=200, rank_threshold=1e-8))]
    #[allow(clippy::too_many_arguments)]
    fn py_new(
        py: Python<'_>,
        kp: &PyKinematicParams,
        harmonics: i64,
        f0: f64,
        start: Option<&Bound<'_, PyAny>>,
        stroke: Option<(f64, f64)>,
        stroke_margin: f64,
        max_joint_rate: f64,
        samples: i64,
        rank_threshold: f64,
    ) -> PyResult<Self> {
        let harmonics: usize = crate::convert::count(harmonics, "harmonics")?;
        let samples: usize = crate::convert::count(samples, "samples")?;
        if harmonics < 2 || !(f0.is_finite() && f0 > 0.0) || samples < 10 {
            return Err(invalid(format!(
                "need harmonics >= 2, f0 > 0 Hz and samples >= 10 (got {harmonics}, {f0}, {samples})"
            )));
        }
        let start = match start {
            Some(s) => vec6(s, "start")?,
            None => rss6_core::home_pose(),
        };
        let mut limits = ExcitationLimits {
            stroke_margin,
            max_joint_rate,
            samples,
            ..ExcitationLimits::default()
        };
        if let Some(s) = stroke {
            limits.stroke = s;
        }
        let kp = kp.inner;
        let columns = py.detach(|| -> Result<Vec<usize>, String> {
            // A small reference motion on every axis exposes every identifiable direction.
            let k = Excitation::free_per_axis(harmonics);
            let free: Vec<f64> = (0..6 * k)
                .map(|j| {
                    let s = if j / k < 3 { 5e-4 } else { 2e-3 };
                    s * ((j as f64 * 1.618_033_988_75).fract() * 2.0 - 1.0)
                })
                .collect();
            let e = Excitation::at_rest(harmonics, f0, &start, &free).map_err(|e| e.to_string())?;
            let h = e
                .stacked_regressor(&kp, samples)
                .map_err(|e| e.to_string())?;
            Ok(base_columns(&h, rank_threshold))
        });
        let columns = columns.map_err(invalid)?;
        Ok(PyExcitationProblem {
            inner: ExcitationProblem {
                kp,
                limits,
                harmonics,
                f0,
                start,
                columns,
                samples,
            },
        })
    }

    /// Number of free coefficients: 6 × 2(n − 1).
    #[getter]
    fn dimension(&self) -> usize {
        6 * Excitation::free_per_axis(self.inner.harmonics)
    }

    /// The identifiable columns of Ξ (indices 0..64) whose O_in is maximised.
    #[getter]
    fn columns(&self) -> Vec<usize> {
        self.inner.columns.clone()
    }

    /// Objective of each candidate (rows of `population` (K, dimension), or one (dimension,)): −O_in
    /// if feasible, else 1 + the excess over the first violated limit. Evaluated in parallel with the
    /// GIL released.
    fn objectives<'py>(
        &self,
        py: Python<'py>,
        population: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let (dims, data) = crate::convert::array(population, "population")?;
        let d = self.dimension();
        let rows: Vec<Vec<f64>> = match dims.as_slice() {
            [n] if *n == d => vec![data],
            [k, n] if *n == d => (0..*k).map(|i| data[i * d..(i + 1) * d].to_vec()).collect(),
            _ => {
                return Err(shape(format!(
                    "population must have shape (K, {d}) or ({d},), got {dims:?}"
                )))
            }
        };
        let out = py.detach(|| self.inner.objectives(&rows));
        Ok(out1(py, &out))
    }

    /// The coefficients (6, 2n + 1) of the trajectory of the free coefficients `free` (dimension,).
    fn coefficients<'py>(
        &self,
        py: Python<'py>,
        free: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (_, data) = crate::convert::array(free, "free")?;
        let p = &self.inner;
        let e = Excitation::at_rest(p.harmonics, p.f0, &p.start, &data)
            .map_err(|e| invalid(e.to_string()))?;
        Ok(out_coefficients(py, &e))
    }

    /// The first violated limit of the trajectory (f0, coefficients) as (constraint, time s, excess),
    /// or None if it is feasible.
    fn check(
        &self,
        py: Python<'_>,
        coefficients: &Bound<'_, PyAny>,
    ) -> PyResult<Option<(String, f64, f64)>> {
        let e = excitation(self.inner.f0, coefficients)?;
        let p = &self.inner;
        Ok(py
            .detach(|| e.check(&p.kp, &p.limits))
            .map(|v| (v.constraint.to_string(), v.time, v.excess)))
    }

    /// (O_in, cond) of the trajectory's stacked regressor restricted to the identifiable columns.
    fn observability(
        &self,
        py: Python<'_>,
        coefficients: &Bound<'_, PyAny>,
    ) -> PyResult<(f64, f64)> {
        let e = excitation(self.inner.f0, coefficients)?;
        let p = &self.inner;
        py.detach(|| e.observability(&p.kp, &p.columns, p.samples))
            .map_err(|e| invalid(e.to_string()))
    }

    /// The start pose (6,).
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out6(py, &self.inner.start)
    }

    fn __repr__(&self) -> String {
        format!(
            "ExcitationProblem(n = {}, f0 = {} Hz, {} identifiable columns)",
            self.inner.harmonics,
            self.inner.f0,
            self.inner.columns.len()
        )
    }
}

/// (O_in, cond, identifiable names, frames, relative σ of each): what [`loop_observability`] returns.
type LoopObservabilityTuple = (f64, f64, Vec<String>, usize, Vec<f64>);

/// (O_in, cond, identifiable names, frames, relative σ of each) of the closed loop's output sensitivity on the Fourier
/// trajectory (`f0`, `coefficients`) from rest at `start` for `duration` s, at the model (`kp`, `dp`,
/// drive gains `pid`): eq. 5.13 on the camera poses' sensitivity to CLOE's log-parameters, weighted
/// by `noise` = (position m, angle rad; default Table 4.1), the quantities in `hold` left out and
/// the identifiable ones chosen by the pivoted QR at `identifiability_threshold`
/// (`rss6_ident::output_observability`). The loop's settings as for `simulate_identification`.
/// One simulation with sensitivities. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (kp, dp, pid, f0, coefficients, *, start, duration, torque_limit=30.0, dt=1e-3, derivative_filter=0.0, friction_smoothing=0.0, implicit_friction=false, noise=None, hold=None, identifiability_threshold=1e-3))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn loop_observability(
    py: Python<'_>,
    kp: &PyKinematicParams,
    dp: &PyDynamicParams,
    pid: (f64, f64, f64),
    f0: f64,
    coefficients: &Bound<'_, PyAny>,
    start: &Bound<'_, PyAny>,
    duration: f64,
    torque_limit: f64,
    dt: f64,
    derivative_filter: f64,
    friction_smoothing: f64,
    implicit_friction: bool,
    noise: Option<(f64, f64)>,
    hold: Option<Vec<String>>,
    identifiability_threshold: f64,
) -> PyResult<LoopObservabilityTuple> {
    let exc = excitation(f0, coefficients)?;
    let cfg = loop_config(
        kp,
        start,
        duration,
        torque_limit,
        0.0,
        dt,
        derivative_filter,
        (friction_smoothing, implicit_friction),
        (None, None, None),
    )?;
    let at = LoopParams {
        dynamics: dp.inner,
        pid: pid_gains(pid),
    };
    let mut options = CloeOptions {
        hold: hold.unwrap_or_default(),
        identifiability_threshold,
        ..CloeOptions::default()
    };
    if let Some((p, a)) = noise {
        options.noise = [p, a];
    }
    let o = py
        .detach(|| output_observability(&cfg, &at, &exc, &options))
        .map_err(cloe_err)?;
    Ok((
        o.o_in,
        o.condition,
        o.identifiable,
        o.frames,
        o.relative_std,
    ))
}
