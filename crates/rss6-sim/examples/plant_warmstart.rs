//! Effect of rapier's `warmstart_joints` on the raw plant solver (projection off): loop gap after
//! one tick from an exactly closed state at rest (PID holding the home angles), the worst gap over
//! 1 s of that hold, the worst gap over 2 s of the default exciting trajectory, and CPU µs/tick,
//! for 2, 4 and 8 solver iterations with joint warm-starting off and on.
//!
//! `cargo run --release -p rss6-sim --example plant_warmstart`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::KinematicParams;
use rss6_sim::{ExcitingTrajectory, Plant, RobotSim, SimConfig};
use std::time::Instant;

fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit_once(')').map(|r| r.1).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let t = |i: usize| {
        f.get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    (t(11) + t(12)) / 100.0
}

fn main() {
    let nominal = KinematicParams::nominal();
    let traj = ExcitingTrajectory::default();
    let n_dyn = 2000;
    let cmds: Vec<_> = (0..n_dyn)
        .map(|k| traj.joint_command(&nominal, k as f64 * 1e-3).expect("ik"))
        .collect();
    println!("| iterations×PGS | warmstart_joints | gap after 1 tick at rest (µm) | worst over 1 s at rest (µm) | worst over 2 s exciting (µm) | CPU µs/tick |");
    println!("|---|---|---|---|---|---|");
    for it in [2usize, 4, 8] {
        for warm in [false, true] {
            let mut cfg = SimConfig::nominal();
            cfg.solver.iterations = it;
            cfg.solver.projection = false;
            cfg.solver.warmstart_joints = warm;
            let pgs = cfg.solver.pgs_iterations;
            let mut plant = Plant::new(cfg.clone()).expect("plant");
            let hold = plant.true_theta();
            plant.step_joint_command(&hold).expect("step");
            let first = plant.solver_gap();
            let mut rest_worst = first;
            for _ in 1..1000 {
                plant.step_joint_command(&hold).expect("step");
                rest_worst = rest_worst.max(plant.loop_closure_error());
            }
            let mut plant = Plant::new(cfg).expect("plant");
            let mut dyn_worst: f64 = 0.0;
            let cpu0 = cpu_seconds();
            let t0 = Instant::now();
            for c in &cmds {
                plant.step_joint_command(c).expect("step");
                dyn_worst = dyn_worst.max(plant.loop_closure_error());
            }
            let _wall = t0.elapsed();
            let cpu = (cpu_seconds() - cpu0) / n_dyn as f64;
            println!(
                "| {it}×{pgs} | {warm} | {:.3} | {:.3} | {:.3} | {:.1} |",
                first * 1e6,
                rest_worst * 1e6,
                dyn_worst * 1e6,
                cpu * 1e6
            );
        }
    }
}
