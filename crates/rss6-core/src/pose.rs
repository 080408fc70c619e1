//! Pose χ = [x, y, z, α, β, γ] and its rotation R = Rx(α)·Ry(β)·Rz(γ) (eq. 3.2); the Euler-rate
//! Jacobian J_e (eq. 3.22), J_s (eq. 3.23), their time derivatives and the angular acceleration of
//! eq. 5.12.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::types::{Mat3, Mat6, Vec3, Vec6};
use libm::{asin, atan2, cos, sin, sincos};
use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion};

/// Sines and cosines of the Euler angles of a pose, computed once and shared by R (eq. 3.2) and
/// J_e (eq. 3.22) in the hot paths.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EulerTrig {
    sa: f64,
    ca: f64,
    sb: f64,
    cb: f64,
    sg: f64,
    cg: f64,
}

impl EulerTrig {
    /// sin/cos of α, β, γ.
    pub(crate) fn new(alpha: f64, beta: f64, gamma: f64) -> Self {
        let (sa, ca) = sincos(alpha);
        let (sb, cb) = sincos(beta);
        let (sg, cg) = sincos(gamma);
        EulerTrig {
            sa,
            ca,
            sb,
            cb,
            sg,
            cg,
        }
    }

    /// sin/cos of the Euler angles of pose χ.
    pub(crate) fn of_pose(pose: &Vec6) -> Self {
        Self::new(pose[3], pose[4], pose[5])
    }

    /// R = Rx(α)·Ry(β)·Rz(γ) (eq. 3.2).
    pub(crate) fn rotation(&self) -> Mat3 {
        let EulerTrig {
            sa,
            ca,
            sb,
            cb,
            sg,
            cg,
        } = *self;
        Mat3::new(
            cb * cg,
            -cb * sg,
            sb,
            ca * sg + cg * sb * sa,
            -sb * sa * sg + ca * cg,
            -cb * sa,
            sa * sg - ca * cg * sb,
            ca * sb * sg + cg * sa,
            cb * ca,
        )
    }

    /// Euler rates φ̇ = J_e⁻¹ ω (closed form of the inverse of eq. 3.22); `None` when cos β = 0.
    pub(crate) fn euler_rates(&self, omega: &Vec3) -> Option<Vec3> {
        let EulerTrig { sa, ca, sb, cb, .. } = *self;
        if cb.abs() < 1e-12 {
            return None;
        }
        let beta_dot = ca * omega[1] + sa * omega[2];
        let gamma_dot = (ca * omega[2] - sa * omega[1]) / cb;
        let alpha_dot = omega[0] - sb * gamma_dot;
        Some(Vec3::new(alpha_dot, beta_dot, gamma_dot))
    }
}

/// Rotation matrix R = Rx(α)·Ry(β)·Rz(γ) (eq. 3.2). Angles in rad.
pub fn rotation(alpha: f64, beta: f64, gamma: f64) -> Mat3 {
    EulerTrig::new(alpha, beta, gamma).rotation()
}

/// Rotation of a pose χ (uses χ[3..6]).
pub fn pose_rotation(pose: &Vec6) -> Mat3 {
    rotation(pose[3], pose[4], pose[5])
}

/// Euler angles [α, β, γ] of a rotation matrix, inverse of [`rotation`], with β ∈ [−π/2, π/2].
pub fn euler_from_rotation(r: &Mat3) -> Vec3 {
    let sb = r[(0, 2)].clamp(-1.0, 1.0);
    let beta = asin(sb);
    let alpha = atan2(-r[(1, 2)], r[(2, 2)]);
    let gamma = atan2(-r[(0, 1)], r[(0, 0)]);
    Vec3::new(alpha, beta, gamma)
}

/// The Euler-rate Jacobian J_e(α, β) with ω = J_e·[α̇, β̇, γ̇] (eq. 3.22); ω in the base frame.
pub fn euler_rate_jacobian(alpha: f64, beta: f64) -> Mat3 {
    RateTrig::new(alpha, beta).je()
}

/// Time derivative J̇_e given the Euler angles and their rates.
pub fn euler_rate_jacobian_dot(alpha: f64, beta: f64, alpha_dot: f64, beta_dot: f64) -> Mat3 {
    RateTrig::new(alpha, beta).je_dot(alpha_dot, beta_dot)
}

/// sin and cos of the Euler angles α, β: all that J_e, J̇_e and their derivatives read of the
/// pose, computed once for the several matrices a derivative needs (the same values, so the same
/// matrices bit for bit).
#[derive(Debug, Clone, Copy)]
pub(crate) struct RateTrig {
    pub(crate) sa: f64,
    pub(crate) ca: f64,
    pub(crate) sb: f64,
    pub(crate) cb: f64,
}

impl RateTrig {
    pub(crate) fn new(alpha: f64, beta: f64) -> Self {
        RateTrig {
            sa: sin(alpha),
            ca: cos(alpha),
            sb: sin(beta),
            cb: cos(beta),
        }
    }

    /// Of the pose's α and β.
    pub(crate) fn of(pose: &Vec6) -> Self {
        RateTrig::new(pose[3], pose[4])
    }

    /// J_e ([`euler_rate_jacobian`]).
    pub(crate) fn je(&self) -> Mat3 {
        let RateTrig { sa, ca, sb, cb } = *self;
        Mat3::new(1.0, 0.0, sb, 0.0, ca, -cb * sa, 0.0, sa, cb * ca)
    }

