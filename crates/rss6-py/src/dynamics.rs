//! Dynamics bindings (thesis eq. 6.1–6.4, 5.1, 5.14): M̃, C̃, G̃, τ̃_f, inverse/forward dynamics,
//! the regressor Γ and one RK4 step. Optional `g` is the gravity vector (m/s², base frame).

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::{ModelState, Vec3, GRAVITY, N_DYN};

use crate::convert::{out6, out_mat6, out_rows, vec6, vecn};
use crate::errors::{core, invalid};
use crate::params::{PyDynamicParams, PyKinematicParams};

/// Two (6,) arrays.
type Pair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// The gravity vector argument `g` (3,) m/s², default `GRAVITY`.
pub(crate) fn grav(g: Option<&Bound<'_, PyAny>>) -> PyResult<Vec3> {
    match g {
        Some(g) => Ok(Vec3::from(vecn::<3>(g, "g")?)),
        None => Ok(GRAVITY),
    }
}

vec6_fn!(
    /// Mass matrix M̃(χ) (6, 6) in χ coordinates (eq. 6.2).
    fn mass_matrix(kp: &PyKinematicParams, dp: &PyDynamicParams; pose) -> PyArray2 via out_mat6 =
        rss6_core::mass_matrix(&kp.inner, &dp.inner, &pose)
);

vec6_fn!(
    /// Coriolis/centrifugal matrix C̃(χ, χ̇) (6, 6) (eq. 6.2); the velocity force is C̃ χ̇.
    fn coriolis(kp: &PyKinematicParams, dp: &PyDynamicParams; pose, pose_dot) -> PyArray2
        via out_mat6 = rss6_core::coriolis(&kp.inner, &dp.inner, &pose, &pose_dot)
);

vec6_fn!(
    /// Gravity vector G̃(χ) (6,) (eq. 6.2), N and N·m.
    fn gravity(kp: &PyKinematicParams, dp: &PyDynamicParams; pose; g) -> PyArray1 via out6 =
        rss6_core::gravity_with(&kp.inner, &dp.inner, &pose, &g)
);

vec6_fn!(
    /// Joint friction mapped to χ coordinates τ̃_f(χ, χ̇) (6,) (eq. 6.4).
    fn friction(kp: &PyKinematicParams, dp: &PyDynamicParams; pose, pose_dot) -> PyArray1
        via out6 = rss6_core::friction(&kp.inner, &dp.inner, &pose, &pose_dot)
);

vec6_fn!(
    /// Actuator torques τ_a (6,) N·m for the motion (χ, χ̇, χ̈) (eq. 6.1–6.4).
    fn inverse_dynamics(kp: &PyKinematicParams, dp: &PyDynamicParams; pose, pose_dot, pose_ddot; g)
        -> PyArray1 via out6 = rss6_core::inverse_dynamics_with_gravity(
            &kp.inner, &dp.inner, &pose, &pose_dot, &pose_ddot, &g,
        )
);

vec6_fn!(
    /// Forward dynamics χ̈ (6,) from (χ, χ̇) and actuator torques τ_a (eq. 5.14).
    fn forward_dynamics(kp: &PyKinematicParams, dp: &PyDynamicParams; pose, pose_dot, tau_a; g)
        -> PyArray1 via out6 = rss6_core::forward_dynamics_with_gravity(
            &kp.inner, &dp.inner, &pose, &pose_dot, &tau_a, &g,
        )
);

/// Regressor Γ (6, 64) with τ_a = Γ·Ξ (actuator-torque form of eq. 5.1).
#[pyfunction]
#[pyo3(signature = (kp, pose, pose_dot, pose_ddot, *, g=None))]
pub(crate) fn regressor<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    pose: &Bound<'py, PyAny>,
    pose_dot: &Bound<'py, PyAny>,
    pose_ddot: &Bound<'py, PyAny>,
    g: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let p = vec6(pose, "pose")?;
    let pd = vec6(pose_dot, "pose_dot")?;
    let pdd = vec6(pose_ddot, "pose_ddot")?;
    let g = grav(g)?;
    let r = rss6_core::regressor_with_gravity(&kp.inner, &p, &pd, &pdd, &g).map_err(core)?;
    let rows: Vec<[f64; N_DYN]> = (0..6)
        .map(|i| {
            let mut row = [0.0; N_DYN];
            for (j, x) in row.iter_mut().enumerate() {
                *x = r[(i, j)];
            }
            row
        })
        .collect();
    Ok(out_rows::<N_DYN>(py, &rows))
}

/// Every term of eq. 6.1–6.4 at (χ, χ̇): dict with m, c (6, 6), g, f (6,), j_ad, j_s, j_theta (6, 6).
#[pyfunction]
pub(crate) fn dynamics_terms<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    dp: &PyDynamicParams,
    pose: &Bound<'py, PyAny>,
    pose_dot: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = vec6(pose, "pose")?;
    let pd = vec6(pose_dot, "pose_dot")?;
    let t = rss6_core::dynamics_terms(&kp.inner, &dp.inner, &p, &pd).map_err(core)?;
    let d = PyDict::new(py);
    d.set_item("m", out_mat6(py, &t.m))?;
    d.set_item("c", out_mat6(py, &t.c))?;
    d.set_item("g", out6(py, &t.g))?;
    d.set_item("f", out6(py, &t.f))?;
    d.set_item("j_ad", out_mat6(py, &t.j_ad))?;
    d.set_item("j_s", out_mat6(py, &t.j_s))?;
    d.set_item("j_theta", out_mat6(py, &t.j_theta))?;
    Ok(d)
}

/// One RK4 step of length dt (s) of the forward dynamics with τ_a held: returns (pose, pose_dot).
#[pyfunction]
#[pyo3(signature = (kp, dp, pose, pose_dot, tau_a, dt, *, g=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn rk4_step<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    dp: &PyDynamicParams,
    pose: &Bound<'py, PyAny>,
    pose_dot: &Bound<'py, PyAny>,
    tau_a: &Bound<'py, PyAny>,
    dt: f64,
    g: Option<&Bound<'py, PyAny>>,
) -> PyResult<Pair<'py>> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(invalid(format!("dt must be finite and > 0, got {dt}")));
    }
    let state = ModelState {
        pose: vec6(pose, "pose")?,
        pose_dot: vec6(pose_dot, "pose_dot")?,
    };
    let tau = vec6(tau_a, "tau_a")?;
    let g = grav(g)?;
    let s = rss6_core::rk4_step_with_gravity(&kp.inner, &dp.inner, &state, &tau, dt, &g)
        .map_err(core)?;
    Ok((out6(py, &s.pose), out6(py, &s.pose_dot)))
}
