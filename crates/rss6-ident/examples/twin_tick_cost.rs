//! Where a model-twin replay's time goes (the discrepancy workflow's unit of work): per 1 kHz tick,
//! the core's implicit-friction tick alone, the twin's `step_joint_command` (drive PID, sensors,
//! effects), and the experiment layer's identification loop around it (reference, visual PID,
//! records), on Table 5.2's truth with the stick–slip law.
//!
//! `cargo run --release -p rss6-ident --example twin_tick_cost` (idle machine; prints µs/tick).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use rss6_core::{
    home_pose, ik, implicit_friction, rk4_step_implicit_friction, Environment, ModelState, Vec6,
};
use rss6_exp::{ident, Externals};
use rss6_ident::{table_5_2_truth, Excitation};
use rss6_sim::{ModelSim, RobotSim, SimConfig};
use std::time::Instant;

const TICKS: usize = 10_000;

fn main() {
    let a = table_5_2_truth();
    let mut sc = SimConfig::new(rss6_core::KinematicParams::nominal(), a.dynamics, a.pid);
    sc.implicit_friction = true;
    let free = [
        0.010, -0.004, 0.006, 0.003, -0.008, 0.005, 0.004, -0.002, 0.006, 0.002, -0.005, 0.004,
        0.04, -0.02, 0.03, 0.01, -0.03, 0.02, 0.02, -0.01, 0.05, 0.01, -0.03, 0.02,
    ];
    let exc = Excitation::at_rest(3, 0.5, &home_pose(), &free).unwrap();
    let ext = Externals {
        sensor_in_base: sc.sensor_in_base,
        target_in_effector: sc.target_in_effector,
    };
    let mut spec = ident::IdentSpec::new(sc.kinematics, ext);
    spec.duration = TICKS as f64 * sc.dt;

    // 1. The identification loop on the twin, records kept (as the Python binding collects them).
    let mut twin = ModelSim::new(sc.clone()).unwrap();
    twin.reset(&home_pose()).unwrap();
    let mut recs = Vec::new();
    let t0 = Instant::now();
    ident::run(&mut twin, &spec, &exc, &mut recs).unwrap();
    let loop_us = t0.elapsed().as_secs_f64() * 1e6 / TICKS as f64;
    // The joint commands it sent, replayed on a fresh twin and on the core alone.
    let cmds: Vec<Vec6> = recs.iter().map(|r| r.theta_cmd).collect();
    let torques: Vec<Vec6> = recs.iter().map(|r| r.torque.unwrap()).collect();

    // 2. The twin's own tick.
    let mut twin = ModelSim::new(sc.clone()).unwrap();
    twin.reset(&home_pose()).unwrap();
    let t0 = Instant::now();
    for c in &cmds {
        twin.step_joint_command(c).unwrap();
    }
    let twin_us = t0.elapsed().as_secs_f64() * 1e6 / TICKS as f64;

    // 3. The core's tick under the same torques (open loop: the state drifts from the twin's, the
    // arithmetic per tick is the same).
    let (kp, dp) = (sc.kinematics, sc.dynamics);
    let env = Environment::default();
    let mut s = ModelState::at_rest(&home_pose());
    let mut theta = ik(&kp, &s.pose).unwrap();
    let t0 = Instant::now();
    for tau in &torques {
        let (next, _) =
            rk4_step_implicit_friction(&kp, &dp, &s, tau, sc.dt, &env, Some(&theta)).unwrap();
        s = next;
        theta = ik(&kp, &s.pose).unwrap();
    }
    let core_us = t0.elapsed().as_secs_f64() * 1e6 / TICKS as f64;
    // 4. Its friction step alone, on the same states; the sweeps it took.
    let mut s = ModelState::at_rest(&home_pose());
    let mut states = Vec::with_capacity(TICKS);
    for tau in &torques {
        states.push(s);
        s = rk4_step_implicit_friction(&kp, &dp, &s, tau, sc.dt, &env, None)
            .unwrap()
            .0;
    }
    let mut sweeps = 0u64;
    let t0 = Instant::now();
    for (s, tau) in states.iter().zip(&torques) {
        let f = implicit_friction(&kp, &dp, &s.pose, &s.pose_dot, tau, &env, sc.dt).unwrap();
        sweeps += u64::from(f.sweeps);
    }
    let friction_us = t0.elapsed().as_secs_f64() * 1e6 / TICKS as f64;
    println!(
        "friction step alone {friction_us:.2} µs, {:.1} Gauss–Seidel sweeps a tick",
        sweeps as f64 / TICKS as f64
    );
    println!(
        "µs per tick: identification loop {loop_us:.2}, twin step {twin_us:.2}, core tick + IK {core_us:.2}"
    );
}
