//! The least-squares problem of each method: residuals Φ and their Jacobian at a parameter vector.

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
}

/// A failed evaluation: the (usable-list) index of the configuration and the kinematics error.
pub(super) type EvalError = (usize, CoreError);

impl Problem {
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
        }
    }

    pub(super) fn n_res(&self) -> usize {
        match self.layout.method {
            Method::Rpba => 6 * (self.kappa.len() - 1),
            Method::Implicit => 6 * self.kappa.len(),
        }
    }

    pub(super) fn eval(
        &mut self,
        x: &DVector<f64>,
        jac: bool,
    ) -> core::result::Result<Eval, EvalError> {
        match self.layout.method {
            Method::Rpba => self.eval_rpba(x, jac),
            Method::Implicit => Ok(self.eval_implicit(x, jac)),
        }
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
        Ok(Eval { r, j })
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
        Eval { r, j }
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

pub(super) struct Eval {
    pub(super) r: DVector<f64>,
    pub(super) j: Option<DMatrix<f64>>,
}

/// κ, ᶜχ_t and data indices of the configurations without a defect.
pub(super) fn usable(data: &CalibrationData) -> (Vec<Vec6>, Vec<Vec6>, Vec<usize>) {
    let mut kappa = Vec::new();
    let mut cam = Vec::new();
    let mut idx = Vec::new();
    for (i, c) in data.configurations.iter().enumerate() {
        if c.defect().is_none() {
            if let Some(p) = c.sensor_pose_vec() {
                kappa.push(c.kappa_vec());
                cam.push(p);
                idx.push(i);
            }
        }
    }
    (kappa, cam, idx)
}
