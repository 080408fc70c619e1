//! The log format of rss6-exp from Python: `LogWriter` (the chunked, crash-safe writer), `read_log`
//! (the reader) and `mean_pose` (the one pose mean of the project, used by the dwells).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rss6_core::Vec6;
use rss6_exp::dwell::ConfigurationData;
use rss6_exp::log::{read_log as read, LogError, LogWriter, DEFAULT_CHUNK_SIZE};

use crate::convert::{array, check_finite, out1, out6, out_rows6, rows6, vec6};
use crate::errors::{invalid, make, shape, Attr};
use crate::exp::exp_err;

/// Times (N,) s: a 1-D finite array.
fn times(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let (dims, data) = array(obj, name)?;
    if dims.len() != 1 {
        return Err(shape(format!("{name} must have shape (N,), got {dims:?}")));
    }
    check_finite(&data, &dims, name)?;
    Ok(data)
}

/// Writes one run to an MCAP file as it goes (rss6-exp's `LogWriter`): ZSTD chunks of about
/// `chunk_size` bytes (uncompressed) with CRCs; `t0` (s) is added to every time stamp. Streams:
/// poses `true_pose`, `camera_pose`, `desired_pose`, `estimate_pose`, `sensor_pose`; six-vectors
/// `theta_cmd`, `theta`, `kappa`, `torque`; calibration dwells (`write_dwell`).
#[pyclass(name = "LogWriter", module = "rss6._rss6")]
pub(crate) struct PyLogWriter {
    inner: Mutex<LogWriter>,
}

impl PyLogWriter {
    fn lock(&self) -> PyResult<MutexGuard<'_, LogWriter>> {
        self.inner
            .lock()
            .map_err(|_| make("LogError", "the log writer panicked earlier", vec![]))
    }

    /// The writer, if not finished yet.
    fn open(&self) -> PyResult<MutexGuard<'_, LogWriter>> {
        let w = self.lock()?;
        if w.is_finished() {
            return Err(make(
                "LogError",
                format!("{}: the log is already closed", w.path().display()),
                vec![],
            ));
        }
        Ok(w)
    }
}

#[pymethods]
impl PyLogWriter {
    /// Creates (truncates) `path` and writes the header; `chunk_size` defaults to 256 KiB.
    #[new]
    #[pyo3(signature = (path, *, chunk_size=None, t0=0.0))]
    fn py_new(path: PathBuf, chunk_size: Option<u64>, t0: f64) -> PyResult<Self> {
        let size = chunk_size.unwrap_or(DEFAULT_CHUNK_SIZE);
        let inner = LogWriter::create(&path, size, t0).map_err(exp_err)?;
        Ok(PyLogWriter {
            inner: Mutex::new(inner),
        })
    }

    /// Appends N samples of stream `name`: times `t` (N,) s, `values` (N, 6) (poses
    /// [x, y, z, α, β, γ] in m, rad). Releases the GIL.
    fn write(
        &self,
        py: Python<'_>,
        name: &str,
        t: &Bound<'_, PyAny>,
        values: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let (t, v) = (times(t, "t")?, rows6(values, "values")?);
        if t.len() != v.len() {
            return Err(shape(format!(
                "{name}: {} times for {} values",
                t.len(),
                v.len()
            )));
        }
        let mut g = self.open()?;
        let w: &mut LogWriter = &mut g;
        py.detach(|| {
            t.iter()
                .zip(&v)
                .try_for_each(|(tk, vk)| w.write(name, *tk, vk))
        })
        .map_err(exp_err)
    }

