//! Pose noise of the default optical CMM at the home pose (Monte Carlo), against Table 4.1.
//!
//! `cargo run -p rss6-sim --example cmm_noise [pixel_noise] [frames]`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{compose, home_pose, pose_inverse, Vec6};
use rss6_sim::{measure_with, CmmConfig, SimConfig, CMM_ANGLE_NOISE, CMM_POSITION_NOISE};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut cfg = CmmConfig::c_track();
    if let Some(s) = args.get(1) {
        cfg.pixel_noise = s.parse().expect("pixel noise");
    }
    let n: usize = args
        .get(2)
        .map(|s| s.parse().expect("frames"))
        .unwrap_or(5000);
    let sim = SimConfig::nominal();
    let truth = compose(
        &pose_inverse(&sim.sensor_in_base),
        &compose(&home_pose(), &sim.target_in_effector),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut sum2 = Vec6::zeros();
    for _ in 0..n {
        let m = measure_with(&cfg, &truth, &mut rng).expect("frame");
        let e = m - truth;
        sum2 += e.component_mul(&e);
    }
    let std = (sum2 / n as f64).map(f64::sqrt);
    let pos = (std.fixed_rows::<3>(0).norm_squared() / 3.0).sqrt();
    let ang = (std.fixed_rows::<3>(3).norm_squared() / 3.0).sqrt();
    println!("pixel noise {} px, {} frames", cfg.pixel_noise, n);
    println!(
        "per-axis std: x {:.4} y {:.4} z {:.4} mm; a {:.4} b {:.4} c {:.4} deg",
        std[0] * 1e3,
        std[1] * 1e3,
        std[2] * 1e3,
        std[3].to_degrees(),
        std[4].to_degrees(),
        std[5].to_degrees()
    );
    println!(
        "RMS over axes: position {:.4} mm (Table 4.1: {:.4}), angle {:.4} deg (Table 4.1: {:.4})",
        pos * 1e3,
        CMM_POSITION_NOISE * 1e3,
        ang.to_degrees(),
        CMM_ANGLE_NOISE.to_degrees()
    );
}
