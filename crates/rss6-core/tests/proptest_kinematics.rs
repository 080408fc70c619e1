//! Property tests: round trips over the documented box, and typed errors (never NaN) on unreachable or
//! non-finite input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
use proptest::prelude::*;
use rss6_core::*;

fn box_pose() -> impl Strategy<Value = Vec6> {
    let bx = PoseBox::documented();
    proptest::array::uniform6(-1.0f64..=1.0).prop_map(move |u| bx.point(&Vec6::from(u)))
}

fn table_4_2_errors() -> impl Strategy<Value = [f64; N_KIN_ERRORS]> {
    // Uniform within ±2σ of Table 4.2.
    proptest::collection::vec(-2.0f64..=2.0, N_KIN_ERRORS).prop_map(|u| {
        let mut b = [0.0; N_KIN_ERRORS];
        for (k, (bk, uk)) in b.iter_mut().zip(u).enumerate() {
            let sigma = match k {
                0..=47 => rss6_core::thesis::SIGMA_LENGTH,
                48..=53 => rss6_core::thesis::SIGMA_ETA,
                _ => rss6_core::thesis::SIGMA_DTHETA,
            };
            *bk = sigma * uk;
        }
        b
    })
}

fn all_finite(v: &Vec6) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// A value with at least one NaN or ±∞ component.
fn non_finite_pose() -> impl Strategy<Value = Vec6> {
    (
        proptest::array::uniform6(-1.0f64..1.0),
        0usize..6,
        prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY)],
    )
        .prop_map(|(u, k, bad)| {
            let mut p = home_pose() + Vec6::from(u) * 0.01;
            p[k] = bad;
            p
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn fk_of_ik_is_identity(pose in box_pose(), b in table_4_2_errors()) {
        let kp = KinematicParams::perturbed(&b);
        let theta = ik(&kp, &pose).unwrap();
        let opts = FkOptions::default();
        let a = fk(&kp, &theta, &home_pose(), &opts).unwrap();
        let n = fk_theta_newton(&kp, &theta, &home_pose(), &opts).unwrap();
        prop_assert!((a.pose - pose).amax() <= 1e-10, "fk: {}", a.pose - pose);
        prop_assert!((n.pose - pose).amax() <= 1e-10, "newton: {}", n.pose - pose);
        prop_assert!((ik(&kp, &a.pose).unwrap() - theta).amax() <= 1e-10);
    }

    #[test]
    fn readings_round_trip(pose in box_pose(), b in table_4_2_errors()) {
        let kp = KinematicParams::perturbed(&b);
        let kappa = ik_reading(&kp, &pose).unwrap();
        let theta = kp.theta_from_reading(&kappa);
        prop_assert!((theta - ik(&kp, &pose).unwrap()).amax() <= 1e-12);
        prop_assert!((kp.reading_from_theta(&theta) - kappa).amax() <= 1e-6);
    }

    #[test]
    fn unreachable_pose_is_a_typed_error_naming_a_leg(
        u in proptest::array::uniform6(-1.0f64..=1.0),
        z in 0.33f64..5.0,
    ) {
        // Above z = 0.33 m every leg is out of reach (|A − B| > l_TB + l_AT ≈ 0.27 m for all i).
        let pose = Vec6::new(0.05 * u[0], 0.05 * u[1], z, 0.3 * u[3], 0.3 * u[4], 0.3 * u[5]);
        let kp = KinematicParams::nominal();
        match ik(&kp, &pose) {
            Err(CoreError::Unreachable { leg, excess }) => {
                prop_assert!(leg < 6);
                prop_assert!(excess > 0.0 && !excess.is_nan());
            }
            other => prop_assert!(false, "expected Unreachable, got {:?}", other),
        }
        let ok = matches!(jacobian_ad(&kp, &pose), Err(CoreError::Unreachable { .. }));
        prop_assert!(ok, "jacobian_ad");
        let ok = matches!(singularity_check(&kp, &pose), Err(CoreError::Unreachable { .. }));
        prop_assert!(ok, "singularity_check");
    }

    #[test]
    fn any_finite_input_gives_finite_output_or_a_typed_error(
        p in proptest::array::uniform6(-3.0f64..3.0),
        th in proptest::array::uniform6(-3.2f64..3.2),
    ) {
        let kp = KinematicParams::nominal();
        let pose = Vec6::from(p);
        let theta = Vec6::from(th);
        if let Ok(t) = ik(&kp, &pose) {
            prop_assert!(all_finite(&t) && t.iter().all(|x| x.abs() <= core::f64::consts::FRAC_PI_2));
        }
        if let Ok(j) = jacobian_theta(&kp, &pose) {
            prop_assert!(j.iter().all(|x| x.is_finite()));
        }
        let opts = FkOptions::default();
        for r in [fk(&kp, &theta, &home_pose(), &opts), fk_theta_newton(&kp, &theta, &home_pose(), &opts)] {
            match r {
                Ok(s) => prop_assert!(all_finite(&s.pose) && s.residual.is_finite()),
                Err(CoreError::NotConverged { residual, .. }) => prop_assert!(!residual.is_nan()),
                Err(_) => {}
            }
        }
    }

    #[test]
    fn non_finite_input_is_rejected(bad in non_finite_pose()) {
        let kp = KinematicParams::nominal();
        let opts = FkOptions::default();
        prop_assert_eq!(ik(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(ik_reading(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(jacobian_ad(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(jacobian_a1(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(jacobian_a2(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(jacobian_theta(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(LegGeometry::at_pose(&kp, &bad), Err(CoreError::NonFinite));
        prop_assert_eq!(singularity_check(&kp, &bad).err(), Some(CoreError::NonFinite));
        prop_assert_eq!(check_pose(&bad), Err(CoreError::NonFinite));
        // As joint angles and as the FK guess.
        let theta0 = Vec6::zeros();
        prop_assert_eq!(fk(&kp, &bad, &home_pose(), &opts), Err(CoreError::NonFinite));
        prop_assert_eq!(fk(&kp, &theta0, &bad, &opts), Err(CoreError::NonFinite));
        prop_assert_eq!(fk_theta_newton(&kp, &bad, &home_pose(), &opts), Err(CoreError::NonFinite));
        prop_assert_eq!(fk_theta_newton(&kp, &theta0, &bad, &opts), Err(CoreError::NonFinite));
        prop_assert_eq!(jacobian_stewart(&kp, &bad, &wrench_tips(&kp, &theta0)).err(), Some(CoreError::NonFinite));
    }

    #[test]
    fn non_finite_parameters_are_rejected(k in 0usize..N_KIN_ERRORS, bad in prop_oneof![Just(f64::NAN), Just(f64::INFINITY)]) {
        let mut b = [0.0; N_KIN_ERRORS];
        b[k] = bad;
        let kp = KinematicParams::perturbed(&b);
        prop_assert_eq!(kp.validate(), Err(CoreError::NonFinite));
    }
}
