//! Criterion benches of the rss6-core dynamics (target: inverse dynamics ≤ 2 µs).
//!
//! `cargo bench -p rss6-benches --bench dynamics -- --warm-up-time 1 --measurement-time 2`, or
//! `scripts/bench.sh dynamics`; load-robust CPU times: `cargo run --release -p rss6-benches --example dyn_cpu`.
#![allow(missing_docs, clippy::unwrap_used)]
use criterion::{criterion_group, criterion_main, Criterion};
use rss6_core::*;
use std::hint::black_box;

fn state() -> (KinematicParams, DynamicParams, Vec6, Vec6, Vec6) {
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.2; 6];
    dp.viscous = [0.05; 6];
    (
        KinematicParams::nominal(),
        dp,
        Vec6::new(0.012, -0.015, 0.128, 0.03, -0.04, 0.02),
        Vec6::new(0.1, -0.2, 0.05, 0.3, 0.1, -0.2),
        Vec6::new(1.0, 0.5, -0.3, -2.0, 1.0, 0.4),
    )
}

fn bench_dynamics(c: &mut Criterion) {
    let (kp, dp, p, pd, pdd) = state();
    let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
    let s = ModelState {
        pose: p,
        pose_dot: pd,
    };
    let mut g = c.benchmark_group("dynamics");
    g.bench_function("leg_geometry_ik", |b| {
        b.iter(|| LegGeometry::at_pose(black_box(&kp), black_box(&p)))
    });
    g.bench_function("inverse_dynamics", |b| {
        b.iter(|| inverse_dynamics(black_box(&kp), &dp, black_box(&p), &pd, &pdd))
    });
    g.bench_function("mass_matrix", |b| {
        b.iter(|| mass_matrix(black_box(&kp), &dp, black_box(&p)))
    });
    g.bench_function("forward_dynamics", |b| {
        b.iter(|| forward_dynamics(black_box(&kp), &dp, black_box(&p), &pd, &tau))
    });
    g.bench_function("regressor", |b| {
        b.iter(|| regressor(black_box(&kp), black_box(&p), &pd, &pdd))
    });
    g.bench_function("dynamics_terms", |b| {
        b.iter(|| dynamics_terms(black_box(&kp), &dp, black_box(&p), &pd))
    });
    g.bench_function("leg_jacobians", |b| {
        b.iter(|| leg_jacobians(black_box(&kp), black_box(&p), &pd))
    });
    g.bench_function("rk4_step", |b| {
        b.iter(|| rk4_step(black_box(&kp), &dp, black_box(&s), &tau, 1e-3))
    });
    // One tick of the implicit friction law: the two calls, and core's one call that shares the
    // first RK4 stage with the friction step (and takes the angles of the last IK).
    let env = Environment::default();
    let mut nf = dp;
    nf.coulomb = [0.0; 6];
    nf.viscous = [0.0; 6];
    let theta = ik(&kp, &p).unwrap();
    g.bench_function("implicit_friction_tick_two_calls", |b| {
        b.iter(|| {
            let f = implicit_friction(&kp, &dp, &p, &pd, &tau, &env, 1e-3).unwrap();
            rk4_step_with_env(&kp, &nf, black_box(&s), &(tau - f.torque), 1e-3, &env)
        })
    });
    g.bench_function("implicit_friction_tick_one_call", |b| {
        b.iter(|| {
            rk4_step_implicit_friction(&kp, &dp, black_box(&s), &tau, 1e-3, &env, Some(&theta))
        })
    });
    // One RK4 stage of the smoothed Coulomb law (f_c tanh(θ̇/ε) as a known torque, the twin's
    // and CLOE's default): θ̇ by `jacobian_theta` then the forward dynamics (two IKs), and
    // `forward_dynamics_by_joint_rates` (one).
    let mut nc = dp;
    nc.coulomb = [0.0; 6];
    let law = |td: &Vec6| Vec6::from_fn(|i, _| tau[i] - dp.coulomb[i] * (td[i] / 1e-3).tanh());
    g.bench_function("smoothed_stage_two_calls", |b| {
        b.iter(|| {
            let td = jacobian_theta(black_box(&kp), black_box(&p)).unwrap() * pd;
            forward_dynamics_with_env(&kp, &nc, black_box(&p), &pd, &law(&td), &env)
        })
    });
    g.bench_function("smoothed_stage_one_call", |b| {
        b.iter(|| {
            forward_dynamics_by_joint_rates(black_box(&kp), &nc, black_box(&p), &pd, &env, law)
        })
    });
    g.finish();
}

criterion_group!(benches, bench_dynamics);
criterion_main!(benches);
