//! The calibration parameter vector x = [b (60); external], its names, its Table 4.2 scales and the
//! gauge (frame-choice) symmetries that no pose measurement can resolve (§4.3.4).
//!
//! # Gauge freedoms
//!
//! Both residuals are unchanged by two families of frame changes, so the Jacobians J_I (eq. 4.15) and
//! J_R (eq. 4.21) always have a 10-dimensional null space (the thesis reports full rank; with exact
//! derivatives it cannot be):
//!
//! * **base frame** (4): translating the base frame by t and rotating it by φ about ŝ = ẑ moves every
//!   B_i to R_z(φ)B_i + t and adds φ to every offset Δθ_i (θ0 is not a parameter, so Δθ carries the
//!   wrench direction). The revolute axes stay along ẑ, so tilts of the base are *not* gauge. RPBA sees
//!   only pose changes, which this leaves invariant; the implicit method absorbs it in ᴼχ_C.
//! * **end-effector frame** (6): any rigid change H of ΣE maps A'_i to H⁻¹A'_i and ᴱχ_t to H⁻¹∘ᴱχ_t and
//!   leaves every A_i and every target pose unchanged.
//!
//! The solvers restrict their steps to the orthogonal complement of these directions in the metric
//! scaled by Table 4.2 (the minimum-norm choice), and the error norms of Tables 4.3/4.4 are compared after
//! the best gauge alignment ([`gauge_aligned_error`]).

use crate::error::Method;
use crate::se3::iso;
use nalgebra::{DMatrix, DVector, Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rss6_core::{
    compose, isometry_to_pose, pose_inverse, KinematicParams, Vec6, LEGS, N_KIN_ERRORS,
};

/// Number of gauge (frame-choice) directions: 4 for the base frame, 6 for the end-effector frame.
pub const N_GAUGE: usize = 10;

/// Table 4.2 standard deviations: positions and lengths (m).
pub const SIGMA_LENGTH: f64 = rss6_core::thesis::SIGMA_LENGTH;
/// Table 4.2: potentiometer gain η (rad/bit).
pub const SIGMA_ETA: f64 = rss6_core::thesis::SIGMA_ETA;
/// Table 4.2: potentiometer offset Δθ (rad).
pub const SIGMA_DTHETA: f64 = rss6_core::thesis::SIGMA_DTHETA;
/// Table 4.2: external pose positions (m).
pub const SIGMA_EXT_POSITION: f64 = rss6_core::thesis::SIGMA_EXT_POSITION;
/// Table 4.2: external pose angles (rad).
pub const SIGMA_EXT_ANGLE: f64 = rss6_core::thesis::SIGMA_EXT_ANGLE;

/// Layout of the parameter vector for one method.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Layout {
    pub(crate) method: Method,
    pub(crate) reference: KinematicParams,
}

impl Layout {
    pub(crate) fn new(method: Method, reference: KinematicParams) -> Self {
        Layout { method, reference }
    }

    /// Total parameters: 66 (RPBA) or 72 (implicit).
    pub(crate) fn n(&self) -> usize {
        match self.method {
            Method::Rpba => N_KIN_ERRORS + 6,
            Method::Implicit => N_KIN_ERRORS + 12,
        }
    }

    pub(crate) fn sensor_offset(&self) -> Option<usize> {
        match self.method {
            Method::Rpba => None,
            Method::Implicit => Some(N_KIN_ERRORS),
        }
    }

    pub(crate) fn target_offset(&self) -> usize {
        self.n() - 6
    }

    pub(crate) fn pack(
        &self,
        kp: &KinematicParams,
        sensor: Option<&Vec6>,
        target: &Vec6,
    ) -> DVector<f64> {
        let mut x = DVector::zeros(self.n());
        let b = kp.errors_from(&self.reference);
        x.rows_mut(0, N_KIN_ERRORS).copy_from_slice(&b);
        if let (Some(o), Some(s)) = (self.sensor_offset(), sensor) {
            x.rows_mut(o, 6).copy_from(s);
        }
        x.rows_mut(self.target_offset(), 6).copy_from(target);
        x
    }

    pub(crate) fn errors(&self, x: &DVector<f64>) -> [f64; N_KIN_ERRORS] {
        let mut b = [0.0; N_KIN_ERRORS];
        b.copy_from_slice(x.rows(0, N_KIN_ERRORS).as_slice());
        b
    }

    pub(crate) fn kp(&self, x: &DVector<f64>) -> KinematicParams {
        self.reference.with_errors(&self.errors(x))
    }

    pub(crate) fn sensor(&self, x: &DVector<f64>) -> Option<Vec6> {
        self.sensor_offset()
            .map(|o| Vec6::from_iterator(x.rows(o, 6).iter().copied()))
    }

