//! Mapping of the Rust error enums onto the Python exception hierarchy of `rss6.errors`.
//!
//! The exception classes are defined in pure Python (`python/rss6/errors.py`) so that
//! `UnreachableError` can derive from both `Rss6Error` and `ValueError`; they are looked up here by name
//! when an error is raised. The fields of each Rust variant become attributes of the exception.

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rss6_core::{CoreError, SingularKind};

/// An attribute value set on a raised exception.
pub(crate) enum Attr {
    /// A float attribute.
    F(f64),
    /// An integer attribute.
    I(i64),
    /// A string attribute.
    S(String),
    /// A list-of-integers attribute.
    IL(Vec<i64>),
    /// A list-of-floats attribute.
    FL(Vec<f64>),
    /// A list-of-strings attribute.
    SL(Vec<String>),
}

/// Builds an instance of `rss6.errors.<class>` with `msg` and the given attributes.
pub(crate) fn make(class: &str, msg: impl Into<String>, attrs: Vec<(&'static str, Attr)>) -> PyErr {
    let msg = msg.into();
    Python::attach(|py| {
        let build = || -> PyResult<PyErr> {
            let cls = py.import("rss6.errors")?.getattr(class)?;
            let exc = cls.call1((msg.clone(),))?;
            for (k, v) in attrs {
                match v {
                    Attr::F(x) => exc.setattr(k, x)?,
                    Attr::I(x) => exc.setattr(k, x)?,
                    Attr::S(x) => exc.setattr(k, x)?,
                    Attr::IL(x) => exc.setattr(k, x)?,
                    Attr::FL(x) => exc.setattr(k, x)?,
                    Attr::SL(x) => exc.setattr(k, x)?,
                }
            }
            Ok(PyErr::from_value(exc))
        };
        build().unwrap_or_else(|e| {
            PyRuntimeError::new_err(format!("{msg} (and rss6.errors failed: {e})"))
        })
    })
}

/// `rss6.InvalidInputError` (a `ValueError`).
pub(crate) fn invalid(msg: impl Into<String>) -> PyErr {
    make("InvalidInputError", msg, vec![])
}

/// `rss6.ShapeError` (a `ValueError`).
pub(crate) fn shape(msg: impl Into<String>) -> PyErr {
    make("ShapeError", msg, vec![])
}

/// `rss6.NonFiniteError` (a `ValueError`).
pub(crate) fn non_finite(msg: impl Into<String>) -> PyErr {
    make("NonFiniteError", msg, vec![])
}

/// Maps a [`CoreError`] onto its exception class; `context` (e.g. "row 3") prefixes the message.
pub(crate) fn core_at(e: CoreError, context: Option<String>) -> PyErr {
    let text = match &context {
        Some(c) => format!("{c}: {e}"),
        None => e.to_string(),
    };
    match e {
        CoreError::NonFinite => non_finite(text),
        CoreError::Unreachable { leg, excess } => make(
            "UnreachableError",
            text,
            vec![
                ("leg", Attr::I(i64::from(leg) + 1)),
                ("excess", Attr::F(excess)),
            ],
        ),
        CoreError::OutOfBranch { leg, theta } => make(
            "OutOfBranchError",
            text,
            vec![
                ("leg", Attr::I(i64::from(leg) + 1)),
                ("theta", Attr::F(theta)),
            ],
        ),
        CoreError::NotConverged {
            iterations,
            residual,
        } => make(
            "NotConvergedError",
            text,
            vec![
                ("iterations", Attr::I(i64::from(iterations))),
                ("residual", Attr::F(residual)),
            ],
        ),
        CoreError::Singular(kind) => {
            let k = match kind {
                SingularKind::TypeI => "TypeI",
                SingularKind::TypeII => "TypeII",
                SingularKind::StewartJacobian => "StewartJacobian",
                SingularKind::Euler => "Euler",
                SingularKind::Matrix => "Matrix",
                _ => "Other",
            };
            make(
                "SingularError",
                text,
                vec![("kind", Attr::S(k.to_string()))],
            )
        }
        CoreError::InvalidParameter(_) => make("InvalidParameterError", text, vec![]),
        _ => make("Rss6Error", text, vec![]),
    }
}

/// Maps a [`CoreError`] onto its exception class.
pub(crate) fn core(e: CoreError) -> PyErr {
    core_at(e, None)
}
