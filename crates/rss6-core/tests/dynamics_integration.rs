//! Forward/inverse dynamics and time integration: both inverse-dynamics paths agree, round trips,
//! power balance of RK4 runs, fourth-order convergence, typed errors.
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
fn inverse_dynamics_matches_matrix_form() {
    // Newton–Euler vector path vs J_θ^{-T}(M̃χ̈ + C̃χ̇ + G̃ + τ̃_f) assembled from the matrices.
    let mut r = rng(8);
    let mut worst: f64 = 0.0;
    for n in 0..30 {
        let kp = robot(n, &mut r);
        let dp = random_xi(&mut r);
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let t = dynamics_terms(&kp, &dp, &p, &pd).unwrap();
        let rhs = t.m * pdd + t.c * pd + t.g + t.f;
        let lhs = t.j_theta.transpose() * tau;
        worst = worst.max((lhs - rhs).norm() / rhs.norm());
        // one-pass terms equal the individual functions
        assert!((t.m - mass_matrix(&kp, &dp, &p).unwrap()).amax() <= 1e-13 * t.m.amax());
        assert!((t.c - coriolis(&kp, &dp, &p, &pd).unwrap()).amax() <= 1e-12 * t.c.amax());
        assert!((t.g - gravity(&kp, &dp, &p).unwrap()).amax() <= 1e-12 * t.g.amax());
        assert!((t.f - friction(&kp, &dp, &p, &pd).unwrap()).amax() <= 1e-12 * t.f.amax());
        assert!((t.j_theta - jacobian_theta(&kp, &p).unwrap()).amax() <= 1e-12 * t.j_theta.amax());
    }
    println!("inverse dynamics vector vs matrix form: max rel {worst:.3e}");
    assert!(worst < 1e-11, "{worst}");
}

#[test]
fn forward_and_inverse_dynamics_round_trip() {
    let mut r = rng(11);
    let (mut w1, mut w2) = (0.0f64, 0.0f64);
    for k in 0..40 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
        let tau = inverse_dynamics(&kp, &dp, &p, &Vec6::zeros(), &Vec6::zeros()).unwrap()
            + uniform6(&mut r, 5.0, 5.0);
        let acc = forward_dynamics(&kp, &dp, &p, &pd, &tau).unwrap();
        let back = inverse_dynamics(&kp, &dp, &p, &pd, &acc).unwrap();
        w1 = w1.max((back - tau).amax() / tau.amax());
        let pdd = random_acc(&mut r);
        let t2 = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let a2 = forward_dynamics(&kp, &dp, &p, &pd, &t2).unwrap();
        w2 = w2.max((a2 - pdd).amax() / pdd.amax());
    }
    println!("ID(FD(τ)) − τ: {w1:.3e} rel; FD(ID(χ̈)) − χ̈: {w2:.3e} rel");
    assert!(w1 < 1e-10 && w2 < 1e-9, "{w1} {w2}");
}

/// RK4 run with friction off and a zero-order-hold joint PD: per step the work of the held torque is
/// τᵀΔθ, so E(T) − E(0) = Σ τ_kᵀ Δθ_k (d(T+V)/dt = θ̇ᵀτ_a, integrated exactly over each step).
#[test]
fn power_balance_on_rk4_run() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let hold = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap();
    let energy = |s: &ModelState| {
        kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap()
            + potential_energy_with_gravity(&kp, &dp, &s.pose, &GRAVITY).unwrap()
    };
    let dt = 1e-3;
    let mut s = ModelState {
        pose: home_pose() + Vec6::new(0.005, 0.0, 0.0, 0.0, 0.01, 0.0),
        pose_dot: Vec6::zeros(),
    };
    let e0 = energy(&s);
    let mut work = 0.0;
    let mut work_abs = 0.0;
    let mut k_max: f64 = 0.0;
    let mut theta = ik(&kp, &s.pose).unwrap();
    for step in 0..500 {
        let t = step as f64 * dt;
        let th_dot = jacobian_theta(&kp, &s.pose).unwrap() * s.pose_dot;
        let theta_ref = Vec6::from_fn(|i, _| 0.05 * libm::sin(8.0 * t + i as f64));
        let tau = hold + (theta_ref - theta) * 40.0 - th_dot * 0.5;
        s = rk4_step(&kp, &dp, &s, &tau, dt).unwrap();
        let th_new = ik(&kp, &s.pose).unwrap();
        let dw = tau.dot(&(th_new - theta));
        work += dw;
        work_abs += dw.abs();
        theta = th_new;
        k_max = k_max.max(kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap());
    }
    let de = energy(&s) - e0;
    let err = (de - work).abs() / work_abs;
    println!(
        "power balance over 0.5 s: ΔE = {de:.6e} J, Σ τᵀΔθ = {work:.6e} J, Σ|τᵀΔθ| = {work_abs:.3e} J, max T = {k_max:.3e} J, rel err {err:.3e}"
    );
    assert!(k_max > 1e-3, "the run must actually move");
    assert!(err < 1e-6, "{err}");
}

