//! Plant vs model twin like Fig. 5.5–5.6: writes the pose difference over time as CSV and prints the
//! worst values overall and after the transient.
//!
//! `cargo run -p rss6-sim --example validation [out.csv] [seconds]`
//! (then `python3 docs/figures/plot_sim_validation.py out.csv docs/figures/sim_validation.png`)
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::KinematicParams;
use rss6_sim::{pose_distance, ExcitingTrajectory, ModelSim, Plant, RobotSim, SimConfig};
use std::io::Write;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .get(1)
        .cloned()
        .unwrap_or_else(|| "sim_validation.csv".into());
    let secs: f64 = args
        .get(2)
        .map(|s| s.parse().expect("seconds"))
        .unwrap_or(10.0);
    let cfg = SimConfig::nominal();
    let mut plant = Plant::new(cfg.clone()).unwrap();
    let mut twin = ModelSim::new(cfg).unwrap();
    let traj = ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    let mut f = std::io::BufWriter::new(std::fs::File::create(&out).unwrap());
    writeln!(f, "time_s,dx_mm,dy_mm,dz_mm,dalpha_mrad,dbeta_mrad,dgamma_mrad,position_mm,angle_mrad,loop_gap_um,solver_gap_um,x_mm,y_mm,z_mm").unwrap();
    let (mut worst, mut late, mut gap) = ((0.0f64, 0.0f64), (0.0f64, 0.0f64), 0.0f64);
    let mut solver_gap = 0.0f64;
    let n = (secs / 1e-3) as usize;
    for k in 0..n {
        let cmd = traj.joint_command(&nominal, k as f64 * 1e-3).unwrap();
        plant.step_joint_command(&cmd).unwrap();
        twin.step_joint_command(&cmd).unwrap();
        let (a, b) = (plant.true_pose(), twin.true_pose());
        let (dp, da) = pose_distance(&a, &b);
        let g = plant.loop_closure_error();
        worst = (worst.0.max(dp), worst.1.max(da));
        if plant.time() >= 1.0 {
            late = (late.0.max(dp), late.1.max(da));
        }
        gap = gap.max(g);
        solver_gap = solver_gap.max(plant.solver_gap());
        if k % 5 == 4 {
            let d = a - b;
            writeln!(
                f,
                "{:.3},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.4},{:.4},{:.4},{:.4},{:.4}",
                plant.time(),
                d[0] * 1e3, d[1] * 1e3, d[2] * 1e3, d[3] * 1e3, d[4] * 1e3, d[5] * 1e3,
                dp * 1e3, da * 1e3, g * 1e6, plant.solver_gap() * 1e6, a[0] * 1e3, a[1] * 1e3, a[2] * 1e3
            )
            .unwrap();
        }
    }
    println!("{secs} s of the exciting trajectory, plant vs twin (nominal robot, same PID and sensor noise)");
    println!(
        "worst difference: {:.4} mm, {:.4} mrad (Fig. 5.5-5.6 bound: 1.25 mm, 3.25 mrad)",
        worst.0 * 1e3,
        worst.1 * 1e3
    );
    println!(
        "after 1 s:        {:.4} mm, {:.4} mrad (bound: 0.1 mm, 0.25 mrad)",
        late.0 * 1e3,
        late.1 * 1e3
    );
    println!(
        "worst loop-closure gap after a tick: {:.3} µm (bound 10 µm); rapier's own gap before the projection: {:.2} µm",
        gap * 1e6,
        solver_gap * 1e6
    );
    println!("CSV: {out}");
}
