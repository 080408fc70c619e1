#![allow(clippy::unwrap_used, dead_code, clippy::needless_range_loop)]
mod common;
use common::*;
use rss6_core::*;
use rss6_ctrl::*;
#[test]
fn scratch2() {
    let mut setup = Setup::new(KinematicParams::nominal(), Noise { camera: false, potentiometer: false }, 4.0, 0);
    if let Ok(q) = std::env::var("QP") { let q: f64 = q.parse().unwrap(); setup.config.kalman.q_jerk = Vec6::new(q, q, q, q * 300.0, q * 300.0, q * 300.0); }
    let s = run_scheme(Which::Dsmc, &Sinusoid::experiment1(), &setup);
    for (t, f, fc) in s.sliding.iter().filter(|x| x.0 > 3.0 && x.0 < 3.5) {
        println!("t={t:.3} Ftrue y {:+.3e} z {:+.3e}  Fctrl y {:+.3e} z {:+.3e}", f[1], f[2], fc[1], fc[2]);
    }
}
