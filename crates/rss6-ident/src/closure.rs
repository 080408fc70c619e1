//! Leg-closure equations of the error model (eq. 4.3 / 4.10) with their analytic derivatives, and the
//! forward-kinematics derivative by implicit differentiation: dχ/db = −(∂Φ/∂χ)⁻¹ ∂Φ/∂b.

use crate::se3::twist_from_pose_delta;
use nalgebra::{Isometry3, Point3, SMatrix};
use rss6_core::{
    fk, pose_to_isometry, CoreError, FkOptions, KinematicParams, Mat6, SingularKind, Vec3, Vec6,
    LEGS, N_KIN_ERRORS,
};

/// 6 × 60 derivative block ∂(6 equations)/∂b.
pub(crate) type Mat6x60 = SMatrix<f64, 6, N_KIN_ERRORS>;

/// Leg-closure residuals Φ_i = ‖T_i − A_i‖ − l_AT,i (eq. 4.10) at readings κ and platform transform
/// ᴼM_E, with ∂Φ/∂b (6 × 60) and ∂Φ/∂ξ (6 × 6) for a left perturbation ξ of ᴼM_E.
#[derive(Debug, Clone)]
pub(crate) struct Closure {
    pub(crate) phi: Vec6,
    pub(crate) d_b: Mat6x60,
    pub(crate) d_xi: Mat6,
}

pub(crate) fn leg_closure(kp: &KinematicParams, kappa: &Vec6, m_oe: &Isometry3<f64>) -> Closure {
    let rot = m_oe.rotation.to_rotation_matrix().into_inner();
    let theta = kp.theta_from_reading(kappa);
    let mut phi = Vec6::zeros();
    let mut d_b = Mat6x60::zeros();
    let mut d_xi = Mat6::zeros();
    for i in 0..LEGS {
        let a = (m_oe * Point3::from(kp.platform_joints[i])).coords;
        let ang = theta[i] + kp.theta0[i];
        let (s, c) = ang.sin_cos();
        let dir = Vec3::new(c, s, 0.0);
        let t = kp.base_joints[i] + kp.wrench_lengths[i] * dir;
        let d = a - t;
        let n = d.norm();
        let u = if n > 0.0 { d / n } else { Vec3::zeros() };
        phi[i] = n - kp.link_lengths[i];
        // dΦ = u·(dA − dT) − dl_AT
        let du_a = u.transpose() * rot;
        let dphi_dtheta = -kp.wrench_lengths[i] * u.dot(&Vec3::new(-s, c, 0.0));
        for k in 0..3 {
            d_b[(i, 3 * i + k)] = du_a[k];
            d_b[(i, 18 + 3 * i + k)] = -u[k];
            d_xi[(i, k)] = u[k];
        }
        let m = a.cross(&u);
        for k in 0..3 {
            d_xi[(i, 3 + k)] = m[k];
        }
        d_b[(i, 36 + i)] = -1.0;
        d_b[(i, 42 + i)] = -u.dot(&dir);
        d_b[(i, 48 + i)] = dphi_dtheta * kappa[i];
        d_b[(i, 54 + i)] = dphi_dtheta;
    }
    Closure { phi, d_b, d_xi }
}

/// Forward kinematics from readings κ with the derivative of the pose w.r.t. the 60 error parameters.
#[derive(Debug, Clone)]
pub(crate) struct FkDerivative {
    pub(crate) pose: Vec6,
    /// dχ/db (6 × 60).
    pub(crate) d_b: Mat6x60,
}

/// FK pose at readings κ (bits) for parameters `kp`, warm-started at `guess`.
pub(crate) fn fk_reading(
    kp: &KinematicParams,
    kappa: &Vec6,
    guess: &Vec6,
) -> Result<Vec6, CoreError> {
    let theta = kp.theta_from_reading(kappa);
    let opts = FkOptions {
        eps_c: 1e-13,
        eps_p: 1e-14,
        max_iterations: 50,
    };
    let sol = fk(kp, &theta, guess, &opts)?;
    if sol.residual > 1e-9 {
        return Err(CoreError::NotConverged {
            iterations: sol.iterations,
            residual: sol.residual,
        });
    }
    Ok(sol.pose)
}

/// FK with dχ/db = −(∂Φ/∂χ)⁻¹ ∂Φ/∂b, ∂Φ/∂χ = ∂Φ/∂ξ · E(χ).
pub(crate) fn fk_with_derivative(
    kp: &KinematicParams,
    kappa: &Vec6,
    guess: &Vec6,
) -> Result<FkDerivative, CoreError> {
    let pose = fk_reading(kp, kappa, guess)?;
    let c = leg_closure(kp, kappa, &pose_to_isometry(&pose));
    let d_chi = c.d_xi * twist_from_pose_delta(&pose);
    let lu = d_chi.lu();
    let mut d_b = Mat6x60::zeros();
    for j in 0..N_KIN_ERRORS {
        let col = lu
            .solve(&c.d_b.column(j).into_owned())
            .ok_or(CoreError::Singular(SingularKind::TypeII))?;
        d_b.set_column(j, &(-col));
    }
    Ok(FkDerivative { pose, d_b })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use rss6_core::{home_pose, ik};

    fn perturbed_kp(seed: u64) -> KinematicParams {
        let mut b = [0.0; N_KIN_ERRORS];
        for (j, v) in b.iter_mut().enumerate() {
            let x = ((j as u64 * 7919 + seed * 104729) % 1000) as f64 / 1000.0 - 0.5;
            *v = x * crate::model::parameter_scale(j);
        }
        KinematicParams::nominal().with_errors(&b)
    }

    #[test]
    fn closure_vanishes_on_ik_solutions() {
        let kp = perturbed_kp(3);
        let pose = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.03, 0.04);
        let theta = ik(&kp, &pose).unwrap();
        let kappa = kp.reading_from_theta(&theta);
        let c = leg_closure(&kp, &kappa, &pose_to_isometry(&pose));
        assert!(c.phi.amax() < 1e-12, "{}", c.phi);
    }

    #[test]
    fn fk_derivative_matches_finite_differences() {
        let kp = perturbed_kp(5);
        let kappa = Vec6::new(150.0, -300.0, 400.0, -100.0, 250.0, -50.0);
        let d = fk_with_derivative(&kp, &kappa, &home_pose()).unwrap();
        let h = 1e-7;
        for j in 0..N_KIN_ERRORS {
            let step = h * crate::model::parameter_scale(j) / 1e-3;
            let mut b = [0.0; N_KIN_ERRORS];
            b[j] = step;
            let plus = fk_reading(&kp.with_errors(&b), &kappa, &d.pose).unwrap();
            b[j] = -step;
            let minus = fk_reading(&kp.with_errors(&b), &kappa, &d.pose).unwrap();
            let fd = (plus - minus) / (2.0 * step);
            let an = d.d_b.column(j).into_owned();
            assert!(
                (fd - an).amax() < 1e-5 * (1.0 + an.amax()),
                "param {j}: fd {fd} an {an}"
            );
        }
    }
}
