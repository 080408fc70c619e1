//! Per-call latency of the rss6-ctrl hot paths with a plain timing loop: median and p99 (criterion gives
//! only central estimates). Run: `cargo run --release -p rss6-benches --example control_latency`.
#![allow(clippy::unwrap_used)]

use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::{
    CommandGuard, CommandLimits, Dsmc, DsmcGains, KalmanConfig, PidGains, PoseKalman, Sinusoid,
    TorqueToPosition, Trajectory,
};
use std::hint::black_box;
use std::time::Instant;

const N: usize = 200_000;

fn report(name: &str, ns: &mut [u64]) {
    ns.sort_unstable();
    let q = |p: f64| ns[((ns.len() as f64 - 1.0) * p).round() as usize];
    let (med, p99) = (q(0.5), q(0.99));
    println!(
        "{name:<24} median {:>7.3} µs   p99 {:>7.3} µs   p99/median {:.2}   max {:>8.3} µs   (n = {})",
        med as f64 / 1e3,
        p99 as f64 / 1e3,
        p99 as f64 / med as f64,
        *ns.last().unwrap() as f64 / 1e3,
        ns.len()
    );
}

fn main() {
    let kp = KinematicParams::nominal();
    let mut kf = PoseKalman::new(KalmanConfig::thesis(), &home_pose()).unwrap();
    let mut dsmc = Dsmc::new(kp, DynamicParams::nominal(), DsmcGains::tuned()).unwrap();
    let traj = Sinusoid::experiment1();
    let refs: Vec<_> = (0..1000).map(|k| traj.sample(k as f64 * 0.033)).collect();
    let mut ns = vec![0u64; N];
    for (k, slot) in ns.iter_mut().enumerate() {
        let r = &refs[k % refs.len()];
        let z = r.pose + Vec6::repeat(1e-5);
        let t0 = Instant::now();
        let est = kf.step(black_box(0.033), Some(black_box(&z))).unwrap();
        black_box(dsmc.step(r, &est, 0.033).unwrap());
        *slot = t0.elapsed().as_nanos() as u64;
    }
    report("camera step (KF+DSMC)", &mut ns);

    let mut conv = TorqueToPosition::new(PidGains::nominal(), 1e-3, 30.0).unwrap();
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
}