    pub(crate) fn target(&self, x: &DVector<f64>) -> Vec6 {
        Vec6::from_iterator(x.rows(self.target_offset(), 6).iter().copied())
    }

    /// Table 4.2 standard deviation of every parameter (the column scaling of the solver).
    pub(crate) fn scales(&self) -> DVector<f64> {
        DVector::from_iterator(self.n(), (0..self.n()).map(parameter_scale))
    }

    pub(crate) fn names(&self) -> Vec<String> {
        parameter_names(self.method)
    }

    /// Applies the gauge transformation g = [t_x, t_y, t_z, φ_z, h (pose of the new ΣE in the old)].
    pub(crate) fn apply_gauge(&self, x: &DVector<f64>, g: &[f64; N_GAUGE]) -> DVector<f64> {
        let base = Isometry3::from_parts(
            Translation3::new(g[0], g[1], g[2]),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), g[3]),
        );
        let h = Vec6::new(g[4], g[5], g[6], g[7], g[8], g[9]);
        let h_inv = iso(&h).inverse();
        let mut kp = self.kp(x);
        for i in 0..LEGS {
            let b = base * Point3::from(kp.base_joints[i]);
            kp.base_joints[i] = b.coords;
            kp.dtheta[i] += g[3];
            let a = h_inv * Point3::from(kp.platform_joints[i]);
            kp.platform_joints[i] = a.coords;
        }
        let sensor = self
            .sensor(x)
            .map(|s| compose(&isometry_to_pose(&base), &s));
        let target = compose(&pose_inverse(&h), &self.target(x));
        self.pack(&kp, sensor.as_ref(), &target)
    }

    /// The 10 gauge directions at x (columns, unscaled parameter units), by central differences of the
    /// exact gauge action.
    pub(crate) fn gauge_basis(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let h = 1e-6;
        let mut g = DMatrix::zeros(self.n(), N_GAUGE);
        for k in 0..N_GAUGE {
            let mut gp = [0.0; N_GAUGE];
            gp[k] = h;
            let plus = self.apply_gauge(x, &gp);
            gp[k] = -h;
            let minus = self.apply_gauge(x, &gp);
            let mut col = (plus - minus) / (2.0 * h);
            // angles wrap: keep the derivative finite near ±π
            for j in 0..self.n() {
                if col[j].abs() > 1e3 {
                    col[j] = 0.0;
                }
            }
            g.set_column(k, &col);
        }
        g
    }

    /// Orthonormal basis (n × (n − 10)) of the complement of the gauge span in the scaled metric.
    pub(crate) fn free_basis(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let s = self.scales();
        let mut g = self.gauge_basis(x);
        for j in 0..self.n() {
            let inv = 1.0 / s[j];
            g.row_mut(j).scale_mut(inv);
        }
        complement_basis(&g)
    }

    /// Free basis when the sensor pose ᴼχ_C is held fixed (implicit only): the base-frame gauge is
    /// then resolved by the fixed sensor, leaving the 6 end-effector gauge directions and the 6 pinned
    /// coordinates to remove (n − 12 free directions).
    pub(crate) fn free_basis_fixed_sensor(&self, x: &DVector<f64>) -> DMatrix<f64> {
        let Some(o) = self.sensor_offset() else {
            return self.free_basis(x);
        };
        let s = self.scales();
        let g = self.gauge_basis(x);
        let mut m = DMatrix::zeros(self.n(), 12);
        for k in 0..6 {
            let mut col = g.column(4 + k).into_owned();
            for j in 0..self.n() {
                col[j] /= s[j];
            }
            for j in o..o + 6 {
                col[j] = 0.0;
            }
            m.set_column(k, &col);
            m[(o + k, 6 + k)] = 1.0;
        }
        complement_basis(&m)
    }
}

/// Orthonormal basis of the orthogonal complement of the column span of `g` (n × k, full column rank).
pub(crate) fn complement_basis(g: &DMatrix<f64>) -> DMatrix<f64> {
    let n = g.nrows();
    let k = g.ncols();
    // Full SVD via the eigen-decomposition of the projector I − G G⁺ would also do; SVD of [G | I] is
    // simplest: the left singular vectors of G beyond its rank span the complement.
    let svd = nalgebra::linalg::SVD::new(g.clone() * g.transpose(), true, false);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let mut q = DMatrix::zeros(n, n - k);
    if let Some(u) = svd.u.as_ref() {
        for (c, &j) in order.iter().skip(k).enumerate() {
            q.set_column(c, &u.column(j));
        }
    }
    q
}

