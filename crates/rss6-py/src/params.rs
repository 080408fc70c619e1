//! `rss6.KinematicParams` and `rss6.DynamicParams`: dict and TOML round trips with the keys of docs/architecture.md.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use rss6_core::{DynamicParams, KinematicParams, LEGS, N_DYN, N_KIN_ERRORS};
use std::path::PathBuf;

use crate::convert::{exact, out1, out_rows, per_row, vecn};
use crate::errors::{core, invalid, make};

// The TOML layout and its conversions are rss6-sim's (one format for Rust and Python).
use rss6_sim::{
    BodiesFile, BodyFile, DynamicParamsFile as DynFile, KinematicParamsFile as KinFile,
};

/// Maps a parameter-file error of rss6-sim onto `rss6.ParamsFileError` (or the core error inside).
fn file_err(e: rss6_sim::SimError) -> PyErr {
    match e {
        rss6_sim::SimError::Core(c) => core(c),
        other => make("ParamsFileError", other.to_string(), vec![]),
    }
}

/// Looks up `key` in a dict, naming it when missing.
fn item<'py>(d: &Bound<'py, PyDict>, key: &str, what: &str) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?
        .ok_or_else(|| invalid(format!("{what} dict is missing key '{key}'")))
}

fn check_keys(d: &Bound<'_, PyDict>, allowed: &[&str], what: &str) -> PyResult<()> {
    for k in d.keys() {
        let k: String = k.extract()?;
        if !allowed.contains(&k.as_str()) {
            return Err(invalid(format!(
                "{what} dict has unknown key '{k}' (expected {})",
                allowed.join(", ")
            )));
        }
    }
    Ok(())
}

fn rows3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[[f64; 3]; LEGS]> {
    let d = exact(obj, name, &[LEGS, 3])?;
    let mut out = [[0.0; 3]; LEGS];
    for (i, r) in out.iter_mut().enumerate() {
        r.copy_from_slice(&d[3 * i..3 * i + 3]);
    }
    Ok(out)
}

const KIN_KEYS: [&str; 7] = [
    "base_joints",
    "platform_joints",
    "wrench_lengths",
    "link_lengths",
    "theta0",
    "eta",
    "dtheta",
];

/// Kinematic parameters of a 6-RSS robot (SI units; see `rss6_core::KinematicParams`).
#[pyclass(name = "KinematicParams", module = "rss6._rss6", frozen, eq)]
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PyKinematicParams {
    pub(crate) inner: KinematicParams,
}

impl PyKinematicParams {
    pub(crate) fn wrap(inner: KinematicParams) -> Self {
        PyKinematicParams { inner }
    }
}

#[pymethods]
impl PyKinematicParams {
    /// Builds parameters from arrays: base_joints (6, 3) B_i, platform_joints (6, 3) A'_i in ΣE,
    /// wrench_lengths, link_lengths, theta0, eta, dtheta (6 each). Validated.
    #[new]
    #[pyo3(signature = (base_joints, platform_joints, wrench_lengths, link_lengths, theta0, eta, dtheta))]
    fn py_new(
        base_joints: &Bound<'_, PyAny>,
        platform_joints: &Bound<'_, PyAny>,
        wrench_lengths: &Bound<'_, PyAny>,
        link_lengths: &Bound<'_, PyAny>,
        theta0: &Bound<'_, PyAny>,
        eta: &Bound<'_, PyAny>,
        dtheta: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let f = KinFile {
            base_joints: rows3(base_joints, "base_joints")?,
            platform_joints: rows3(platform_joints, "platform_joints")?,
            wrench_lengths: vecn(wrench_lengths, "wrench_lengths")?,
            link_lengths: vecn(link_lengths, "link_lengths")?,
            theta0: vecn(theta0, "theta0")?,
            eta: vecn(eta, "eta")?,
            dtheta: vecn(dtheta, "dtheta")?,
        };
        let kp = KinematicParams::from(&f);
        kp.validate().map_err(core)?;
        Ok(Self::wrap(kp))
    }

    /// The nominal robot (geometry of docs/kinematics.md, "The nominal geometry"; home χ = [0, 0, 0.115, 0, 0, 0] ↔ θ = 0).
    #[staticmethod]
    fn nominal() -> Self {
        Self::wrap(KinematicParams::nominal())
    }

    /// The nominal robot plus the 60 error parameters b (eq. 4.3 order: ΔA'(18), ΔB(18), Δl_AT(6),
    /// Δl_TB(6), Δη(6), Δθ(6)).
    #[staticmethod]
    fn perturbed(b: &Bound<'_, PyAny>) -> PyResult<Self> {
        let b = vecn::<N_KIN_ERRORS>(b, "b")?;
        Ok(Self::wrap(KinematicParams::perturbed(&b)))
    }

