//! Zero heap allocations in the kinematic hot paths, counted by an instrumented `#[global_allocator]`.
//!
//! Runs without libtest (`harness = false` in Cargo.toml): the counter is process-wide, and libtest's own
//! threads allocate now and then (seen once under heavy load), which would make the count flaky.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis
use rss6_core::*;
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;
use std::hint::black_box;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Runs `f` and returns the number of allocations (incl. reallocations) it made.
fn allocations(f: impl FnOnce()) -> usize {
    let region = Region::new(GLOBAL);
    f();
    let s = region.change();
    s.allocations + s.reallocations
}

fn kinematic_hot_paths_do_not_allocate() {
    // The counter must see an allocation when there is one.
    assert!(
        allocations(|| drop(black_box(vec![1u8; 64]))) > 0,
        "allocation counter is not counting"
    );

    let kp = KinematicParams::perturbed(&[2e-4; N_KIN_ERRORS]);
    let pose = Vec6::new(0.012, -0.015, 0.128, 0.03, -0.04, 0.02);
    let pose_dot = Vec6::new(0.1, -0.2, 0.05, 0.3, 0.1, -0.2);
    let pose_ddot = Vec6::new(1.0, 0.5, -0.3, -2.0, 1.0, 0.4);
    let theta = ik(&kp, &pose).unwrap();
    let opts = FkOptions::default();
    let limits = BoxLimits::documented();
    let bx = PoseBox::documented();
    let mut sink = 0.0;

    let n = allocations(|| {
        for _ in 0..10 {
            let th = ik(black_box(&kp), black_box(&pose)).unwrap();
            sink += th[0];
            sink += ik_reading(&kp, &pose).unwrap()[1];
            sink += ik_leg(&kp, 3, &platform_joints_in_base(&kp, &pose)[3]).unwrap();
            sink += fk(&kp, black_box(&theta), &home_pose(), &opts)
                .unwrap()
                .pose[2];
            sink += fk(&kp, &theta, &pose, &opts).unwrap().pose[2];
            sink += fk_theta_newton(&kp, &theta, &home_pose(), &opts)
                .unwrap()
                .pose[2];
            let geo = LegGeometry::at_pose(&kp, &pose).unwrap();
            sink += geo.j_a1()[0] + geo.j_a2()[(1, 1)] + geo.j_ad().unwrap()[(2, 2)];
            sink += geo.j_theta().unwrap()[(3, 3)];
            sink += jacobian_a1(&kp, &pose).unwrap()[0];
            sink += jacobian_a2(&kp, &pose).unwrap()[(0, 0)];
            sink += jacobian_ad(&kp, &pose).unwrap()[(0, 0)];
            sink += jacobian_theta(&kp, &pose).unwrap()[(0, 0)];
            sink += jacobian_stewart(&kp, &pose, &wrench_tips(&kp, &theta))
                .unwrap()
                .0[(0, 0)];
            sink += twist_jacobian(&pose)[(4, 4)] + twist_jacobian_dot(&pose, &pose_dot)[(4, 5)];
            sink += twist_jacobian_inverse(&pose).unwrap()[(5, 5)];
            sink += twist_dot(&pose, &pose_dot, &pose_ddot)[3];
            sink += euler_rate_jacobian(pose[3], pose[4])[(1, 1)];
            let c = singularity_check(&kp, &pose).unwrap();
            sink += c.type_i.margin + c.type_ii.condition + c.homeomorphism.ratio;
            sink += type_i_check(&geo).margin;
            sink += type_ii_check(&geo).unwrap().sigma_min;
            sink += homeomorphism_check(&geo).unwrap().ratio;
            // Error paths allocate nothing either.
            sink += f64::from(ik(&kp, &Vec6::new(0.0, 0.0, 1.0, 0.0, 0.0, 0.0)).is_err() as u8);
            sink += f64::from(ik(&kp, &Vec6::repeat(f64::NAN)).is_err() as u8);
            let bad = FkOptions {
                max_iterations: 1,
                ..opts
            };
            sink += f64::from(fk(&kp, &theta, &home_pose(), &bad).is_err() as u8);
        }
        sink += scan_box(&kp, &bx, 2, &limits).unwrap().max_condition;
        sink += verify_box(&kp, &bx, 2, &limits).unwrap().max_abs_theta;
    });
    assert!(sink.is_finite());
    assert_eq!(n, 0, "the kinematic hot paths allocated {n} times");
}

fn main() {
    kinematic_hot_paths_do_not_allocate();
    println!("test kinematic_hot_paths_do_not_allocate ... ok");
    println!("1 passed, 0 failed");
}
