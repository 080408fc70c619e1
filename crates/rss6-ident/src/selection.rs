//! Configuration selection for calibration: the actuator stroke of §4.4.1 (eq. 4.24 under the
//! type-I, type-II and homeomorphism constraints, eq. 4.22) and the optimal configuration set of
//! §4.4.2 maximising the observability index O1 (eq. 4.23) with the add-if-better / drop-if-worse
//! search of Nubiola et al.

use crate::calibrate::{residuals_and_jacobian, JacobianMode};
use crate::closure::fk_reading;
use crate::data::{CalibrationData, ConfigurationData};
use crate::error::{IdentError, Method, Result};
use crate::generator::{NOMINAL_SENSOR_IN_BASE, NOMINAL_TARGET_IN_EFFECTOR};
use crate::model::{Layout, N_GAUGE};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::{
    compose, home_pose, ik, leg_side, pose_inverse, KinematicParams, LegGeometry, Vec6, LEGS,
};

/// Options of the stroke search (§4.4.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrokeOptions {
    /// C of eq. 4.22: the homeomorphism condition (Σσ_i²)^{n/2} ≤ C·|Π λ_i| on J_ad2 = J_a2⁻¹J_a1.
    /// Its minimum possible value is n^{n/2} = 216 (all singular values equal).
    pub homeomorphism_c: f64,
    /// Smallest accepted |diag J_a1| (m²) and |det J_a2| relative to its home value.
    pub singular_margin: f64,
    /// Points checked along each straight joint-space path from θ = 0 to a box vertex.
    pub path_steps: usize,
    /// Additional random interior points checked per box.
    pub random_points: usize,
    /// Bisection steps per bound.
    pub bisection_steps: usize,
    /// Seed of the interior points.
    pub seed: u64,
}

impl Default for StrokeOptions {
    fn default() -> Self {
        StrokeOptions {
            homeomorphism_c: 1e6,
            singular_margin: 1e-3,
            path_steps: 24,
            random_points: 256,
            bisection_steps: 14,
            seed: 0,
        }
    }
}

/// Why a joint vector is rejected, or `None` if it satisfies all constraints of §4.3.3. `guess` is the
/// FK warm start; the pose found is returned on success.
fn check_point(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    det_home: f64,
    opts: &StrokeOptions,
) -> core::result::Result<Vec6, &'static str> {
    let kappa = kp.reading_from_theta(theta);
    let pose = fk_reading(kp, &kappa, guess).map_err(|_| "forward kinematics failed")?;
    // homeomorphism of the joint/pose map: IK must return the same joint vector (unique branch)
    let back = ik(kp, &pose).map_err(|_| "inverse kinematics failed")?;
    if (back - theta).amax() > 1e-7 {
        return Err("IK branch differs from the commanded joints");
    }
    let g = LegGeometry::from_pose_and_theta(kp, &pose, theta);
    let a1 = g.j_a1();
    for i in 0..LEGS {
        if a1[i] * leg_side(i) < opts.singular_margin * 1e-2 {
            return Err("type-I singularity (sign of J_a1 changed)");
        }
    }
    let a2 = g.j_a2();
    let det = a2.determinant();
    let rel = det / det_home;
    if rel.is_nan() || rel <= opts.singular_margin {
        return Err("type-II singularity (det J_a2 sign change or near zero)");
    }
    let Some(a2_inv) = a2.try_inverse() else {
        return Err("type-II singularity");
    };
    let jad2 = a2_inv * nalgebra::Matrix6::from_diagonal(&a1);
    let frob2 = jad2.norm_squared();
    let det_jad2 = jad2.determinant().abs();
    if frob2.powi(3) > opts.homeomorphism_c * det_jad2 {
        return Err("homeomorphism condition eq. 4.22 violated");
    }
    Ok(pose)
}

fn det_home(kp: &KinematicParams) -> Result<f64> {
    let pose = fk_reading(kp, &kp.reading_from_theta(&Vec6::zeros()), &home_pose())
        .map_err(IdentError::Core)?;
    Ok(LegGeometry::from_pose_and_theta(kp, &pose, &Vec6::zeros())
        .j_a2()
        .determinant())
}

