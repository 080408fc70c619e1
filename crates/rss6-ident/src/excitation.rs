//! Exciting trajectories for dynamic identification (§5.4): a finite Fourier series per pose axis
//! (eq. 5.11), its feasibility on a dense sampling (IK, stroke with a margin, type I/II singularities,
//! eq. 4.22, joint-rate and acceleration limits) and the observability index O_in of the stacked
//! regressor of the identifiable parameters (eq. 5.13).
//!
//! χ_i(t) = Σ_l [ s_i^l sin(2π f0 l t)/(2π f0 l) − c_i^l cos(2π f0 l t)/(2π f0 l) ] + χ0_i (eq. 5.11),
//! so χ̇_i = Σ_l [s_i^l cos + c_i^l sin] and χ̈_i = Σ_l 2π f0 l [−s_i^l sin + c_i^l cos]. A trajectory
//! that starts (and, being periodic, ends) at rest at a pose χ_start needs Σ_l s_i^l = 0 (χ̇ = 0),
//! Σ_l l c_i^l = 0 (χ̈ = 0) and χ0_i = χ_start,i + Σ_l c_i^l/(2π f0 l): [`Excitation::at_rest`] builds
//! one from the free coefficients s^2..s^n, c^2..c^n of every axis, so every candidate an optimiser
//! proposes meets them exactly.

use crate::error::{IdentError, Result};
use nalgebra::DMatrix;
use rss6_core::{ik, jacobian_theta, regressor, singularity_check, KinematicParams, Vec6, N_DYN};
use rss6_ctrl::{Reference, Trajectory};
use std::f64::consts::PI;

/// A Fourier exciting trajectory: `coefficients[i]` = [s^1, c^1, …, s^n, c^n, χ0] of pose axis i.
#[derive(Debug, Clone, PartialEq)]
pub struct Excitation {
    harmonics: usize,
    f0: f64,
    coefficients: [Vec<f64>; 6],
}

/// Limits an exciting trajectory must respect.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExcitationLimits {
    /// Actuator stroke (rad, drive convention ≈ model convention here), e.g. from
    /// [`crate::stroke`].
    pub stroke: (f64, f64),
    /// Margin kept inside the stroke (rad): covers the uncertainty of the true robot's joint offsets.
    pub stroke_margin: f64,
    /// Largest |θ̇_i| (rad/s); the command guard's rate is 3 rad/s.
    pub max_joint_rate: f64,
    /// Largest |χ̈| per axis (m/s², rad/s²).
    pub max_acceleration: Vec6,
    /// C of eq. 4.22.
    pub homeomorphism_c: f64,
    /// Largest cond(J_ad) accepted (type-II margin).
    pub max_condition: f64,
    /// Samples per period on which the limits are checked.
    pub samples: usize,
}

impl Default for ExcitationLimits {
    /// The derived geometry's stroke ±31° with a 3σ Table 4.2 margin on Δθ (0.15 rad), 1.5 rad/s,
    /// 2 m/s² and 10 rad/s², C = 2·10⁴, cond ≤ 15, 1000 samples.
    fn default() -> Self {
        ExcitationLimits {
            stroke: (-31.0_f64.to_radians(), 31.0_f64.to_radians()),
            stroke_margin: 0.15,
            max_joint_rate: 1.5,
            max_acceleration: Vec6::new(2.0, 2.0, 2.0, 10.0, 10.0, 10.0),
            homeomorphism_c: 2e4,
            max_condition: 15.0,
            samples: 1000,
        }
    }
}

/// Why a trajectory is not feasible, and where.
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    /// The constraint violated: "ik", "stroke", "type I", "type II", "eq. 4.22", "joint rate",
    /// "acceleration".
    pub constraint: &'static str,
    /// Time of the first violating sample (s).
    pub time: f64,
    /// How far past the limit (in the constraint's unit; 1 for "ik" and the singularities).
    pub excess: f64,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} violated at t = {:.3} s (by {:.3e})",
            self.constraint, self.time, self.excess
        )
    }
}

impl Excitation {
    /// A trajectory from its full coefficients (`coefficients[i]` of length 2n + 1).
    pub fn from_coefficients(f0: f64, coefficients: [Vec<f64>; 6]) -> Result<Self> {
        let len = coefficients[0].len();
        if !(f0.is_finite() && f0 > 0.0) || len < 3 || len % 2 == 0 {
            return Err(IdentError::InvalidInput(format!(
                "f0 must be > 0 Hz and every axis needs 2n + 1 ≥ 3 coefficients (f0 {f0}, {len})"
            )));
        }
        if coefficients
            .iter()
            .any(|c| c.len() != len || c.iter().any(|v| !v.is_finite()))
        {
            return Err(IdentError::InvalidInput(
                "every axis needs the same number of finite coefficients".into(),
            ));
        }
        Ok(Excitation {
            harmonics: (len - 1) / 2,
            f0,
            coefficients,
        })
    }