/// Instantaneous power balance with a constant torque (friction off): along the RK4 trajectory,
/// dE/dt from a 4th-order difference of E over consecutive steps equals θ̇ᵀτ_a at every step.
#[test]
fn instantaneous_power_balance_constant_torque() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap()
        + Vec6::new(0.4, -0.3, 0.2, 0.5, -0.1, 0.3);
    let energy = |s: &ModelState| {
        kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap()
            + potential_energy_with_gravity(&kp, &dp, &s.pose, &GRAVITY).unwrap()
    };
    let dt = 1e-3;
    let mut states = vec![ModelState::at_rest(&home_pose())];
    for _ in 0..200 {
        let s = rk4_step(&kp, &dp, states.last().unwrap(), &tau, dt).unwrap();
        states.push(s);
    }
    let e: Vec<f64> = states.iter().map(energy).collect();
    let mut worst: f64 = 0.0;
    let mut p_max: f64 = 0.0;
    for k in 2..states.len() - 2 {
        let de = (e[k - 2] - e[k + 2] + 8.0 * (e[k + 1] - e[k - 1])) / (12.0 * dt);
        let th_dot = jacobian_theta(&kp, &states[k].pose).unwrap() * states[k].pose_dot;
        let p = th_dot.dot(&tau);
        p_max = p_max.max(p.abs());
        worst = worst.max((de - p).abs());
    }
    let rel_err = worst / p_max;
    println!("instantaneous power: max |dE/dt − θ̇ᵀτ| = {worst:.3e} W, max |θ̇ᵀτ| = {p_max:.3e} W, rel {rel_err:.3e}");
    assert!(p_max > 1e-2, "the run must do work");
    assert!(rel_err < 1e-6, "{rel_err}");
}

/// RK4 is 4th order: halving dt divides the error at t = 0.1 s by ≈ 16.
#[test]
fn rk4_converges_at_fourth_order() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap()
        + Vec6::new(1.0, -0.5, 0.8, 0.2, -0.6, 0.4);
    let run = |n: usize| {
        let dt = 0.1 / n as f64;
        let mut s = ModelState::at_rest(&home_pose());
        for _ in 0..n {
            s = rk4_step(&kp, &dp, &s, &tau, dt).unwrap();
        }
        s
    };
    let reference = run(400);
    let errs: Vec<f64> = [10usize, 20, 40]
        .iter()
        .map(|&n| (run(n).pose - reference.pose).amax())
        .collect();
    let (r1, r2) = (errs[0] / errs[1], errs[1] / errs[2]);
    println!("RK4 errors {errs:?}, ratios {r1:.2} {r2:.2}");
    assert!(
        (12.0..20.0).contains(&r1) && (12.0..20.0).contains(&r2),
        "{r1} {r2}"
    );
}

#[test]
fn errors_are_typed() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let far = Vec6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0);
    assert!(matches!(
        mass_matrix(&kp, &dp, &far),
        Err(CoreError::Unreachable { .. })
    ));
    let nan = Vec6::new(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert_eq!(
        inverse_dynamics(&kp, &dp, &home_pose(), &nan, &Vec6::zeros()),
        Err(CoreError::NonFinite)
    );
    assert_eq!(
        forward_dynamics(&kp, &dp, &nan, &Vec6::zeros(), &Vec6::zeros()),
        Err(CoreError::NonFinite)
    );
}
