//! The workspace checks (type I, type II, eq. 4.22) and the documented singularity-free box.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
mod common;

use rss6_core::*;

#[test]
fn documented_box_is_singularity_free_for_the_nominal_robot() {
    let kp = KinematicParams::nominal();
    let bx = PoseBox::documented();
    // ≥ ±20 mm and ±0.05 rad, centred at home.
    assert_eq!(bx.center, home_pose());
    for k in 0..6 {
        assert!(bx.half_width[k] >= if k < 3 { 0.02 } else { 0.05 });
    }
    let rep = verify_box(&kp, &bx, 7, &BoxLimits::documented())
        .unwrap_or_else(|e| panic!("documented box not free: {e}"));
    assert_eq!(rep.points, 7u32.pow(6));
    assert!(rep.is_free() && rep.first_violation.is_none());
    assert!(rep.max_abs_theta < core::f64::consts::FRAC_PI_2);
    println!(
        "nominal, 7^6 grid: max|θ| = {:.2}°, min type-I margin = {:.3e} m², det J_a2 sign {} (min |det| {:.3e}), \
         min σ(J_ad) = {:.3}, max cond(J_ad) = {:.2} at {}, max eq. 4.22 ratio = {:.4e}",
        rep.max_abs_theta.to_degrees(),
        rep.min_type_i_margin,
        rep.det_sign,
        rep.min_abs_det_j_a2,
        rep.min_sigma,
        rep.max_condition,
        rep.worst_condition_pose,
        rep.max_homeomorphism_ratio
    );
}

#[test]
fn documented_box_is_singularity_free_for_perturbed_robots() {
    // Table 4.2 errors keep both singularity types out of the box (same type-I margin, one sign of
    // det J_a2); the quality bounds may degrade, by less than a factor 2.
    let doc = BoxLimits::documented();
    let limits = BoxLimits {
        max_condition: 2.0 * doc.max_condition,
        homeomorphism_c: 2.0 * doc.homeomorphism_c,
        ..doc
    };
    let mut rng = common::rng(21);
    let (mut cond, mut ratio) = (0.0f64, 0.0f64);
    for _ in 0..8 {
        let kp = common::perturbed_robot(&mut rng);
        let rep = verify_box(&kp, &PoseBox::documented(), 3, &limits)
            .unwrap_or_else(|e| panic!("perturbed robot: {e}"));
        assert_eq!(rep.points, 729);
        cond = cond.max(rep.max_condition);
        ratio = ratio.max(rep.max_homeomorphism_ratio);
    }
    println!("perturbed robots: max cond(J_ad) = {cond:.2}, max eq. 4.22 ratio = {ratio:.4e}");
}

#[test]
fn a_larger_box_is_reported_as_not_free() {
    let kp = KinematicParams::nominal();
    let bx = PoseBox {
        center: home_pose(),
        half_width: Vec6::new(0.06, 0.06, 0.06, 0.3, 0.3, 0.3),
    };
    let rep = scan_box(&kp, &bx, 3, &BoxLimits::documented()).unwrap();
    assert!(!rep.is_free());
    assert!(rep.violations > 0 && rep.violations <= rep.points);
    let v = rep.first_violation.unwrap();
    assert!(bx.contains(&v.pose));
    let err = verify_box(&kp, &bx, 3, &BoxLimits::documented()).unwrap_err();
    assert_eq!(err, v.to_error());
}

#[test]
fn tighter_limits_are_violated_where_the_scan_says() {
    // Limits just below the scanned extremes must fail, each with its own kind.
    let kp = KinematicParams::nominal();
    let bx = PoseBox::documented();
    let rep = scan_box(&kp, &bx, 3, &BoxLimits::documented()).unwrap();
    let base = BoxLimits::documented();
    let cases = [
        (
            BoxLimits {
                min_type_i_margin: rep.min_type_i_margin * 1.01,
                ..base
            },
            "type I",
        ),
        (
            BoxLimits {
                max_condition: rep.max_condition * 0.99,
                ..base
            },
            "conditioning",
        ),
        (
            BoxLimits {
                homeomorphism_c: rep.max_homeomorphism_ratio * 0.99,
                ..base
            },
            "eq. 4.22",
        ),
    ];
    for (limits, what) in cases {
        let r = scan_box(&kp, &bx, 3, &limits).unwrap();
        let kind = r.first_violation.map(|v| v.kind);
        let ok = match what {
            "type I" => matches!(kind, Some(ViolationKind::TypeI { .. })),
            "conditioning" => matches!(kind, Some(ViolationKind::Conditioning)),
            _ => matches!(kind, Some(ViolationKind::Homeomorphism)),
        };
        assert!(ok, "{what}: {kind:?}");
        assert!(verify_box(&kp, &bx, 3, &limits).is_err());
    }
}