    /// Number of free coefficients per axis of [`Self::at_rest`]: 2(n − 1).
    pub fn free_per_axis(harmonics: usize) -> usize {
        2 * harmonics.saturating_sub(1)
    }

    /// The trajectory with `harmonics` ≥ 2 harmonics of `f0` that starts and ends at rest at `start`,
    /// from the free coefficients `free` (6 × 2(n − 1), per axis [s^2, c^2, …, s^n, c^n]).
    pub fn at_rest(harmonics: usize, f0: f64, start: &Vec6, free: &[f64]) -> Result<Self> {
        let k = Self::free_per_axis(harmonics);
        if harmonics < 2 || free.len() != 6 * k {
            return Err(IdentError::InvalidInput(format!(
                "at_rest needs n ≥ 2 harmonics and 6 × 2(n − 1) = {} free coefficients, got n = {harmonics}, {}",
                6 * k,
                free.len()
            )));
        }
        let w = 2.0 * PI * f0;
        let coefficients = std::array::from_fn(|i| {
            let axis = &free[i * k..(i + 1) * k];
            let mut c = vec![0.0; 2 * harmonics + 1];
            let (mut s_sum, mut lc_sum) = (0.0, 0.0);
            for l in 2..=harmonics {
                let (s, cc) = (axis[2 * (l - 2)], axis[2 * (l - 2) + 1]);
                c[2 * (l - 1)] = s;
                c[2 * (l - 1) + 1] = cc;
                s_sum += s;
                lc_sum += l as f64 * cc;
            }
            c[0] = -s_sum;
            c[1] = -lc_sum;
            let chi0: f64 = (1..=harmonics)
                .map(|l| c[2 * (l - 1) + 1] / (w * l as f64))
                .sum();
            c[2 * harmonics] = start[i] + chi0;
            c
        });
        Self::from_coefficients(f0, coefficients)
    }

    /// Number of harmonics n.
    pub fn harmonics(&self) -> usize {
        self.harmonics
    }

    /// Fundamental frequency f0 (Hz).
    pub fn f0(&self) -> f64 {
        self.f0
    }

    /// One period 1/f0 (s).
    pub fn period(&self) -> f64 {
        1.0 / self.f0
    }

    /// The coefficients, per axis [s^1, c^1, …, s^n, c^n, χ0].
    pub fn coefficients(&self) -> &[Vec<f64>; 6] {
        &self.coefficients
    }

    /// (χ, χ̇, χ̈) at time `t` (s), eq. 5.11 and its derivatives.
    pub fn at(&self, t: f64) -> Reference {
        let w = 2.0 * PI * self.f0;
        let mut r = Reference {
            pose: Vec6::zeros(),
            pose_dot: Vec6::zeros(),
            pose_ddot: Vec6::zeros(),
        };
        for (i, c) in self.coefficients.iter().enumerate() {
            let mut p = c[2 * self.harmonics];
            let (mut v, mut a) = (0.0, 0.0);
            for l in 1..=self.harmonics {
                let wl = w * l as f64;
                let (s, cc) = (c[2 * (l - 1)], c[2 * (l - 1) + 1]);
                let (sn, cs) = (wl * t).sin_cos();
                p += (s * sn - cc * cs) / wl;
                v += s * cs + cc * sn;
                a += wl * (-s * sn + cc * cs);
            }
            r.pose[i] = p;
            r.pose_dot[i] = v;
            r.pose_ddot[i] = a;
        }
        r
    }

    /// `m` samples at t_k = k·T/m, k = 0..m (one period).
    pub fn samples(&self, m: usize) -> Vec<(f64, Reference)> {
        let h = self.period() / m.max(1) as f64;
        (0..m.max(1))
            .map(|k| {
                let t = k as f64 * h;
                (t, self.at(t))
            })
            .collect()
    }

