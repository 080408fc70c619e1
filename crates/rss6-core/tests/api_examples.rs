//! The API examples of `docs/kinematics.md`, verbatim, so the documentation cannot drift from the code.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may panic

use rss6_core::*;

#[test]
fn ik_fk_round_trip() {
    let kp = KinematicParams::nominal();
    let pose = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03); // m, rad
    let theta = ik(&kp, &pose).unwrap(); // physical joint angles (rad)
    let kappa = kp.reading_from_theta(&theta); // potentiometer bits (eq. 4.2)
    let sol = fk(&kp, &theta, &home_pose(), &FkOptions::default()).unwrap();
    assert!((sol.pose - pose).amax() < 1e-10);
    assert!(sol.iterations <= 5 && sol.residual < 1e-12);
    assert!((kp.theta_from_reading(&kappa) - theta).amax() < 1e-12);
    // Warm start from the previous solution (e.g. the last control tick):
    let next = fk(&kp, &theta, &sol.pose, &FkOptions::default()).unwrap();
    assert_eq!(next.iterations, 0);
}

#[test]
fn typed_errors() {
    let kp = KinematicParams::nominal();
    match ik(&kp, &Vec6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0)) {
        Err(CoreError::Unreachable { leg, excess }) => assert!(leg < 6 && excess > 0.0),
        other => panic!("{other:?}"),
    }
    assert_eq!(ik(&kp, &Vec6::repeat(f64::NAN)), Err(CoreError::NonFinite));
    let tight = FkOptions {
        max_iterations: 1,
        ..FkOptions::default()
    };
    let theta = ik(&kp, &Vec6::new(0.02, 0.02, 0.135, 0.05, 0.0, 0.0)).unwrap();
    assert!(matches!(
        fk(&kp, &theta, &home_pose(), &tight),
        Err(CoreError::NotConverged { iterations: 1, .. })
    ));
}

#[test]
fn jacobians_and_checks() {
    let kp = KinematicParams::nominal();
    let pose = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03);
    let geo = LegGeometry::at_pose(&kp, &pose).unwrap(); // one IK, all leg vectors
    let j_a1 = geo.j_a1(); // diag J_a1 (eq. 3.29), m²
    let j_ad = geo.j_ad().unwrap(); // θ̇ = J_ad·[Ė; ω] (eq. 3.30)
    let j_theta = geo.j_theta().unwrap(); // θ̇ = J_θ·χ̇ (eq. 5.3)
    assert!(j_a1.amax() > 0.0 && j_ad.amax() > 0.0 && j_theta.amax() > 0.0);
    let c = singularity_check(&kp, &pose).unwrap();
    assert!(c.type_i.is_free()); // sign pattern [+,−,+,−,+,−]
    assert!(c.type_ii.is_free(1.0, 15.0)); // det J_a2 > 0, cond(J_ad) ≤ 15
    assert!(c.homeomorphism.holds(2e4)); // eq. 4.22 with C = 2·10⁴
    let rep = verify_box(&kp, &PoseBox::documented(), 3, &BoxLimits::documented()).unwrap();
    assert!(rep.max_condition < 15.0);
}

#[test]
fn perturbed_robot() {
    let mut b = [0.0; N_KIN_ERRORS];
    b[36] = 1e-3; // Δl_AT,1 = +1 mm (eq. 4.3 order: ΔA', ΔB, Δl_AT, Δl_TB, Δη, Δθ)
    let kp = KinematicParams::perturbed(&b);
    let back = kp.errors_from(&KinematicParams::nominal());
    assert!(back
        .iter()
        .zip(b.iter())
        .all(|(x, y)| (x - y).abs() < 1e-15));
    kp.validate().unwrap();
}
