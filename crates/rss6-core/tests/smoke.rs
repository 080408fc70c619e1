//! Quick smoke checks of the kinematic core (the exhaustive suites live beside this file).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
use rss6_core::*;

#[test]
fn home_is_theta_zero_and_sign_pattern_holds() {
    let kp = KinematicParams::nominal();
    let th = ik(&kp, &home_pose()).unwrap();
    assert!(th.amax() < 1e-12, "{th}");
    let d = jacobian_a1(&kp, &home_pose()).unwrap();
    for i in 0..6 {
        assert_eq!(d[i] > 0.0, i % 2 == 0, "leg {i}: {}", d[i]);
    }
}

#[test]
fn fk_both_methods_round_trip() {
    let kp = KinematicParams::nominal();
    let target = Vec6::new(0.02, -0.02, 0.135, 0.05, -0.05, 0.05);
    let th = ik(&kp, &target).unwrap();
    let a = fk(&kp, &th, &home_pose(), &FkOptions::default()).unwrap();
    let b = fk_theta_newton(&kp, &th, &home_pose(), &FkOptions::default()).unwrap();
    assert!(
        (a.pose - target).amax() < 1e-12,
        "{} {}",
        a.pose,
        a.iterations
    );
    assert!(
        (b.pose - target).amax() < 1e-12,
        "{} {}",
        b.pose,
        b.iterations
    );
    std::println!(
        "quasi-stewart {} iters, newton-theta {} iters, max|theta| {}",
        a.iterations,
        b.iterations,
        th.amax()
    );
}