    /// The first violated limit on `limits.samples` samples of one period, or `None` if feasible.
    pub fn check(&self, kp: &KinematicParams, limits: &ExcitationLimits) -> Option<Violation> {
        let (lo, hi) = (
            limits.stroke.0 + limits.stroke_margin,
            limits.stroke.1 - limits.stroke_margin,
        );
        let home_sign = singularity_check(kp, &rss6_core::home_pose())
            .map(|c| c.type_ii.det_j_a2.signum())
            .unwrap_or(1.0);
        for (t, r) in self.samples(limits.samples) {
            let v = |constraint, excess| {
                Some(Violation {
                    constraint,
                    time: t,
                    excess,
                })
            };
            for i in 0..6 {
                let a = r.pose_ddot[i].abs();
                if a > limits.max_acceleration[i] {
                    return v("acceleration", a - limits.max_acceleration[i]);
                }
            }
            let theta = match ik(kp, &r.pose) {
                Ok(th) => th,
                Err(_) => return v("ik", 1.0),
            };
            let out = theta
                .iter()
                .map(|&th| (lo - th).max(th - hi))
                .fold(f64::NEG_INFINITY, f64::max);
            if out > 0.0 {
                return v("stroke", out);
            }
            let check = match singularity_check(kp, &r.pose) {
                Ok(c) => c,
                Err(_) => return v("type II", 1.0),
            };
            if !check.type_i.is_free() {
                return v("type I", 1.0);
            }
            if !check.type_ii.is_free(home_sign, limits.max_condition) {
                return v("type II", check.type_ii.condition - limits.max_condition);
            }
            if !check.homeomorphism.holds(limits.homeomorphism_c) {
                return v(
                    "eq. 4.22",
                    check.homeomorphism.ratio - limits.homeomorphism_c,
                );
            }
            let rate = match jacobian_theta(kp, &r.pose) {
                Ok(j) => (j * r.pose_dot).amax(),
                Err(_) => return v("type II", 1.0),
            };
            if rate > limits.max_joint_rate {
                return v("joint rate", rate - limits.max_joint_rate);
            }
        }
        None
    }

    /// The stacked regressor H (6m × 64) of `m` samples of one period (rows: actuator torques).
    pub fn stacked_regressor(&self, kp: &KinematicParams, m: usize) -> Result<DMatrix<f64>> {
        let samples = self.samples(m);
        let mut h = DMatrix::zeros(6 * samples.len(), N_DYN);
        for (k, (_, r)) in samples.iter().enumerate() {
            let g = regressor(kp, &r.pose, &r.pose_dot, &r.pose_ddot)?;
            h.view_mut((6 * k, 0), (6, N_DYN)).copy_from(&g);
        }
        Ok(h)
    }

    /// O_in (eq. 5.13) and the condition number of H restricted to `columns` (the identifiable
    /// parameters, e.g. from [`base_columns`]) on `m` samples: O_in = (Π σ_i)^{1/ς} / √m.
    pub fn observability(
        &self,
        kp: &KinematicParams,
        columns: &[usize],
        m: usize,
    ) -> Result<(f64, f64)> {
        let h = self.stacked_regressor(kp, m)?;
        observability_of(&h, columns, m)
    }
}

/// O_in and cond of the columns `columns` of a stacked regressor of `m` samples.
pub fn observability_of(h: &DMatrix<f64>, columns: &[usize], m: usize) -> Result<(f64, f64)> {
    if columns.is_empty() || columns.iter().any(|&c| c >= h.ncols()) {
        return Err(IdentError::InvalidInput(format!(
            "columns must be non-empty indices below {}",
            h.ncols()
        )));
    }
    let sub = h.select_columns(columns);
    let sv = sub.singular_values();
    let (mut max, mut min, mut log_sum) = (0.0_f64, f64::INFINITY, 0.0);
    for &s in sv.iter() {
        max = max.max(s);
        min = min.min(s);
        log_sum += s.max(f64::MIN_POSITIVE).ln();
    }
    let o_in = (log_sum / sv.len() as f64).exp() / (m.max(1) as f64).sqrt();
    Ok((o_in, max / min))
}

/// Columns whose residual norm is within this fraction of the largest count as tied when
/// [`base_columns`] pivots; the earliest of them is taken.
pub const PIVOT_TIE: f64 = 0.1;

