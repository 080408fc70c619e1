//! Singularity and uniqueness checks of the workspace (thesis §4.3.3, §4.4.1).
//!
//! Three conditions, evaluated at a pose from one [`LegGeometry`]:
//!
//! * **type I** (inverse-kinematic singularity, §4.3.3): every diagonal entry of J_a1 (eq. 3.29) keeps
//!   the nominal sign [+, −, +, −, +, −] ([`TYPE_I_SIGNS`]); the *margin* is min_i s_i·(J_a1)_ii (m²),
//!   positive when the pose is type-I free;
//! * **type II** (direct-kinematic singularity): det J_a2 ≠ 0 with the sign it has at home (the Cauchy
//!   index ∇ of J_a2 does not change along a path iff the sign of det J_a2 does not), plus the
//!   conditioning of J_ad = J_a1⁻¹J_a2 (eq. 3.30): its smallest singular value σ_min and its condition
//!   number σ_max/σ_min (SI units: columns m/s and rad/s, rows rad/s);
//! * **homeomorphism** (eq. 4.22): (Σσ_i²)^{n/2} ≤ C·|Πλ_i| for J_ad2 = J_a2⁻¹J_a1 (= J_ad⁻¹), n = 6.
//!   Σσ_i² is the squared Frobenius norm and |Πλ_i| = |det J_ad2|, so no eigen-decomposition is
//!   needed; [`HomeomorphismCheck::ratio`] is the smallest C that satisfies eq. 4.22 at the pose. By the
//!   AM–GM inequality the ratio is ≥ n^{n/2} = 216 everywhere; the condition says it stays bounded.
//!
//! [`scan_box`] evaluates all three on a regular grid of a pose box ([`PoseBox`]) and reports the
//! extreme values; [`verify_box`] turns the first violation of [`BoxLimits`] into a typed error.
//!
//! # The documented singularity-free box
//!
//! [`PoseBox::documented`] is home χ = [0, 0, 0.115, 0, 0, 0] ± [20 mm, 20 mm, 20 mm, 0.05 rad,
//! 0.05 rad, 0.05 rad]. For the nominal robot a 7⁶-point grid (117 649 poses, every vertex included)
//! gives (see `docs/kinematics.md`, reproduced by `tests/workspace.rs`): every pose reachable in the
//! IK branch with max |θ_i| = 61.7°; type-I margin ≥ 4.78·10⁻³ m² (home: 9.77·10⁻³); det J_a2 > 0
//! everywhere (≥ 8.9·10⁻⁷ m⁹); cond(J_ad) ≤ 14.39 (home: 7.22); eq. 4.22 ratio ≤ 1.84·10⁴ (home:
//! 5.68·10³). So [`BoxLimits::documented`] (margin ≥ 10⁻³ m², cond ≤ 15, C = 2·10⁴) holds on the
//! whole grid. All numbers are SI.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::jacobian::{LegGeometry, TYPE_I_TOLERANCE};
use crate::params::{home_pose, leg_side, KinematicParams};
use crate::types::{Mat6, Vec6, LEGS};

/// `x ≥ bound`, false if either is NaN (so `!at_least` flags NaN as a violation).
fn at_least(x: f64, bound: f64) -> bool {
    x >= bound
}

/// Sign pattern of diag J_a1 in the working mode (§4.4.1 condition (2)): [+, −, +, −, +, −].
pub const TYPE_I_SIGNS: [f64; LEGS] = [
    leg_side(0),
    leg_side(1),
    leg_side(2),
    leg_side(3),
    leg_side(4),
    leg_side(5),
];

/// Result of the type-I check at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TypeICheck {
    /// diag J_a1 = (w_i × l_i)·ẑ (eq. 3.29), m².
    pub diag: Vec6,
    /// min_i s_i·(J_a1)_ii with s = [`TYPE_I_SIGNS`] (m²): > 0 iff every sign matches.
    pub margin: f64,
    /// The leg (0-based) attaining the margin.
    pub worst_leg: u8,
}

