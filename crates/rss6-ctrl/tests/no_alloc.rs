//! Zero heap allocations in every `step`, counted by an instrumented `#[global_allocator]`.
//!
//! `harness = false` (see Cargo.toml): the counter is process-wide, so this runs as a plain `main` on one
//! thread, with no libtest threads that could allocate while a region is open.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

mod common;

use common::*;
use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::servo::run;
use rss6_ctrl::*;
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;
use std::hint::black_box;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

fn allocations(f: impl FnOnce()) -> usize {
    let region = Region::new(GLOBAL);
    f();
    let s = region.change();
    s.allocations + s.reallocations
}

fn main() {
    every_step_is_allocation_free();
    println!("no_alloc: every step and the servo loop made 0 allocations");
}

fn every_step_is_allocation_free() {
    assert!(
        allocations(|| drop(black_box(vec![1u8; 64]))) > 0,
        "allocation counter is not counting"
    );

    let kp = KinematicParams::nominal();
    let dp = DynamicParams::nominal();
    let traj1 = Sinusoid::experiment1();
    let traj2 = Fourier::experiment2();
    let est = PoseEstimate {
        pose: home_pose() + Vec6::new(0.002, -0.001, 0.003, 0.01, -0.02, 0.005),
        pose_dot: Vec6::new(0.01, 0.0, -0.01, 0.02, 0.0, 0.01),
        pose_ddot: Vec6::zeros(),
    };
    let theta = Vec6::repeat(0.01);
    let mut kf = PoseKalman::new(KalmanConfig::tuned(), &home_pose()).unwrap();
    let mut kf_ss = PoseKalman::new(
        KalmanConfig {
            steady_state: true,
            ..KalmanConfig::tuned()
        },
        &home_pose(),
    )
    .unwrap();
    let mut dsmc = Dsmc::new(kp, dp, DsmcGains::tuned()).unwrap();
    let mut kcsc = Kcsc::new(kp, CartesianPidGains::thesis(), &Vec6::zeros()).unwrap();
    let mut vpid = VisualPid::new(kp, CartesianPidGains::thesis(), &Vec6::zeros()).unwrap();
    let mut kjsc = Kjsc::new(kp, JointSpaceGains::from_visual_pid(), &Vec6::zeros()).unwrap();
    let mut conv = TorqueToPosition::new(PidGains::tuned(), 1e-3, 30.0).unwrap();
    let mut guard = CommandGuard::new(CommandLimits::nominal(), &Vec6::zeros()).unwrap();
    let mut pid = JointPid::new(PidGains::tuned(), 1e-3, 30.0).unwrap();
    let mut sink = 0.0;

    let n = allocations(|| {
        for k in 0..50 {
            let t = k as f64 * 0.033;
            let r1 = traj1.sample(t);
            let r2 = traj2.sample(t);
            let z = (k % 3 != 0).then_some(r1.pose);
            sink += kf.step(0.033, z.as_ref()).unwrap().pose[0];
            sink += kf_ss.step(0.033, z.as_ref()).unwrap().pose_dot[1];
            sink += kf
                .update_rate(&r1.pose_dot, &Vec6::repeat(1e-6))
                .unwrap()
                .pose_dot[2];
            sink += dsmc.step(&r1, &est, 0.033).unwrap().tau_a[2];
            sink += kcsc.step(&r2, &est, 0.033).unwrap().theta_d[3];
            sink += vpid
                .step(&r1, &est.pose, &est.pose_dot, 0.033)
                .unwrap()
                .theta_d[4];
            sink += kjsc.step(&r2, &theta, 0.033).unwrap().theta_d[5];
            let tau = Vec6::repeat(1.0 + 0.01 * k as f64);
            let out = conv.step(&tau, &theta, &mut guard).unwrap();
            sink += pid.step(&out.theta_cmd, &theta)[0];
            sink += guard.apply(&Vec6::repeat(2.0), 1e-3).unwrap().command[0];
            sink += rss6_ctrl::sat(0.3, 0.1);
        }
        // Fault paths allocate nothing either.
        let mut bad = est;
        bad.pose[0] = f64::NAN;
        sink += dsmc.step(&r_hold(), &bad, 0.033).map_or(1.0, |_| 0.0);
        sink += dsmc.step(&r_hold(), &est, 0.033).map_or(1.0, |_| 0.0);
        sink += kf.step(0.033, Some(&bad.pose)).map_or(1.0, |_| 0.0);
        sink += kf
            .update_rate(&bad.pose, &Vec6::repeat(1e-6))
            .map_or(1.0, |_| 0.0);
    });
    black_box(sink);
    assert_eq!(n, 0, "controller steps allocated {n} times");

    // The whole servo loop on the analytic plant: Servo::tick + servo::run (the plant is allocation-free
    // too; the observer does nothing).
    let aided = ServoConfig {
        kalman: rss6_ctrl::KalmanConfig::model_aided(),
        kalman_model_input: true,
        ..ServoConfig::tuned()
    };
    for (which, config, gains) in [
        (Which::Dsmc, ServoConfig::tuned(), DsmcGains::tuned()),
        (Which::Dsmc, aided, DsmcGains::tuned()),
        (
            Which::Dsmc,
            ServoConfig::low_noise(),
            DsmcGains::low_noise(),
        ),
        (Which::Kcsc, ServoConfig::tuned(), DsmcGains::tuned()),
        (Which::Kjsc, ServoConfig::tuned(), DsmcGains::tuned()),
    ] {
        let start = home_pose();
        let mut plant = rig(
            KinematicParams::perturbed(&table_4_2_errors(3)),
            dp,
            &start,
            Noise {
                camera: true,
                potentiometer: true,
            },
            5,
        );
        let kappa0 = <Rig as Plant>::potentiometers(&plant);
        let theta0 = kp.theta_from_reading(&kappa0);
        let mut servo = Servo::new(
            kp,
            config,
            scheme(which, &theta0, gains),
            &start,
            &kappa0,
            0.0,
        )
        .unwrap();
        let mut frames = 0;
        let n = allocations(|| {
            let s = run(&mut plant, &mut servo, &traj1, 0.0, 300, |rec, _| {
                frames += rec.tick.map_or(0, |t| t.frame as u32);
            })
            .unwrap();
            black_box(s);
        });
        assert_eq!(n, 0, "{which:?}: servo loop allocated {n} times");
        assert!(
            frames >= 9,
            "the loop must have consumed camera frames ({frames})"
        );
    }
}

fn r_hold() -> Reference {
    Reference::hold(&home_pose())
}
