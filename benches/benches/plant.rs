//! Speed of the rapier plant: one 1 kHz tick (PID + rapier step + sensors) with the default solver
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]
//! settings (the ones that meet the ≤ 10 µm loop-closure target), and of the model twin.
//! Real-time factor = 1 ms / time per tick.
//!
//! `cargo bench -p rss6-benches --bench plant -- --warm-up-time 1 --measurement-time 2`

use criterion::{criterion_group, criterion_main, Criterion};
use rss6_core::KinematicParams;
use rss6_sim::{ExcitingTrajectory, ModelSim, Plant, RobotSim, SimConfig};
use std::hint::black_box;

fn commands() -> Vec<rss6_core::Vec6> {
    let traj = ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    (0..2000)
        .map(|k| traj.joint_command(&nominal, k as f64 * 1e-3).expect("ik"))
        .collect()
}

fn bench_plant(c: &mut Criterion) {
    let cmds = commands();
    for it in [4usize, 8, 16] {
        let mut cfg = SimConfig::nominal();
        cfg.solver.iterations = it;
        let mut plant = Plant::new(cfg).expect("plant");
        let mut k = 0;
        c.bench_function(&format!("plant_tick_{it}_iterations"), |b| {
            b.iter(|| {
                if k == cmds.len() {
                    plant.reset(&rss6_core::home_pose()).expect("reset");
                    k = 0;
                }
                plant.step_joint_command(black_box(&cmds[k])).expect("step");
                k += 1;
            })
        });
    }
    let mut twin = ModelSim::new(SimConfig::nominal()).expect("twin");
    let mut k = 0;
    c.bench_function("twin_tick_rk4", |b| {
        b.iter(|| {
            if k == cmds.len() {
                twin.reset(&rss6_core::home_pose()).expect("reset");
                k = 0;
            }
            twin.step_joint_command(black_box(&cmds[k])).expect("step");
            k += 1;
        })
    });
}

criterion_group!(benches, bench_plant);
criterion_main!(benches);