impl TypeICheck {
    /// True if every diagonal entry has the nominal sign with |entry| > [`TYPE_I_TOLERANCE`].
    pub fn is_free(&self) -> bool {
        self.margin > TYPE_I_TOLERANCE
    }
}

/// Type-I check from a leg geometry: the sign pattern of diag J_a1 (§4.3.3).
pub fn type_i_check(geo: &LegGeometry) -> TypeICheck {
    let diag = geo.j_a1();
    let mut margin = f64::INFINITY;
    let mut worst_leg = 0u8;
    for (i, (d, s)) in diag.iter().zip(TYPE_I_SIGNS.iter()).enumerate() {
        let m = d * s;
        // `!at_least` also catches NaN.
        if !at_least(m, margin) {
            margin = m;
            worst_leg = i as u8;
        }
    }
    TypeICheck {
        diag,
        margin,
        worst_leg,
    }
}

/// Result of the type-II check at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TypeIICheck {
    /// det J_a2 (eq. 3.29), m⁹.
    pub det_j_a2: f64,
    /// Smallest singular value of J_ad (eq. 3.30), SI units.
    pub sigma_min: f64,
    /// Largest singular value of J_ad, SI units.
    pub sigma_max: f64,
    /// Condition number σ_max/σ_min of J_ad (∞ if σ_min = 0).
    pub condition: f64,
}

impl TypeIICheck {
    /// True if det J_a2 has the sign `reference_sign` (e.g. its sign at home) and
    /// cond(J_ad) ≤ `max_condition`.
    pub fn is_free(&self, reference_sign: f64, max_condition: f64) -> bool {
        self.det_j_a2 * reference_sign > 0.0 && self.condition <= max_condition
    }
}

/// Type-II check from a leg geometry: det J_a2 and the singular values of J_ad.
///
/// Errors: [`CoreError::Singular`]`(TypeI)` when J_ad is undefined (a diagonal entry of J_a1 vanished),
/// [`CoreError::Singular`]`(Matrix)` when the singular-value decomposition does not converge,
/// [`CoreError::NonFinite`] when J_ad overflowed (extreme geometry): nalgebra's SVD panics on a
/// NaN singular value, so it never sees one.
pub fn type_ii_check(geo: &LegGeometry) -> Result<TypeIICheck> {
    let det_j_a2 = geo.j_a2().determinant();
    let j_ad = geo.j_ad()?;
    check_finite(j_ad.as_slice())?;
    let sv = j_ad
        .try_svd(false, false, f64::EPSILON, 200)
        .ok_or(CoreError::Singular(SingularKind::Matrix))?
        .singular_values;
    let sigma_min = sv.min();
    let sigma_max = sv.max();
    let condition = if sigma_min > 0.0 {
        sigma_max / sigma_min
    } else {
        f64::INFINITY
    };
    Ok(TypeIICheck {
        det_j_a2,
        sigma_min,
        sigma_max,
        condition,
    })
}

/// Result of the homeomorphism check (eq. 4.22) at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HomeomorphismCheck {
    /// Σσ_i² = ‖J_ad2‖_F² for J_ad2 = J_a2⁻¹ J_a1, SI units.
    pub frobenius_sq: f64,
    /// |Πλ_i| = |det J_ad2|.
    pub abs_det: f64,
    /// (Σσ_i²)^{n/2} / |Πλ_i| with n = 6: the smallest C for which eq. 4.22 holds here (≥ 216).
    pub ratio: f64,
}

impl HomeomorphismCheck {
    /// Eq. 4.22 with bound `c`: (Σσ_i²)^{n/2} ≤ C·|Πλ_i|.
    pub fn holds(&self, c: f64) -> bool {
        self.ratio <= c
    }
}

