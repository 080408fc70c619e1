//! Kinematics bindings: `ik`, `ik_batch`, `fk`, `fk_batch`, Jacobians, `home_pose`.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use rss6_core::{FkOptions, KinematicParams, Vec6};

use crate::convert::{out6, out_rows6, rows6, vec6};
use crate::errors::{core, core_at, invalid};
use crate::params::PyKinematicParams;

/// The FK method selected by name.
#[derive(Debug, Clone, Copy)]
enum FkMethod {
    QuasiStewart,
    ThetaNewton,
}

fn fk_method(name: &str) -> PyResult<FkMethod> {
    match name {
        "quasi_stewart" => Ok(FkMethod::QuasiStewart),
        "theta_newton" => Ok(FkMethod::ThetaNewton),
        other => Err(invalid(format!(
            "method must be 'quasi_stewart' or 'theta_newton', got '{other}'"
        ))),
    }
}

fn fk_options(max_iterations: u32, tol: f64) -> PyResult<FkOptions> {
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(invalid(format!("tol must be finite and >= 0, got {tol}")));
    }
    Ok(FkOptions {
        eps_c: tol,
        eps_p: tol,
        max_iterations,
    })
}

fn fk_one(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    opts: &FkOptions,
    m: FkMethod,
) -> rss6_core::Result<Vec6> {
    let sol = match m {
        FkMethod::QuasiStewart => rss6_core::fk(kp, theta, guess, opts)?,
        FkMethod::ThetaNewton => rss6_core::fk_theta_newton(kp, theta, guess, opts)?,
    };
    Ok(sol.pose)
}

/// Home pose χ = [0, 0, 0.115, 0, 0, 0] (m, rad).
#[pyfunction]
pub(crate) fn home_pose(py: Python<'_>) -> Bound<'_, PyArray1<f64>> {
    out6(py, &rss6_core::home_pose())
}

vec6_fn!(
    /// Inverse kinematics θ = H_inv(χ) (eq. 3.3–3.16): joint angles (6,) rad for pose (6,) [m, rad].
    /// Raises UnreachableError (a ValueError) naming the leg.
    fn ik(kp: &PyKinematicParams; pose) -> PyArray1 via out6 = rss6_core::ik(&kp.inner, &pose)
);

/// IK of every row of poses (N, 6) → thetas (N, 6). Releases the GIL. An error names the row.
#[pyfunction]
pub(crate) fn ik_batch<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    poses: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let poses = rows6(poses, "poses")?;
    let k = kp.inner;
    let out = py.detach(move || {
        poses
            .iter()
            .enumerate()
            .map(|(i, p)| rss6_core::ik(&k, p).map_err(|e| (i, e)))
            .collect::<Result<Vec<_>, _>>()
    });
    let out = out.map_err(|(i, e)| core_at(e, Some(format!("poses row {i}"))))?;
    Ok(out_rows6(py, &out))
}

/// Forward kinematics χ = H_fwd(θ) (§3.4) from joint angles (6,) rad, starting at `guess` (default: home).
/// method "quasi_stewart" (the thesis's) or "theta_newton" (Fig. 3.2's "normal" method).
/// Raises NotConvergedError after `max_iterations`.
#[pyfunction]
#[pyo3(signature = (kp, theta, guess=None, *, max_iterations=30, tol=1e-13, method="quasi_stewart"))]
pub(crate) fn fk<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    theta: &Bound<'py, PyAny>,
    guess: Option<&Bound<'py, PyAny>>,
    max_iterations: i64,
    tol: f64,
    method: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let max_iterations: u32 = crate::convert::count(max_iterations, "max_iterations")?;
    let theta = vec6(theta, "theta")?;
    let guess = match guess {
        Some(g) => vec6(g, "guess")?,
        None => rss6_core::home_pose(),
    };
    let opts = fk_options(max_iterations, tol)?;
    let pose = fk_one(&kp.inner, &theta, &guess, &opts, fk_method(method)?).map_err(core)?;
    Ok(out6(py, &pose))
}

/// FK of every row of thetas (N, 6) → poses (N, 6); each solve warm-starts from the previous solution
/// (the first from `guess`, default home). Releases the GIL. An error names the row.
#[pyfunction]
#[pyo3(signature = (kp, thetas, guess=None, *, max_iterations=30, tol=1e-13, method="quasi_stewart"))]
pub(crate) fn fk_batch<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    thetas: &Bound<'py, PyAny>,
    guess: Option<&Bound<'py, PyAny>>,
    max_iterations: i64,
    tol: f64,
    method: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let max_iterations: u32 = crate::convert::count(max_iterations, "max_iterations")?;
    let thetas = rows6(thetas, "thetas")?;
    let mut g = match guess {
        Some(g) => vec6(g, "guess")?,
        None => rss6_core::home_pose(),
    };
    let opts = fk_options(max_iterations, tol)?;
    let m = fk_method(method)?;
    let k = kp.inner;
    let out = py.detach(move || {
        let mut out = Vec::with_capacity(thetas.len());
        for (i, th) in thetas.iter().enumerate() {
            let p = fk_one(&k, th, &g, &opts, m).map_err(|e| (i, e))?;
            out.push(p);
            g = p;
        }
        Ok::<_, (usize, rss6_core::CoreError)>(out)
    });
    let out = out.map_err(|(i, e)| core_at(e, Some(format!("thetas row {i}"))))?;
    Ok(out_rows6(py, &out))
}

vec6_fn!(
    /// J_θ (6, 6) at pose (eq. 5.3): θ̇ = J_θ χ̇.
    fn jacobian_theta(kp: &PyKinematicParams; pose) -> PyArray2 via out_mat6 =
        rss6_core::jacobian_theta(&kp.inner, &pose)
);

vec6_fn!(
    /// J_ad (6, 6) at pose (eq. 3.30): θ̇ = J_ad [Ė; ω].
    fn jacobian_ad(kp: &PyKinematicParams; pose) -> PyArray2 via out_mat6 =
        rss6_core::jacobian_ad(&kp.inner, &pose)
);
