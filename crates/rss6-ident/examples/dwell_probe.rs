//! Probe of the dwell checks on the rapier plant: per configuration, the reach error κ̄ − κ_cmd and
//! the scatter of the potentiometers and the camera, for robots whose offsets Δθ are large.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use rand::SeedableRng;
use rayon::prelude::*;
use rss6_core::{KinematicParams, Vec6};
use rss6_exp::dwell::DriveConvention;
use rss6_ident::*;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|v| v.parse().ok()).unwrap_or(2);
    let dwell: f64 = args.get(2).and_then(|v| v.parse().ok()).unwrap_or(2.0);
    let nominal = KinematicParams::nominal();
    let sel = select_configurations(&nominal, Method::Rpba, 0).unwrap();
    let drive = DriveConvention::of(&nominal);
    let t = std::time::Instant::now();
    let out: Vec<String> = (0..n)
        .into_par_iter()
        .map(|r| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1000 + r as u64);
            let truth = loop {
                let t = TrueRobot::draw(&nominal, &mut rng);
                let worst = (0..6).map(|i| (t.kp.dtheta[i] - nominal.dtheta[i]).abs()).fold(0.0, f64::max);
                if worst >= 5f64.to_radians() {
                    break t;
                }
            };
            let (mut src, _) = plant_with_kinematics(&nominal, &truth.kp, &mut rng, r as u64).unwrap();
            let mut s = String::new();
            let dth: Vec<String> = (0..6).map(|i| format!("{:.1}", (truth.kp.dtheta[i]).to_degrees())).collect();
            s += &format!("robot {r}: dtheta(deg) {}\n", dth.join(" "));
            for (k, th) in sel.iter().enumerate() {
                match src.measure(th, dwell) {
                    Ok(c) => {
                        let cmd = drive.reading(&c.theta_cmd);
                        let reach = (0..6).map(|i| (c.kappa[i] - cmd[i]).abs()).fold(0.0, f64::max);
                        let ks = c.kappa_std.unwrap().iter().copied().fold(0.0, f64::max) / 0.2233;
                        let ps = c.sensor_pose_std.map(|p| {
                            let v: Vec<String> = (0..6).map(|i| format!("{:.2}", p[i] / if i < 3 { 0.0096e-3 } else { 0.0261f64.to_radians() })).collect();
                            v.join(" ")
                        }).unwrap_or_default();
                        s += &format!("  cfg {k:2}: reach {reach:9.4} bit  kstd/s {ks:.2}  pstd/s [{ps}] frames {} fault {:?}\n", c.camera_frames, c.fault.map(|f| f.to_string()));
                    }
                    Err(e) => { s += &format!("  cfg {k:2}: ERROR {e}\n"); break; }
                }
            }
            let _ = Vec6::zeros();
            s
        })
        .collect();
    for s in out {
        print!("{s}");
    }
    println!("{:.1} s", t.elapsed().as_secs_f64());
}