/// The homeomorphism quantities of eq. 4.22 from a leg geometry.
///
/// Errors: [`CoreError::Singular`]`(TypeII)` if J_a2 cannot be inverted.
pub fn homeomorphism_check(geo: &LegGeometry) -> Result<HomeomorphismCheck> {
    let d = geo.j_a1();
    let inv = geo
        .j_a2()
        .try_inverse()
        .ok_or(CoreError::Singular(SingularKind::TypeII))?;
    // J_ad2 = J_a2⁻¹·diag(d): scale column k of J_a2⁻¹ by d_k.
    let j_ad2 = Mat6::from_fn(|r, c| inv[(r, c)] * d[c]);
    let frobenius_sq = j_ad2.norm_squared();
    let abs_det = j_ad2.determinant().abs();
    let ratio = if abs_det > 0.0 {
        // (Σσ²)^{n/2} with n = 6 is (Σσ²)³.
        frobenius_sq * frobenius_sq * frobenius_sq / abs_det
    } else {
        f64::INFINITY
    };
    Ok(HomeomorphismCheck {
        frobenius_sq,
        abs_det,
        ratio,
    })
}

/// All three checks at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingularityCheck {
    /// Joint angles θ from IK (rad).
    pub theta: Vec6,
    /// Type-I check (sign pattern of diag J_a1).
    pub type_i: TypeICheck,
    /// Type-II check (det J_a2, conditioning of J_ad).
    pub type_ii: TypeIICheck,
    /// Homeomorphism check (eq. 4.22).
    pub homeomorphism: HomeomorphismCheck,
}

/// Runs IK at `pose` and the type-I, type-II and homeomorphism checks.
///
/// Errors: those of [`crate::ik`] (NaN input, unreachable, out of branch), [`CoreError::Singular`] if
/// J_ad or J_ad2 is undefined at the pose.
///
/// ```
/// use rss6_core::{home_pose, singularity_check, KinematicParams};
/// let c = singularity_check(&KinematicParams::nominal(), &home_pose()).unwrap();
/// assert!(c.type_i.is_free());
/// assert!(c.type_ii.condition < 12.0);
/// ```
pub fn singularity_check(kp: &KinematicParams, pose: &Vec6) -> Result<SingularityCheck> {
    let geo = LegGeometry::at_pose(kp, pose)?;
    Ok(SingularityCheck {
        theta: geo.theta,
        type_i: type_i_check(&geo),
        type_ii: type_ii_check(&geo)?,
        homeomorphism: homeomorphism_check(&geo)?,
    })
}

/// An axis-aligned box of poses: centre ± half widths, per component (m, rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseBox {
    /// Centre pose χ_c (m, rad).
    pub center: Vec6,
    /// Half widths (m for x, y, z; rad for α, β, γ), all ≥ 0.
    pub half_width: Vec6,
}

/// Half widths of the documented singularity-free box: ±20 mm in x, y, z, ±0.05 rad in α, β, γ.
pub const DOCUMENTED_BOX_HALF_WIDTH: [f64; 6] = [0.02, 0.02, 0.02, 0.05, 0.05, 0.05];

impl PoseBox {
    /// The documented singularity-free box: home ± [`DOCUMENTED_BOX_HALF_WIDTH`].
    pub fn documented() -> Self {
        PoseBox {
            center: home_pose(),
            half_width: Vec6::from_column_slice(&DOCUMENTED_BOX_HALF_WIDTH),
        }
    }

    /// The pose at normalised coordinates u ∈ [−1, 1]⁶: χ_c + u ⊙ half_width.
    pub fn point(&self, u: &Vec6) -> Vec6 {
        self.center + u.component_mul(&self.half_width)
    }

    /// True if `pose` lies in the closed box, with 1e-12 (m or rad) of slack for rounding so that
    /// [`Self::point`] of a vertex is inside (false for NaN).
    pub fn contains(&self, pose: &Vec6) -> bool {
        (0..6).all(|k| (pose[k] - self.center[k]).abs() <= self.half_width[k] + 1e-12)
    }
}

/// Acceptance bounds for [`scan_box`] / [`verify_box`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxLimits {
    /// Smallest accepted type-I margin min_i s_i·(J_a1)_ii (m²).
    pub min_type_i_margin: f64,
    /// Largest accepted condition number of J_ad.
    pub max_condition: f64,
    /// The constant C of eq. 4.22 (≥ 216 for n = 6, see the module docs).
    pub homeomorphism_c: f64,
}