    /// Appends samples of several streams `{name: (times (N,), values (N, 6))}` merged in time order
    /// (ties in the order of the dict), so chunks hold contiguous time ranges. Releases the GIL.
    fn write_streams(&self, py: Python<'_>, streams: &Bound<'_, PyDict>) -> PyResult<()> {
        let mut series: Vec<(String, Vec<f64>, Vec<Vec6>)> = Vec::new();
        for (k, s) in streams.iter() {
            let name: String = k.extract()?;
            let (t, v): (Bound<'_, PyAny>, Bound<'_, PyAny>) = s
                .extract()
                .map_err(|_| invalid(format!("{name}: expected a (times, values) pair")))?;
            let (t, v) = (times(&t, &name)?, rows6(&v, &name)?);
            if t.len() != v.len() {
                return Err(shape(format!(
                    "{name}: {} times for {} values",
                    t.len(),
                    v.len()
                )));
            }
            series.push((name, t, v));
        }
        let mut g = self.open()?;
        let w: &mut LogWriter = &mut g;
        py.detach(|| {
            let mut order: Vec<(f64, usize, usize)> = series
                .iter()
                .enumerate()
                .flat_map(|(s, (_, t, _))| t.iter().enumerate().map(move |(k, tk)| (*tk, s, k)))
                .collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            order.iter().try_for_each(|&(tk, s, k)| {
                let (name, _, v) = &series[s];
                w.write(name, tk, &v[k])
            })
        })
        .map_err(exp_err)
    }

    /// Appends the means of a finished calibration dwell: configuration `index`, its `window`
    /// (first, last tick time, s), `theta_cmd` (6,) rad, `kappa` (6,) bit, `sensor_pose` (6,) m, rad
    /// or None, and the sample counts.
    #[pyo3(signature = (index, window, theta_cmd, kappa, sensor_pose, kappa_samples, camera_frames))]
    #[allow(clippy::too_many_arguments)]
    fn write_dwell(
        &self,
        index: usize,
        window: (f64, f64),
        theta_cmd: &Bound<'_, PyAny>,
        kappa: &Bound<'_, PyAny>,
        sensor_pose: Option<&Bound<'_, PyAny>>,
        kappa_samples: u32,
        camera_frames: u32,
    ) -> PyResult<()> {
        let data = ConfigurationData {
            theta_cmd: vec6(theta_cmd, "theta_cmd")?.into(),
            kappa: vec6(kappa, "kappa")?.into(),
            sensor_pose: match sensor_pose {
                Some(p) => Some(vec6(p, "sensor_pose")?.into()),
                None => None,
            },
            kappa_samples,
            camera_frames,
            ..ConfigurationData::default()
        };
        self.open()?
            .write_dwell(index, [window.0, window.1], &data)
            .map_err(exp_err)
    }

    /// Appends a metadata record `name` (string pairs) after the samples written so far, and flushes.
    #[pyo3(signature = (pairs, name="rss6"))]
    fn add_metadata(&self, pairs: BTreeMap<String, String>, name: &str) -> PyResult<()> {
        self.open()?.add_metadata(name, &pairs).map_err(exp_err)
    }

    /// Finishes the chunk in progress and hands everything to the OS; with `sync`, to the disk too.
    #[pyo3(signature = (sync=false))]
    fn flush(&self, sync: bool) -> PyResult<()> {
        self.open()?.flush(sync).map_err(exp_err)
    }

    /// Writes the summary and footer, after a metadata record `{status: status}` if given. Finishing
    /// twice does nothing.
    #[pyo3(signature = (status=None))]
    fn finish(&self, status: Option<&str>) -> PyResult<()> {
        let mut w = self.lock()?;
        if w.is_finished() {
            return Ok(());
        }
        w.finish(status).map_err(exp_err)
    }

    /// Messages written so far.
    #[getter]
    fn messages(&self) -> PyResult<u64> {
        Ok(self.lock()?.messages())
    }

    /// True once `finish` ran.
    #[getter]
    fn finished(&self) -> PyResult<bool> {
        Ok(self.lock()?.is_finished())
    }

    /// The file.
    #[getter]
    fn path(&self) -> PyResult<String> {
        Ok(self.lock()?.path().display().to_string())
    }

    fn __repr__(&self) -> PyResult<String> {
        let w = self.lock()?;
        Ok(format!(
            "LogWriter({}, {} messages)",
            w.path().display(),
            w.messages()
        ))
    }
}