#[test]
fn type_i_margin_vanishes_at_the_reach_boundary() {
    // Raising the platform stretches every leg: at the reach limit w_i ∥ l_i, so (J_a1)_ii → 0.
    let kp = KinematicParams::nominal();
    let at = |z: f64| Vec6::new(0.0, 0.0, z, 0.0, 0.0, 0.0);
    let (mut lo, mut hi) = (HOME_Z, 0.5);
    assert!(ik(&kp, &at(hi)).is_err());
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if ik(&kp, &at(mid)).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let home = type_i_check(&LegGeometry::at_pose(&kp, &home_pose()).unwrap());
    let edge = type_i_check(&LegGeometry::at_pose(&kp, &at(lo)).unwrap());
    assert!(home.is_free());
    assert!(
        edge.margin.abs() < 1e-6 * home.margin,
        "margin at the boundary {}",
        edge.margin
    );
    assert!(!edge.is_free());
    assert!(matches!(
        ik(&kp, &at(hi + 1e-9)),
        Err(CoreError::Unreachable { .. })
    ));
}

#[test]
fn type_i_check_reports_a_flipped_leg() {
    let kp = KinematicParams::nominal();
    let mut geo = LegGeometry::at_pose(&kp, &home_pose()).unwrap();
    // Mirror leg 4's link about its wrench: the sign of (w × l)·ẑ flips.
    let w = geo.w[3].normalize();
    let l = geo.l[3];
    geo.l[3] = 2.0 * w * w.dot(&l) - l + Vec3::new(0.0, 0.0, 2.0 * l[2]);
    let c = type_i_check(&geo);
    assert!(!c.is_free());
    assert_eq!(c.worst_leg, 3);
    assert!(c.diag[3] > 0.0);
}

#[test]
fn type_ii_check_detects_a_rank_deficient_j_a2() {
    let kp = KinematicParams::nominal();
    let geo = LegGeometry::at_pose(&kp, &home_pose()).unwrap();
    let home = type_ii_check(&geo).unwrap();
    assert!(home.det_j_a2 > 0.0 && home.is_free(1.0, 15.0));
    assert!(!home.is_free(-1.0, 15.0));
    assert!(!home.is_free(1.0, home.condition * 0.999));
    // Give leg 2 the same link vector and platform arm as leg 1: two equal rows in J_a2.
    let mut bad = geo;
    bad.l[1] = geo.l[0];
    bad.a_rel[1] = geo.a_rel[0];
    let c = type_ii_check(&bad).unwrap();
    assert!(
        c.det_j_a2.abs() < 1e-12 * home.det_j_a2.abs(),
        "det {}",
        c.det_j_a2
    );
    assert!(c.condition > 1e8, "cond {}", c.condition);
    assert!(!c.is_free(1.0, 15.0));
    assert!(homeomorphism_check(&bad).map_or(true, |h| !h.holds(2e4)));
}

#[test]
fn homeomorphism_ratio_matches_singular_values_and_eigenvalues() {
    // Eq. 4.22 evaluated literally: σ_i from an SVD, λ_i from the complex eigenvalues of J_ad2.
    let mut rng = common::rng(3);
    let kp = KinematicParams::nominal();
    for _ in 0..50 {
        let pose = common::random_pose(&mut rng, &PoseBox::documented());
        let geo = LegGeometry::at_pose(&kp, &pose).unwrap();
        let j_ad2 = geo.j_a2().try_inverse().unwrap() * Mat6::from_diagonal(&geo.j_a1());
        let sigma2: f64 = j_ad2.singular_values().iter().map(|s| s * s).sum();
        let lambda = j_ad2.complex_eigenvalues();
        let p = lambda
            .iter()
            .fold(nalgebra::Complex::new(1.0, 0.0), |p, l| p * l);
        let prod = (p.re * p.re + p.im * p.im).sqrt();
        let expect = sigma2.powf(6.0 / 2.0) / prod;
        let h = homeomorphism_check(&geo).unwrap();
        assert!(
            (h.ratio - expect).abs() <= 1e-9 * expect,
            "{} vs {expect}",
            h.ratio
        );
        assert!(h.ratio >= 216.0 * (1.0 - 1e-12), "AM–GM bound");
        // J_ad2 = J_ad⁻¹.
        assert!((j_ad2 * geo.j_ad().unwrap() - Mat6::identity()).amax() < 1e-9);
    }
}

#[test]
fn scan_box_rejects_bad_arguments() {
    let kp = KinematicParams::nominal();
    let l = BoxLimits::documented();
    let bx = PoseBox::documented();
    for n in [0, 1, MAX_POINTS_PER_AXIS + 1] {
        assert!(matches!(
            scan_box(&kp, &bx, n, &l),
            Err(CoreError::InvalidParameter(_))
        ));
    }
    let neg = PoseBox {
        half_width: Vec6::repeat(-0.01),
        ..bx
    };
    assert!(matches!(
        scan_box(&kp, &neg, 3, &l),
        Err(CoreError::InvalidParameter(_))
    ));
    let nan = PoseBox {
        center: Vec6::repeat(f64::NAN),
        ..bx
    };
    assert_eq!(scan_box(&kp, &nan, 3, &l).err(), Some(CoreError::NonFinite));
    let far = PoseBox {
        center: Vec6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0),
        ..bx
    };
    assert!(matches!(
        scan_box(&kp, &far, 3, &l),
        Err(CoreError::Unreachable { .. })
    ));
    assert!(!bx.contains(&Vec6::repeat(f64::NAN)));
    assert!(bx.contains(&bx.point(&Vec6::repeat(1.0))));
}
