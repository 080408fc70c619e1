//! Accuracy/speed table of the rapier plant for 2, 4, 8 and 16 solver iterations, with and without
//! the post-step projection (`SolverConfig::projection`): the gap the solver leaves, the loop gap
//! after the tick, the plant–twin difference (Fig. 5.5–5.6 bounds), the cost per 1 kHz tick and the
//! link spin (Assumption 2). Nominal robot, 10 s of the default exciting trajectory.
//!
//! `cargo run --release -p rss6-sim --example plant_table`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::KinematicParams;
use rss6_sim::{pose_distance, ExcitingTrajectory, ModelSim, Plant, RobotSim, SimConfig, TJoint};
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

#[derive(Default)]
struct Row {
    solver_gap: f64,
    gap: f64,
    twin_worst: (f64, f64),
    twin_late: (f64, f64),
    wall: f64,
    cpu: f64,
    spin: f64,
}

fn run(iterations: usize, projection: bool, t_joint: TJoint, secs: f64, twin: bool) -> Row {
    let mut cfg = SimConfig::nominal();
    cfg.solver.iterations = iterations;
    cfg.solver.projection = projection;
    cfg.solver.t_joint = t_joint;
    let nominal = KinematicParams::nominal();
    let mut plant = Plant::new(cfg.clone()).expect("plant");
    let traj = ExcitingTrajectory::default();
    let n = (secs / 1e-3) as usize;
    let cmds: Vec<_> = (0..n)
        .map(|k| traj.joint_command(&nominal, k as f64 * 1e-3).expect("ik"))
        .collect();
    let mut row = Row::default();
    // Timing pass: the plant alone.
    let start = Instant::now();
    let cpu0 = cpu_seconds();
    for c in &cmds {
        plant.step_joint_command(c).expect("step");
    }
    row.wall = start.elapsed().as_secs_f64() / n as f64;
    row.cpu = match (cpu0, cpu_seconds()) {
        (Some(a), Some(b)) => (b - a) / n as f64,
        _ => f64::NAN,
    };
    // Accuracy pass, a fresh plant against the twin.
    let mut plant = Plant::new(cfg.clone()).expect("plant");
    let mut model = ModelSim::new(cfg).expect("twin");
    for (k, c) in cmds.iter().enumerate() {
        plant.step_joint_command(c).expect("step");
        row.solver_gap = row.solver_gap.max(plant.solver_gap());
        row.gap = row.gap.max(plant.loop_closure_error());
        row.spin = plant
            .link_spin_rates()
            .iter()
            .fold(row.spin, |m, s| m.max(s.abs()));
        if twin {
            model.step_joint_command(c).expect("twin step");
            let (dp, da) = pose_distance(&plant.true_pose(), &model.true_pose());
            row.twin_worst = (row.twin_worst.0.max(dp), row.twin_worst.1.max(da));
            if k >= 1000 {
                row.twin_late = (row.twin_late.0.max(dp), row.twin_late.1.max(da));
            }
        }
    }
    row
}

fn main() {
    println!("| solver iterations | projection | solver gap (µm) | loop gap after tick (µm) | plant − twin worst (mm / mrad) | after 1 s (mm / mrad) | link spin (rad/s) | wall µs/tick | CPU µs/tick | real-time factor (CPU) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for projection in [true, false] {
        for it in [2, 4, 8, 16] {
            let r = run(it, projection, TJoint::Spherical, 10.0, true);
            println!(
                "| {it} | {} | {:.1} | {:.3} | {:.4} / {:.4} | {:.4} / {:.4} | {:.1e} | {:.1} | {:.1} | {:.1}x |",
                if projection { "on" } else { "off" },
                r.solver_gap * 1e6,
                r.gap * 1e6,
                r.twin_worst.0 * 1e3,
                r.twin_worst.1 * 1e3,
                r.twin_late.0 * 1e3,
                r.twin_late.1 * 1e3,
                r.spin,
                r.wall * 1e6,
                r.cpu * 1e6,
                1e-3 / r.cpu
            );
        }
    }
    println!();
    println!("| joint at T_i (default solver) | max link spin rate (rad/s) |");
    println!("|---|---|");
    let d = SimConfig::nominal().solver;
    for tj in [TJoint::Spherical, TJoint::Universal] {
        let r = run(d.iterations, d.projection, tj, 3.0, false);
        println!("| {tj:?} | {:.3e} |", r.spin);
    }
}