    /// J̇_e at the rates α̇, β̇ ([`euler_rate_jacobian_dot`]).
    pub(crate) fn je_dot(&self, alpha_dot: f64, beta_dot: f64) -> Mat3 {
        let RateTrig { sa, ca, sb, cb } = *self;
        Mat3::new(
            0.0,
            0.0,
            cb * beta_dot,
            0.0,
            -sa * alpha_dot,
            sb * sa * beta_dot - cb * ca * alpha_dot,
            0.0,
            ca * alpha_dot,
            -sb * ca * beta_dot - cb * sa * alpha_dot,
        )
    }

    /// J_s⁻¹ ([`twist_jacobian_inverse`]); fails at cos β = 0.
    pub(crate) fn js_inv(&self) -> Result<Mat6> {
        let je_inv = self
            .je()
            .try_inverse()
            .ok_or(CoreError::Singular(SingularKind::Euler))?;
        if self.cb.abs() < 1e-9 {
            return Err(CoreError::Singular(SingularKind::Euler));
        }
        let mut js = Mat6::identity();
        js.fixed_view_mut::<3, 3>(3, 3).copy_from(&je_inv);
        Ok(js)
    }

    /// J_s = diag(I₃, J_e) ([`twist_jacobian`]).
    pub(crate) fn js(&self) -> Mat6 {
        let mut js = Mat6::identity();
        js.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.je());
        js
    }
}

/// J_s = diag(I₃, J_e): maps χ̇ to the twist v_E = [Ė; ω] (eq. 3.23).
pub fn twist_jacobian(pose: &Vec6) -> Mat6 {
    let mut js = Mat6::identity();
    js.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&euler_rate_jacobian(pose[3], pose[4]));
    js
}

/// J̇_s = diag(0, J̇_e).
pub fn twist_jacobian_dot(pose: &Vec6, pose_dot: &Vec6) -> Mat6 {
    let mut js = Mat6::zeros();
    js.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&euler_rate_jacobian_dot(
            pose[3],
            pose[4],
            pose_dot[3],
            pose_dot[4],
        ));
    js
}

/// Inverse of J_s; fails at the Euler singularity cos β = 0.
pub fn twist_jacobian_inverse(pose: &Vec6) -> Result<Mat6> {
    RateTrig::of(pose).js_inv()
}

/// Twist v_E = J_s·χ̇ (eq. 3.23).
pub fn twist(pose: &Vec6, pose_dot: &Vec6) -> Vec6 {
    twist_jacobian(pose) * pose_dot
}

/// Twist acceleration v̇_E = J_s·χ̈ + J̇_s·χ̇; its angular part is ω̇ = J_e φ̈ + J̇_e φ̇ (eq. 5.12).
pub fn twist_dot(pose: &Vec6, pose_dot: &Vec6, pose_ddot: &Vec6) -> Vec6 {
    twist_jacobian(pose) * pose_ddot + twist_jacobian_dot(pose, pose_dot) * pose_dot
}

/// The rigid transform of a pose (rotation R of eq. 3.2, translation [x, y, z]).
pub fn pose_to_isometry(pose: &Vec6) -> Isometry3<f64> {
    let rot = Rotation3::from_matrix_unchecked(pose_rotation(pose));
    Isometry3::from_parts(
        Translation3::new(pose[0], pose[1], pose[2]),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

/// Pose χ of a rigid transform (β ∈ [−π/2, π/2]).
pub fn isometry_to_pose(iso: &Isometry3<f64>) -> Vec6 {
    let r = iso.rotation.to_rotation_matrix().into_inner();
    let e = euler_from_rotation(&r);
    let t = iso.translation.vector;
    Vec6::new(t[0], t[1], t[2], e[0], e[1], e[2])
}

/// Composition of poses: the pose of `b` expressed through `a` (ᵃχ ∘ ᵇχ, i.e. M_a·M_b).
pub fn compose(a: &Vec6, b: &Vec6) -> Vec6 {
    isometry_to_pose(&(pose_to_isometry(a) * pose_to_isometry(b)))
}

/// Inverse pose: M⁻¹.
pub fn inverse(a: &Vec6) -> Vec6 {
    isometry_to_pose(&pose_to_isometry(a).inverse())
}

/// `Err(NonFinite)` unless all six components are finite.
pub fn check_pose(pose: &Vec6) -> Result<()> {
    check_finite(pose.as_slice())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_is_the_product_of_elementary_rotations_and_rates_invert() {
        // Eq. 3.2, R = Rx(α)·Ry(β)·Rz(γ), checked against an independent construction: nalgebra's
        // axis-angle rotations about x, y, z multiplied in that order.
        use nalgebra::{Rotation3, Vector3};
        let cases = [
            (0.3, -0.7, 1.1),
            (-2.9, 1.4, 3.0),
            (0.0, core::f64::consts::FRAC_PI_2, -0.4),
        ];
        for (a, b, g) in cases {
            let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), a);
            let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), b);
            let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), g);
            let product = (rx * ry * rz).into_inner();
            assert!(
                (rotation(a, b, g) - product).amax() < 1e-15,
                "({a}, {b}, {g})"
            );
        }
        let (a, b, g) = (0.3, -0.7, 1.1);
        let w = Vec3::new(0.2, -0.5, 0.9);
        let rates = EulerTrig::new(a, b, g).euler_rates(&w);
        let back = rates.map(|r| euler_rate_jacobian(a, b) * r);
        assert!(back.is_some_and(|v| (v - w).amax() < 1e-14));
        assert!(EulerTrig::new(0.0, core::f64::consts::FRAC_PI_2, 0.0)
            .euler_rates(&w)
            .is_none());
    }
}
