//! CPU time per call of the kinematic hot paths, robust to a loaded machine (criterion measures wall
//! time, which other processes inflate). Prints a Markdown table; the process's user+system CPU time
//! is read from `/proc/self/stat` (Linux).
//!
//! `cargo run --release -p rss6-benches --example kin_cpu [repetitions]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "support/poses.rs"]
mod poses;

use rss6_core::{
    fk, fk_theta_newton, home_pose, ik, jacobian_theta, FkOptions, KinematicParams, Vec6,
};
use std::hint::black_box;

/// User + system CPU time of this process (s), from /proc/self/stat fields 14 and 15.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat");
    let after = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = after.split_whitespace().collect();
    let ticks: f64 = f[11].parse::<f64>().unwrap() + f[12].parse::<f64>().unwrap();
    ticks / 100.0 // USER_HZ
}

fn measure(name: &str, reps: usize, n: usize, mut op: impl FnMut(usize)) {
    let t0 = cpu_seconds();
    for _ in 0..reps {
        for k in 0..n {
            op(k);
        }
    }
    let ns = (cpu_seconds() - t0) * 1e9 / (reps * n) as f64;
    println!("| {name} | {ns:.0} ns |");
}

fn main() {
    let reps: usize = std::env::args().nth(1).map_or(200, |s| s.parse().unwrap());
    let kp = KinematicParams::nominal();
    let opts = FkOptions::default();
    let n = 1024;
    let cold = poses::box_poses(n);
    let cold_theta: Vec<Vec6> = cold.iter().map(|p| ik(&kp, p).unwrap()).collect();
    let path = poses::smooth_path(n + 1);
    let path_theta: Vec<Vec6> = path.iter().map(|p| ik(&kp, p).unwrap()).collect();
    println!("| operation ({reps} × {n} calls) | CPU time per call |");
    println!("|---|---|");
    measure("ik", reps, n, |k| {
        black_box(ik(&kp, black_box(&cold[k])).unwrap());
    });
    measure("fk_warm", reps, n, |k| {
        black_box(fk(&kp, black_box(&path_theta[k + 1]), &path[k], &opts).unwrap());
    });
    measure("fk_cold", reps, n, |k| {
        black_box(fk(&kp, black_box(&cold_theta[k]), &home_pose(), &opts).unwrap());
    });
    measure("fk_theta_newton_cold", reps / 4 + 1, n, |k| {
        black_box(fk_theta_newton(&kp, black_box(&cold_theta[k]), &home_pose(), &opts).unwrap());
    });
    measure("jacobian_theta", reps, n, |k| {
        black_box(jacobian_theta(&kp, black_box(&cold[k])).unwrap());
    });
}
