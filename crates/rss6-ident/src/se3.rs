//! First-order perturbations of rigid transforms, used to differentiate the calibration residuals
//! analytically.
//!
//! A transform M = (R, p) is perturbed *on the left* by a twist ξ = [v; ω] (base-frame, m and rad):
//! M' ≈ (I + ξ^)·M, i.e. R' = (I + [ω]×)R and p' = p + v + ω × p. A pose χ = [x, y, z, α, β, γ]
//! (eq. 3.2) moves by δχ; the two are related by ω = J_e(α, β)·δφ (eq. 3.22) and v = δp − ω × p.

use nalgebra::Isometry3;
use rss6_core::{euler_rate_jacobian, pose_to_isometry, Mat3, Mat6, Vec3, Vec6};

/// Skew-symmetric matrix [a]× with [a]×·b = a × b.
pub(crate) fn skew(a: &Vec3) -> Mat3 {
    Mat3::new(0.0, -a[2], a[1], a[2], 0.0, -a[0], -a[1], a[0], 0.0)
}

/// Transform of a pose 6-vector (alias kept local for brevity).
pub(crate) fn iso(pose: &Vec6) -> Isometry3<f64> {
    pose_to_isometry(pose)
}

/// E(χ): maps a pose change δχ to the left-perturbation twist ξ of its transform.
pub(crate) fn twist_from_pose_delta(pose: &Vec6) -> Mat6 {
    let je = euler_rate_jacobian(pose[3], pose[4]);
    let p = Vec3::new(pose[0], pose[1], pose[2]);
    let mut e = Mat6::zeros();
    e.fixed_view_mut::<3, 3>(0, 0).copy_from(&Mat3::identity());
    e.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(&p) * je));
    e.fixed_view_mut::<3, 3>(3, 3).copy_from(&je);
    e
}

/// D(χ) = E(χ)⁻¹: maps a left-perturbation twist ξ of M to the change δχ of its pose χ = L(M).
/// `None` at the Euler singularity cos β = 0.
pub(crate) fn pose_delta_from_twist(pose: &Vec6) -> Option<Mat6> {
    let je_inv = euler_rate_jacobian(pose[3], pose[4]).try_inverse()?;
    let p = Vec3::new(pose[0], pose[1], pose[2]);
    let mut d = Mat6::zeros();
    d.fixed_view_mut::<3, 3>(0, 0).copy_from(&Mat3::identity());
    // δp = v + ω × p = v − [p]× ω
    d.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-skew(&p)));
    d.fixed_view_mut::<3, 3>(3, 3).copy_from(&je_inv);
    Some(d)
}

/// Adjoint Ad_A: (I + ξ^) conjugated by A, A·ξ^·A⁻¹ = (Ad_A ξ)^. For A = (R, p):
/// Ad_A = [[R, [p]×R], [0, R]] on ξ = [v; ω].
pub(crate) fn adjoint(a: &Isometry3<f64>) -> Mat6 {
    let r = a.rotation.to_rotation_matrix().into_inner();
    let p = a.translation.vector;
    let mut ad = Mat6::zeros();
    ad.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    ad.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(&p) * r));
    ad.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
    ad
}

/// Component-wise pose difference a − b with the angle differences wrapped to (−π, π].
pub(crate) fn pose_difference(a: &Vec6, b: &Vec6) -> Vec6 {
    let mut d = a - b;
    for k in 3..6 {
        d[k] = rss6_core::wrap_angle(d[k]);
    }
    d
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use rss6_core::{compose, isometry_to_pose};

    fn perturb(m: &Isometry3<f64>, xi: &Vec6) -> Isometry3<f64> {
        let v = nalgebra::Vector3::new(xi[0], xi[1], xi[2]);
        let w = nalgebra::Vector3::new(xi[3], xi[4], xi[5]);
        let exp = Isometry3::new(v, w); // exact exponential differs only at second order
        exp * m
    }

    #[test]
    fn pose_delta_maps_invert_each_other_and_match_finite_differences() {
        let pose = Vec6::new(0.1, -0.2, 0.3, 0.4, -0.3, 1.1);
        let e = twist_from_pose_delta(&pose);
        let d = pose_delta_from_twist(&pose).unwrap();
        assert!((d * e - Mat6::identity()).amax() < 1e-12);
        let h = 1e-6;
        for k in 0..6 {
            let mut xi = Vec6::zeros();
            xi[k] = h;
            let plus = isometry_to_pose(&perturb(&iso(&pose), &xi));
            xi[k] = -h;
            let minus = isometry_to_pose(&perturb(&iso(&pose), &xi));
            let fd = (plus - minus) / (2.0 * h);
            assert!(
                (fd - d.column(k)).amax() < 1e-6,
                "column {k}: {fd} vs {}",
                d.column(k)
            );
        }
    }

    #[test]
    fn adjoint_conjugates_perturbations() {
        let a = Vec6::new(0.3, 0.1, -0.2, -0.5, 0.2, 0.7);
        let m = Vec6::new(-0.1, 0.4, 0.2, 0.1, 0.3, -0.6);
        let xi = Vec6::new(1e-7, -2e-7, 3e-7, 2e-7, 1e-7, -1e-7);
        // A·exp(ξ)·M = exp(Ad_A ξ)·A·M
        let lhs = iso(&a) * perturb(&iso(&m), &xi);
        let rhs = perturb(&(iso(&a) * iso(&m)), &(adjoint(&iso(&a)) * xi));
        let diff = isometry_to_pose(&lhs) - isometry_to_pose(&rhs);
        assert!(diff.amax() < 1e-12, "{diff}");
        assert!((compose(&a, &m) - isometry_to_pose(&(iso(&a) * iso(&m)))).amax() < 1e-12);
    }
}
