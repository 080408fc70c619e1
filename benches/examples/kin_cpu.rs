//! Time per call of the kinematic hot paths, robust to a loaded machine: criterion's median of wall
//! time includes the time other processes hold the core. Here each operation runs in many short rounds
//! (256 calls, well under a scheduler time slice) and the fastest round is reported next to the median
//! round: the fastest round is one that ran undisturbed.
//!
//! `cargo run --release -p rss6-benches --example kin_cpu [rounds] [calls_per_round]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "support/poses.rs"]
mod poses;
#[path = "support/rounds.rs"]
mod rounds;
use rounds::measure;

use rss6_core::{
    fk, fk_theta_newton, home_pose, ik, jacobian_theta, FkOptions, KinematicParams, Vec6,
};
use std::hint::black_box;

fn main() {
    let reps: usize = std::env::args().nth(1).map_or(400, |s| s.parse().unwrap());
    let kp = KinematicParams::nominal();
    let opts = FkOptions::default();
    // Calls per round (default 256); a large value (e.g. 100000) makes each round span several time
    // slices, and on a loaded machine its time per call rises to criterion's level.
    let n: usize = std::env::args().nth(2).map_or(256, |s| s.parse().unwrap());
    let cold = poses::box_poses(n);
    let cold_theta: Vec<Vec6> = cold.iter().map(|p| ik(&kp, p).unwrap()).collect();
    let path = poses::smooth_path(n + 1);
    let path_theta: Vec<Vec6> = path.iter().map(|p| ik(&kp, p).unwrap()).collect();
    println!("| operation ({reps} rounds × {n} calls) | median round (ns/call) | fastest round (ns/call) |");
    println!("|---|---|---|");
    measure("ik", reps, n, |k| {
        black_box(ik(&kp, black_box(&cold[k])).unwrap());
    });
    measure("fk_warm", reps, n, |k| {
        black_box(fk(&kp, black_box(&path_theta[k + 1]), &path[k], &opts).unwrap());
    });
    measure("fk_cold", reps, n, |k| {
        black_box(fk(&kp, black_box(&cold_theta[k]), &home_pose(), &opts).unwrap());
    });
    measure("fk_theta_newton_cold", reps, n, |k| {
        black_box(fk_theta_newton(&kp, black_box(&cold_theta[k]), &home_pose(), &opts).unwrap());
    });
    measure("jacobian_theta", reps, n, |k| {
        black_box(jacobian_theta(&kp, black_box(&cold[k])).unwrap());
    });
}