/// Whether the whole box [lo, hi]⁶ satisfies the constraints: every vertex reached along a straight
/// path from θ = 0 (continuation, so a sign change of det J_a2 on the way is seen: the Cauchy-index
/// test), plus random interior points.
fn box_feasible(kp: &KinematicParams, lo: f64, hi: f64, dh: f64, opts: &StrokeOptions) -> bool {
    for v in 0..64u32 {
        let vertex = Vec6::from_fn(|i, _| if v & (1 << i) != 0 { hi } else { lo });
        let mut guess = home_pose();
        for s in 1..=opts.path_steps {
            let th = vertex * (s as f64 / opts.path_steps as f64);
            match check_point(kp, &th, &guess, dh, opts) {
                Ok(p) => guess = p,
                Err(_) => return false,
            }
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(opts.seed);
    for _ in 0..opts.random_points {
        let th = Vec6::from_fn(|_, _| rng.random_range(lo..=hi));
        // reach it by continuation too
        let mut guess = home_pose();
        for s in 1..=4 {
            match check_point(kp, &(th * (s as f64 / 4.0)), &guess, dh, opts) {
                Ok(p) => guess = p,
                Err(_) => return false,
            }
        }
    }
    true
}

/// The actuator stroke (lo, hi) (rad, relative to the initial angles θ0) of §4.4.1 with default
/// options. The thesis reports (−57.1°, 57.1°) for its robot.
pub fn stroke(kp: &KinematicParams) -> Result<(f64, f64)> {
    stroke_with(kp, &StrokeOptions::default())
}

/// Stroke search (eq. 4.24, all μ_i = 1, common bounds for all legs by symmetry): bisection of a
/// symmetric bound, then of each bound alone, keeping the box [lo, hi]⁶ free of type-I and type-II
/// singularities and inside the homeomorphism region of eq. 4.22.
pub fn stroke_with(kp: &KinematicParams, opts: &StrokeOptions) -> Result<(f64, f64)> {
    kp.validate()?;
    let dh = det_home(kp)?;
    let limit = core::f64::consts::FRAC_PI_2 - 1e-6;
    let bisect = |feasible: &dyn Fn(f64) -> bool, mut ok: f64, mut bad: f64| {
        for _ in 0..opts.bisection_steps {
            let mid = 0.5 * (ok + bad);
            if feasible(mid) {
                ok = mid;
            } else {
                bad = mid;
            }
        }
        ok
    };
    if !box_feasible(kp, -1e-3, 1e-3, dh, opts) {
        return Err(IdentError::InvalidInput(
            "the initial configuration itself violates the stroke constraints".into(),
        ));
    }
    let s = if box_feasible(kp, -limit, limit, dh, opts) {
        limit
    } else {
        bisect(&|s| box_feasible(kp, -s, s, dh, opts), 1e-3, limit)
    };
    let hi = bisect(&|h| box_feasible(kp, -s, h, dh, opts), s, limit);
    let lo = -bisect(&|l| box_feasible(kp, -l, hi, dh, opts), s, limit);
    Ok((lo, hi))
}

/// Options of the configuration selection (§4.4.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectionOptions {
    /// Size of the random starting set (thesis: 13).
    pub start: usize,
    /// Number of random candidates tried (thesis: 5000).
    pub candidates: usize,
    /// Stroke (rad); `None` computes it with [`stroke`].
    pub stroke: Option<(f64, f64)>,
    /// Margin for the uncertainty of the true robot, in Table 4.2 σ (default 3; 0 = none). The true
    /// joint angle under a command θ (drive convention) is θ + Δθ_err + Δη_err·κ, so configurations
    /// are drawn from the stroke shrunk by `margin_sigma`·√(σ_Δθ² + (σ_η·θ/η)²) at each end (see
    /// [`stroke_margin`]), and each candidate must also satisfy the stroke constraints on
    /// `prior_robots` robots drawn from Table 4.2 (lengths and positions included), at the joint
    /// angles the command gives them.
    pub margin_sigma: f64,
    /// Robots drawn from Table 4.2 on which every candidate must be feasible (default 8; 0 = none).
    pub prior_robots: usize,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        SelectionOptions {
            start: 13,
            candidates: 5000,
            stroke: None,
            margin_sigma: 3.0,
            prior_robots: 8,
        }
    }
}

/// The stroke (lo, hi) (rad) shrunk so that a command inside it stays inside `stroke` on a true robot
/// whose offset and gain errors are `k_sigma` × Table 4.2's σ: each end θ_e moves to the θ with
/// |θ| + k·√(σ_Δθ² + (σ_η·|θ|/η)²) = |θ_e| (η: the mean nominal gain of `kp`).
pub fn stroke_margin(kp: &KinematicParams, stroke: (f64, f64), k_sigma: f64) -> (f64, f64) {
    if k_sigma <= 0.0 {
        return stroke;
    }
    let eta = kp.eta.iter().map(|e| e.abs()).sum::<f64>() / LEGS as f64;
    let widen = |t: f64| {
        let rel = crate::model::SIGMA_ETA * t / eta;
        t + k_sigma * (crate::model::SIGMA_DTHETA.powi(2) + rel * rel).sqrt()
    };
    let shrink = |end: f64| {
        let (mut lo, mut hi) = (0.0, end.abs());
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if widen(mid) <= end.abs() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo.copysign(end)
    };
    (shrink(stroke.0), shrink(stroke.1))
}

