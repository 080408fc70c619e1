//! The simulation study of §4.4 (thesis Tables 4.3–4.5) over many random robots.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]
//!
//! ```text
//! cargo run --release -p rss6-ident --example calibration_study [-- --robots 24 --seed 0 --dwell-ms 2000]
//! cargo run --release -p rss6-ident --example calibration_study -- --plant 4   # on the rapier plant
//! ```
//! Prints the actuator stroke (§4.4.1), the selected configuration sets (§4.4.2), the identifiability
//! report, and the mean / 95th percentile over robots of Tables 4.3, 4.4 and 4.5.

use rand::SeedableRng;
use rayon::prelude::*;
use rss6_core::{KinematicParams, Vec6};
use rss6_ident::{
    collect, mean_p95, rpba, run_study, select_configurations_with, stroke, AnalyticRobot,
    CalibrationOptions, Method, NoiseModel, SelectionOptions, StudyOptions, StudyRow, TrueRobot,
};
use rss6_ident::{plant_nominal_target, run_plant_robot, NOMINAL_TARGET_IN_EFFECTOR};
use std::time::Instant;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robots = arg("--robots", 24) as usize;
    let seed = arg("--seed", 0);
    // dwell per configuration in ms; 0 = a single sample per configuration (the thesis's simulation)
    let dwell = arg("--dwell-ms", 2000) as f64 * 1e-3;
    let nominal = KinematicParams::nominal();

    let t = Instant::now();
    let s = stroke(&nominal)?;
    println!(
        "§4.4.1 actuator stroke: ({:.1}°, {:.1}°)   [thesis (−57.1°, 57.1°)]   ({:.2} s)",
        s.0.to_degrees(),
        s.1.to_degrees(),
        t.elapsed().as_secs_f64()
    );
    let sel = SelectionOptions {
        stroke: Some(s),
        ..SelectionOptions::default()
    };
    let t = Instant::now();
    let sel_r = select_configurations_with(&nominal, Method::Rpba, seed, &sel)?;
    let sel_i = select_configurations_with(&nominal, Method::Implicit, seed, &sel)?;
    println!(
        "§4.4.2 selection (13 random start, 5000 candidates): RPBA {} configurations + initial, \
         O1 = {:.4} (last gain at candidate {}); implicit {} + initial, O1 = {:.4} (last gain at {})   \
         [thesis: 22 and 34]   ({:.2} s)",
        sel_r.thetas.len() - 1,
        sel_r.index,
        sel_r.last_improvement,
        sel_i.thetas.len() - 1,
        sel_i.index,
        sel_i.last_improvement,
        t.elapsed().as_secs_f64()
    );

    // Identifiability report on one robot.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let truth = TrueRobot::draw(&nominal, &mut rng);
    let mut src = AnalyticRobot::new(truth, nominal, NoiseModel::default(), seed);
    let data = collect(&mut src, &sel_r.thetas, 2.0)?;
    let res = rpba(&data, &nominal, &CalibrationOptions::default())?;
    let sv = &res.singular_values;
    println!(
        "§4.3.4 identifiability (RPBA, one robot): rank {} of {} — {} gauge directions; \
         smallest non-zero σ / σ_max = {:.2e}, next = {:.2e}",
        res.rank,
        res.parameter_count,
        res.parameter_count - res.rank,
        sv[res.rank - 1] / sv[0],
        sv.get(res.rank).copied().unwrap_or(0.0) / sv[0],
    );
    for g in &res.gauge_directions {
        println!("    gauge: {g}");
    }
    println!(
        "    not individually identifiable: {}",
        res.unidentifiable.join(" ")
    );

    let opts = StudyOptions {
        robots,
        seed,
        rpba_thetas: sel_r.thetas.clone(),
        implicit_thetas: sel_i.thetas.clone(),
        dwell,
        noise: NoiseModel::default(),
        test_configurations: 100,
        stroke: s,
        solver: CalibrationOptions::default(),
        target_nominal: NOMINAL_TARGET_IN_EFFECTOR,
    };
    let t = Instant::now();
    let plant_robots = arg("--plant", 0) as usize;
    let (results, source) = if plant_robots > 0 {
        // the rapier plant: its PID, 500 Hz potentiometers and stereo CMM produce the data
        let opts = StudyOptions {
            robots: plant_robots,
            target_nominal: plant_nominal_target().into(),
            ..opts.clone()
        };
        let r: Vec<_> = (0..plant_robots)
            .into_par_iter()
            .map(|i| run_plant_robot(&nominal, &opts, i))
            .collect();
        (r, "rapier plant")
    } else {
        (run_study(&nominal, &opts), "analytic generator")
    };
    let robots = results.len();
    let mut rows: Vec<StudyRow> = Vec::new();
    for (i, r) in results.into_iter().enumerate() {
        match r {
            Ok(row) => rows.push(row),
            Err(e) => println!("robot {i}: FAILED: {e}"),
        }
    }
    println!(
        "\n§4.4.3 simulation study ({source}): {} of {robots} robots ({:.1} s), Table 4.1 noise averaged over a {dwell} s \
         dwell (500 Hz κ, 29 Hz camera; 0 s = one sample), Table 4.2 errors; implicit started with ᴼχ_C off by \
         Table 4.2 external sizes. Values: mean / 95th percentile over robots.",
        rows.len(),
        t.elapsed().as_secs_f64()
    );
    let stat = |f: &dyn Fn(&StudyRow) -> f64| {
        let v: Vec<f64> = rows.iter().map(f).collect();
        mean_p95(&v)
    };
    let pr = |label: &str, f: &dyn Fn(&StudyRow) -> f64, g: &dyn Fn(&StudyRow) -> f64| {
        let (a, a95) = stat(f);
        let (b, b95) = stat(g);
        println!("  {label:<44} {a:>11.4e} / {a95:<11.4e} {b:>11.4e} / {b95:<11.4e}");
    };
    println!("\nTable 4.3 (implicit, 72 parameters)            before calibration          after calibration");
    pr(
        "‖S⁻¹(b_I − b_I^n)‖, gauge removed (σ units)",
        &|r| r.implicit_param_error.0,
        &|r| r.implicit_param_error.1,
    );
    pr(
        "‖b_I − b_I^n‖₂, gauge removed (SI)",
        &|r| r.implicit_param_error_si.0,
        &|r| r.implicit_param_error_si.1,
    );
    pr("Σ_l ‖Φ_I^l‖ (m)", &|r| r.implicit_residual.0, &|r| {
        r.implicit_residual.1
    });
    let (tn, tn95) = stat(&|r| r.implicit_residual.2);
    println!(
        "  {:<44} {tn:>11.4e} / {tn95:<11.4e}",
        "Σ_l ‖Φ_I^l‖ at the true parameters"
    );
    let t = rss6_core::thesis::TABLE_4_3_IMPLICIT;
    println!(
        "  [thesis: {} → {}; {} → {}]",
        t.param_error.0, t.param_error.1, t.residual.0, t.residual.1
    );
    println!("\nTable 4.4 (RPBA, 66 parameters)                before calibration          after calibration");
    pr(
        "‖S⁻¹(b_R − b_R^n)‖, gauge removed (σ units)",
        &|r| r.rpba_param_error.0,
        &|r| r.rpba_param_error.1,
    );
    pr(
        "‖b_R − b_R^n‖₂, gauge removed (SI)",
        &|r| r.rpba_param_error_si.0,
        &|r| r.rpba_param_error_si.1,
    );
    pr(
        "Σ_l ‖Φ_R^l‖ (m, rad mixed)",
        &|r| r.rpba_residual.0,
        &|r| r.rpba_residual.1,
    );
    let (tn, tn95) = stat(&|r| r.rpba_residual.2);
    println!(
        "  {:<44} {tn:>11.4e} / {tn95:<11.4e}",
        "Σ_l ‖Φ_R^l‖ at the true parameters"
    );
    let t = rss6_core::thesis::TABLE_4_4_RPBA;
    println!(
        "  [thesis: {:.4} → {}; {} → {}]",
        t.param_error.0, t.param_error.1, t.residual.0, t.residual.1
    );
    let (ii, _) = stat(&|r| r.iterations.0 as f64);
    let (ir, _) = stat(&|r| r.iterations.1 as f64);
    println!(
        "  mean LM iterations: implicit {ii:.1} [thesis {}], RPBA {ir:.1} [thesis {}]",
        rss6_core::thesis::TABLE_4_3_IMPLICIT.iterations,
        rss6_core::thesis::TABLE_4_4_RPBA.iterations
    );
    println!(
        "  ranks: implicit {:?}, RPBA {:?}",
        rows.iter()
            .map(|r| r.ranks.0)
            .collect::<std::collections::BTreeSet<_>>(),
        rows.iter()
            .map(|r| r.ranks.1)
            .collect::<std::collections::BTreeSet<_>>()
    );

    println!("\nTable 4.5 RMS relative pose errors on 100 random test configurations (mean / p95 over robots)");
    println!("  axis      uncalibrated              implicit                  RPBA                      thesis RPBA  target met (p95)  implicit, ᴼχ_C fixed rough");
    let thesis = rss6_core::thesis::TABLE_4_5_RPBA;
    let names = [
        "x (mm)", "y (mm)", "z (mm)", "α (rad)", "β (rad)", "γ (rad)",
    ];
    for k in 0..6 {
        let unit = if k < 3 { 1e3 } else { 1.0 };
        let (u, u95) = stat(&|r| r.rms_uncalibrated[k]);
        let (i, i95) = stat(&|r| r.rms_implicit[k]);
        let (rr, r95) = stat(&|r| r.rms_rpba[k]);
        let (f, f95) = stat(&|r| r.rms_implicit_fixed_sensor[k]);
        println!(
            "  {:<8} {:>10.3e} / {:<10.3e}  {:>10.3e} / {:<10.3e}  {:>10.3e} / {:<10.3e}  {:>10.3e}   {:<16} {:>10.3e} / {:<10.3e}",
            names[k],
            u * unit,
            u95 * unit,
            i * unit,
            i95 * unit,
            rr * unit,
            r95 * unit,
            thesis[k] * unit,
            if r95 <= thesis[k] { "yes" } else { "NO" },
            f * unit,
            f95 * unit
        );
    }
    println!("  (thesis Table 4.5 orders the angles γ, β, α; here they are listed as α, β, γ)");
    let _ = Vec6::zeros();
    Ok(())
}