    /// These parameters with the 60 error parameters b added.
    fn with_errors(&self, b: &Bound<'_, PyAny>) -> PyResult<Self> {
        let b = vecn::<N_KIN_ERRORS>(b, "b")?;
        Ok(Self::wrap(self.inner.with_errors(&b)))
    }

    /// The error vector b (60,) with `self == reference.with_errors(b)`.
    fn errors_from<'py>(&self, py: Python<'py>, reference: &Self) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.errors_from(&reference.inner))
    }

    /// Raises `InvalidParameterError`/`NonFiniteError` unless every value is finite and lengths and
    /// gains are positive.
    fn validate(&self) -> PyResult<()> {
        self.inner.validate().map_err(core)
    }

    /// θ = η κ + Δθ (eq. 4.2): joint angles (rad) from potentiometer readings κ (bits), shape (6,),
    /// or (N, 6) with one reading per row (the same shape back).
    fn theta_from_reading<'py>(
        &self,
        py: Python<'py>,
        kappa: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        per_row(py, kappa, "kappa", |k| self.inner.theta_from_reading(k))
    }

    /// κ = (θ − Δθ)/η: potentiometer readings (bits) from joint angles θ (rad), shape (6,) or
    /// (N, 6).
    fn reading_from_theta<'py>(
        &self,
        py: Python<'py>,
        theta: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        per_row(py, theta, "theta", |t| self.inner.reading_from_theta(t))
    }

    /// B_i, shape (6, 3), m.
    #[getter]
    fn base_joints<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        out_rows::<3>(py, &KinFile::from(&self.inner).base_joints)
    }

    /// A'_i in ΣE, shape (6, 3), m.
    #[getter]
    fn platform_joints<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        out_rows::<3>(py, &KinFile::from(&self.inner).platform_joints)
    }

    /// l_TB,i (6,), m.
    #[getter]
    fn wrench_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.wrench_lengths)
    }

    /// l_AT,i (6,), m.
    #[getter]
    fn link_lengths<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.link_lengths)
    }

    /// θ0_i (6,), rad.
    #[getter]
    fn theta0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.theta0)
    }

    /// η_i (6,), rad/bit.
    #[getter]
    fn eta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.eta)
    }

    /// Δθ_i (6,), rad.
    #[getter]
    fn dtheta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.dtheta)
    }

    /// A dict of numpy arrays with the keys base_joints, platform_joints, wrench_lengths, link_lengths,
    /// theta0, eta, dtheta.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("base_joints", self.base_joints(py))?;
        d.set_item("platform_joints", self.platform_joints(py))?;
        d.set_item("wrench_lengths", self.wrench_lengths(py))?;
        d.set_item("link_lengths", self.link_lengths(py))?;
        d.set_item("theta0", self.theta0(py))?;
        d.set_item("eta", self.eta(py))?;
        d.set_item("dtheta", self.dtheta(py))?;
        Ok(d)
    }

    /// Inverse of `to_dict` (array-likes accepted; every key required, no others).
    #[classmethod]
    fn from_dict(_cls: &Bound<'_, PyType>, d: &Bound<'_, PyDict>) -> PyResult<Self> {
        check_keys(d, &KIN_KEYS, "KinematicParams")?;
        let w = "KinematicParams";
        Self::py_new(
            &item(d, "base_joints", w)?,
            &item(d, "platform_joints", w)?,
            &item(d, "wrench_lengths", w)?,
            &item(d, "link_lengths", w)?,
            &item(d, "theta0", w)?,
            &item(d, "eta", w)?,
            &item(d, "dtheta", w)?,
        )
    }

    /// Writes a TOML file with the `to_dict` keys (rss6-sim's parameter-file format).
    fn to_toml(&self, path: PathBuf) -> PyResult<()> {
        rss6_sim::save_kinematic_params(&path, &self.inner).map_err(file_err)
    }

    /// Reads a TOML file written by `to_toml` (validated).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        let kp = rss6_sim::load_kinematic_params(&path).map_err(file_err)?;
        kp.validate().map_err(core)?;
        Ok(Self::wrap(kp))
    }

    fn __repr__(&self) -> String {
        let nominal = KinematicParams::nominal();
        let b = self.inner.errors_from(&nominal);
        let norm = b.iter().map(|x| x * x).sum::<f64>().sqrt();
        format!("KinematicParams(|b - nominal| = {norm:.3e})")
    }
}

const DYN_KEYS: [&str; 5] = ["platform", "wrenches", "links", "coulomb", "viscous"];

/// Dynamic parameters Ξ of eq. 5.1 (SI units; see `rss6_core::DynamicParams`).
#[pyclass(name = "DynamicParams", module = "rss6._rss6", frozen, eq)]
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PyDynamicParams {
    pub(crate) inner: DynamicParams,
}

