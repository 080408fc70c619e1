//! Python bindings (issue 7). Work in progress.
use pyo3::prelude::*;

/// The compiled part of the `rss6` package.
#[pymodule]
fn _rss6(_m: &Bound<'_, PyModule>) -> PyResult<()> {
    Ok(())
}
