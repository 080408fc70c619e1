//! Every Jacobian against central finite differences (relative error ≤ 1e-6), at home and at random
//! poses of the documented box, for the nominal and perturbed robots.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
mod common;

use rss6_core::*;

const REL_TOL: f64 = 1e-6;
const H: f64 = 1e-6;

/// max |a − b| / max(|b|_max, 1e-12) over all entries.
fn rel_err<const R: usize, const C: usize>(
    a: &nalgebra::SMatrix<f64, R, C>,
    b: &nalgebra::SMatrix<f64, R, C>,
) -> f64 {
    (a - b).amax() / b.amax().max(1e-12)
}

/// Central difference of f: R⁶ → R^R along the unit vectors: column k = (f(x + h e_k) − f(x − h e_k))/2h.
fn fd_jacobian<const R: usize>(
    x: &Vec6,
    f: impl Fn(&Vec6) -> nalgebra::SVector<f64, R>,
) -> nalgebra::SMatrix<f64, R, 6> {
    let mut j = nalgebra::SMatrix::<f64, R, 6>::zeros();
    for k in 0..6 {
        let mut xp = *x;
        let mut xm = *x;
        xp[k] += H;
        xm[k] -= H;
        j.set_column(k, &((f(&xp) - f(&xm)) / (2.0 * H)));
    }
    j
}

/// Vee of a skew matrix (its axial vector).
fn vee(m: &Mat3) -> Vec3 {
    Vec3::new(
        m[(2, 1)] - m[(1, 2)],
        m[(0, 2)] - m[(2, 0)],
        m[(1, 0)] - m[(0, 1)],
    ) / 2.0
}

/// The pose reached from χ by the twist step [dE; dω] (rotation applied in the base frame).
fn apply_twist(pose: &Vec6, dv: &Vec6) -> Vec6 {
    let dr = nalgebra::Rotation3::new(Vec3::new(dv[3], dv[4], dv[5])).into_inner();
    let ang = euler_from_rotation(&(dr * pose_rotation(pose)));
    Vec6::new(
        pose[0] + dv[0],
        pose[1] + dv[1],
        pose[2] + dv[2],
        ang[0],
        ang[1],
        ang[2],
    )
}

/// Loop-closure residuals f_i(θ, χ) = (|A_i − T_i|² − l_AT,i²)/2, whose derivatives define J_a1, J_a2.
fn closure(kp: &KinematicParams, theta: &Vec6, pose: &Vec6) -> Vec6 {
    let a = platform_joints_in_base(kp, pose);
    let t = wrench_tips(kp, theta);
    Vec6::from_fn(|i, _| ((a[i] - t[i]).norm_squared() - kp.link_lengths[i].powi(2)) / 2.0)
}

fn test_poses() -> Vec<(KinematicParams, Vec6)> {
    let mut rng = common::rng(5);
    let bx = PoseBox::documented();
    let mut v = vec![(KinematicParams::nominal(), home_pose())];
    for k in 0..40 {
        let kp = if k % 2 == 0 {
            KinematicParams::nominal()
        } else {
            common::perturbed_robot(&mut rng)
        };
        v.push((kp, common::random_pose(&mut rng, &bx)));
    }
    v
}

#[test]
fn j_a1_and_j_a2_are_the_closure_derivatives() {
    for (kp, pose) in test_poses() {
        let geo = LegGeometry::at_pose(&kp, &pose).unwrap();
        // ∂f/∂θ = −diag J_a1 (θ̇ enters with the opposite sign: J_a1 θ̇ = J_a2 v_E).
        let d_theta = fd_jacobian(&geo.theta, |th| closure(&kp, th, &pose));
        let j_a1 = Mat6::from_diagonal(&jacobian_a1(&kp, &pose).unwrap());
        assert!(
            rel_err(&(-d_theta), &j_a1) <= REL_TOL,
            "J_a1 at {pose}: {}",
            rel_err(&(-d_theta), &j_a1)
        );
        // ∂f/∂v_E via twist steps.
        let d_twist = fd_jacobian(&Vec6::zeros(), |dv| {
            closure(&kp, &geo.theta, &apply_twist(&pose, dv))
        });
        let j_a2 = jacobian_a2(&kp, &pose).unwrap();
        assert!(
            rel_err(&d_twist, &j_a2) <= REL_TOL,
            "J_a2 at {pose}: {}",
            rel_err(&d_twist, &j_a2)
        );
        assert_eq!(j_a2, geo.j_a2());
    }
}

#[test]
fn j_ad_and_j_theta_are_the_ik_derivatives() {
    let mut worst = 0.0f64;
    let poses = test_poses();
    assert_eq!(poses.len(), 41);
    for (kp, pose) in poses {
        let j_ad = jacobian_ad(&kp, &pose).unwrap();
        let fd_ad = fd_jacobian(&Vec6::zeros(), |dv| {
            ik(&kp, &apply_twist(&pose, dv)).unwrap()
        });
        assert!(
            rel_err(&fd_ad, &j_ad) <= REL_TOL,
            "J_ad at {pose}: {}",
            rel_err(&fd_ad, &j_ad)
        );
        let j_th = jacobian_theta(&kp, &pose).unwrap();
        let fd_th = fd_jacobian(&pose, |p| ik(&kp, p).unwrap());
        assert!(
            rel_err(&fd_th, &j_th) <= REL_TOL,
            "J_θ at {pose}: {}",
            rel_err(&fd_th, &j_th)
        );
        worst = worst
            .max(rel_err(&fd_ad, &j_ad))
            .max(rel_err(&fd_th, &j_th));
    }
    println!("worst relative error of J_ad, J_θ: {worst:.2e}");
}

