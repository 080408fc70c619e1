//! DSMC: on the sliding surface with the exact model it reproduces inverse dynamics (eq. 6.25–6.26);
//! the boundary layer is continuous; faults latch and reset.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use rss6_core::{home_pose, inverse_dynamics, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::{sat, CtrlError, Dsmc, DsmcGains, FaultReason, PoseEstimate, Reference};

#[test]
fn on_the_surface_dsmc_is_inverse_dynamics() {
    let kp = KinematicParams::nominal();
    let mut dp = DynamicParams::nominal();
    dp.viscous = [0.05; 6];
    dp.coulomb = [0.2; 6];
    let mut dsmc = Dsmc::new(kp, dp, DsmcGains::tuned()).unwrap();
    let r = Reference {
        pose: home_pose() + Vec6::new(0.01, -0.008, 0.004, 0.02, -0.03, 0.01),
        pose_dot: Vec6::new(0.01, 0.02, -0.01, 0.05, 0.02, -0.03),
        pose_ddot: Vec6::new(0.3, -0.2, 0.1, 0.5, -0.4, 0.2),
    };
    let est = PoseEstimate {
        pose: r.pose,
        pose_dot: r.pose_dot,
        pose_ddot: Vec6::zeros(),
    };
    let out = dsmc.step(&r, &est, 0.033).unwrap();
    let expect = inverse_dynamics(&kp, &dp, &r.pose, &r.pose_dot, &r.pose_ddot).unwrap();
    assert!(out.sliding.amax() == 0.0);
    assert!(
        (out.tau_a - expect).amax() < 1e-9 * expect.amax().max(1.0),
        "{} vs {expect}",
        out.tau_a
    );
    assert!(out.in_boundary_layer);
}

#[test]
fn off_the_surface_the_feedback_terms_add_up() {
    let kp = KinematicParams::nominal();
    let dp = DynamicParams::nominal();
    let g = DsmcGains::tuned();
    let mut dsmc = Dsmc::new(kp, dp, g).unwrap();
    let r = Reference::hold(&home_pose());
    let mut est = PoseEstimate {
        pose: home_pose(),
        pose_dot: Vec6::zeros(),
        pose_ddot: Vec6::zeros(),
    };
    est.pose[1] -= 0.001; // e_y = +1 mm → F_y = λ·1e-3 = 6e-3 m/s, inside the layer
    let dt = 0.033;
    let out = dsmc.step(&r, &est, dt).unwrap();
    let f = g.lambda[1] * 1e-3;
    assert!((out.sliding[1] - f).abs() < 1e-15);
    // u − τ_m = K_p F + K_i F dt + K_r F/ε on the y axis.
    let extra = out.generalized - out.tau_model;
    let want = g.kp[1] * f + g.ki[1] * f * dt + g.kr[1] * (f / g.epsilon[1]);
    assert!((extra[1] - want).abs() < 1e-9, "{} vs {want}", extra[1]);
    for i in [0, 2, 3, 4, 5] {
        assert!(extra[i].abs() < 1e-12);
    }
}

#[test]
fn boundary_layer_sat_is_continuous() {
    let eps = 0.02;
    assert_eq!(sat(0.01, eps), 0.5);
    assert_eq!(sat(-0.5, eps), -1.0);
    // No jump at |F| = ε (eq. 6.28 jumps from ε to 1 there).
    assert!((sat(eps * (1.0 - 1e-12), eps) - sat(eps * (1.0 + 1e-12), eps)).abs() < 1e-11);
}

#[test]
fn nan_estimate_latches_until_reset() {
    let mut dsmc = Dsmc::new(
        KinematicParams::nominal(),
        DynamicParams::nominal(),
        DsmcGains::tuned(),
    )
    .unwrap();
    let r = Reference::hold(&home_pose());
    let good = PoseEstimate {
        pose: home_pose(),
        pose_dot: Vec6::zeros(),
        pose_ddot: Vec6::zeros(),
    };
    let held = dsmc.step(&r, &good, 0.033).unwrap();
    let mut bad = good;
    bad.pose_dot[3] = f64::NAN;
    assert_eq!(
        dsmc.step(&r, &bad, 0.033),
        Err(CtrlError::Faulted(FaultReason::NonFiniteMeasurement))
    );
    assert_eq!(
        dsmc.step(&r, &good, 0.033),
        Err(CtrlError::Faulted(FaultReason::NonFiniteMeasurement))
    );
    assert_eq!(dsmc.fault(), Some(FaultReason::NonFiniteMeasurement));
    assert_eq!(dsmc.last_output(), Some(held));
    // Unreachable pose: a model fault with the core's reason.
    dsmc.reset();
    let far = PoseEstimate {
        pose: home_pose() + Vec6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0),
        ..good
    };
    assert!(matches!(
        dsmc.step(&r, &far, 0.033),
        Err(CtrlError::Faulted(FaultReason::Model(_)))
    ));
    dsmc.reset();
    assert!(dsmc.step(&r, &good, 0.033).is_ok());
}

/// The hold stiffness H cancels, to first order, the pose dependence of a held holding torque: at
/// χ0 + δ the model accelerates by ≈ S δ under τ_g(χ0) (≈ 190 rad/s² per rad in α, β at home), and by
/// O(δ²) under τ_g(χ0) + H (θ(χ0 + δ) − θ(χ0)).
#[test]
fn hold_stiffness_cancels_the_held_torque_instability() {
    use rss6_core::{forward_dynamics, ik};
    let kp = KinematicParams::nominal();
    let dp = DynamicParams::nominal();
    let dsmc = Dsmc::new(kp, dp, DsmcGains::tuned()).unwrap();
    for pose0 in [
        home_pose(),
        home_pose() + Vec6::new(0.01, -0.008, 0.005, 0.03, -0.02, 0.01),
    ] {
        let tau0 = dsmc.holding_torque(&pose0).unwrap();
        assert!(
            forward_dynamics(&kp, &dp, &pose0, &Vec6::zeros(), &tau0)
                .unwrap()
                .amax()
                < 1e-9
        );
        let h = dsmc.hold_stiffness(&pose0).unwrap();
        let th0 = ik(&kp, &pose0).unwrap();
        for j in 0..6 {
            let mut d = Vec6::zeros();
            d[j] = if j < 3 { 2e-4 } else { 1e-3 };
            let p = pose0 + d;
            let held = forward_dynamics(&kp, &dp, &p, &Vec6::zeros(), &tau0).unwrap();
            let tau = tau0 + h * (ik(&kp, &p).unwrap() - th0);
            let comp = forward_dynamics(&kp, &dp, &p, &Vec6::zeros(), &tau).unwrap();
            println!(
                "axis {j}: |accel| held {:.3e}, compensated {:.3e}",
                held.amax(),
                comp.amax()
            );
            assert!(
                held.amax() > 1e-2,
                "axis {j}: no hold instability to cancel?"
            );
            assert!(
                comp.amax() < 0.02 * held.amax(),
                "axis {j}: compensation left {:e} of {:e}",
                comp.amax(),
                held.amax()
            );
        }
    }
}
