//! The data of one calibration collection as Python sees it: the dwells' means, counts and camera
//! covariance (`rss6.CalibrationData`).

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use rss6_core::Vec6;
use rss6_ident::{CalibrationData, ConfigurationData};

use crate::convert::{array, out1, out_rows, rows6};
use crate::errors::{invalid, shape};

/// Means over one dwell per configuration (configuration 0 = the initial configuration).
#[pyclass(name = "CalibrationData", module = "rss6._rss6")]
#[derive(Debug, Clone)]
pub(crate) struct PyCalibrationData {
    pub(crate) inner: CalibrationData,
}

#[pymethods]
impl PyCalibrationData {
    /// Data from arrays: kappa (m, 6) mean readings (bits), sensor_pose (m, 6) mean ᶜχ_t (a NaN row
    /// marks a configuration without camera frames), theta_cmd (m, 6) commands (optional; NaN if
    /// absent), and the sample counts per row kappa_samples, camera_frames (m,) (optional; default
    /// 1, and 1 or 0 frames by the NaN rows); sensor_pose_cov (m, 6, 6) each dwell's sample
    /// covariance of one frame (optional; a NaN block: not recorded).
    #[staticmethod]
    #[pyo3(signature = (kappa, sensor_pose, theta_cmd=None, *, kappa_samples=None, camera_frames=None, sensor_pose_cov=None))]
    fn from_arrays(
        kappa: &Bound<'_, PyAny>,
        sensor_pose: &Bound<'_, PyAny>,
        theta_cmd: Option<&Bound<'_, PyAny>>,
        kappa_samples: Option<Vec<u32>>,
        camera_frames: Option<Vec<u32>>,
        sensor_pose_cov: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let kappa = rows6(kappa, "kappa")?;
        let (dims, data) = array(sensor_pose, "sensor_pose")?;
        if dims.len() != 2 || dims[1] != 6 || dims[0] != kappa.len() {
            return Err(shape(format!(
                "sensor_pose must have shape ({}, 6), got {dims:?}",
                kappa.len()
            )));
        }
        let covs: Vec<Option<[[f64; 6]; 6]>> = match sensor_pose_cov {
            None => vec![None; kappa.len()],
            Some(c) => {
                let (cd, cv) = array(c, "sensor_pose_cov")?;
                if cd != [kappa.len(), 6, 6] {
                    return Err(shape(format!(
                        "sensor_pose_cov must have shape ({}, 6, 6), got {cd:?}",
                        kappa.len()
                    )));
                }
                cv.chunks_exact(36)
                    .map(|b| {
                        let m: [[f64; 6]; 6] =
                            std::array::from_fn(|r| std::array::from_fn(|c| b[6 * r + c]));
                        if b.iter().all(|v| v.is_nan()) {
                            Ok(None)
                        } else if let Some(m) = crate::convert::symmetrised6(&m)
                            .filter(|_| b.iter().all(|v| v.is_finite()))
                        {
                            Ok(Some(m))
                        } else {
                            Err(invalid(
                                "each sensor_pose_cov block must be finite and symmetric to 1e-12 relative (or all NaN: not recorded)",
                            ))
                        }
                    })
                    .collect::<PyResult<_>>()?
            }
        };
        let theta = match theta_cmd {
            Some(t) => rows6(t, "theta_cmd")?,
            None => vec![Vec6::repeat(f64::NAN); kappa.len()],
        };
        if theta.len() != kappa.len() {
            return Err(shape("theta_cmd must have as many rows as kappa"));
        }
        for (name, c) in [
            ("kappa_samples", &kappa_samples),
            ("camera_frames", &camera_frames),
        ] {
            if c.as_ref().is_some_and(|c| c.len() != kappa.len()) {
                return Err(shape(format!("{name} must have as many entries as kappa")));
            }
        }
        let configurations = kappa
            .iter()
            .zip(data.chunks_exact(6))
            .zip(theta.iter())
            .enumerate()
            .map(|(i, ((k, s), th))| ConfigurationData {
                theta_cmd: (*th).into(),
                kappa: (*k).into(),
                sensor_pose: if s.iter().any(|x| x.is_nan()) {
                    None
                } else {
                    let mut p = [0.0; 6];
                    p.copy_from_slice(s);
                    Some(p)
                },
                kappa_samples: kappa_samples.as_ref().map_or(1, |c| c[i]),
                camera_frames: camera_frames
                    .as_ref()
                    .map_or(u32::from(!s.iter().any(|x| x.is_nan())), |c| c[i]),
                sensor_pose_cov: covs[i],
                ..ConfigurationData::default()
            })
            .collect();
        Ok(PyCalibrationData {
            inner: CalibrationData { configurations },
        })
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Mean potentiometer readings κ (m, 6) bits.
    #[getter]
    fn kappa<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let r: Vec<[f64; 6]> = self.inner.configurations.iter().map(|c| c.kappa).collect();
        out_rows::<6>(py, &r)
    }

    /// Mean sensor poses ᶜχ_t (m, 6); NaN rows where no frame arrived.
    #[getter]
    fn sensor_pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let r: Vec<[f64; 6]> = self
            .inner
            .configurations
            .iter()
            .map(|c| c.sensor_pose.unwrap_or([f64::NAN; 6]))
            .collect();
        out_rows::<6>(py, &r)
    }

    /// Commanded joint angles (m, 6) rad (nominal convention).
    #[getter]
    fn theta_cmd<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let r: Vec<[f64; 6]> = self
            .inner
            .configurations
            .iter()
            .map(|c| c.theta_cmd)
            .collect();
        out_rows::<6>(py, &r)
    }

    /// Each dwell's sample covariance of one camera frame's ᶜχ_t (m, 6, 6) (m², m·rad, rad²); a NaN
    /// block where it was not recorded (data from arrays without it, fewer than 2 frames).
    #[getter]
    fn sensor_pose_cov<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let m = self.inner.len();
        let flat: Vec<f64> = self
            .inner
            .configurations
            .iter()
            .flat_map(|c| match &c.sensor_pose_cov {
                Some(b) => b.iter().flatten().copied().collect::<Vec<_>>(),
                None => vec![f64::NAN; 36],
            })
            .collect();
        Ok(PyArray1::from_vec(py, flat).reshape([m, 6, 6])?.into_any())
    }

    /// Camera frames averaged per configuration (m,).
    #[getter]
    fn camera_frames<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let r: Vec<f64> = self
            .inner
            .configurations
            .iter()
            .map(|c| f64::from(c.camera_frames))
            .collect();
        out1(py, &r)
    }

    fn __repr__(&self) -> String {
        format!("CalibrationData({} configurations)", self.inner.len())
    }
}
