//! Speed of the rapier plant: one 1 kHz tick (PID + rapier step + post-step projection + sensors)
//! with 4 (the default), 8 and 16 solver iterations, 16 without the projection (the old accurate
//! setting), 4 with the shared implicit friction law and the velocity projection (Table 5.2-sized
//! friction), 48 with the implicit law and no velocity projection, and of the model twin.
//! Real-time factor = 1 ms / time per tick.
//!
//! `cargo bench -p rss6-benches --bench plant -- --warm-up-time 1 --measurement-time 2`
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

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
    for (it, projection) in [(4usize, true), (8, true), (16, true), (16, false)] {
        let mut cfg = SimConfig::nominal();
        cfg.solver.iterations = it;
        cfg.solver.projection = projection;
        let mut plant = Plant::new(cfg).expect("plant");
        let mut k = 0;
        let name = if projection {
            format!("plant_tick_{it}_iterations")
        } else {
            format!("plant_tick_{it}_iterations_no_projection")
        };
        c.bench_function(&name, |b| {
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
    // The shared friction law (docs/sim.md): the two settings that follow the twin.
    for (it, vproj) in [(4usize, true), (48, false)] {
        let mut cfg = SimConfig::nominal();
        for i in 0..rss6_core::LEGS {
            cfg.dynamics.coulomb[i] = rss6_core::thesis::TABLE_5_2_COULOMB[i] * 40.0;
            cfg.dynamics.viscous[i] = rss6_core::thesis::TABLE_5_2_VISCOUS[i] * 40.0;
        }
        cfg.implicit_friction = true;
        cfg.solver.iterations = it;
        cfg.solver.velocity_projection = vproj;
        let mut plant = Plant::new(cfg).expect("plant");
        let mut k = 0;
        let name = if vproj {
            format!("plant_tick_{it}_iterations_implicit_friction_velocity_projection")
        } else {
            format!("plant_tick_{it}_iterations_implicit_friction")
        };
        c.bench_function(&name, |b| {
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
