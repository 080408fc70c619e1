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

#[test]
fn the_converter_inverts_a_drive_with_a_filtered_derivative() {
    let gains = PidGains::tuned();
    let (dt, limit, t_f) = (1e-3, 30.0, 5e-3);
    let mut drive = JointPid::new(gains, dt, limit)
        .unwrap()
        .with_derivative_filter(t_f)
        .unwrap();
    let mut conv = TorqueToPosition::mirroring(&drive).unwrap();
    let wide = CommandLimits {
        min: Vec6::repeat(-10.0),
        max: Vec6::repeat(10.0),
        max_rate: 1e6,
    };
    let mut guard = CommandGuard::new(wide, &Vec6::zeros()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut theta = Vec6::zeros();
    let mut tau = Vec6::zeros();
    let mut worst: f64 = 0.0;
    for k in 0..3000 {
        if k % 33 == 0 {
            tau = random_vec(&mut rng, 8.0);
        }
        theta += random_vec(&mut rng, 2e-4);
        let out = conv.step(&tau, &theta, &mut guard).unwrap();
        let applied = drive.step(&out.theta_cmd, &theta);
        worst = worst.max((applied - tau).amax());
        assert_eq!(applied, out.tau_expected);
    }
    // Measured ≈ 1e-14 N·m (rounding); the unfiltered inverse would be off by the filter's memory.
    assert!(worst < 1e-9, "largest torque mismatch {worst} N·m");
}

#[test]
fn a_filtered_derivative_spreads_a_command_step_over_its_time_constant() {
    let gains = PidGains {
        lp: 0.0,
        li: 0.0,
        ld: 4.0,
    };
    let dt = 1e-3;
    let mut raw = JointPid::new(gains, dt, f64::INFINITY).unwrap();
    let mut filt = raw.clone().with_derivative_filter(4e-3).unwrap();
    let zero = Vec6::zeros();
    raw.step(&zero, &zero);
    filt.step(&zero, &zero);
    // A 1 mrad command step: the unfiltered D kicks l_d·Δ/dt = 4 N·m for one tick; the filtered
    // one starts at l_d·Δ/(T_f + dt) = 0.8 N·m and decays by T_f/(T_f + dt) = 0.8 a tick.
    let step = Vec6::repeat(1e-3);
    let k_raw = raw.step(&step, &zero)[0];
    let k_filt = filt.step(&step, &zero)[0];
    assert!((k_raw - 4.0).abs() < 1e-12, "{k_raw}");
    assert!((k_filt - 0.8).abs() < 1e-12, "{k_filt}");
    let next = filt.step(&step, &zero)[0];
    assert!((next - 0.64).abs() < 1e-12, "{next}");
    assert_eq!(raw.step(&step, &zero)[0], 0.0);
    // Time constant 0 is the unfiltered law, bit for bit.
    let mut zero_filter = JointPid::new(PidGains::tuned(), dt, 30.0)
        .unwrap()
        .with_derivative_filter(0.0)
        .unwrap();
    let mut plain = JointPid::new(PidGains::tuned(), dt, 30.0).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..100 {
        let (c, m) = (random_vec(&mut rng, 0.01), random_vec(&mut rng, 0.01));
        assert_eq!(zero_filter.step(&c, &m), plain.step(&c, &m));
    }
}
