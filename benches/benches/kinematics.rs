//! Kinematics benchmarks: IK, FK warm-started along a smooth path, FK cold from home, Newton-on-θ FK,
//! Jacobians and the workspace check. Targets (2-core dev machine): fk warm ≤ 1 µs, fk cold ≤ 3 µs,
//! ik ≤ 0.3 µs. Run all benches with `scripts/bench.sh`.
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

#[path = "../examples/support/poses.rs"]
mod poses;

use criterion::{criterion_group, criterion_main, Criterion};
use rss6_core::{
    fk, fk_theta_newton, home_pose, ik, jacobian_theta, singularity_check, FkOptions,
    KinematicParams, LegGeometry, Vec6,
};
use std::hint::black_box;

const N: usize = 1024;

fn kinematics(c: &mut Criterion) {
    let kp = KinematicParams::nominal();
    let opts = FkOptions::default();
    let cold: Vec<Vec6> = poses::box_poses(N);
    let cold_theta: Vec<Vec6> = cold.iter().map(|p| ik(&kp, p).unwrap()).collect();
    let path: Vec<Vec6> = poses::smooth_path(N + 1);
    let path_theta: Vec<Vec6> = path.iter().map(|p| ik(&kp, p).unwrap()).collect();

    let mut g = c.benchmark_group("kinematics");
    let mut k = 0usize;
    g.bench_function("ik", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            ik(black_box(&kp), black_box(&cold[k])).unwrap()
        })
    });
    // Both FK methods, warm and cold. Warm: solve sample k+1 of the 1 kHz path starting from sample
    // k's pose (what the previous solve returned, to 1e-13). Cold: a box pose from home.
    type FkFn =
        fn(&KinematicParams, &Vec6, &Vec6, &FkOptions) -> rss6_core::Result<rss6_core::FkSolution>;
    let home = home_pose();
    for (method, solve) in [
        ("fk", fk as FkFn),
        ("fk_theta_newton", fk_theta_newton as FkFn),
    ] {
        let mut k = 0usize;
        g.bench_function(format!("{method}_warm"), |b| {
            b.iter(|| {
                k = (k + 1) % N;
                solve(
                    &kp,
                    black_box(&path_theta[k + 1]),
                    black_box(&path[k]),
                    &opts,
                )
                .unwrap()
            })
        });
        let mut k = 0usize;
        g.bench_function(format!("{method}_cold"), |b| {
            b.iter(|| {
                k = (k + 1) % N;
                solve(&kp, black_box(&cold_theta[k]), black_box(&home), &opts).unwrap()
            })
        });
    }
    let mut k = 0usize;
    g.bench_function("jacobian_theta", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            jacobian_theta(&kp, black_box(&cold[k])).unwrap()
        })
    });
    // IK + J_a1, J_a2, J_ad and J_θ from one leg geometry (what a control step needs).
    let mut k = 0usize;
    g.bench_function("jacobians_all", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            let geo = LegGeometry::at_pose(&kp, black_box(&cold[k])).unwrap();
            (
                geo.j_a1(),
                geo.j_a2(),
                geo.j_ad().unwrap(),
                geo.j_theta().unwrap(),
            )
        })
    });
    let mut k = 0usize;
    g.bench_function("singularity_check", |b| {
        b.iter(|| {
            k = (k + 1) % N;
            singularity_check(&kp, black_box(&cold[k])).unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, kinematics);
criterion_main!(benches);
