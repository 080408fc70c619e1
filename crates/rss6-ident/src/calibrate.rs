//! The two calibration methods of §4.3 and their Levenberg–Marquardt solver.
//!
//! * [`implicit`]: leg-closure residuals Φ_I (eq. 4.10) with ᴼM_E^l = ᴼM_C·ᶜM_t^l·ᵗM_E (eq. 4.12);
//!   60 kinematic + 12 external parameters (ᴼχ_C, ᴱχ_t), cost eq. 4.13.
//! * [`rpba`]: relative-pose residuals Φ_R = L(ᶜM_t⁰⁻¹ᶜM_t^l) − L(ᴱM_t⁻¹·ᴼM_E⁰⁻¹·ᴼM_E^l·ᴱM_t)
//!   (eq. 4.16–4.18) with forward kinematics inside; 60 + 6 parameters (ᴱχ_t), cost eq. 4.19.
//!
//! Both are solved by Levenberg–Marquardt (eq. 4.14 / 4.20 are its undamped Gauss–Newton case) with
//! analytic Jacobians: the FK derivative comes from implicit differentiation of the leg closure,
//! dχ/db = −(∂Φ/∂χ)⁻¹ ∂Φ/∂b. The finite differences of eq. 4.25 remain available
//! ([`JacobianMode::FiniteDifference`]) and are used by the tests to check the analytic Jacobian.
//! Parameters are scaled by their Table 4.2 σ, and steps are restricted to the complement of the 10
//! gauge directions (see [`crate::model`]): the minimum-norm fix of the frame choice.

use crate::closure::{fk_reading, fk_with_derivative, leg_closure, FkDerivative, Mat6x60};
use crate::data::CalibrationData;
use crate::error::{IdentError, Method, Result};
use crate::model::{Layout, GAUGE_DESCRIPTIONS, N_GAUGE};
use crate::se3::{adjoint, iso, pose_delta_from_twist, pose_difference, twist_from_pose_delta};
use nalgebra::{DMatrix, DVector};
use rss6_core::{
    home_pose, isometry_to_pose, CoreError, KinematicParams, Mat6, SingularKind, Vec6, N_KIN_ERRORS,
};

/// How the Jacobian of the residuals is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JacobianMode {
    /// Analytic (implicit differentiation of the leg closure for the FK derivative). Default.
    Analytic,
    /// Forward differences of eq. 4.25 with step ε·σ_j/1 mm per parameter (ε = 10⁻⁶ as in the thesis
    /// gives 10⁻⁶ m for lengths).
    FiniteDifference {
        /// ε of eq. 4.25.
        epsilon: f64,
    },
}

/// Solver options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// Maximum LM iterations (accepted and rejected steps).
    pub max_iterations: usize,
    /// Stop when the relative cost decrease of an accepted step is below this.
    pub cost_tolerance: f64,
    /// Stop when the scaled step norm is below this.
    pub step_tolerance: f64,
    /// Initial Marquardt damping λ (relative to diag JᵀJ).
    pub initial_damping: f64,
    /// Jacobian computation.
    pub jacobian: JacobianMode,
    /// RPBA residual weights [x, y, z, α, β, γ] (1/m, 1/rad): default 1/σ of Table 4.1, so
    /// translations and rotations count by their measurement precision.
    pub pose_weights: [f64; 6],
    /// Implicit residual weight (1/m); default 1/σ_position of Table 4.1.
    pub leg_weight: f64,
    /// Singular values below `rank_tolerance`·σ_max count as zero.
    pub rank_tolerance: f64,
    /// Starting value of ᴱχ_t (m, rad); default [`crate::NOMINAL_TARGET_IN_EFFECTOR`].
    pub target_guess: [f64; 6],
    /// Implicit only: hold ᴼχ_C at its (rough) guess instead of estimating it, as when the base frame
    /// is taken from a separate, rough measurement. Default `false`.
    pub fix_sensor_pose: bool,
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        let sp = rss6_core::thesis::POSE_POSITION_NOISE;
        let sa = rss6_core::thesis::POSE_ANGLE_NOISE;
        CalibrationOptions {
            max_iterations: 60,
            cost_tolerance: 1e-12,
            step_tolerance: 1e-10,
            initial_damping: 1e-4,
            jacobian: JacobianMode::Analytic,
            pose_weights: [1.0 / sp, 1.0 / sp, 1.0 / sp, 1.0 / sa, 1.0 / sa, 1.0 / sa],
            leg_weight: 1.0 / sp,
            rank_tolerance: 1e-9,
            target_guess: crate::generator::NOMINAL_TARGET_IN_EFFECTOR,
            fix_sensor_pose: false,
        }
    }
}

