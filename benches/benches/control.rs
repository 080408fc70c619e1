//! rss6-ctrl hot paths: one camera-rate step (Kalman update + DSMC with M̃, C̃, G̃; target ≤ 5 µs) and
//! one joint-rate converter tick (eq. 6.37–6.38 + command guard).
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion};
use rss6_core::thesis::CONTROL_PERIOD;
use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::{
    CommandGuard, CommandLimits, Dsmc, DsmcGains, KalmanConfig, PidGains, PoseKalman, Sinusoid,
    TorqueToPosition, Trajectory,
};
use std::hint::black_box;

fn camera_step(c: &mut Criterion) {
    let kp = KinematicParams::nominal();
    let mut kf = PoseKalman::new(KalmanConfig::tuned(), &home_pose()).unwrap();
    let mut dsmc = Dsmc::new(kp, DynamicParams::nominal(), DsmcGains::tuned()).unwrap();
    let traj = Sinusoid::experiment1();
    let mut k = 0u32;
    c.bench_function("control/camera_step", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let t = f64::from(k % 1000) * CONTROL_PERIOD;
            let r = traj.sample(t);
            let z = r.pose + Vec6::repeat(1e-5);
            let est = kf
                .step(black_box(CONTROL_PERIOD), Some(black_box(&z)))
                .unwrap();
            black_box(dsmc.step(&r, &est, CONTROL_PERIOD).unwrap())
        })
    });
}

fn converter_tick(c: &mut Criterion) {
    let mut conv = TorqueToPosition::new(PidGains::tuned(), 1e-3, 30.0).unwrap();
    let mut guard = CommandGuard::new(CommandLimits::nominal(), &Vec6::zeros()).unwrap();
    let tau = Vec6::new(3.0, -2.0, 4.0, 1.0, -3.5, 2.5);
    let theta = Vec6::repeat(0.01);
    c.bench_function("control/converter_tick", |b| {
        b.iter(|| {
            black_box(
                conv.step(black_box(&tau), black_box(&theta), &mut guard)
                    .unwrap(),
            )
        })
    });
}

criterion_group!(benches, camera_step, converter_tick);
criterion_main!(benches);
