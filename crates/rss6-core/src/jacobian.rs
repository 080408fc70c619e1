//! Velocity analysis (§3.5): J_a1, J_a2, J_ad (eq. 3.28–3.30), J_θ (eq. 5.3) and the leg-length
//! Jacobian J' of the equivalent Stewart platform (eq. 3.19).
//!
//! Vectors follow eq. 3.1/3.24 with a_i = A_i − E = R·A'_i (eq. 3.24; eq. 3.1 prints the opposite sign,
//! which contradicts 3.24 and 3.26), w_i = T_i − B_i, l_i = A_i − T_i, ŝ = ẑ.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::ik::{ik_leg, platform_joints_in_base, wrench_tips};
use crate::params::KinematicParams;
use crate::pose::{pose_rotation, twist_jacobian};
use crate::types::{Mat3, Mat6, Vec3, Vec6, LEGS};

/// Smallest |(w_i × l_i)·ẑ| (m²) accepted before a pose is called type-I singular.
pub const TYPE_I_TOLERANCE: f64 = 1e-9;

/// Per-pose leg vectors (the "Data" of the Model/Data split): everything the Jacobians and the dynamics
/// need, computed once by [`LegGeometry::at_pose`] with one IK.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegGeometry {
    /// The pose χ this geometry belongs to.
    pub pose: Vec6,
    /// Rotation R of ΣE (eq. 3.2).
    pub rot: Mat3,
    /// Joint angles θ from IK (rad).
    pub theta: Vec6,
    /// B_i (m).
    pub b: [Vec3; LEGS],
    /// T_i (m).
    pub t: [Vec3; LEGS],
    /// A_i in the base frame (m).
    pub a: [Vec3; LEGS],
    /// a_i = A_i − E = R A'_i (m).
    pub a_rel: [Vec3; LEGS],
    /// w_i = T_i − B_i (m).
    pub w: [Vec3; LEGS],
    /// l_i = A_i − T_i (m).
    pub l: [Vec3; LEGS],
}

/// Largest relative error of |l_i|² accepted from angles said to be IK(χ) (rounding is ~10⁻¹⁵).
pub(crate) const CLOSURE_TOL: f64 = 1e-9;

impl LegGeometry {
    /// Runs IK at χ and assembles the leg vectors.
    pub fn at_pose(kp: &KinematicParams, pose: &Vec6) -> Result<Self> {
        check_finite(pose.as_slice())?;
        let rot = pose_rotation(pose);
        let a = platform_joints_in_base(kp, pose);
        let mut theta = Vec6::zeros();
        for (i, ai) in a.iter().enumerate() {
            theta[i] = ik_leg(kp, i, ai)?;
        }
        Ok(Self::from_parts(kp, pose, &theta, rot, a))
    }

    /// [`Self::at_pose`] from the angles of an earlier IK of `pose` when known (`theta`; one IK
    /// less), else with one IK. Angles that do not close every leg at the pose (relative error of
    /// |l_i|² above [`CLOSURE_TOL`], e.g. those of an earlier pose) are refused; the other root of
    /// a leg's IK closes it too, so angles from anything but [`crate::ik`] are the caller's risk.
    ///
    /// Errors: as [`Self::at_pose`]; [`CoreError::NonFinite`] for non-finite angles,
    /// [`CoreError::InvalidParameter`] for angles that do not close the legs.
    pub(crate) fn at_pose_from(
        kp: &KinematicParams,
        pose: &Vec6,
        theta: Option<&Vec6>,
    ) -> Result<Self> {
        let Some(th) = theta else {
            return Self::at_pose(kp, pose);
        };
        check_finite(pose.as_slice())?;
        check_finite(th.as_slice())?;
        let g = Self::from_pose_and_theta(kp, pose, th);
        for i in 0..LEGS {
            let l = kp.link_lengths[i];
            if (g.l[i].norm_squared() - l * l).abs() > CLOSURE_TOL * l * l {
                return Err(CoreError::InvalidParameter(
                    "theta does not close the legs at the pose: not IK(pose)",
                ));
            }
        }
        Ok(g)
    }

    /// Leg vectors for a pose and joint angles that are already known to be consistent (e.g. inside FK).
    pub fn from_pose_and_theta(kp: &KinematicParams, pose: &Vec6, theta: &Vec6) -> Self {
        let rot = pose_rotation(pose);
        let a = platform_joints_in_base(kp, pose);
        Self::from_parts(kp, pose, theta, rot, a)
    }

    fn from_parts(
        kp: &KinematicParams,
        pose: &Vec6,
        theta: &Vec6,
        rot: Mat3,
        a: [Vec3; LEGS],
    ) -> Self {
        let t = wrench_tips(kp, theta);
        let e = Vec3::new(pose[0], pose[1], pose[2]);
        let mut g = LegGeometry {
            pose: *pose,
            rot,
            theta: *theta,
            b: kp.base_joints,
            t,
            a,
            a_rel: [Vec3::zeros(); LEGS],
            w: [Vec3::zeros(); LEGS],
            l: [Vec3::zeros(); LEGS],
        };
        for i in 0..LEGS {
            g.a_rel[i] = a[i] - e;
            g.w[i] = t[i] - kp.base_joints[i];
            g.l[i] = a[i] - t[i];
        }
        g
    }

