//! The least-squares problem of each method: residuals Φ and their Jacobian at a parameter vector.

use super::noise::{implicit_whitening, rpba_whitening, NoiseInput, Whitening};
use super::options::{CalibrationOptions, JacobianMode};
use crate::closure::{fk_reading, fk_with_derivative, leg_closure, FkDerivative, Mat6x60};
use crate::data::CalibrationData;
use crate::error::Method;
use crate::model::Layout;
use crate::se3::{adjoint, iso, pose_delta_from_twist, pose_difference, twist_from_pose_delta};
use nalgebra::{DMatrix, DVector};
use rss6_core::{home_pose, isometry_to_pose, CoreError, Mat6, SingularKind, Vec6, N_KIN_ERRORS};

pub(super) struct Problem {
    layout: Layout,
    /// Readings and sensor poses of the usable configurations (RPBA: index 0 = reference).
    kappa: Vec<Vec6>,
    cam: Vec<Vec6>,
    /// RPBA: measured relative poses L(ᶜM_t⁰⁻¹ᶜM_t^l) for l ≥ 1.
    rel: Vec<Vec6>,
    guesses: Vec<Vec6>,
    pose_weights: Vec6,
    leg_weight: f64,
    /// Noise whitening of the residuals ([`Problem::weigh_by_noise`]); replaces the fixed weights.
    white: Option<Whitening>,
    /// RPBA: the FK derivatives of the last evaluation with a Jacobian (reused by the noise model).
    last_fk: Vec<FkDerivative>,
}

/// A failed evaluation: the (usable-list) index of the configuration and the kinematics error.
pub(super) type EvalError = (usize, CoreError);

impl Problem {
    /// The problem of the configurations (`kappa`, `cam`) with the fixed weights of `opts`.
    pub(super) fn new(
        layout: Layout,
        kappa: Vec<Vec6>,
        cam: Vec<Vec6>,
        opts: &CalibrationOptions,
    ) -> Self {
        let rel = match layout.method {
            Method::Rpba => {
                let c0_inv = iso(&cam[0]).inverse();
                cam.iter()
                    .map(|c| isometry_to_pose(&(c0_inv * iso(c))))
                    .collect()
            }
            Method::Implicit => Vec::new(),
        };
        let m = kappa.len();
        Problem {
            layout,
            kappa,
            cam,
            rel,
            guesses: vec![home_pose(); m],
            pose_weights: Vec6::from(opts.pose_weights),
            leg_weight: opts.leg_weight,
            white: None,
            last_fk: Vec::new(),
        }
    }

    /// Weighs the residuals by the inverse square root of their covariance under `noise`, evaluated at
    /// `x` (call after an evaluation at `x`, so the FK warm starts are there); `counts` are the samples
    /// averaged (κ, camera) per configuration. `false` if the covariance is not positive definite.
    pub(super) fn weigh_by_noise(
        &mut self,
        x: &DVector<f64>,
        noise: &super::MeasurementNoise,
        counts: &[(f64, f64)],
    ) -> bool {
        let kp = self.layout.kp(x);
        let input = NoiseInput {
            kp: &kp,
            sensor: self.layout.sensor(x).unwrap_or_else(home_pose),
            target: self.layout.target(x),
            kappa: &self.kappa,
            cam: &self.cam,
            guesses: &self.guesses,
            fk: (self.last_fk.len() == self.kappa.len()).then_some(self.last_fk.as_slice()),
            counts,
        };
        let white = match self.layout.method {
            Method::Rpba => rpba_whitening(&input, noise),
            Method::Implicit => implicit_whitening(&input, noise),
        };
        self.pose_weights = Vec6::repeat(1.0);
        self.leg_weight = 1.0;
        self.white = white;
        self.white.is_some()
    }

    /// Applies the noise weighting to residuals and a Jacobian evaluated before it was set.
    pub(super) fn whiten(&self, r: &mut DVector<f64>, j: &mut DMatrix<f64>) {
        if let Some(w) = &self.white {
            w.vector(r);
            w.matrix(j);
        }
    }

    /// Per residual block (RPBA: configurations 1.., implicit: all), r_lᵀΣ_ll⁻¹r_l / 6 of the raw
    /// residual; `None` without noise weighting.
    pub(super) fn normalized_blocks(&self, raw: &DVector<f64>) -> Option<Vec<f64>> {
        self.white.as_ref().map(|w| w.normalized_blocks(raw))
    }

