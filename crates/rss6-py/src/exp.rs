//! What every binding of an rss6-exp runner shares: the error mapping of [`ExpError`], Python
//! callbacks and Ctrl-C inside a run with the GIL released ([`Interrupt`]), and the run's log
//! ([`create_log`], [`finish_log`]).

use std::collections::BTreeMap;
use std::path::Path;

use pyo3::prelude::*;
use rss6_exp::log::{LogObserver, LogWriter, DEFAULT_CHUNK_SIZE};
use rss6_exp::{ExpError, Flow};

use crate::ctrl::ctrl_err;
use crate::errors::{core, invalid, make, Attr};
use crate::plant::sim_error;

/// Maps an [`ExpError`] onto its exception class.
pub(crate) fn exp_err(e: ExpError) -> PyErr {
    let msg = e.to_string();
    match e {
        ExpError::InvalidInput(m) => invalid(m),
        ExpError::Sim(s) => sim_error(s),
        ExpError::Ctrl(c) => ctrl_err(c),
        ExpError::Core(c) => core(c),
        ExpError::Robot(_) => make("SimulationError", msg, vec![]),
        ExpError::Io { path, source } => make(
            "LogError",
            format!("cannot write {path}: {source}"),
            vec![("path", Attr::S(path.clone()))],
        ),
        ExpError::Mcap(_) => make("LogError", msg, vec![]),
        ExpError::CorruptLog { path, .. } => {
            make("CorruptLogError", msg, vec![("path", Attr::S(path))])
        }
        _ => make("Rss6Error", msg, vec![]),
    }
}

/// Python callbacks and Ctrl-C inside a run that released the GIL: the first exception raised (a
/// callback's, or KeyboardInterrupt from a signal) is kept and stops the run; the binding raises it
/// once the runner returned.
#[derive(Default)]
pub(crate) struct Interrupt {
    error: Option<PyErr>,
}

impl Interrupt {
    /// Checks for Ctrl-C, then runs `f`, with the GIL. [`Flow::Stop`] once anything raised.
    pub(crate) fn call(&mut self, f: impl FnOnce(Python<'_>) -> PyResult<()>) -> Flow {
        if self.error.is_some() {
            return Flow::Stop;
        }
        match Python::attach(|py| py.check_signals().and_then(|()| f(py))) {
            Ok(()) => Flow::Continue,
            Err(e) => {
                self.error = Some(e);
                Flow::Stop
            }
        }
    }

    /// The exception that stopped the run, if any.
    pub(crate) fn take(&mut self) -> Option<PyErr> {
        self.error.take()
    }
}

/// A log at `path` (created or truncated) with the metadata record `rss6` = `pairs`.
pub(crate) fn create_log(path: &Path, pairs: &[(&str, String)]) -> PyResult<LogObserver> {
    let mut w = LogWriter::create(path, DEFAULT_CHUNK_SIZE, 0.0).map_err(exp_err)?;
    let md: BTreeMap<String, String> = pairs
        .iter()
        .map(|(k, v)| ((*k).to_string(), v.clone()))
        .collect();
    w.add_metadata("rss6", &md).map_err(exp_err)?;
    Ok(LogObserver::new(w))
}

/// "TypeName: message" of a Python exception (the status a failed run's log ends with).
fn describe(py: Python<'_>, e: &PyErr) -> String {
    let name = e
        .get_type(py)
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "Exception".into());
    let text = e.value(py).str().map(|s| s.to_string()).unwrap_or_default();
    format!("{name}: {text}")
}

/// Ends a run: finishes its log (the metadata `end`, then status "finished", or "failed: …") and
/// returns the run's value, or the first of: the exception raised inside the run (`raised`), the
/// log's write error, the runner's error, the error finishing the log.
pub(crate) fn finish_log<T>(
    py: Python<'_>,
    log: Option<LogObserver>,
    outcome: Result<T, ExpError>,
    raised: Option<PyErr>,
    end: &[(&str, String)],
) -> PyResult<T> {
    let log_error = log
        .as_ref()
        .and_then(|l| l.error())
        .map(|e| exp_err(ExpError::Mcap(e.to_string())));
    let (value, run_error) = match outcome {
        Ok(v) => (Some(v), None),
        Err(e) => (None, Some(exp_err(e))),
    };
    let failure = raised.or(log_error).or(run_error);
    let finished = match log {
        Some(mut l) => {
            let status = match &failure {
                None => "finished".to_string(),
                Some(e) => format!("failed: {}", describe(py, e)),
            };
            let end: BTreeMap<String, String> = end
                .iter()
                .map(|(k, v)| ((*k).to_string(), v.clone()))
                .collect();
            py.detach(|| {
                if !end.is_empty() {
                    l.writer.add_metadata("rss6", &end)?;
                }
                l.writer.finish(Some(&status))
            })
        }
        None => Ok(()),
    };
    if let Some(e) = failure {
        return Err(e);
    }
    finished.map_err(exp_err)?;
    value.ok_or_else(|| invalid("the run returned no value"))
}
