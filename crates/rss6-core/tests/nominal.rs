//! One test per fact of the nominal geometry (module docs of `params.rs`, docs/kinematics.md "The nominal geometry").
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
mod common;

use core::f64::consts::PI;
use rss6_core::*;

fn rz(angle: f64) -> Mat3 {
    rotation(0.0, 0.0, angle)
}

#[test]
fn home_pose_is_theta_zero_both_ways() {
    let kp = KinematicParams::nominal();
    let th = ik(&kp, &home_pose()).unwrap();
    assert!(th.amax() < 1e-12, "IK(home) = {th}");
    // FK of θ = 0 from a guess away from home lands on home.
    let guess = Vec6::new(0.01, -0.01, 0.11, 0.02, 0.01, -0.02);
    for sol in [
        fk(&kp, &Vec6::zeros(), &guess, &FkOptions::default()).unwrap(),
        fk_theta_newton(&kp, &Vec6::zeros(), &guess, &FkOptions::default()).unwrap(),
    ] {
        assert!(
            (sol.pose - home_pose()).amax() < 1e-12,
            "FK(0) = {}",
            sol.pose
        );
    }
    assert_eq!(home_pose(), Vec6::new(0.0, 0.0, 0.115, 0.0, 0.0, 0.0));
    let th0: [f64; 6] = [-60.0, -60.0, 180.0, 180.0, 60.0, 60.0];
    for i in 0..LEGS {
        assert!(
            (wrap_angle(kp.theta0[i] - th0[i].to_radians())).abs() < 1e-15,
            "θ0_{i}"
        );
    }
}

#[test]
fn sign_pattern_of_j_a1_at_home() {
    let kp = KinematicParams::nominal();
    let d = jacobian_a1(&kp, &home_pose()).unwrap();
    let expected = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0];
    for i in 0..LEGS {
        assert_eq!(
            d[i].signum(),
            expected[i],
            "leg {}: (J_a1)_ii = {}",
            i + 1,
            d[i]
        );
        assert!(
            d[i].abs() > 1e-3,
            "leg {} too close to type I: {}",
            i + 1,
            d[i]
        );
    }
    assert_eq!(TYPE_I_SIGNS, expected);
}

#[test]
fn three_fold_symmetry_of_parameters() {
    let kp = KinematicParams::nominal();
    let r = rz(2.0 * PI / 3.0);
    for i in 0..LEGS {
        let j = (i + 4) % LEGS; // θ0: −60° + 120° = 60° (leg 1 → 5)
        assert!(
            (r * kp.base_joints[i] - kp.base_joints[j]).amax() < 1e-15,
            "B {i}->{j}"
        );
        assert!(
            (r * kp.platform_joints[i] - kp.platform_joints[j]).amax() < 1e-15,
            "A' {i}->{j}"
        );
        assert_eq!(kp.link_lengths[i].to_bits(), kp.link_lengths[j].to_bits());
        assert_eq!(kp.wrench_lengths[i], kp.wrench_lengths[j]);
        assert!(wrap_angle(kp.theta0[i] + 2.0 * PI / 3.0 - kp.theta0[j]).abs() < 1e-15);
    }
}

#[test]
fn three_fold_symmetry_of_ik() {
    // Conjugating a pose by a 120° turn about z (E ↦ R_z E, R ↦ R_z R R_zᵀ) maps A_i to R_z A_i and
    // so permutes the legs i ↦ i + 4 (mod 6): θ0 −60° ↦ 60° ↦ 180°.
    let kp = KinematicParams::nominal();
    let mut rng = common::rng(7);
    let r = rz(2.0 * PI / 3.0);
    for _ in 0..200 {
        let p = common::random_pose(&mut rng, &PoseBox::documented());
        let e = r * Vec3::new(p[0], p[1], p[2]);
        let ang = euler_from_rotation(&(r * pose_rotation(&p) * r.transpose()));
        let q = Vec6::new(e[0], e[1], e[2], ang[0], ang[1], ang[2]);
        let (tp, tq) = (ik(&kp, &p).unwrap(), ik(&kp, &q).unwrap());
        for i in 0..LEGS {
            assert!((tp[i] - tq[(i + 4) % LEGS]).abs() < 1e-12, "{p}: leg {i}");
        }
    }
}

