//! Per-call latency of the rss6-ctrl hot paths with a plain timing loop: median and p99 (criterion gives
//! only central estimates). Run: `cargo run --release -p rss6-benches --example control_latency`.
#![allow(clippy::unwrap_used)]

use rss6_core::thesis::CONTROL_PERIOD;
use rss6_core::{home_pose, ik, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::{
    CommandGuard, CommandLimits, Dsmc, DsmcGains, KalmanConfig, PidGains, PoseKalman, Scheme,
    Servo, ServoConfig, Sinusoid, TorqueToPosition, Trajectory,
};
use std::hint::black_box;
use std::time::Instant;

const N: usize = 200_000;

fn report(name: &str, ns: &mut [u64]) {
    ns.sort_unstable();
    let q = |p: f64| ns[((ns.len() as f64 - 1.0) * p).round() as usize];
    let (med, p99) = (q(0.5), q(0.99));
    println!(
        "{name:<30} median {:>7.3} µs   p99 {:>7.3} µs   p99/median {:.2}   max {:>8.3} µs   (n = {})",
        med as f64 / 1e3,
        p99 as f64 / 1e3,
        p99 as f64 / med as f64,
        *ns.last().unwrap() as f64 / 1e3,
        ns.len()
    );
}

fn main() {
    let kp = KinematicParams::nominal();
    let mut kf = PoseKalman::new(KalmanConfig::tuned(), &home_pose()).unwrap();
    let mut dsmc = Dsmc::new(kp, DynamicParams::nominal(), DsmcGains::tuned()).unwrap();
    let traj = Sinusoid::experiment1();
    let refs: Vec<_> = (0..1000)
        .map(|k| traj.sample(k as f64 * CONTROL_PERIOD))
        .collect();
    let mut ns = vec![0u64; N];
    for (k, slot) in ns.iter_mut().enumerate() {
        let r = &refs[k % refs.len()];
        let z = r.pose + Vec6::repeat(1e-5);
        let t0 = Instant::now();
        let est = kf
            .step(black_box(CONTROL_PERIOD), Some(black_box(&z)))
            .unwrap();
        black_box(dsmc.step(r, &est, CONTROL_PERIOD).unwrap());
        *slot = t0.elapsed().as_nanos() as u64;
    }
    report("camera step (KF+DSMC)", &mut ns);

    let mut conv = TorqueToPosition::new(PidGains::tuned(), 1e-3, 30.0).unwrap();
    let mut guard = CommandGuard::new(CommandLimits::nominal(), &Vec6::zeros()).unwrap();
    let theta = Vec6::repeat(0.01);
    for (k, slot) in ns.iter_mut().enumerate() {
        let tau = Vec6::repeat(2.0 + 1e-3 * (k % 100) as f64);
        let t0 = Instant::now();
        black_box(
            conv.step(black_box(&tau), black_box(&theta), &mut guard)
                .unwrap(),
        );
        *slot = t0.elapsed().as_nanos() as u64;
    }
    report("converter tick", &mut ns);

    // The whole DSMC servo (Servo::tick) on synthetic readings along the reference: the camera-frame tick
    // (filter, DSMC, converter; with low_noise also the potentiometer rate and the hold compensation) and
    // the joint ticks between frames, for the default and the low-noise configuration.
    let frames = N / 33;
    for (name, config, gains) in [
        ("servo default", ServoConfig::tuned(), DsmcGains::tuned()),
        (
            "servo low-noise",
            ServoConfig::low_noise(),
            DsmcGains::low_noise(),
        ),
    ] {
        let dsmc = Dsmc::new(kp, DynamicParams::nominal(), gains).unwrap();
        let kappa0 = kp.reading_from_theta(&ik(&kp, &home_pose()).unwrap());
        let mut servo =
            Servo::new(kp, config, Scheme::Dsmc(dsmc), &home_pose(), &kappa0, 0.0).unwrap();
        let mut frame_ns = vec![0u64; frames];
        let mut joint_ns = Vec::with_capacity(frames * 32);
        let mut tick = 0u64;
        for slot in frame_ns.iter_mut() {
            for j in 0..33 {
                tick += 1;
                let t = tick as f64 * 1e-3;
                let r = traj.sample(t % 30.0);
                let kappa = kp.reading_from_theta(&ik(&kp, &r.pose).unwrap());
                let z = r.pose + Vec6::repeat(1e-5);
                let camera = (j == 32).then_some(&z);
                let t0 = Instant::now();
                black_box(servo.tick(t, &r, camera, &kappa).unwrap());
                let dt = t0.elapsed().as_nanos() as u64;
                if j == 32 {
                    *slot = dt;
                } else {
                    joint_ns.push(dt);
                }
            }
        }
        report(&format!("{name}: frame tick"), &mut frame_ns);
        report(&format!("{name}: joint tick"), &mut joint_ns);
    }
}
