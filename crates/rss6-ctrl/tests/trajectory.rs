//! Reference trajectories: analytic derivatives, the box, reachability and the initial steps.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use rss6_core::{home_pose, ik, KinematicParams, Vec6};
use rss6_ctrl::{Fourier, Sinusoid, Trajectory};

fn check_derivatives(tr: &dyn Trajectory, t_end: f64) {
    let h = 1e-5;
    let mut t = 0.1;
    while t < t_end {
        let r = tr.sample(t);
        let (a, b) = (tr.sample(t - h), tr.sample(t + h));
        let vel_fd = (b.pose - a.pose) / (2.0 * h);
        let acc_fd = (b.pose_dot - a.pose_dot) / (2.0 * h);
        assert!(
            (vel_fd - r.pose_dot).amax() < 1e-8,
            "velocity at t={t}: {vel_fd} vs {}",
            r.pose_dot
        );
        assert!(
            (acc_fd - r.pose_ddot).amax() < 1e-8,
            "acceleration at t={t}"
        );
        t += 0.37;
    }
}

fn check_box_and_reach(tr: &dyn Trajectory, t_end: f64) {
    let kp = KinematicParams::nominal();
    let home = home_pose();
    let mut t = 0.0;
    while t <= t_end {
        let d = tr.sample(t).pose - home;
        for i in 0..3 {
            assert!(
                d[i].abs() <= 0.020,
                "axis {i} leaves the ±20 mm box at t={t}: {}",
                d[i]
            );
            assert!(
                d[i + 3].abs() <= 0.05,
                "axis {} leaves the ±0.05 rad box at t={t}",
                i + 3
            );
        }
        ik(&kp, &tr.sample(t).pose).expect("reference must be reachable");
        t += 0.05;
    }
}

#[test]
fn experiment1_derivatives_box_and_step() {
    let tr = Sinusoid::experiment1();
    check_derivatives(&tr, 30.0);
    check_box_and_reach(&tr, 2.0 * core::f64::consts::PI / 0.5);
    let d0 = tr.sample(0.0).pose - home_pose();
    // The step is in y and z only.
    assert!(
        d0[1].abs() > 5e-3 && d0[2].abs() > 3e-3,
        "initial step in y and z: {d0}"
    );
    for i in [0, 3, 4, 5] {
        assert!(d0[i].abs() < 1e-12, "axis {i} should start at home");
    }
    assert!((tr.omega - 0.5).abs() < 1e-15);
}

#[test]
fn experiment2_derivatives_box_and_step() {
    let tr = Fourier::<5>::experiment2();
    assert!((tr.omega0 - 0.15).abs() < 1e-15);
    check_derivatives(&tr, 60.0);
    // Full period 2π/ω0 ≈ 41.9 s.
    check_box_and_reach(&tr, 2.0 * core::f64::consts::PI / 0.15);
    let d0 = tr.sample(0.0).pose - home_pose();
    for i in 0..6 {
        let min = if i < 3 { 5e-4 } else { 1e-3 };
        assert!(
            d0[i].abs() > min,
            "axis {i} must start off home (step in all dimensions): {d0}"
        );
    }
}

#[test]
fn fourier_matches_eq_6_43_term_by_term() {
    // One harmonic, one axis: compare with the formula written out by hand.
    let mut tr = Fourier::<1> {
        s: [[0.0; 1]; 6],
        c: [[0.0; 1]; 6],
        offset: Vec6::zeros(),
        omega0: 0.3,
    };
    tr.s[2][0] = 0.002;
    tr.c[2][0] = -0.001;
    let t = 1.7;
    let w: f64 = 0.3;
    let expect = (w * t).sin() / w * 0.002 - (w * t).cos() / w * (-0.001);
    assert!((tr.sample(t).pose[2] - expect).abs() < 1e-15);
    assert_eq!(tr.sample(t).pose[0], 0.0);
}