/// Maps a reader [`LogError`] onto `rss6.LogError` / `CorruptLogError` / `TruncatedLogError`.
fn log_err(e: LogError) -> PyErr {
    let msg = e.to_string();
    match e {
        LogError::Io { path, .. } => make("LogError", msg, vec![("path", Attr::S(path))]),
        LogError::Corrupt { path, offset, .. } => make(
            "CorruptLogError",
            msg,
            vec![("path", Attr::S(path)), ("offset", Attr::I(offset as i64))],
        ),
        LogError::Truncated { path, .. } => make(
            "TruncatedLogError",
            msg,
            vec![
                ("path", Attr::S(path)),
                ("readable", Attr::I(0)),
                ("chunks", Attr::I(0)),
                ("messages", Attr::I(0)),
            ],
        ),
        _ => make("LogError", msg, vec![]),
    }
}

/// Reads a log written by rss6 (rss6-exp's reader). A file cut mid-run (no footer) is read up to its
/// last whole record (`complete` False). Returns a dict: streams {name: (times (N,) s, values (N, 6))},
/// dwells (list of dicts: index, window, theta_cmd, kappa, sensor_pose or None, kappa_samples,
/// camera_frames), metadata (the `rss6` records merged), records [(name, pairs)], complete, size,
/// readable (bytes of whole records), chunks, messages. Raises `rss6.LogError` (unreadable),
/// `rss6.CorruptLogError` (damaged, not MCAP) or `rss6.TruncatedLogError` (nothing usable). Releases
/// the GIL.
#[pyfunction]
pub(crate) fn read_log<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let log = py.detach(|| read(&path)).map_err(log_err)?;
    let streams = PyDict::new(py);
    for (name, (t, v)) in &log.streams {
        streams.set_item(name, (out1(py, t), out_rows6(py, v)))?;
    }
    let dwells = PyList::empty(py);
    for dw in &log.dwells {
        let d = PyDict::new(py);
        let c = &dw.data;
        d.set_item("index", dw.index)?;
        d.set_item("window", (dw.window[0], dw.window[1]))?;
        d.set_item("theta_cmd", out6(py, &Vec6::from(c.theta_cmd)))?;
        d.set_item("kappa", out6(py, &c.kappa_vec()))?;
        d.set_item("sensor_pose", c.sensor_pose_vec().map(|p| out6(py, &p)))?;
        d.set_item("kappa_samples", c.kappa_samples)?;
        d.set_item("camera_frames", c.camera_frames)?;
        d.set_item(
            "sensor_pose_cov",
            c.sensor_pose_cov
                .map(|m| crate::convert::out_rows::<6>(py, m.as_ref())),
        )?;
        d.set_item("defect", c.defect())?;
        dwells.append(d)?;
    }
    let d = PyDict::new(py);
    d.set_item("streams", streams)?;
    d.set_item("dwells", dwells)?;
    d.set_item("metadata", log.metadata.clone())?;
    d.set_item("records", log.records.clone())?;
    d.set_item("complete", log.complete)?;
    d.set_item("size", log.size)?;
    d.set_item("readable", log.readable)?;
    d.set_item("chunks", log.chunks)?;
    d.set_item("messages", log.messages)?;
    Ok(d)
}

/// Mean of poses (N, 6) [x, y, z, α, β, γ] (m, rad): the mean position and the rotation whose
/// quaternion maximises Σ (q · q_k)² (sign- and ±π-safe; rss6-exp's `mean_pose`, the mean of the
/// calibration dwells).
#[pyfunction]
pub(crate) fn mean_pose<'py>(
    py: Python<'py>,
    poses: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let p = rows6(poses, "poses")?;
    let m = rss6_exp::mean_pose(p.iter())
        .ok_or_else(|| shape("poses must have shape (N >= 1, 6), got (0, 6)"))?;
    Ok(out6(py, &m))
}
