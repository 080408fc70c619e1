//! Ticks per second of the rapier plant driven by a Rust loop: one joint command per tick, reading
//! after each tick what `rss6.Plant.step_joint_commands` returns to Python (time, true pose and joint
//! angles, potentiometers, torques, camera frames). `benches/python/plant_step.py` runs the same loop
//! from Python and compares.
//!
//! `cargo run --release -p rss6-benches --example plant_loop [ticks] [rounds]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::PidGains;
use rss6_sim::{Plant, RobotSim, SimConfig};
use std::time::Instant;

/// The commands both benchmarks send: legs alternating ±0.15 rad sinusoids at 0.5 Hz (rad, drive
/// convention), from home.
fn command(k: usize, dt: f64) -> Vec6 {
    let s = 0.15 * (std::f64::consts::PI * k as f64 * dt).sin();
    Vec6::from_fn(|i, _| if i % 2 == 0 { s } else { -s })
}

fn main() {
    let mut args = std::env::args().skip(1);
    let ticks: usize = args.next().map_or(10_000, |s| s.parse().unwrap());
    let rounds: usize = args.next().map_or(5, |s| s.parse().unwrap());
    let pid = PidGains {
        lp: 400.0,
        li: 2000.0,
        ld: 4.0,
    };
    let cfg = SimConfig::new(KinematicParams::nominal(), DynamicParams::nominal(), pid);
    let cmds: Vec<Vec6> = (0..ticks).map(|k| command(k, cfg.dt)).collect();
    let mut rates = Vec::with_capacity(rounds);
    for _ in 0..rounds {
        let mut plant = Plant::new(cfg.clone()).unwrap();
        plant.reset(&home_pose()).unwrap();
        let start = Instant::now();
        let (mut time, mut pose, mut theta, mut kappa, mut torque) = (
            Vec::with_capacity(ticks),
            Vec::with_capacity(ticks),
            Vec::with_capacity(ticks),
            Vec::with_capacity(ticks),
            Vec::with_capacity(ticks),
        );
        let (mut cam_t, mut cam) = (Vec::new(), Vec::new());
        for c in &cmds {
            plant.step_joint_command(c).unwrap();
            let t = plant.time();
            time.push(t);
            pose.push(plant.true_pose());
            theta.push(plant.true_theta());
            kappa.push(plant.potentiometers());
            torque.push(plant.torques());
            if let Some(z) = plant.camera() {
                cam_t.push(t);
                cam.push(z);
            }
        }
        let elapsed = start.elapsed().as_secs_f64();
        std::hint::black_box((&time, &pose, &theta, &kappa, &torque, &cam_t, &cam));
        rates.push(ticks as f64 / elapsed);
    }
    rates.sort_by(f64::total_cmp);
    println!(
        "rust plant loop: {ticks} ticks x {rounds} rounds: best {:.0} ticks/s, median {:.0} ticks/s",
        rates[rounds - 1],
        rates[rounds / 2]
    );
}