impl BoxLimits {
    /// The bounds the documented box is verified against: type-I margin ≥ 1·10⁻³ m² (≈ 10 % of the
    /// home value 0.1·0.0977 m²), cond(J_ad) ≤ 15 (home: 7.2), C = 2·10⁴ (home ratio: 5.7·10³).
    pub fn documented() -> Self {
        BoxLimits {
            min_type_i_margin: 1e-3,
            max_condition: 15.0,
            homeomorphism_c: 2e4,
        }
    }
}

/// Which condition a pose of a scanned box violated.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ViolationKind {
    /// IK failed (unreachable or out of branch) or a Jacobian was undefined.
    Kinematics(CoreError),
    /// Type-I margin below the limit at this leg (0-based).
    TypeI {
        /// Leg index, 0..6.
        leg: u8,
    },
    /// det J_a2 has the opposite sign from the box centre (a type-II surface was crossed) or vanished.
    TypeIISign,
    /// cond(J_ad) above the limit.
    Conditioning,
    /// Eq. 4.22 violated for the limit's C.
    Homeomorphism,
}

/// The first violation found by [`scan_box`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxViolation {
    /// The offending pose (m, rad).
    pub pose: Vec6,
    /// What failed there.
    pub kind: ViolationKind,
}

impl BoxViolation {
    /// The typed error corresponding to the violation.
    pub fn to_error(&self) -> CoreError {
        match self.kind {
            ViolationKind::Kinematics(e) => e,
            ViolationKind::TypeI { .. } => CoreError::Singular(SingularKind::TypeI),
            ViolationKind::TypeIISign | ViolationKind::Conditioning => {
                CoreError::Singular(SingularKind::TypeII)
            }
            ViolationKind::Homeomorphism => CoreError::Singular(SingularKind::Homeomorphism),
        }
    }
}

/// Extreme values over a scanned pose box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxReport {
    /// Grid points evaluated.
    pub points: u32,
    /// Grid points that violated a limit.
    pub violations: u32,
    /// The first violation in scan order, if any.
    pub first_violation: Option<BoxViolation>,
    /// max |θ_i| over the box (rad).
    pub max_abs_theta: f64,
    /// Smallest type-I margin (m²).
    pub min_type_i_margin: f64,
    /// Sign of det J_a2 at the box centre (±1).
    pub det_sign: f64,
    /// Smallest |det J_a2| among points with the centre's sign (m⁹).
    pub min_abs_det_j_a2: f64,
    /// Smallest σ_min(J_ad).
    pub min_sigma: f64,
    /// Largest cond(J_ad).
    pub max_condition: f64,
    /// Largest eq. 4.22 ratio (the smallest C that holds over the whole grid).
    pub max_homeomorphism_ratio: f64,
    /// The pose with the largest cond(J_ad).
    pub worst_condition_pose: Vec6,
}

impl BoxReport {
    /// True if no grid point violated a limit.
    pub fn is_free(&self) -> bool {
        self.violations == 0
    }
}

/// Largest accepted `points_per_axis` of [`scan_box`] (16⁶ ≈ 1.7·10⁷ poses).
pub const MAX_POINTS_PER_AXIS: u32 = 16;

