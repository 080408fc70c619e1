//! Accuracy/speed table of the rapier plant: loop-closure gap and cost per 1 kHz step for 4, 8 and 16
//! solver iterations, on the default exciting trajectory (plant alone, nominal robot, 3 s).
//!
//! `cargo run --release -p rss6-sim --example plant_table`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::KinematicParams;
use rss6_sim::{ExcitingTrajectory, Plant, RobotSim, SimConfig, TJoint};
use std::time::Instant;

/// Process CPU time (s) from /proc/self/stat (utime + stime, in 1/100 s clock ticks), so the
/// table is meaningful on a loaded machine; None off Linux.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = stat.rsplit_once(')')?.1;
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn run(iterations: usize, pgs: usize, t_joint: TJoint, secs: f64) -> (f64, f64, f64, f64, f64) {
    let mut cfg = SimConfig::nominal();
    cfg.solver.iterations = iterations;
    cfg.solver.pgs_iterations = pgs;
    cfg.solver.t_joint = t_joint;
    cfg.solver.multibody_legs = std::env::var("MB").is_ok();
    if let Ok(v) = std::env::var("STAB") {
        cfg.solver.stabilization_iterations = v.parse().expect("STAB");
    }
    let nominal = KinematicParams::nominal();
    let mut plant = Plant::new(cfg).expect("plant");
    let traj = ExcitingTrajectory::default();
    let n = (secs / 1e-3) as usize;
    let cmds: Vec<_> = (0..n)
        .map(|k| traj.joint_command(&nominal, k as f64 * 1e-3).expect("ik"))
        .collect();
    let (mut worst, mut worst_late, mut spin) = (0.0f64, 0.0f64, 0.0f64);
    let start = Instant::now();
    let cpu0 = cpu_seconds();
    for (k, c) in cmds.iter().enumerate() {
        plant.step_joint_command(c).expect("step");
        let e = plant.loop_closure_error();
        worst = worst.max(e);
        if k as f64 * 1e-3 > 1.0 {
            worst_late = worst_late.max(e);
        }
        spin = plant
            .link_spin_rates()
            .iter()
            .fold(spin, |m, s| m.max(s.abs()));
    }
    let per_step = start.elapsed().as_secs_f64() / n as f64;
    let cpu = match (cpu0, cpu_seconds()) {
        (Some(a), Some(b)) => (b - a) / n as f64,
        _ => f64::NAN,
    };
    (worst, worst_late, per_step, cpu, spin)
}

fn main() {
    println!("| solver iterations | PGS per iteration | worst loop gap (µm) | after 1 s (µm) | wall µs/step | CPU µs/step | real-time factor (CPU) |");
    println!("|---|---|---|---|---|---|---|");
    for pgs in [1, 2, 3] {
        for it in [4, 8, 16] {
            let (w, wl, s, cpu, _) = run(it, pgs, TJoint::Spherical, 5.0);
            println!(
                "| {it} | {pgs} | {:.2} | {:.2} | {:.1} | {:.1} | {:.1}x |",
                w * 1e6,
                wl * 1e6,
                s * 1e6,
                cpu * 1e6,
                1e-3 / cpu
            );
        }
    }
    println!();
    println!("| joint at T_i | max link spin rate (rad/s) |");
    println!("|---|---|");
    for tj in [TJoint::Spherical, TJoint::Universal] {
        let (_, _, _, _, spin) = run(16, 2, tj, 3.0);
        println!("| {tj:?} | {spin:.3e} |");
    }
}