/// A configuration left out of the estimate, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedConfiguration {
    /// Index in [`CalibrationData::configurations`].
    pub index: usize,
    /// Reason (missing frames, NaN, FK failure …).
    pub reason: String,
}

/// Progress of the solver, passed to the callback after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Iteration number (accepted + rejected steps so far).
    pub iteration: usize,
    /// Current cost Σ‖W·r‖².
    pub cost: f64,
    /// Current damping λ.
    pub damping: f64,
}

/// Outcome of a calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationResult {
    /// Method used.
    pub method: Method,
    /// Calibrated kinematic parameters.
    pub params: KinematicParams,
    /// The parameters the calibration started from (the nominal model; b is relative to them).
    pub reference: KinematicParams,
    /// Calibrated error vector b relative to the parameters passed in (docs/architecture.md order).
    pub errors: [f64; N_KIN_ERRORS],
    /// Calibrated ᴱχ_t (m, rad).
    pub target_in_effector: Vec6,
    /// Calibrated ᴼχ_C (implicit only).
    pub sensor_in_base: Option<Vec6>,
    /// Cost Σ‖W·r‖² at the start and after every accepted step.
    pub cost_history: Vec<f64>,
    /// Numerical rank of the Table 4.2-scaled Jacobian at the solution (full parameter set).
    pub rank: usize,
    /// Number of parameters (66 or 72).
    pub parameter_count: usize,
    /// Parameters that are not individually identifiable: those with ≥ 5 % of their (scaled) unit
    /// vector in the Jacobian's null space, i.e. in a gauge (frame-choice) direction.
    pub unidentifiable: Vec<String>,
    /// The null-space (gauge) directions removed from the problem, described.
    pub gauge_directions: Vec<String>,
    /// Singular values of the scaled Jacobian at the solution, descending.
    pub singular_values: Vec<f64>,
    /// Accepted LM steps.
    pub iterations: usize,
    /// Configurations that were left out, with the reason.
    pub dropped: Vec<DroppedConfiguration>,
    /// Indices of the configurations used.
    pub used: Vec<usize>,
}