/// Evaluates [`singularity_check`] on a regular grid of `points_per_axis`⁶ poses of `bx` (every
/// vertex included) and reports the extremes and the first violation of `limits`.
///
/// Errors (only for bad arguments; violations are reported, not raised): [`CoreError::NonFinite`],
/// [`CoreError::InvalidParameter`] if `points_per_axis` ∉ [2, [`MAX_POINTS_PER_AXIS`]] or a half width is
/// negative, and the centre's own failure if the box centre is not a regular pose.
pub fn scan_box(
    kp: &KinematicParams,
    bx: &PoseBox,
    points_per_axis: u32,
    limits: &BoxLimits,
) -> Result<BoxReport> {
    check_finite(bx.center.as_slice())?;
    check_finite(bx.half_width.as_slice())?;
    if bx.half_width.iter().any(|&h| h < 0.0) {
        return Err(CoreError::InvalidParameter("box half widths must be >= 0"));
    }
    if !(2..=MAX_POINTS_PER_AXIS).contains(&points_per_axis) {
        return Err(CoreError::InvalidParameter(
            "points_per_axis must be in 2..=16",
        ));
    }
    let centre = singularity_check(kp, &bx.center)?;
    let det_sign = if centre.type_ii.det_j_a2 >= 0.0 {
        1.0
    } else {
        -1.0
    };
    let mut rep = BoxReport {
        points: 0,
        violations: 0,
        first_violation: None,
        max_abs_theta: 0.0,
        min_type_i_margin: f64::INFINITY,
        det_sign,
        min_abs_det_j_a2: f64::INFINITY,
        min_sigma: f64::INFINITY,
        max_condition: 0.0,
        max_homeomorphism_ratio: 0.0,
        worst_condition_pose: bx.center,
    };
    let n = points_per_axis;
    let total = n.pow(6);
    let step = 2.0 / f64::from(n - 1);
    for idx in 0..total {
        let mut u = Vec6::zeros();
        let mut rest = idx;
        for uk in u.iter_mut() {
            *uk = -1.0 + step * f64::from(rest % n);
            rest /= n;
        }
        let pose = bx.point(&u);
        rep.points += 1;
        let kind = match singularity_check(kp, &pose) {
            Err(e) => Some(ViolationKind::Kinematics(e)),
            Ok(c) => {
                rep.max_abs_theta = rep.max_abs_theta.max(c.theta.amax());
                rep.min_type_i_margin = rep.min_type_i_margin.min(c.type_i.margin);
                if c.type_ii.det_j_a2 * det_sign > 0.0 {
                    rep.min_abs_det_j_a2 = rep.min_abs_det_j_a2.min(c.type_ii.det_j_a2.abs());
                }
                rep.min_sigma = rep.min_sigma.min(c.type_ii.sigma_min);
                if !at_least(rep.max_condition, c.type_ii.condition) {
                    rep.max_condition = c.type_ii.condition;
                    rep.worst_condition_pose = pose;
                }
                rep.max_homeomorphism_ratio =
                    rep.max_homeomorphism_ratio.max(c.homeomorphism.ratio);
                if !at_least(c.type_i.margin, limits.min_type_i_margin) {
                    Some(ViolationKind::TypeI {
                        leg: c.type_i.worst_leg,
                    })
                } else if !at_least(c.type_ii.det_j_a2 * det_sign, f64::MIN_POSITIVE) {
                    Some(ViolationKind::TypeIISign)
                } else if !at_least(limits.max_condition, c.type_ii.condition) {
                    Some(ViolationKind::Conditioning)
                } else if !c.homeomorphism.holds(limits.homeomorphism_c) {
                    Some(ViolationKind::Homeomorphism)
                } else {
                    None
                }
            }
        };
        if let Some(kind) = kind {
            rep.violations += 1;
            if rep.first_violation.is_none() {
                rep.first_violation = Some(BoxViolation { pose, kind });
            }
        }
    }
    Ok(rep)
}

/// [`scan_box`] that fails with the typed error of the first violation
/// ([`CoreError::Singular`] of kind TypeI / TypeII / Homeomorphism, or the IK error).
///
/// ```
/// use rss6_core::{verify_box, BoxLimits, KinematicParams, PoseBox};
/// let rep = verify_box(&KinematicParams::nominal(), &PoseBox::documented(), 3, &BoxLimits::documented())
///     .unwrap();
/// assert!(rep.is_free() && rep.max_abs_theta.to_degrees() < 62.0); // measured: 61.7°
/// ```
pub fn verify_box(
    kp: &KinematicParams,
    bx: &PoseBox,
    points_per_axis: u32,
    limits: &BoxLimits,
) -> Result<BoxReport> {
    let rep = scan_box(kp, bx, points_per_axis, limits)?;
    match rep.first_violation {
        Some(v) => Err(v.to_error()),
        None => Ok(rep),
    }
}