/// Table 4.2 standard deviation of parameter j of the (RPBA or implicit) parameter vector. External
/// parameters (j ≥ 60) alternate position/angle triples.
pub fn parameter_scale(j: usize) -> f64 {
    match j {
        0..=47 => SIGMA_LENGTH,
        48..=53 => SIGMA_ETA,
        54..=59 => SIGMA_DTHETA,
        _ => {
            if (j - 60) % 6 < 3 {
                SIGMA_EXT_POSITION
            } else {
                SIGMA_EXT_ANGLE
            }
        }
    }
}

/// Names of the parameters of `method`, in vector order: `dA'1x … dA'6z`, `dB1x … dB6z`, `dl_AT1 …`,
/// `dl_TB1 …`, `deta1 …`, `dtheta1 …`, then (implicit only) `sensor_x … sensor_gamma` (ᴼχ_C) and
/// `target_x … target_gamma` (ᴱχ_t).
pub fn parameter_names(method: Method) -> Vec<String> {
    let mut names = Vec::with_capacity(72);
    let axes = ["x", "y", "z"];
    for i in 1..=LEGS {
        for a in axes {
            names.push(format!("dA'{i}{a}"));
        }
    }
    for i in 1..=LEGS {
        for a in axes {
            names.push(format!("dB{i}{a}"));
        }
    }
    for prefix in ["dl_AT", "dl_TB", "deta", "dtheta"] {
        for i in 1..=LEGS {
            names.push(format!("{prefix}{i}"));
        }
    }
    let pose = ["x", "y", "z", "alpha", "beta", "gamma"];
    if method == Method::Implicit {
        for p in pose {
            names.push(format!("sensor_{p}"));
        }
    }
    for p in pose {
        names.push(format!("target_{p}"));
    }
    names
}

/// Descriptions of the 10 gauge directions, in the order of the gauge vector.
pub const GAUGE_DESCRIPTIONS: [&str; N_GAUGE] = [
    "base frame x-translation (all dB_ix together, with sensor pose)",
    "base frame y-translation (all dB_iy together, with sensor pose)",
    "base frame z-translation (all dB_iz together, with sensor pose)",
    "base frame rotation about the motor axis z (dB_i rotate, all dtheta_i shift equally)",
    "end-effector frame x-translation (all dA'_i with the target pose)",
    "end-effector frame y-translation (all dA'_i with the target pose)",
    "end-effector frame z-translation (all dA'_i with the target pose)",
    "end-effector frame rotation about x (dA'_i with the target pose)",
    "end-effector frame rotation about y (dA'_i with the target pose)",
    "end-effector frame rotation about z (dA'_i with the target pose)",
];

/// Parameter estimation error after removing the gauge: the smallest Table 4.2-scaled distance
/// ‖S⁻¹(g(x̂) − x_true)‖ over all frame changes g, and the aligned raw difference g(x̂) − x_true
/// (SI units). `estimate` and `truth` are parameter vectors of the same method (see
/// [`crate::calibrate::parameter_vector`]).
pub fn gauge_aligned_error(
    method: Method,
    reference: &KinematicParams,
    estimate: &DVector<f64>,
    truth: &DVector<f64>,
) -> (f64, DVector<f64>) {
    let layout = Layout::new(method, *reference);
    let s = layout.scales();
    let scaled = |d: &DVector<f64>| d.component_div(&s);
    let diff = |x: &DVector<f64>| {
        let mut d = x - truth;
        for o in [layout.sensor_offset(), Some(layout.target_offset())]
            .into_iter()
            .flatten()
        {
            for k in 3..6 {
                d[o + k] = rss6_core::wrap_angle(d[o + k]);
            }
        }
        d
    };
    let mut g = [0.0; N_GAUGE];
    for _ in 0..10 {
        let x = layout.apply_gauge(estimate, &g);
        let r = scaled(&diff(&x));
        // Jacobian of the aligned residual w.r.t. g by central differences of the exact action.
        let h = 1e-7;
        let mut j = DMatrix::zeros(layout.n(), N_GAUGE);
        for k in 0..N_GAUGE {
            let mut gp = g;
            gp[k] += h;
            let mut gm = g;
            gm[k] -= h;
            let col = (scaled(&diff(&layout.apply_gauge(estimate, &gp)))
                - scaled(&diff(&layout.apply_gauge(estimate, &gm))))
                / (2.0 * h);
            j.set_column(k, &col);
        }
        let Some(step) = (j.transpose() * &j).lu().solve(&(-(j.transpose() * &r))) else {
            break;
        };
        for k in 0..N_GAUGE {
            g[k] += step[k];
        }
        if step.amax() < 1e-12 {
            break;
        }
    }
    let d = diff(&layout.apply_gauge(estimate, &g));
    (scaled(&d).norm(), d)
}
