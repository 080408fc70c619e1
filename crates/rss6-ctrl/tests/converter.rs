//! Torque-to-position converter: exact discrete inverse of the drive PID, also under command limits.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::Vec6;
use rss6_ctrl::{CommandGuard, CommandLimits, JointPid, PidGains, TorqueToPosition};

fn random_vec(rng: &mut ChaCha8Rng, scale: f64) -> Vec6 {
    Vec6::from_fn(|_, _| rng.random_range(-scale..scale))
}

#[test]
fn drive_pid_applies_exactly_the_requested_torque() {
    let gains = PidGains::tuned();
    let (dt, limit) = (1e-3, 30.0);
    let mut drive = JointPid::new(gains, dt, limit).unwrap();
    let mut conv = TorqueToPosition::new(gains, dt, limit).unwrap();
    let wide = CommandLimits {
        min: Vec6::repeat(-10.0),
        max: Vec6::repeat(10.0),
        max_rate: 1e6,
    };
    let mut guard = CommandGuard::new(wide, &Vec6::zeros()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut theta = Vec6::zeros();
    let mut worst: f64 = 0.0;
    let mut tau = Vec6::zeros();
    for k in 0..3000 {
        // Torque held for 33 ticks like a 30 Hz DSMC, potentiometer angle wandering with noise.
        if k % 33 == 0 {
            tau = random_vec(&mut rng, 8.0);
        }
        theta += random_vec(&mut rng, 2e-4);
        let out = conv.step(&tau, &theta, &mut guard).unwrap();
        let applied = drive.step(&out.theta_cmd, &theta);
        worst = worst.max((applied - tau).amax());
        assert!(
            (applied - out.tau_expected).amax() == 0.0,
            "shadow must equal the drive bit for bit"
        );
    }
    assert!(worst < 1e-9, "largest torque mismatch {worst} N·m");
}

#[test]
fn shadow_stays_in_sync_when_commands_are_limited() {
    let gains = PidGains::tuned();
    let (dt, limit) = (1e-3, 30.0);
    let mut drive = JointPid::new(gains, dt, limit).unwrap();
    let mut conv = TorqueToPosition::new(gains, dt, limit).unwrap();
    // Tight rate limit: 0.5 rad/s → 0.5 mrad per tick; a 20 N·m request needs ≈ 5 mrad at once.
    let tight = CommandLimits {
        min: Vec6::repeat(-0.2),
        max: Vec6::repeat(0.2),
        max_rate: 0.5,
    };
    let mut guard = CommandGuard::new(tight, &Vec6::zeros()).unwrap();
    let theta = Vec6::repeat(0.1);
    let tau = Vec6::new(20.0, -20.0, 5.0, -5.0, 29.0, 0.0);
    let mut limited = false;
    for _ in 0..2000 {
        let out = conv.step(&tau, &theta, &mut guard).unwrap();
        limited |= out.rate_limited;
        let applied = drive.step(&out.theta_cmd, &theta);
        assert_eq!(applied, out.tau_expected);
        assert_eq!(drive, *conv.shadow());
    }
    assert!(limited, "the test must exercise the rate limit");
    // Once the limit no longer binds the torque is exact again.
    let out = conv.step(&tau, &theta, &mut guard).unwrap();
    let applied = drive.step(&out.theta_cmd, &theta);
    assert!((applied - tau).amax() < 1e-9, "{applied} vs {tau}");
}