/// Result of the configuration selection.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionReport {
    /// Selected joint vectors (rad, nominal convention); element 0 is the initial configuration θ = 0.
    pub thetas: Vec<Vec6>,
    /// O1 (eq. 4.23) of the final set.
    pub index: f64,
    /// Candidates tried.
    pub iterations: usize,
    /// Iteration of the last improvement.
    pub last_improvement: usize,
    /// Stroke (rad) before the margin.
    pub stroke: (f64, f64),
    /// The range configurations were drawn from: the stroke shrunk by the margin (rad).
    pub inner_stroke: (f64, f64),
}

/// Exact (noise-free) data of the nominal model at joint vectors `thetas`.
fn nominal_data(kp: &KinematicParams, thetas: &[Vec6]) -> Result<CalibrationData> {
    let sensor = Vec6::from(NOMINAL_SENSOR_IN_BASE);
    let target = Vec6::from(NOMINAL_TARGET_IN_EFFECTOR);
    let mut data = CalibrationData::default();
    let mut guess = home_pose();
    for th in thetas {
        let kappa = kp.reading_from_theta(th);
        let pose = fk_reading(kp, &kappa, &guess)?;
        guess = pose;
        let cam = compose(&compose(&pose_inverse(&sensor), &pose), &target);
        data.configurations.push(ConfigurationData {
            theta_cmd: (*th).into(),
            kappa: kappa.into(),
            sensor_pose: Some(cam.into()),
            kappa_samples: 1,
            camera_frames: 1,
            ..ConfigurationData::default()
        });
    }
    Ok(data)
}

/// Gram matrix blocks (JᵀJ of the gauge-reduced, Table 4.2-scaled Jacobian) of single configurations.
struct Blocks {
    method: Method,
    kp: KinematicParams,
    x: nalgebra::DVector<f64>,
    q: DMatrix<f64>,
    s: nalgebra::DVector<f64>,
}

impl Blocks {
    fn new(method: Method, kp: &KinematicParams) -> Self {
        let layout = Layout::new(method, *kp);
        let sensor = Vec6::from(NOMINAL_SENSOR_IN_BASE);
        let x = layout.pack(kp, Some(&sensor), &Vec6::from(NOMINAL_TARGET_IN_EFFECTOR));
        let q = layout.free_basis(&x);
        Blocks {
            method,
            kp: *kp,
            x,
            q,
            s: layout.scales(),
        }
    }

    fn free(&self) -> usize {
        self.q.ncols()
    }

    /// Reduced Jacobian rows of configuration θ (6 × free).
    fn rows(&self, theta: &Vec6) -> Result<DMatrix<f64>> {
        let thetas = match self.method {
            Method::Rpba => vec![Vec6::zeros(), *theta],
            Method::Implicit => vec![*theta, *theta],
        };
        let data = nominal_data(&self.kp, &thetas)?;
        let (_, mut j) = residuals_and_jacobian(
            self.method,
            &data,
            &self.kp,
            &self.x,
            JacobianMode::Analytic,
        )?;
        for c in 0..j.ncols() {
            j.column_mut(c).scale_mut(self.s[c]);
        }
        Ok(j.rows(0, 6) * &self.q)
    }

    fn gram(&self, theta: &Vec6) -> Result<DMatrix<f64>> {
        let r = self.rows(theta)?;
        Ok(r.transpose() * r)
    }
}

/// O1 = (σ_1·…·σ_ς)^{1/ς}/√m (eq. 4.23) from the Gram matrix JᵀJ of m configurations; 0 if singular.
fn index_from_gram(gram: &DMatrix<f64>, m: usize) -> f64 {
    let n = gram.nrows();
    match gram.clone().cholesky() {
        Some(ch) => {
            let logdet: f64 = ch.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
            (logdet / (2.0 * n as f64)).exp() / (m as f64).sqrt()
        }
        None => 0.0,
    }
}

/// Observability index O1 (eq. 4.23) of a configuration set (`thetas[0]` = initial configuration)
/// for `method`, on the gauge-reduced Jacobian scaled by Table 4.2 (ς = 56 for RPBA, 62 implicit).
pub fn observability_index(kp: &KinematicParams, method: Method, thetas: &[Vec6]) -> Result<f64> {
    if thetas.len() < 2 {
        return Err(IdentError::InvalidInput(
            "need the initial and at least one more configuration".into(),
        ));
    }
    let blocks = Blocks::new(method, kp);
    let (grams, m) = set_grams(&blocks, thetas)?;
    let sum = grams
        .iter()
        .fold(DMatrix::zeros(blocks.free(), blocks.free()), |a, g| a + g);
    Ok(index_from_gram(&sum, m))
}

