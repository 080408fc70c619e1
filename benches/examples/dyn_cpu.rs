//! Time per call of the dynamics hot paths, robust to a loaded machine (same method as `kin_cpu`):
//! many short rounds of calls, each shorter than a scheduler time slice; the fastest round ran
//! undisturbed, the median round shows typical interference.
//!
//! `cargo run --release -p rss6-benches --example dyn_cpu [rounds]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[allow(dead_code)] // the shared pose module also serves other examples
#[path = "support/poses.rs"]
mod poses;
#[path = "support/rounds.rs"]
mod rounds;
use rounds::measure;

use rss6_core::{
    dynamics_terms, forward_dynamics, forward_dynamics_by_joint_rates, forward_dynamics_with_env,
    inverse_dynamics, jacobian_theta, leg_jacobians, mass_matrix, regressor, rk4_step,
    DynamicParams, Environment, KinematicParams, ModelState, Vec6,
};
use std::hint::black_box;

fn main() {
    let reps: usize = std::env::args().nth(1).map_or(400, |s| s.parse().unwrap());
    let kp = KinematicParams::nominal();
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.2; 6];
    dp.viscous = [0.05; 6];
    let n = 128;
    let poses = poses::box_poses(n);
    let rate = |k: usize| Vec6::from_fn(|i, _| 0.1 * (((k * 7 + i * 3) % 11) as f64 - 5.0) / 5.0);
    let rates: Vec<Vec6> = (0..n).map(rate).collect();
    let accs: Vec<Vec6> = (0..n).map(|k| rate(k + 5) * 20.0).collect();
    let taus: Vec<Vec6> = (0..n)
        .map(|k| inverse_dynamics(&kp, &dp, &poses[k], &rates[k], &accs[k]).unwrap())
        .collect();
    println!("| operation ({reps} rounds × {n} calls) | median round (ns/call) | fastest round (ns/call) |");
    println!("|---|---|---|");
    measure("inverse_dynamics", reps, n, |k| {
        black_box(inverse_dynamics(&kp, &dp, black_box(&poses[k]), &rates[k], &accs[k]).unwrap());
    });
    measure("mass_matrix", reps, n, |k| {
        black_box(mass_matrix(&kp, &dp, black_box(&poses[k])).unwrap());
    });
    measure("forward_dynamics", reps, n, |k| {
        black_box(forward_dynamics(&kp, &dp, black_box(&poses[k]), &rates[k], &taus[k]).unwrap());
    });
    measure("regressor", reps, n, |k| {
        black_box(regressor(&kp, black_box(&poses[k]), &rates[k], &accs[k]).unwrap());
    });
    measure("dynamics_terms", reps, n, |k| {
        black_box(dynamics_terms(&kp, &dp, black_box(&poses[k]), &rates[k]).unwrap());
    });
    measure("leg_jacobians", reps, n, |k| {
        black_box(leg_jacobians(&kp, black_box(&poses[k]), &rates[k]).unwrap());
    });
    measure("rk4_step", reps, n, |k| {
        let s = ModelState {
            pose: poses[k],
            pose_dot: rates[k],
        };
        black_box(rk4_step(&kp, &dp, black_box(&s), &taus[k], 1e-3).unwrap());
    });
    // One stage of the smoothed Coulomb law (the twin's default): θ̇ then the dynamics by two
    // calls (two IKs), and by `forward_dynamics_by_joint_rates` (one IK).
    let mut nc = dp;
    nc.coulomb = [0.0; 6];
    let env = Environment::default();
    let law = |k: usize, td: &Vec6| {
        Vec6::from_fn(|i, _| taus[k][i] - dp.coulomb[i] * (td[i] / 1e-3).tanh())
    };
    measure("smoothed_stage_two_calls", reps, n, |k| {
        let td = jacobian_theta(&kp, black_box(&poses[k])).unwrap() * rates[k];
        let tau = law(k, &td);
        black_box(forward_dynamics_with_env(&kp, &nc, &poses[k], &rates[k], &tau, &env).unwrap());
    });
    measure("smoothed_stage_one_call", reps, n, |k| {
        let p = black_box(&poses[k]);
        let a = forward_dynamics_by_joint_rates(&kp, &nc, p, &rates[k], &env, |td| law(k, td));
        black_box(a.unwrap());
    });
}