#[pymethods]
impl PyDynamicParams {
    /// Table 5.1 (manufacturer values), friction zero.
    #[staticmethod]
    fn nominal() -> Self {
        PyDynamicParams {
            inner: DynamicParams::nominal(),
        }
    }

    /// From Ξ (64,): [m, Ix, Iy, Iz] for platform, wrenches 1..6, links 1..6, then f_c (6), f_v (6).
    #[staticmethod]
    fn from_vector(x: &Bound<'_, PyAny>) -> PyResult<Self> {
        let x = vecn::<N_DYN>(x, "x")?;
        Ok(PyDynamicParams {
            inner: DynamicParams::from_vector(&x),
        })
    }

    /// Ξ (64,).
    fn to_vector<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.to_vector())
    }

    /// Raises unless masses are positive and inertias and friction non-negative.
    fn validate(&self) -> PyResult<()> {
        self.inner.validate().map_err(core)
    }

    /// Coulomb friction f_c (6,), N·m.
    #[getter]
    fn coulomb<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.coulomb)
    }

    /// Viscous friction f_v (6,), N·m·s/rad.
    #[getter]
    fn viscous<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        out1(py, &self.inner.viscous)
    }

    /// {"platform": {"mass", "inertia"(3,)}, "wrenches": {"mass"(6,), "inertia"(6, 3)}, "links": {...},
    /// "coulomb"(6,), "viscous"(6,)}.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = DynFile::from(&self.inner);
        let d = PyDict::new(py);
        let p = PyDict::new(py);
        p.set_item("mass", f.platform.mass)?;
        p.set_item("inertia", out1(py, &f.platform.inertia))?;
        d.set_item("platform", p)?;
        for (key, g) in [("wrenches", &f.wrenches), ("links", &f.links)] {
            let gd = PyDict::new(py);
            gd.set_item("mass", out1(py, &g.mass))?;
            gd.set_item("inertia", out_rows::<3>(py, &g.inertia))?;
            d.set_item(key, gd)?;
        }
        d.set_item("coulomb", out1(py, &f.coulomb))?;
        d.set_item("viscous", out1(py, &f.viscous))?;
        Ok(d)
    }

    /// Inverse of `to_dict`.
    #[classmethod]
    fn from_dict(_cls: &Bound<'_, PyType>, d: &Bound<'_, PyDict>) -> PyResult<Self> {
        let w = "DynamicParams";
        check_keys(d, &DYN_KEYS, w)?;
        let p = item(d, "platform", w)?;
        let p = p
            .cast::<PyDict>()
            .map_err(|_| invalid("DynamicParams['platform'] must be a dict"))?;
        check_keys(p, &["mass", "inertia"], "DynamicParams['platform']")?;
        let mass: f64 = item(p, "mass", "DynamicParams['platform']")?
            .extract()
            .map_err(|_| invalid("DynamicParams['platform']['mass'] must be a float"))?;
        let group = |key: &str| -> PyResult<BodiesFile> {
            let g = item(d, key, w)?;
            let g = g
                .cast::<PyDict>()
                .map_err(|_| invalid(format!("DynamicParams['{key}'] must be a dict")))?;
            let gw = format!("DynamicParams['{key}']");
            check_keys(g, &["mass", "inertia"], &gw)?;
            Ok(BodiesFile {
                mass: vecn(&item(g, "mass", &gw)?, &format!("{gw}['mass']"))?,
                inertia: rows3(&item(g, "inertia", &gw)?, &format!("{gw}['inertia']"))?,
            })
        };
        let f = DynFile {
            platform: BodyFile {
                mass,
                inertia: vecn(
                    &item(p, "inertia", "DynamicParams['platform']")?,
                    "DynamicParams['platform']['inertia']",
                )?,
            },
            wrenches: group("wrenches")?,
            links: group("links")?,
            coulomb: vecn(&item(d, "coulomb", w)?, "coulomb")?,
            viscous: vecn(&item(d, "viscous", w)?, "viscous")?,
        };
        let dp = DynamicParams::from(&f);
        dp.validate().map_err(core)?;
        Ok(PyDynamicParams { inner: dp })
    }

    /// Writes a TOML file with the `to_dict` layout.
    fn to_toml(&self, path: PathBuf) -> PyResult<()> {
        rss6_sim::save_dynamic_params(&path, &self.inner).map_err(file_err)
    }

    /// Reads a TOML file written by `to_toml` (validated).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, path: PathBuf) -> PyResult<Self> {
        let dp = rss6_sim::load_dynamic_params(&path).map_err(file_err)?;
        dp.validate().map_err(core)?;
        Ok(PyDynamicParams { inner: dp })
    }

    fn __repr__(&self) -> String {
        format!(
            "DynamicParams(platform mass {:.3} kg, wrench mass {:.3} kg, link mass {:.3} kg)",
            self.inner.platform.mass, self.inner.wrenches[0].mass, self.inner.links[0].mass
        )
    }
}
