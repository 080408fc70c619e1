//! Energies from body positions alone (an independent derivation): kinetic energy by finite differences,
//! G̃ as the gradient of the potential (vertical and tilted gravity), static hold torques, friction.
#![allow(
    non_snake_case,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis

mod dynamics_support;

use dynamics_support::*;
use rss6_core::*;

#[test]
fn kinetic_energy_matches_bodies_by_finite_differences() {
    let mut r = rng(3);
    let mut worst: f64 = 0.0;
    for k in 0..30 {
        let kp = robot(k / 2, &mut r);
        // nominal and random (unequal I_x, I_y) parameters
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let m = mass_matrix(&kp, &dp, &p).unwrap();
        let t_model = 0.5 * pd.dot(&(m * pd));
        let t_fd = kinetic_energy_fd(&kp, &dp, &p, &pd);
        worst = worst.max(rel(t_model, t_fd));
        assert!((kinetic_energy(&kp, &dp, &p, &pd).unwrap() - t_model).abs() <= 1e-14 * t_model);
    }
    println!("kinetic energy: max rel. err. model vs bodies-by-FD = {worst:.3e}");
    assert!(worst <= 1e-6, "{worst}");
}

#[test]
fn gravity_is_gradient_of_body_potential() {
    let mut r = rng(4);
    let mut worst: f64 = 0.0;
    for k in 0..30 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let p = random_pose(&mut r);
        let g = gravity(&kp, &dp, &p).unwrap();
        let grad = Vec6::from_fn(|j, _| {
            let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
            d4(|t| potential_energy_bodies(&kp, &dp, &(p + e * t)), 1e-4)
        });
        worst = worst.max((g - grad).norm() / grad.norm());
        let v_lib = potential_energy_with_gravity(&kp, &dp, &p, &GRAVITY).unwrap();
        assert!(rel(v_lib, potential_energy_bodies(&kp, &dp, &p)) < 1e-12);
    }
    println!("gravity: max rel. err. G~ vs grad V (FD) = {worst:.3e}");
    assert!(worst <= 1e-6, "{worst}");
}

#[test]
fn tilted_gravity_is_gradient_too() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let g = Vec3::new(0.3, -0.2, -9.8);
    let p = home_pose() + Vec6::new(0.01, -0.005, 0.004, 0.02, -0.03, 0.01);
    let gv = gravity_with(&kp, &dp, &p, &g).unwrap();
    let grad = Vec6::from_fn(|j, _| {
        let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
        d4(
            |t| potential_energy_with_gravity(&kp, &dp, &(p + e * t), &g).unwrap(),
            1e-4,
        )
    });
    assert!((gv - grad).norm() / grad.norm() < 1e-8, "{gv} {grad}");
}

#[test]
fn static_hold_torques_are_gravity_only_and_home_symmetric() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap();
    // three-fold symmetry: legs 1, 3, 5 equal; 2, 4, 6 equal; mirror pairs opposite in sign
    for i in [2, 4] {
        assert!(
            (tau[i] - tau[0]).abs() < 1e-9 && (tau[i + 1] - tau[1]).abs() < 1e-9,
            "{tau}"
        );
    }
    assert!((tau[0] + tau[1]).abs() < 1e-9, "{tau}");
    // the static torques do work against gravity: J_θᵀ τ = G̃
    let g = gravity(&kp, &dp, &home_pose()).unwrap();
    let jt = jacobian_theta(&kp, &home_pose()).unwrap();
    assert!((jt.transpose() * tau - g).norm() < 1e-10 * g.norm());
    let total_mass = 24.0 + 6.0 * (0.685 + 1.31);
    assert!(g[2] > 9.81 * 24.0 && g[2] < 9.81 * total_mass, "{g}");
    println!("home hold torques {tau:.4}");
}

#[test]
fn friction_opposes_joint_motion() {
    let kp = KinematicParams::nominal();
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.3; 6];
    dp.viscous = [0.1; 6];
    let mut r = rng(12);
    let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
    let f = friction(&kp, &dp, &p, &pd).unwrap();
    assert!(
        f.dot(&pd) > 0.0,
        "friction must dissipate: χ̇ᵀτ̃_f = θ̇ᵀτ_f > 0"
    );
    let th_dot = jacobian_theta(&kp, &p).unwrap() * pd;
    let tf = joint_friction(&dp, &th_dot);
    for i in 0..6 {
        assert!((tf[i] - (0.3 * th_dot[i].signum() + 0.1 * th_dot[i])).abs() < 1e-15);
    }
    let smooth = joint_friction_smooth(&dp, &th_dot, 1e-6);
    assert!((smooth - tf).amax() < 1e-9);
    assert_eq!(joint_friction(&dp, &Vec6::zeros()), Vec6::zeros());
}
