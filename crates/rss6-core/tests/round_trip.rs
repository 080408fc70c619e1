//! IK∘FK and FK∘IK round trips on 10 000+ random poses of the documented box, for the nominal robot and
//! for robots perturbed with Table 4.2 error sizes; both FK methods from a cold start at home.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
mod common;

use rss6_core::*;

const TOL: f64 = 1e-10;

/// Runs both round trips for `n` random poses; returns (max pose error, max θ error, max iterations of
/// fk, max iterations of fk_theta_newton).
fn round_trips(kp: &KinematicParams, n: usize, seed: u64) -> (f64, f64, u32, u32) {
    let mut rng = common::rng(seed);
    let bx = PoseBox::documented();
    let opts = FkOptions::default();
    let (mut e_pose, mut e_theta, mut it_qs, mut it_nt) = (0.0f64, 0.0f64, 0, 0);
    for _ in 0..n {
        let pose = common::random_pose(&mut rng, &bx);
        let theta = ik(kp, &pose).unwrap_or_else(|e| panic!("IK failed at {pose}: {e}"));
        for (name, sol) in [
            ("fk", fk(kp, &theta, &home_pose(), &opts)),
            (
                "fk_theta_newton",
                fk_theta_newton(kp, &theta, &home_pose(), &opts),
            ),
        ] {
            let sol =
                sol.unwrap_or_else(|e| panic!("{name} from home failed for θ = {theta}: {e}"));
            // FK∘IK
            let ep = (sol.pose - pose).amax();
            assert!(ep <= TOL, "{name}: FK(IK(χ)) − χ = {ep:e} at {pose}");
            // IK∘FK
            let et = (ik(kp, &sol.pose).unwrap() - theta).amax();
            assert!(et <= TOL, "{name}: IK(FK(θ)) − θ = {et:e} at {theta}");
            e_pose = e_pose.max(ep);
            e_theta = e_theta.max(et);
            if name == "fk" {
                it_qs = it_qs.max(sol.iterations);
            } else {
                it_nt = it_nt.max(sol.iterations);
            }
        }
    }
    (e_pose, e_theta, it_qs, it_nt)
}

#[test]
fn nominal_robot_10000_poses() {
    let kp = KinematicParams::nominal();
    let (ep, et, iq, inn) = round_trips(&kp, 10_000, 1);
    println!("nominal: max pose err {ep:.2e}, max θ err {et:.2e}, max iters {iq}/{inn}");
}

#[test]
fn perturbed_robots_10000_poses() {
    // 20 robots × 500 poses; Table 4.2 σ: 1 mm, 5e-5 rad/bit, 0.05 rad.
    let mut rng = common::rng(2);
    let mut worst = (0.0f64, 0.0f64);
    for r in 0..20u64 {
        let kp = common::perturbed_robot(&mut rng);
        kp.validate().unwrap();
        assert!(kp != KinematicParams::nominal());
        let (ep, et, _, _) = round_trips(&kp, 500, 100 + r);
        worst = (worst.0.max(ep), worst.1.max(et));
    }
    println!(
        "perturbed: max pose err {:.2e}, max θ err {:.2e}",
        worst.0, worst.1
    );
}

#[test]
fn warm_start_along_a_smooth_path_converges_in_few_iterations() {
    let kp = KinematicParams::nominal();
    let bx = PoseBox::documented();
    let opts = FkOptions::default();
    let mut prev = home_pose();
    let mut total = 0u32;
    let n = 1000;
    for k in 0..n {
        // A 1 kHz sample of a Lissajous path spanning the box.
        let t = f64::from(k) * 1e-3 * 4.0;
        let u = Vec6::new(
            (1.1 * t).sin(),
            (1.3 * t).cos(),
            (0.7 * t).sin(),
            (1.7 * t).sin(),
            (0.9 * t).cos(),
            (1.9 * t).sin(),
        );
        let pose = bx.point(&u);
        let sol = fk(&kp, &ik(&kp, &pose).unwrap(), &prev, &opts).unwrap();
        assert!((sol.pose - pose).amax() <= TOL);
        total += sol.iterations;
        prev = sol.pose;
    }
    // Each step moves the pose by < 0.2 mm / 0.5 mrad: Newton needs at most 3 updates to reach 1e-13.
    let mean = f64::from(total) / f64::from(n);
    assert!(mean <= 3.0, "mean warm-start iterations {mean}");
}

#[test]
fn fk_reports_non_convergence_with_the_iteration_bound() {
    let kp = KinematicParams::nominal();
    let theta = ik(&kp, &Vec6::new(0.02, -0.02, 0.095, 0.05, -0.05, 0.05)).unwrap();
    let opts = FkOptions {
        max_iterations: 1,
        ..FkOptions::default()
    };
    for r in [
        fk(&kp, &theta, &home_pose(), &opts),
        fk_theta_newton(&kp, &theta, &home_pose(), &opts),
    ] {
        match r {
            Err(CoreError::NotConverged {
                iterations,
                residual,
            }) => {
                assert_eq!(iterations, 1);
                assert!(residual.is_finite() && residual > 0.0);
            }
            other => panic!("expected NotConverged, got {other:?}"),
        }
    }
}

#[test]
fn invalid_fk_options_are_rejected() {
    let kp = KinematicParams::nominal();
    for bad in [
        FkOptions {
            eps_c: -1.0,
            ..FkOptions::default()
        },
        FkOptions {
            eps_p: f64::NAN,
            ..FkOptions::default()
        },
    ] {
        for r in [
            fk(&kp, &Vec6::zeros(), &home_pose(), &bad),
            fk_theta_newton(&kp, &Vec6::zeros(), &home_pose(), &bad),
        ] {
            assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
        }
    }
}

#[test]
fn out_of_branch_is_a_typed_error() {
    // A platform joint behind leg 1's base joint (opposite its home direction θ0 = −60°): both roots
    // are ≈ ±95° from θ0, outside (−90°, 90°].
    let kp = KinematicParams::nominal();
    let (s, c) = kp.theta0[0].sin_cos();
    let a = kp.base_joints[0] - 0.15 * Vec3::new(c, s, 0.0);
    match ik_leg(&kp, 0, &a) {
        Err(CoreError::OutOfBranch { leg: 0, theta }) => {
            assert!(
                theta.abs() > core::f64::consts::FRAC_PI_2 && theta.abs() < 2.0,
                "{theta}"
            );
        }
        other => panic!("expected OutOfBranch, got {other:?}"),
    }
    assert!(matches!(
        ik_leg(&kp, 6, &a),
        Err(CoreError::InvalidParameter(_))
    ));
}