    /// Index in the usable list of the configuration of residual block `k`.
    pub(super) fn block_configuration(&self, k: usize) -> usize {
        match self.layout.method {
            Method::Rpba => k + 1,
            Method::Implicit => k,
        }
    }

    pub(super) fn n_res(&self) -> usize {
        match self.layout.method {
            Method::Rpba => 6 * (self.kappa.len() - 1),
            Method::Implicit => 6 * self.kappa.len(),
        }
    }

    /// Weighted residuals (and Jacobian if `jac`) at `x`, with the raw residual kept.
    pub(super) fn eval(
        &mut self,
        x: &DVector<f64>,
        jac: bool,
    ) -> core::result::Result<Eval, EvalError> {
        let mut e = match self.layout.method {
            Method::Rpba => self.eval_rpba(x, jac)?,
            Method::Implicit => self.eval_implicit(x, jac),
        };
        if let Some(w) = &self.white {
            e.raw = Some(e.r.clone());
            w.vector(&mut e.r);
            if let Some(j) = e.j.as_mut() {
                w.matrix(j);
            }
        }
        Ok(e)
    }

    fn eval_rpba(&mut self, x: &DVector<f64>, jac: bool) -> core::result::Result<Eval, EvalError> {
        let kp = self.layout.kp(x);
        let t = self.layout.target(x);
        let mt = iso(&t);
        let m = self.kappa.len();
        let mut fks = Vec::with_capacity(m);
        for l in 0..m {
            let f = if jac {
                fk_with_derivative(&kp, &self.kappa[l], &self.guesses[l])
            } else {
                fk_reading(&kp, &self.kappa[l], &self.guesses[l]).map(|pose| FkDerivative {
                    pose,
                    d_b: Mat6x60::zeros(),
                })
            }
            .map_err(|e| (l, e))?;
            fks.push(f);
        }
        for (g, f) in self.guesses.iter_mut().zip(&fks) {
            *g = f.pose;
        }
        let n = self.layout.n();
        let mut r = DVector::zeros(self.n_res());
        let mut j = if jac {
            Some(DMatrix::zeros(self.n_res(), n))
        } else {
            None
        };
        let x0_inv = (iso(&fks[0].pose) * mt).inverse();
        let ad_x0_inv = adjoint(&x0_inv);
        let ad_mt_inv = adjoint(&mt.inverse());
        let e0 = twist_from_pose_delta(&fks[0].pose);
        let xi0 = e0 * fks[0].d_b;
        let et = twist_from_pose_delta(&t);
        for (l, fk_l) in fks.iter().enumerate().skip(1) {
            let p = x0_inv * iso(&fk_l.pose) * mt;
            let pp = isometry_to_pose(&p);
            let w = self.pose_weights;
            let res = pose_difference(&self.rel[l], &pp).component_mul(&w);
            r.rows_mut(6 * (l - 1), 6).copy_from(&res);
            if let Some(j) = j.as_mut() {
                let d = pose_delta_from_twist(&pp)
                    .ok_or((l, CoreError::Singular(SingularKind::Euler)))?;
                let wd = Mat6::from_diagonal(&w) * d;
                let xi_b = ad_x0_inv * (twist_from_pose_delta(&fk_l.pose) * fk_l.d_b - xi0);
                let xi_t = (adjoint(&p) - Mat6::identity()) * ad_mt_inv * et;
                j.view_mut((6 * (l - 1), 0), (6, N_KIN_ERRORS))
                    .copy_from(&(-(wd * xi_b)));
                j.view_mut((6 * (l - 1), self.layout.target_offset()), (6, 6))
                    .copy_from(&(-(wd * xi_t)));
            }
        }
        if jac {
            self.last_fk = fks;
        }
        Ok(Eval { r, j, raw: None })
    }