/// The identifiable (base) columns of a stacked regressor by QR with column pivoting (Gautier's
/// numerical method, eq. 5.2): columns whose |R_ii| exceeds `relative` × the largest |R_ii|, in pivot
/// order, after scaling every column to unit norm (so the threshold does not depend on units).
///
/// The pivot is the column with the largest norm left after projecting out the chosen ones, except
/// that among columns within [`PIVOT_TIE`] of that norm the earliest is taken. Near-parallel pairs
/// (a crank's mass and its moment, say) otherwise go to whichever is ahead by rounding, so a
/// 10⁻³ change of the columns, or another trajectory, swapped the names of the base set; with the
/// tie rule the choice follows the column order. Every |R_ii| taken is still ≥ 0.9 × the largest
/// available at its step (modified Gram–Schmidt with one re-orthogonalisation).
pub fn base_columns(h: &DMatrix<f64>, relative: f64) -> Vec<usize> {
    let mut w = h.clone();
    let mut left: Vec<usize> = Vec::new();
    for (j, mut col) in w.column_iter_mut().enumerate() {
        let n = col.norm();
        if n > 0.0 && n.is_finite() {
            col /= n;
            left.push(j);
        }
    }
    let mut base = Vec::new();
    let mut top = 0.0_f64;
    while !left.is_empty() {
        let norms: Vec<f64> = left.iter().map(|&j| w.column(j).norm()).collect();
        let max = norms.iter().copied().fold(0.0_f64, f64::max);
        if base.is_empty() {
            top = max;
        }
        // Not above the threshold (or a NaN threshold): the rest is not identifiable.
        if max.partial_cmp(&(relative * top)) != Some(std::cmp::Ordering::Greater) {
            break;
        }
        let k = norms
            .iter()
            .position(|&n| n >= (1.0 - PIVOT_TIE) * max)
            .unwrap_or(0);
        let j = left.remove(k);
        base.push(j);
        let q = w.column(j) / norms[k];
        for _ in 0..2 {
            for &l in &left {
                let c = q.dot(&w.column(l));
                w.column_mut(l).axpy(-c, &q, 1.0);
            }
        }
    }
    base
}

/// How the output mimics each column outside `base`: for column u, the least-squares coefficients c
/// with h_u ≈ Σ_j c_j h_{base_j} (columns as given) and the relative residual ‖h_u − H_b c‖ / ‖h_u‖
/// (0: u is exactly a combination of the base columns). With columns ∂Y/∂log q, c_j says that a
/// relative change δ of u moves the output as relative changes c_j δ of the base quantities do:
/// what the estimate of each base quantity absorbs of u. Returned for every u not in `base`, in
/// column order; a zero column gets no coefficients and residual 1.
pub fn aliases(h: &DMatrix<f64>, base: &[usize]) -> Vec<(usize, Vec<f64>, f64)> {
    let hb = h.select_columns(base);
    let svd = hb.clone().svd(true, true);
    (0..h.ncols())
        .filter(|j| !base.contains(j))
        .map(|u| {
            let hu = h.column(u).clone_owned();
            let n = hu.norm();
            if n == 0.0 || base.is_empty() {
                return (u, vec![0.0; base.len()], 1.0);
            }
            let tol = 1e-12 * svd.singular_values.max();
            match svd.solve(&hu, tol) {
                Ok(c) => {
                    let res = (&hu - &hb * &c).norm() / n;
                    (u, c.iter().copied().collect(), res)
                }
                Err(_) => (u, vec![0.0; base.len()], 1.0),
            }
        })
        .collect()
}

/// The trajectory repeats with its period (a run of N periods excites the robot N times, each
/// period starting and ending at rest at the start pose); before t = 0 it holds the start at rest.
impl Trajectory for Excitation {
    fn sample(&self, t: f64) -> Reference {
        if t > 0.0 {
            self.at(t % self.period())
        } else {
            Reference::hold(&self.at(0.0).pose)
        }
    }
}

/// What an optimiser of the free coefficients of [`Excitation::at_rest`] minimises.
#[derive(Debug, Clone, PartialEq)]
pub struct ExcitationProblem {
    /// The kinematic model.
    pub kp: KinematicParams,
    /// Limits checked on every candidate.
    pub limits: ExcitationLimits,
    /// Harmonics n (thesis: 5).
    pub harmonics: usize,
    /// Fundamental frequency (Hz; thesis: 0.1).
    pub f0: f64,
    /// The pose the trajectory starts and ends at, at rest.
    pub start: Vec6,
    /// The identifiable columns whose O_in is maximised.
    pub columns: Vec<usize>,
    /// Samples per period of the stacked regressor.
    pub samples: usize,
}

impl ExcitationProblem {
    /// −O_in of a feasible candidate (to minimise); an infeasible one scores 1 + its excess, so every
    /// feasible candidate beats every infeasible one and less infeasible ones are preferred.
    pub fn objective(&self, free: &[f64]) -> f64 {
        let Ok(e) = Excitation::at_rest(self.harmonics, self.f0, &self.start, free) else {
            return f64::INFINITY;
        };
        if let Some(v) = e.check(&self.kp, &self.limits) {
            return 1.0 + v.excess.min(1e6);
        }
        match e.observability(&self.kp, &self.columns, self.samples) {
            Ok((o_in, _)) => -o_in,
            Err(_) => f64::INFINITY,
        }
    }

    /// [`Self::objective`] of every candidate, in parallel (rayon).
    pub fn objectives(&self, population: &[Vec<f64>]) -> Vec<f64> {
        use rayon::prelude::*;
        population.par_iter().map(|x| self.objective(x)).collect()
    }
}
