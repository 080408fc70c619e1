//! numpy ⇄ nalgebra conversions with shape and finiteness checks that raise clear `rss6` errors.

use nalgebra::DMatrix;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::{Mat6, Vec6};

use crate::errors::{invalid, non_finite, shape};

/// Reads any array-like as a C-contiguous float64 array: (shape, data).
pub(crate) fn array(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<usize>, Vec<f64>)> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let kw = PyDict::new(py);
    kw.set_item("dtype", "float64")?;
    let arr = np
        .call_method("ascontiguousarray", (obj,), Some(&kw))
        .map_err(|e| invalid(format!("{name}: cannot be read as a float64 array ({e})")))?;
    let arr = arr
        .cast_into::<PyArrayDyn<f64>>()
        .map_err(|e| invalid(format!("{name}: cannot be read as a float64 array ({e})")))?;
    let ro = arr.readonly();
    let dims = ro.shape().to_vec();
    let data = ro
        .as_slice()
        .map_err(|e| invalid(format!("{name}: {e}")))?
        .to_vec();
    Ok((dims, data))
}

fn fmt_shape(s: &[usize]) -> String {
    match s.len() {
        1 => format!("({},)", s[0]),
        _ => format!(
            "({})",
            s.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Raises `NonFiniteError` naming the first bad element.
pub(crate) fn check_finite(data: &[f64], dims: &[usize], name: &str) -> PyResult<()> {
    if let Some(k) = data.iter().position(|x| !x.is_finite()) {
        let idx = if dims.len() == 2 && dims[1] > 0 {
            format!("[{}, {}]", k / dims[1], k % dims[1])
        } else {
            format!("[{k}]")
        };
        return Err(non_finite(format!(
            "{name} contains NaN or infinity at index {idx}"
        )));
    }
    Ok(())
}

/// A float64 array of exactly `want` shape, finite.
pub(crate) fn exact(obj: &Bound<'_, PyAny>, name: &str, want: &[usize]) -> PyResult<Vec<f64>> {
    let (dims, data) = array(obj, name)?;
    if dims != want {
        return Err(shape(format!(
            "{name} must have shape {}, got {}",
            fmt_shape(want),
            fmt_shape(&dims)
        )));
    }
    check_finite(&data, &dims, name)?;
    Ok(data)
}

/// A fixed-length finite vector.
pub(crate) fn vecn<const N: usize>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; N]> {
    let d = exact(obj, name, &[N])?;
    let mut out = [0.0; N];
    out.copy_from_slice(&d);
    Ok(out)
}

/// A pose χ or joint vector θ of shape (6,).
pub(crate) fn vec6(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec6> {
    Ok(Vec6::from(vecn::<6>(obj, name)?))
}

/// An (n, C) finite array as rows.
pub(crate) fn rows<const C: usize>(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<[f64; C]>> {
    let (dims, data) = array(obj, name)?;
    if dims.len() != 2 || dims[1] != C {
        return Err(shape(format!(
            "{name} must have shape (N, {C}), got {}",
            fmt_shape(&dims)
        )));
    }
    check_finite(&data, &dims, name)?;
    Ok(data
        .chunks_exact(C)
        .map(|c| {
            let mut r = [0.0; C];
            r.copy_from_slice(c);
            r
        })
        .collect())
}

/// A (6, 6) array as its rows.
pub(crate) fn mat6_rows(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[[f64; 6]; 6]> {
    let r = exact(obj, name, &[6, 6])?;
    Ok(std::array::from_fn(|i| {
        std::array::from_fn(|j| r[6 * i + j])
    }))
}

/// A covariance block made exactly symmetric, or `None` when it is not symmetric to rounding.
///
/// `np.cov` and products like `R C Rᵀ` give matrices whose mirrored entries differ in the last bits;
/// those are accepted (|c_rk − c_kr| ≤ 1e-12·max(|c_rr|, |c_kk|, |c_rk|)) and averaged, anything larger
/// is a caller's mistake and is refused by the caller with its own message.
pub(crate) fn symmetrised6(c: &[[f64; 6]; 6]) -> Option<[[f64; 6]; 6]> {
    const REL: f64 = 1e-12;
    let mut out = *c;
    for r in 0..6 {
        for k in (r + 1)..6 {
            let (a, b) = (c[r][k], c[k][r]);
            let scale = c[r][r].abs().max(c[k][k].abs()).max(a.abs()).max(b.abs());
            if (a - b).abs() > REL * scale || !(a + b).is_finite() {
                return None;
            }
            let m = 0.5 * (a + b);
            out[r][k] = m;
            out[k][r] = m;
        }
    }
    Some(out)
}

/// An (N, 6) array as poses/joint vectors.
pub(crate) fn rows6(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Vec6>> {
    Ok(rows::<6>(obj, name)?.into_iter().map(Vec6::from).collect())
}

/// `f` applied to a (6,) array, or to each row of an (N, 6) one: the same shape back (finite input
/// only; other shapes raise `ShapeError`).
pub(crate) fn per_row<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    name: &str,
    f: impl Fn(&Vec6) -> Vec6,
) -> PyResult<Bound<'py, PyAny>> {
    let (dims, data) = array(obj, name)?;
    match dims.as_slice() {
        [6] | [_, 6] => check_finite(&data, &dims, name)?,
        _ => {
            return Err(shape(format!(
                "{name} must have shape (6,) or (N, 6), got {}",
                fmt_shape(&dims)
            )))
        }
    }
    let out: Vec<Vec6> = data
        .chunks_exact(6)
        .map(|c| f(&Vec6::from_column_slice(c)))
        .collect();
    Ok(match (dims.len(), out.first()) {
        (1, Some(v)) => out6(py, v).into_any(),
        _ => out_rows6(py, &out).into_any(),
    })
}

/// A (6,) float64 numpy array.
pub(crate) fn out6<'py>(py: Python<'py>, v: &Vec6) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v.as_slice())
}

/// A 1-D float64 numpy array.
pub(crate) fn out1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A (rows.len(), C) float64 numpy array.
pub(crate) fn out_rows<'py, const C: usize>(
    py: Python<'py>,
    rows: &[[f64; C]],
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|r| r.iter().copied()).collect();
    // The shape matches the data length by construction.
    Array2::from_shape_vec((rows.len(), C), flat)
        .map(|a| a.into_pyarray(py))
        .unwrap_or_else(|_| PyArray2::zeros(py, (0, C), false))
}