struct Problem {
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

type EvalError = (usize, CoreError);

impl Problem {
    fn new(layout: Layout, kappa: Vec<Vec6>, cam: Vec<Vec6>, opts: &CalibrationOptions) -> Self {
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

    fn n_res(&self) -> usize {
        match self.layout.method {
            Method::Rpba => 6 * (self.kappa.len() - 1),
            Method::Implicit => 6 * self.kappa.len(),
        }
    }

    fn eval(&mut self, x: &DVector<f64>, jac: bool) -> core::result::Result<Eval, EvalError> {
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
    fn eval_full(
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

struct Eval {
    r: DVector<f64>,
    j: Option<DMatrix<f64>>,
}

/// Minimum number of configurations (including configuration 0) each method needs: every
/// configuration gives 6 equations, RPBA loses one configuration to the reference, and the
/// identifiable parameter count is the total minus the 10 gauge directions.
pub fn min_configurations(method: Method) -> usize {
    let free = Layout::new(method, KinematicParams::nominal()).n() - N_GAUGE;
    let per = free.div_ceil(6);
    match method {
        Method::Rpba => per + 1,
        Method::Implicit => per,
    }
}

/// The parameter vector x = [b; (ᴼχ_C); ᴱχ_t] of `method` for parameters `kp` measured from
/// `reference` (b = kp − reference). `sensor` is ignored for RPBA.
pub fn parameter_vector(
    method: Method,
    reference: &KinematicParams,
    kp: &KinematicParams,
    sensor: Option<&Vec6>,
    target: &Vec6,
) -> DVector<f64> {
    Layout::new(method, *reference).pack(kp, sensor, target)
}

/// RPBA (eq. 4.16–4.21) from `data`, starting at kinematic parameters `kp` and the target pose
/// `opts.target_guess` (ᴱχ_t, m/rad; e.g. the nominal target definition).
///
/// Configuration 0 is the reference. Configurations with NaN or missing frames, or where FK fails at
/// the starting parameters, are dropped and reported in [`CalibrationResult::dropped`]; a bad
/// configuration 0 is an error.
pub fn rpba(
    data: &CalibrationData,
    kp: &KinematicParams,
    opts: &CalibrationOptions,
) -> Result<CalibrationResult> {
    rpba_with_progress(data, kp, opts, &mut |_| {})
}

/// [`rpba`] with a progress callback after every LM iteration.
pub fn rpba_with_progress(
    data: &CalibrationData,
    kp: &KinematicParams,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let layout = Layout::new(Method::Rpba, *kp);
    let x0 = layout.pack(kp, None, &Vec6::from(opts.target_guess));
    solve(layout, data, x0, opts, progress)
}

/// Implicit calibration (eq. 4.10–4.15) from `data`, starting at `kp`, the rough sensor pose
/// `sensor_pose_guess` (ᴼχ_C) and `opts.target_guess` (ᴱχ_t). Configuration 0 is used like the
/// others.
pub fn implicit(
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor_pose_guess: &Vec6,
    opts: &CalibrationOptions,
) -> Result<CalibrationResult> {
    implicit_with_progress(data, kp, sensor_pose_guess, opts, &mut |_| {})
}

/// [`implicit`] with a progress callback after every LM iteration.
pub fn implicit_with_progress(
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor_pose_guess: &Vec6,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let layout = Layout::new(Method::Implicit, *kp);
    let x0 = layout.pack(kp, Some(sensor_pose_guess), &Vec6::from(opts.target_guess));
    solve(layout, data, x0, opts, progress)
}

/// Σ_l ‖Φ^l‖₂ (unweighted, SI units) for `data` at the given parameters: the second row of
/// Tables 4.3 (implicit, m) and 4.4 (RPBA, mixed m/rad). Unusable configurations are skipped.
pub fn residual_norm_sum(
    method: Method,
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor: Option<&Vec6>,
    target: &Vec6,
) -> Result<f64> {
    let layout = Layout::new(method, *kp);
    let x = layout.pack(kp, sensor, target);
    let (kappa, cam, _) = usable(data);
    if kappa.len() < 2 {
        return Err(IdentError::InvalidInput("no usable configurations".into()));
    }
    let opts = CalibrationOptions {
        pose_weights: [1.0; 6],
        leg_weight: 1.0,
        ..CalibrationOptions::default()
    };
    let mut p = Problem::new(layout, kappa, cam, &opts);
    let e = p
        .eval(&x, false)
        .map_err(|(config, source)| IdentError::Fk { config, source })?;
    Ok(e.r
        .as_slice()
        .chunks(6)
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .sum())
}

fn usable(data: &CalibrationData) -> (Vec<Vec6>, Vec<Vec6>, Vec<usize>) {
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

fn solve(
    layout: Layout,
    data: &CalibrationData,
    x0: DVector<f64>,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let method = layout.method;
    if x0.iter().any(|v| !v.is_finite()) {
        return Err(IdentError::InvalidInput(
            "starting parameters contain NaN or infinity".into(),
        ));
    }
    layout.kp(&x0).validate()?;
    let mut dropped = Vec::new();
    for (i, c) in data.configurations.iter().enumerate() {
        if let Some(reason) = c.defect() {
            if i == 0 && method == Method::Rpba {
                return Err(IdentError::BadReference(reason));
            }
            dropped.push(DroppedConfiguration { index: i, reason });
        }
    }
    let (mut kappa, mut cam, mut used) = usable(data);
    let needed = min_configurations(method);
    let check_count = |got: usize| {
        if got < needed {
            Err(IdentError::TooFewConfigurations {
                method,
                got,
                needed,
                params: layout.n() - N_GAUGE,
                extra: match method {
                    Method::Rpba => ", configuration 0 is the reference",
                    Method::Implicit => "",
                },
            })
        } else {
            Ok(())
        }
    };
    check_count(used.len())?;

    // Initial evaluation; configurations where FK fails at the start are dropped.
    let (mut problem, (mut r, mut j)) = loop {
        let mut p = Problem::new(layout, kappa.clone(), cam.clone(), opts);
        match p.eval_full(&x0, opts.jacobian) {
            Ok(e) => break (p, e),
            Err((l, e)) => {
                if l == 0 && method == Method::Rpba {
                    return Err(IdentError::Fk {
                        config: used[0],
                        source: e,
                    });
                }
                dropped.push(DroppedConfiguration {
                    index: used[l],
                    reason: format!("forward kinematics failed at the starting parameters: {e}"),
                });
                kappa.remove(l);
                cam.remove(l);
                used.remove(l);
                check_count(used.len())?;
            }
        }
    };

    let s = layout.scales();
    let fixed_sensor = opts.fix_sensor_pose && method == Method::Implicit;
    let q = if fixed_sensor {
        layout.free_basis_fixed_sensor(&x0)
    } else {
        layout.free_basis(&x0)
    };
    let names = layout.names();
    let reduce = |j: &DMatrix<f64>| {
        let mut js = j.clone();
        for c in 0..js.ncols() {
            js.column_mut(c).scale_mut(s[c]);
        }
        js * &q
    };

    // Identifiability at the start: the gauge-reduced Jacobian must have full column rank.
    {
        let jr = reduce(&j);
        let k = jr.ncols();
        let svd = jr.svd(false, true);
        let smax = svd.singular_values.max();
        let tol = opts.rank_tolerance * smax;
        let rank = svd.singular_values.iter().filter(|&&v| v > tol).count();
        if rank < k || smax.is_nan() || smax <= 0.0 {
            let mut weight = vec![0.0; layout.n()];
            if let Some(vt) = svd.v_t.as_ref() {
                for (row, &sv) in svd.singular_values.iter().enumerate() {
                    if sv <= tol {
                        let w = &q * vt.row(row).transpose();
                        for (acc, v) in weight.iter_mut().zip(w.iter()) {
                            *acc += v * v;
                        }
                    }
                }
            }
            let mut unseen: Vec<String> = weight
                .iter()
                .enumerate()
                .filter(|(_, &w)| w > 0.1)
                .map(|(i, _)| names[i].clone())
                .collect();
            if unseen.is_empty() {
                if let Some((i, _)) = weight.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) {
                    unseen.push(names[i].clone());
                }
            }
            return Err(IdentError::RankDeficient {
                rank,
                expected: k,
                unseen,
            });
        }
    }

    let mut x = x0;
    let mut cost = r.norm_squared();
    let mut cost_history = vec![cost];
    let mut lambda = opts.initial_damping;
    let mut accepted = 0;
    for iteration in 1..=opts.max_iterations {
        let jr = reduce(&j);
        let a = jr.transpose() * &jr;
        let g = jr.transpose() * &r;
        let mut damped = a.clone();
        for d in 0..damped.nrows() {
            damped[(d, d)] += lambda * a[(d, d)].max(1e-30);
        }
        let Some(chol) = damped.cholesky() else {
            lambda *= 10.0;
            continue;
        };
        let z = -chol.solve(&g);
        let step = (&q * &z).component_mul(&s);
        let x_new = &x + &step;
        let trial = problem.eval(&x_new, false);
        let improved = match &trial {
            Ok(e) => e.r.norm_squared() < cost,
            Err(_) => false,
        };
        if improved {
            let new_cost = trial.map(|e| e.r.norm_squared()).unwrap_or(cost);
            let decrease = cost - new_cost;
            x = x_new;
            match problem.eval_full(&x, opts.jacobian) {
                Ok((rn, jn)) => {
                    r = rn;
                    j = jn;
                }
                Err((l, e)) => {
                    return Err(IdentError::Fk {
                        config: used[l],
                        source: e,
                    })
                }
            }
            cost = new_cost;
            cost_history.push(cost);
            accepted += 1;
            lambda = (lambda / 10.0).max(1e-15);
            progress(&Progress {
                iteration,
                cost,
                damping: lambda,
            });
            if decrease <= opts.cost_tolerance * cost.max(f64::MIN_POSITIVE)
                || z.norm() <= opts.step_tolerance
            {
                break;
            }
        } else {
            lambda *= 10.0;
            progress(&Progress {
                iteration,
                cost,
                damping: lambda,
            });
            if lambda > 1e12 {
                break;
            }
        }
    }

    // Identifiability report at the solution (full, unreduced scaled Jacobian).
    let mut js = j.clone();
    for c in 0..js.ncols() {
        js.column_mut(c).scale_mut(s[c]);
    }
    let sv = js.singular_values();
    let mut singular_values: Vec<f64> = sv.iter().copied().collect();
    singular_values.sort_by(|a, b| b.total_cmp(a));
    let smax = singular_values.first().copied().unwrap_or(0.0);
    let rank = singular_values
        .iter()
        .filter(|&&v| v > opts.rank_tolerance * smax)
        .count();
    // gauge projector diagonal in the scaled metric
    let proj_diag: Vec<f64> = (0..layout.n())
        .map(|i| 1.0 - q.row(i).norm_squared())
        .collect();
    let unidentifiable = proj_diag
        .iter()
        .enumerate()
        .filter(|(_, &p)| p >= 0.05)
        .map(|(i, _)| names[i].clone())
        .collect();
    let gauge_directions = GAUGE_DESCRIPTIONS
        .iter()
        .map(|d| {
            let d = d.to_string();
            match method {
                Method::Rpba => d.replace(", with sensor pose", ""),
                Method::Implicit => d,
            }
        })
        .collect();

    Ok(CalibrationResult {
        method,
        params: layout.kp(&x),
        reference: layout.reference,
        errors: layout.errors(&x),
        target_in_effector: layout.target(&x),
        sensor_in_base: layout.sensor(&x),
        cost_history,
        rank,
        parameter_count: layout.n(),
        unidentifiable,
        gauge_directions,
        singular_values,
        iterations: accepted,
        dropped,
        used,
    })
}

/// Residuals and Jacobian of `method` at parameter vector `x` (see [`parameter_vector`]) for the
/// usable configurations of `data`, with the default weights. Exposed for identifiability studies and
/// for checking the analytic Jacobian against eq. 4.25.
pub fn residuals_and_jacobian(
    method: Method,
    data: &CalibrationData,
    reference: &KinematicParams,
    x: &DVector<f64>,
    mode: JacobianMode,
) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let layout = Layout::new(method, *reference);
    if x.len() != layout.n() {
        return Err(IdentError::InvalidInput(format!(
            "parameter vector has {} entries, {method} needs {}",
            x.len(),
            layout.n()
        )));
    }
    let (kappa, cam, used) = usable(data);
    if kappa.len() < 2 {
        return Err(IdentError::InvalidInput(
            "fewer than 2 usable configurations".into(),
        ));
    }
    let mut p = Problem::new(layout, kappa, cam, &CalibrationOptions::default());
    p.eval_full(x, mode).map_err(|(l, source)| IdentError::Fk {
        config: used[l],
        source,
    })
}

/// The 10 gauge directions (columns, unscaled parameter units) of `method` at parameter vector `x`.
pub fn gauge_directions(
    method: Method,
    reference: &KinematicParams,
    x: &DVector<f64>,
) -> DMatrix<f64> {
    Layout::new(method, *reference).gauge_basis(x)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::data::collect;
    use crate::generator::{AnalyticRobot, NoiseModel, TrueRobot};
    use rand::SeedableRng;

    /// The gauge claim of `model.rs` is exact, not first-order: finite frame changes leave every
    /// residual unchanged.
    #[test]
    fn residuals_are_invariant_under_finite_gauge_transformations() {
        let nominal = KinematicParams::nominal();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let truth = TrueRobot::draw(&nominal, &mut rng);
        let mut src = AnalyticRobot::new(truth, nominal, NoiseModel::default(), 5);
        let mut thetas = vec![Vec6::zeros()];
        thetas.extend(crate::validate::test_configurations(8, 1, (-0.4, 0.4)));
        let data = collect(&mut src, &thetas, 2.0).unwrap();
        let g = [
            0.01, -0.02, 0.005, 0.03, 0.004, -0.003, 0.01, 0.02, -0.01, 0.05,
        ];
        for method in [Method::Rpba, Method::Implicit] {
            let layout = Layout::new(method, nominal);
            let x = layout.pack(
                &truth.kp,
                Some(&truth.sensor_in_base),
                &truth.target_in_effector,
            );
            let xg = layout.apply_gauge(&x, &g);
            assert!(
                (&xg - &x).amax() > 1e-3,
                "the gauge must actually move the parameters"
            );
            let (kappa, cam, _) = usable(&data);
            let mut p = Problem::new(layout, kappa, cam, &CalibrationOptions::default());
            let r = p.eval(&x, false).unwrap().r;
            let rg = p.eval(&xg, false).unwrap().r;
            assert!(
                (&r - &rg).amax() < 1e-6 * r.amax(),
                "{method}: {}",
                (&r - &rg).amax()
            );
        }
    }
}
