//! Profiling driver (temporary).
#![allow(clippy::unwrap_used, clippy::expect_used)]
use rss6_core::KinematicParams;
use rss6_sim::{pose_distance, ExcitingTrajectory, ModelSim, Plant, RobotSim, SimConfig};
use std::time::Instant;
fn env<T: std::str::FromStr>(k: &str, d: T) -> T
where
    T::Err: std::fmt::Debug,
{
    std::env::var(k).map(|v| v.parse().unwrap()).unwrap_or(d)
}
fn main() {
    let it: usize = env("IT", 16);
    let pgs: usize = env("PGS", 2);
    let secs: f64 = env("SECS", 5.0);
    let mut cfg = SimConfig::nominal();
    cfg.solver.iterations = it;
    cfg.solver.pgs_iterations = pgs;
    cfg.solver.warmstart_joints = std::env::var("WS").is_ok();
    cfg.solver.projection = std::env::var("PROJ").is_ok();
    cfg.solver.stabilization_iterations = env("STAB", 1);
    let nominal = KinematicParams::nominal();
    let mut plant = Plant::new(cfg.clone()).unwrap();
    let twin_on = std::env::var("TWIN").is_ok();
    let mut twin = ModelSim::new(cfg).unwrap();
    let traj = ExcitingTrajectory::default();
    let n = (secs / 1e-3) as usize;
    let stat = std::env::var("STATIC").is_ok();
    let cmds: Vec<_> = (0..n)
        .map(|k| {
            traj.joint_command(&nominal, if stat { 0.0 } else { k as f64 * 1e-3 })
                .unwrap()
        })
        .collect();
    let (mut worst, mut raw, mut dw, mut dl) = (0.0f64, 0.0f64, (0.0f64, 0.0f64), (0.0f64, 0.0f64));
    let mut t_plant = 0.0;
    let mut spin: f64 = 0.0;
    for (k, c) in cmds.iter().enumerate() {
        let t0 = Instant::now();
        plant.step_joint_command(c).unwrap();
        t_plant += t0.elapsed().as_secs_f64();
        worst = worst.max(plant.loop_closure_error());
        raw = raw.max(plant.solver_gap());
        spin = plant
            .link_spin_rates()
            .iter()
            .fold(spin, |m, s| m.max(s.abs()));
        if twin_on {
            twin.step_joint_command(c).unwrap();
            let (dp, da) = pose_distance(&plant.true_pose(), &twin.true_pose());
            dw = (dw.0.max(dp), dw.1.max(da));
            if k >= 1000 {
                dl = (dl.0.max(dp), dl.1.max(da));
            }
        }
    }
    let dt = t_plant / n as f64;
    println!("spin {spin:.2e} it {it} pgs {pgs}: raw {:.2} um, gap {:.3} um, {:.1} us/step, RTF {:.1}; twin worst {:.4} mm {:.4} mrad, after 1 s {:.4} mm {:.4} mrad",
        raw * 1e6, worst * 1e6, dt * 1e6, 1e-3 / dt, dw.0 * 1e3, dw.1 * 1e3, dl.0 * 1e3, dl.1 * 1e3);
}