    fn eval_implicit(&mut self, x: &DVector<f64>, jac: bool) -> Eval {
        let kp = self.layout.kp(x);
        let t = self.layout.target(x);
        let s = self.layout.sensor(x).unwrap_or_else(home_pose);
        let m_oc = iso(&s);
        let mt_inv = iso(&t).inverse();
        let es = twist_from_pose_delta(&s);
        let et = twist_from_pose_delta(&t);
        let w = self.leg_weight;
        let n = self.layout.n();
        let mut r = DVector::zeros(self.n_res());
        let mut j = if jac {
            Some(DMatrix::zeros(self.n_res(), n))
        } else {
            None
        };
        for l in 0..self.kappa.len() {
            let m_oe = m_oc * iso(&self.cam[l]) * mt_inv;
            let c = leg_closure(&kp, &self.kappa[l], &m_oe);
            r.rows_mut(6 * l, 6).copy_from(&(c.phi * w));
            if let Some(j) = j.as_mut() {
                j.view_mut((6 * l, 0), (6, N_KIN_ERRORS))
                    .copy_from(&(c.d_b * w));
                if let Some(o) = self.layout.sensor_offset() {
                    j.view_mut((6 * l, o), (6, 6)).copy_from(&(c.d_xi * es * w));
                }
                j.view_mut((6 * l, self.layout.target_offset()), (6, 6))
                    .copy_from(&(c.d_xi * (-adjoint(&m_oe)) * et * w));
            }
        }
        Eval { r, j, raw: None }
    }

    /// Residuals and Jacobian with the requested Jacobian mode.
    pub(super) fn eval_full(
        &mut self,
        x: &DVector<f64>,
        mode: JacobianMode,
    ) -> core::result::Result<(DVector<f64>, DMatrix<f64>), EvalError> {
        match mode {
            JacobianMode::Analytic => {
                let e = self.eval(x, true)?;
                let j = e.j.unwrap_or_else(|| DMatrix::zeros(0, 0));
                Ok((e.r, j))
            }
            JacobianMode::FiniteDifference { epsilon } => {
                let r = self.eval(x, false)?.r;
                let scales = self.layout.scales();
                let mut j = DMatrix::zeros(r.len(), x.len());
                for k in 0..x.len() {
                    let h = epsilon * scales[k] / 1e-3;
                    let mut xp = x.clone();
                    xp[k] += h;
                    let rp = self.eval(&xp, false)?.r;
                    j.set_column(k, &((rp - &r) / h));
                }
                // restore warm starts at x
                self.eval(x, false)?;
                Ok((r, j))
            }
        }
    }
}

/// One evaluation: weighted residuals, their Jacobian, and (with noise weighting) the raw residuals.
pub(super) struct Eval {
    pub(super) r: DVector<f64>,
    pub(super) j: Option<DMatrix<f64>>,
    pub(super) raw: Option<DVector<f64>>,
}

/// The configurations a problem is built from.
#[derive(Debug, Clone, Default)]
pub(super) struct Usable {
    pub(super) kappa: Vec<Vec6>,
    pub(super) cam: Vec<Vec6>,
    /// Data index of each.
    pub(super) index: Vec<usize>,
    /// Samples averaged (κ, camera) of each.
    pub(super) counts: Vec<(f64, f64)>,
}

impl Usable {
    pub(super) fn len(&self) -> usize {
        self.index.len()
    }

    /// Removes usable configuration `l`.
    pub(super) fn remove(&mut self, l: usize) {
        self.kappa.remove(l);
        self.cam.remove(l);
        self.index.remove(l);
        self.counts.remove(l);
    }

    /// The configurations whose data index passes `keep`, in their order.
    pub(super) fn only(&self, keep: impl Fn(usize) -> bool) -> Usable {
        let mut u = Usable::default();
        for (l, &i) in self.index.iter().enumerate() {
            if keep(i) {
                u.kappa.push(self.kappa[l]);
                u.cam.push(self.cam[l]);
                u.index.push(i);
                u.counts.push(self.counts[l]);
            }
        }
        u
    }
}

/// The configurations without a defect (and, unless `include_faulty`, without a failed collection
/// check).
pub(super) fn usable(data: &CalibrationData, include_faulty: bool) -> Usable {
    let mut u = Usable::default();
    for (i, c) in data.configurations.iter().enumerate() {
        let excluded = if include_faulty {
            c.defect()
        } else {
            c.exclusion()
        };
        if excluded.is_none() {
            if let Some(p) = c.sensor_pose_vec() {
                u.kappa.push(c.kappa_vec());
                u.cam.push(p);
                u.index.push(i);
                u.counts.push((
                    f64::from(c.kappa_samples.max(1)),
                    f64::from(c.camera_frames.max(1)),
                ));
            }
        }
    }
    u
}