    /// diag J_a1 = (w_i × l_i)·ŝ (eq. 3.29), m².
    pub fn j_a1(&self) -> Vec6 {
        Vec6::from_fn(|i, _| self.w[i][0] * self.l[i][1] - self.w[i][1] * self.l[i][0])
    }

    /// J_a2 with rows [l_iᵀ, (a_i × l_i)ᵀ] (eq. 3.29), m and m².
    pub fn j_a2(&self) -> Mat6 {
        let mut j = Mat6::zeros();
        for i in 0..LEGS {
            let m = self.a_rel[i].cross(&self.l[i]);
            for k in 0..3 {
                j[(i, k)] = self.l[i][k];
                j[(i, 3 + k)] = m[k];
            }
        }
        j
    }

    /// J_ad = J_a1⁻¹ J_a2 (eq. 3.30): θ̇ = J_ad v_E. Type-I singular if a diagonal entry of J_a1 vanishes.
    pub fn j_ad(&self) -> Result<Mat6> {
        let d = self.j_a1();
        let mut j = self.j_a2();
        for i in 0..LEGS {
            if d[i].abs() < TYPE_I_TOLERANCE {
                return Err(CoreError::Singular(SingularKind::TypeI));
            }
            let inv = 1.0 / d[i];
            for k in 0..6 {
                j[(i, k)] *= inv;
            }
        }
        Ok(j)
    }

    /// J_θ = J_ad J_s (eq. 5.3): θ̇ = J_θ χ̇.
    pub fn j_theta(&self) -> Result<Mat6> {
        Ok(self.j_ad()? * twist_jacobian(&self.pose))
    }
}

/// J_ad at pose χ (eq. 3.30). Rows: legs; θ̇ = J_ad·[Ė; ω].
pub fn jacobian_ad(kp: &KinematicParams, pose: &Vec6) -> Result<Mat6> {
    LegGeometry::at_pose(kp, pose)?.j_ad()
}

/// diag J_a1 at pose χ (eq. 3.29), m².
pub fn jacobian_a1(kp: &KinematicParams, pose: &Vec6) -> Result<Vec6> {
    Ok(LegGeometry::at_pose(kp, pose)?.j_a1())
}

/// J_a2 at pose χ (eq. 3.29).
pub fn jacobian_a2(kp: &KinematicParams, pose: &Vec6) -> Result<Mat6> {
    Ok(LegGeometry::at_pose(kp, pose)?.j_a2())
}

/// J_θ at pose χ (eq. 5.3): θ̇ = J_θ χ̇.
pub fn jacobian_theta(kp: &KinematicParams, pose: &Vec6) -> Result<Mat6> {
    LegGeometry::at_pose(kp, pose)?.j_theta()
}

/// Leg-length Jacobian J' of the equivalent Stewart platform with fixed base points T_i (eq. 3.19):
/// rows [l̂_iᵀ, (a_i × l̂_i)ᵀ], so L̇ = J' v_E. Also returns the leg lengths L_i.
pub fn jacobian_stewart(
    kp: &KinematicParams,
    pose: &Vec6,
    tips: &[Vec3; LEGS],
) -> Result<(Mat6, Vec6)> {
    check_finite(pose.as_slice())?;
    let (rows, len) = stewart_rows(kp, &pose_rotation(pose), pose, tips)?;
    Ok((Mat6::from_fn(|r, c| rows[r][c]), len))
}

/// A 6 × 6 matrix stored row by row (the FK's linear solver works on rows).
pub(crate) type Rows6 = [[f64; 6]; 6];

/// J' (as rows) and the leg lengths for a rotation already computed from `pose` (the FK loop shares
/// its sines and cosines between R and J_e).
pub(crate) fn stewart_rows(
    kp: &KinematicParams,
    rot: &Mat3,
    pose: &Vec6,
    tips: &[Vec3; LEGS],
) -> Result<(Rows6, Vec6)> {
    let e = Vec3::new(pose[0], pose[1], pose[2]);
    let mut j = [[0.0; 6]; 6];
    let mut len = Vec6::zeros();
    for (i, row) in j.iter_mut().enumerate() {
        let a_rel = rot * kp.platform_joints[i];
        let l = a_rel + e - tips[i];
        let n = l.norm();
        if n.is_nan() || n <= 0.0 {
            return Err(CoreError::Singular(SingularKind::StewartJacobian));
        }
        let u = l / n;
        let m = a_rel.cross(&u);
        *row = [u[0], u[1], u[2], m[0], m[1], m[2]];
        len[i] = n;
    }
    Ok((j, len))
}