fn set_grams(blocks: &Blocks, thetas: &[Vec6]) -> Result<(Vec<DMatrix<f64>>, usize)> {
    let members: &[Vec6] = match blocks.method {
        Method::Rpba => thetas.get(1..).unwrap_or(&[]),
        Method::Implicit => thetas,
    };
    let grams = members
        .iter()
        .map(|t| blocks.gram(t))
        .collect::<Result<Vec<_>>>()?;
    let m = grams.len();
    Ok((grams, m))
}

/// Optimal calibration configurations (§4.4.2) with the default options (13 random start, 5000
/// candidates, stroke from [`stroke`]). Element 0 is the initial configuration θ = 0.
pub fn select_configurations(kp: &KinematicParams, method: Method, seed: u64) -> Result<Vec<Vec6>> {
    Ok(select_configurations_with(kp, method, seed, &SelectionOptions::default())?.thetas)
}

/// Configuration selection with options: starting from `start` random feasible configurations, each
/// of `candidates` random feasible configurations in the stroke is added if it raises O1, after which
/// every configuration whose removal raises O1 is removed (best first).
pub fn select_configurations_with(
    kp: &KinematicParams,
    method: Method,
    seed: u64,
    opts: &SelectionOptions,
) -> Result<SelectionReport> {
    let stroke = match opts.stroke {
        Some(s) => s,
        None => stroke(kp)?,
    };
    if !(stroke.0 < 0.0 && stroke.1 > 0.0) {
        return Err(IdentError::InvalidInput(format!(
            "stroke {stroke:?} must contain 0"
        )));
    }
    let blocks = Blocks::new(method, kp);
    let dh = det_home(kp)?;
    let sopts = StrokeOptions::default();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let inner = stroke_margin(kp, stroke, opts.margin_sigma.max(0.0));
    let mut prior_rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5E1E_C7ED);
    let prior = (0..opts.prior_robots)
        .map(|_| {
            let t = crate::generator::TrueRobot::draw(kp, &mut prior_rng).kp;
            det_home(&t).map(|d| (t, d))
        })
        .collect::<Result<Vec<_>>>()?;
    // the command θ (in `kp`'s convention) moves robot `t` to t.θ(κ(θ))
    let feasible_on_prior = |th: &Vec6| {
        prior.iter().all(|(t, d)| {
            let th_t = t.theta_from_reading(&kp.reading_from_theta(th));
            check_point(t, &th_t, &home_pose(), *d, &sopts).is_ok()
        })
    };
    let draw = |rng: &mut ChaCha8Rng| -> Result<(Vec6, DMatrix<f64>)> {
        for _ in 0..1000 {
            let th = Vec6::from_fn(|_, _| rng.random_range(inner.0..inner.1));
            if check_point(kp, &th, &home_pose(), dh, &sopts).is_ok() && feasible_on_prior(&th) {
                if let Ok(g) = blocks.gram(&th) {
                    return Ok((th, g));
                }
            }
        }
        Err(IdentError::InvalidInput(
            "no feasible configuration found in the stroke".into(),
        ))
    };
    let base = match method {
        Method::Rpba => DMatrix::zeros(blocks.free(), blocks.free()),
        Method::Implicit => blocks.gram(&Vec6::zeros())?,
    };
    let extra = usize::from(method == Method::Implicit);
    let mut set: Vec<(Vec6, DMatrix<f64>)> = Vec::new();
    for _ in 0..opts.start.max(1) {
        set.push(draw(&mut rng)?);
    }
    let total = |set: &[(Vec6, DMatrix<f64>)]| set.iter().fold(base.clone(), |a, (_, g)| a + g);
    let mut sum = total(&set);
    let mut index = index_from_gram(&sum, set.len() + extra);
    let mut last_improvement = 0;
    for it in 1..=opts.candidates {
        let (th, g) = draw(&mut rng)?;
        let with = &sum + &g;
        let new_index = index_from_gram(&with, set.len() + 1 + extra);
        if new_index <= index {
            continue;
        }
        set.push((th, g));
        sum = with;
        index = new_index;
        last_improvement = it;
        // drop-if-worse: remove configurations whose absence raises the index, best first
        loop {
            let mut best: Option<(usize, f64)> = None;
            for k in 0..set.len().saturating_sub(1) {
                let without = &sum - &set[k].1;
                let v = index_from_gram(&without, set.len() - 1 + extra);
                if v > index && best.is_none_or(|(_, b)| v > b) {
                    best = Some((k, v));
                }
            }
            match best {
                Some((k, v)) => {
                    let (_, g) = set.remove(k);
                    sum -= g;
                    index = v;
                }
                None => break,
            }
        }
    }
    let mut thetas = vec![Vec6::zeros()];
    thetas.extend(set.iter().map(|(t, _)| *t));
    let _ = N_GAUGE;
    Ok(SelectionReport {
        thetas,
        index,
        iterations: opts.candidates,
        last_improvement,
        stroke,
        inner_stroke: inner,
    })
}