#[test]
fn stewart_jacobian_is_the_leg_length_derivative() {
    for (kp, pose) in test_poses() {
        let theta = ik(&kp, &pose).unwrap();
        let tips = wrench_tips(&kp, &theta);
        let (jp, len) = jacobian_stewart(&kp, &pose, &tips).unwrap();
        for i in 0..LEGS {
            assert!(
                (len[i] - kp.link_lengths[i]).abs() < 1e-12,
                "closure at IK solution"
            );
        }
        let fd = fd_jacobian(&Vec6::zeros(), |dv| {
            jacobian_stewart(&kp, &apply_twist(&pose, dv), &tips)
                .unwrap()
                .1
        });
        assert!(
            rel_err(&fd, &jp) <= REL_TOL,
            "J' at {pose}: {}",
            rel_err(&fd, &jp)
        );
    }
}

#[test]
fn euler_and_twist_jacobians_match_the_rotation_derivative() {
    let mut rng = common::rng(9);
    for _ in 0..50 {
        let pose = common::random_pose(
            &mut rng,
            &PoseBox {
                center: Vec6::zeros(),
                half_width: Vec6::repeat(1.2),
            },
        );
        // ω̂ = Ṙ Rᵀ along each Euler rate → column k of J_e.
        let r = pose_rotation(&pose);
        let mut fd = Mat3::zeros();
        for k in 0..3 {
            let (mut p, mut m) = (pose, pose);
            p[3 + k] += H;
            m[3 + k] -= H;
            let rdot = (pose_rotation(&p) - pose_rotation(&m)) / (2.0 * H);
            fd.set_column(k, &vee(&(rdot * r.transpose())));
        }
        let je = euler_rate_jacobian(pose[3], pose[4]);
        assert!(rel_err(&fd, &je) <= REL_TOL, "J_e at {pose}");
        // J_s = diag(I, J_e) and twist() = J_s χ̇.
        let js = twist_jacobian(&pose);
        let mut expect = Mat6::identity();
        expect.fixed_view_mut::<3, 3>(3, 3).copy_from(&fd);
        assert!(rel_err(&js, &expect) <= REL_TOL, "J_s at {pose}");
        let inv = twist_jacobian_inverse(&pose).unwrap();
        assert!((inv * js - Mat6::identity()).amax() < 1e-12);
    }
}

#[test]
fn time_derivatives_match_finite_differences_along_a_trajectory() {
    let mut rng = common::rng(13);
    let unit = PoseBox {
        center: Vec6::zeros(),
        half_width: Vec6::repeat(1.0),
    };
    for _ in 0..50 {
        let p0 = common::random_pose(
            &mut rng,
            &PoseBox {
                center: Vec6::zeros(),
                half_width: Vec6::repeat(1.2),
            },
        );
        let v0 = common::random_pose(&mut rng, &unit);
        let a0 = common::random_pose(&mut rng, &unit);
        // χ(t) = χ0 + v0 t + a0 t²/2, so χ̇(0) = v0, χ̈(0) = a0.
        let chi = |t: f64| p0 + v0 * t + a0 * (t * t / 2.0);
        let chi_dot = |t: f64| v0 + a0 * t;
        let fd_jsdot = (twist_jacobian(&chi(H)) - twist_jacobian(&chi(-H))) / (2.0 * H);
        let jsdot = twist_jacobian_dot(&p0, &v0);
        assert!(rel_err(&fd_jsdot, &jsdot) <= REL_TOL, "J̇_s at {p0}");
        let fd_jedot = fd_jsdot.fixed_view::<3, 3>(3, 3).into_owned();
        let jedot = euler_rate_jacobian_dot(p0[3], p0[4], v0[3], v0[4]);
        assert!(rel_err(&fd_jedot, &jedot) <= REL_TOL, "J̇_e at {p0}");
        let fd_vdot = (twist(&chi(H), &chi_dot(H)) - twist(&chi(-H), &chi_dot(-H))) / (2.0 * H);
        let vdot = twist_dot(&p0, &v0, &a0);
        assert!(rel_err(&fd_vdot, &vdot) <= REL_TOL, "twist_dot at {p0}");
        // The angular part is the derivative of ω = vee(Ṙ Rᵀ) (eq. 5.12), independent of J_e.
        let omega = |t: f64| {
            let rdot = (pose_rotation(&chi(t + H)) - pose_rotation(&chi(t - H))) / (2.0 * H);
            vee(&(rdot * pose_rotation(&chi(t)).transpose()))
        };
        let h2 = 1e-4;
        let fd_wdot = (omega(h2) - omega(-h2)) / (2.0 * h2);
        let wdot = Vec3::new(vdot[3], vdot[4], vdot[5]);
        assert!(
            (fd_wdot - wdot).amax() / wdot.amax().max(1e-12) <= 1e-5,
            "ω̇ at {p0}: {fd_wdot} vs {wdot}"
        );
    }
}

#[test]
fn a_wrong_jacobian_is_detected() {
    // The comparison itself must be able to fail: a 1e-5 relative error in one entry is caught.
    let kp = KinematicParams::nominal();
    let pose = home_pose();
    let mut j = jacobian_theta(&kp, &pose).unwrap();
    let fd = fd_jacobian(&pose, |p| ik(&kp, p).unwrap());
    j[(2, 4)] += 1e-5 * j.amax();
    assert!(rel_err(&fd, &j) > REL_TOL);
}