/// An (r, c) float64 numpy array of a matrix (row-major copy).
pub(crate) fn out_dmatrix<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// An (N, 6) array from poses/joint vectors.
pub(crate) fn out_rows6<'py>(py: Python<'py>, v: &[Vec6]) -> Bound<'py, PyArray2<f64>> {
    let r: Vec<[f64; 6]> = v
        .iter()
        .map(|x| [x[0], x[1], x[2], x[3], x[4], x[5]])
        .collect();
    out_rows::<6>(py, &r)
}

/// A (6, 6) matrix, row-major.
pub(crate) fn out_mat6<'py>(py: Python<'py>, m: &Mat6) -> Bound<'py, PyArray2<f64>> {
    let r: Vec<[f64; 6]> = (0..6)
        .map(|i| {
            [
                m[(i, 0)],
                m[(i, 1)],
                m[(i, 2)],
                m[(i, 3)],
                m[(i, 4)],
                m[(i, 5)],
            ]
        })
        .collect();
    out_rows::<6>(py, &r)
}

/// A seed given from Python as any int: `rss6.InvalidInputError` outside [0, 2⁶⁴ − 1] (PyO3's own
/// `u64` extraction raises an `OverflowError` that names neither the argument nor the range).
pub(crate) fn seed(s: i128) -> PyResult<u64> {
    u64::try_from(s).map_err(|_| {
        invalid(format!(
            "seed must be an integer in [0, 2**64 - 1], got {s}"
        ))
    })
}

/// A count or size given from Python as any int: `rss6.InvalidInputError` naming the argument when
/// it does not fit `T` (PyO3's own unsigned extraction raises a bare `OverflowError`).
pub(crate) fn count<T: TryFrom<i64>>(v: i64, name: &str) -> PyResult<T> {
    T::try_from(v).map_err(|_| {
        invalid(format!(
            "{name} must be an integer >= 0 (and in range), got {v}"
        ))
    })
}