/// Counts roots of |A − T(θ)|² = l² for θ in (−π/2, π/2] by sign changes on a fine grid.
fn roots_in_branch(kp: &KinematicParams, leg: usize, a: &Vec3) -> usize {
    const N: usize = 2000;
    let f = |th: f64| {
        let phi = th + kp.theta0[leg];
        let t = kp.base_joints[leg] + kp.wrench_lengths[leg] * Vec3::new(phi.cos(), phi.sin(), 0.0);
        (a - t).norm_squared() - kp.link_lengths[leg].powi(2)
    };
    let th = |k: usize| -PI / 2.0 + PI * (k as f64) / (N as f64);
    (0..N)
        .filter(|&k| f(th(k)).signum() != f(th(k + 1)).signum())
        .count()
}

#[test]
fn ik_branch_is_unique_over_the_box() {
    let kp = KinematicParams::nominal();
    let bx = PoseBox::documented();
    let mut rng = common::rng(11);
    let poses: Vec<Vec6> = common::grid3(&bx)
        .chain((0..1000).map(|_| common::random_pose(&mut rng, &bx)))
        .collect();
    for p in &poses {
        let theta = ik(&kp, p).unwrap();
        let a = platform_joints_in_base(&kp, p);
        for i in 0..LEGS {
            assert_eq!(roots_in_branch(&kp, i, &a[i]), 1, "pose {p}, leg {}", i + 1);
            // …and IK returns that root.
            let t = wrench_tips(&kp, &theta)[i];
            assert!(((a[i] - t).norm() - kp.link_lengths[i]).abs() < 1e-12);
        }
    }
}

#[test]
fn platform_size_is_consistent_with_table_5_1() {
    // Table 5.1: platform m = 24 kg, I_x = I_y = 0.178, I_z = 0.350 kg·m².
    let dp = DynamicParams::nominal();
    let (m, ix, iy, iz) = (
        dp.platform.mass,
        dp.platform.inertia[0],
        dp.platform.inertia[1],
        dp.platform.inertia[2],
    );
    assert!(ix + iy >= iz, "triangle inequality of a rigid body");
    // A uniform disc of radius r: I_z = m r²/2 → r ≈ 0.171 m; thickness h from I_x = m(3r² + h²)/12.
    let r_disc = (2.0 * iz / m).sqrt();
    let h2 = 12.0 * ix / m - 3.0 * r_disc * r_disc;
    assert!(
        h2 > 0.0 && h2.sqrt() < 0.1,
        "disc thickness {}",
        h2.max(0.0).sqrt()
    );
    // The spherical joints sit on the platform's rim: joint radius within [1, 1.25]·r_disc, and beyond
    // the radius of gyration √(I_z/m).
    let kp = KinematicParams::nominal();
    for a in &kp.platform_joints {
        let rho = (a[0] * a[0] + a[1] * a[1]).sqrt();
        assert!((rho - PLATFORM_RADIUS).abs() < 1e-15 && a[2] == 0.0);
        assert!(
            rho >= r_disc && rho <= 1.25 * r_disc,
            "joint radius {rho} vs disc {r_disc}"
        );
        assert!(rho > (iz / m).sqrt());
    }
}

#[test]
fn link_lengths_close_the_home_pose_exactly() {
    let kp = KinematicParams::nominal();
    let a = platform_joints_in_base(&kp, &home_pose());
    let t = wrench_tips(&kp, &Vec6::zeros());
    for i in 0..LEGS {
        assert!(((a[i] - t[i]).norm() - kp.link_lengths[i]).abs() < 1e-15);
        assert!(
            (kp.link_lengths[i] - 0.1725).abs() < 1e-3,
            "l_AT = {}",
            kp.link_lengths[i]
        );
    }
}
