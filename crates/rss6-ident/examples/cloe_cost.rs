//! Cost of the loop's sensitivities and of one CLOE, printed as figures.
//!
//! `cargo run --release -p rss6-ident --example cloe_cost [seconds]` (default 10 s of a 0.1 Hz-free
//! excitation repeated). Prints: one simulation, one simulation with the sensitivities of the 49
//! columns CLOE uses (and of 12), their ratio, then one noise-free CLOE from a 30 % spread start.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{home_pose, KinematicParams};
use rss6_ident::{
    cloe, simulate_loop, table_5_2_truth, CloeData, CloeOptions, Consistent, Excitation, LoopConfig,
};
use std::time::Instant;

fn main() {
    let secs: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10.0);
    let free = [
        0.010, -0.004, 0.006, 0.003, -0.008, 0.005, 0.004, -0.002, 0.006, 0.002, -0.005, 0.004,
        0.04, -0.02, 0.03, 0.01, -0.03, 0.02, 0.02, -0.01, 0.05, 0.01, -0.03, 0.02,
    ];
    let f0 = 1.0 / secs;
    let exc = Excitation::at_rest(3, f0.max(0.05), &home_pose(), &free).unwrap();
    let truth = table_5_2_truth();
    let cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), secs);
    let time = |f: &dyn Fn()| {
        let t0 = Instant::now();
        f();
        t0.elapsed().as_secs_f64()
    };
    let t_sim = time(&|| {
        simulate_loop(&cfg, &truth, &exc, None).unwrap();
    });
    let cols = Consistent::a_columns();
    let t_jac = time(&|| {
        simulate_loop(&cfg, &truth, &exc, Some(&cols)).unwrap();
    });
    let t_jac12 = time(&|| {
        simulate_loop(&cfg, &truth, &exc, Some(&cols[..12])).unwrap();
    });
    println!("{secs} s run at 1 kHz ({} ticks)", (secs * 1e3) as usize);
    println!("  simulation:                      {t_sim:.3} s");
    println!(
        "  simulation + sensitivities (49): {t_jac:.3} s  = {:.1} × one simulation",
        t_jac / t_sim
    );
    println!(
        "  simulation + sensitivities (12): {t_jac12:.3} s  = {:.1} × one simulation",
        t_jac12 / t_sim
    );
    let run = simulate_loop(&cfg, &truth, &exc, None).unwrap();
    let data = CloeData {
        t: run.t,
        measured: run.chi,
    };
    let cons = Consistent::new(&truth).unwrap();
    let psi: Vec<f64> = cons
        .psi(&truth)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, p)| p + (1.0_f64 + 0.3 * if k % 2 == 0 { 1.0 } else { -1.0 }).ln())
        .collect();
    let guess = cons.params(&psi);
    let t0 = Instant::now();
    match cloe(&data, &cfg, &exc, &guess, &CloeOptions::default()) {
        Ok(r) => println!(
            "  CLOE (noise-free, ±30 % start): {:.2} s, {} iterations, {} plain simulations, cost {:.3e} → {:.3e}, {} identified",
            t0.elapsed().as_secs_f64(),
            r.iterations,
            r.simulations,
            r.cost_history[0],
            r.cost_history.last().unwrap(),
            r.identified.len()
        ),
        Err(e) => println!("  CLOE failed after {:.2} s: {e}", t0.elapsed().as_secs_f64()),
    }
}
