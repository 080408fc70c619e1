//! Cost of the loop's sensitivities and of one CLOE, printed as figures.
//!
//! `cargo run --release -p rss6-ident --example cloe_cost [seconds] [--implicit] [--sequential]`
//! (default 10 s: one
//! period of a 3-harmonic at-rest excitation). With `--implicit`: the identification drive (5 ms
//! derivative filter, 30 N·m clamp) and Table 5.2's friction stepped implicitly (stick–slip). Prints one simulation, one simulation with the sensitivities of
//! the 49 columns of A that CLOE's consistent parameters move (and of 12), their ratio to one
//! simulation, then one CLOE of 11 quantities from a ±30 % start on data with Table 4.1 camera noise, in the differentiable
//! configuration of `tests/cloe.rs` (no torque clamp, Table 5.2's Coulomb friction as printed).
//! Each loop timing is the median of three runs. `--sequential`: the stages' derivatives evaluated
//! in turn (`LoopConfig::parallel_stages = false`) instead of ahead on all rayon threads.
//! `--repeat N`: each loop timing is the median of N runs (default 3). `--per-tick-only`: time
//! only, alternating, a simulation, the per-tick sensitivities, the per-tick sensitivities
//! taken from a recorded primal run as CLOE runs them after a trial (also for a profiler; with
//! `--implicit` "per tick" is `StateJacobians::FirstStage`, as CLOE iterates), and
//! the exact sensitivities from a recorded run, as CLOE computes them at its stop.
//! `--exact-only`: one simulation, then only the exact sensitivities from one recorded run (for a
//! profiler, or with `RAYON_NUM_THREADS=1` for the CPU time without the threads' scheduling);
//! `--per-tick-recorded-only`: the same for the per-tick sensitivities CLOE iterates on;
//! `--simulation-only`: only the simulations (for a profiler: the ratio's denominator).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{home_pose, KinematicParams};
use rss6_ident::{
    cloe, simulate_loop, simulate_loop_from, simulate_loop_recording, table_5_2_truth, CloeData,
    CloeOptions, Consistent, Excitation, LoopConfig, DRIVE_UNIT_TO_NM,
};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let secs: f64 = args
        .iter()
        .take_while(|a| *a != "--repeat")
        .find_map(|s| s.parse().ok())
        .unwrap_or(10.0);
    let implicit = args.iter().any(|a| a == "--implicit");
    let sequential = args.iter().any(|a| a == "--sequential");
    let per_tick_only = args.iter().any(|a| a == "--per-tick-only");
    let exact_only = args.iter().any(|a| a == "--exact-only");
    let per_tick_recorded_only = args.iter().any(|a| a == "--per-tick-recorded-only");
    let simulation_only = args.iter().any(|a| a == "--simulation-only");
    let repeat: usize = args
        .iter()
        .position(|a| a == "--repeat")
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(3)
        .max(1);
    let free = [
        0.010, -0.004, 0.006, 0.003, -0.008, 0.005, 0.004, -0.002, 0.006, 0.002, -0.005, 0.004,
        0.04, -0.02, 0.03, 0.01, -0.03, 0.02, 0.02, -0.01, 0.05, 0.01, -0.03, 0.02,
    ];
    // One period over the run; coefficients scaled so the pose amplitudes match the 2 s test
    // excitation of tests/cloe.rs.
    let f0 = 1.0 / secs;
    let free: Vec<f64> = free.iter().map(|v| v * f0 / 0.5).collect();
    let exc = Excitation::at_rest(3, f0, &home_pose(), &free).unwrap();
    let mut truth = table_5_2_truth();
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), secs);
    if implicit {
        cfg.implicit_friction = true;
        cfg.derivative_filter = 5e-3;
    } else {
        for f in truth.dynamics.coulomb.iter_mut() {
            *f /= DRIVE_UNIT_TO_NM;
        }
        cfg.torque_limit = 1e4;
    }
    cfg.parallel_stages = !sequential;
    let time = |f: &dyn Fn()| {
        let mut t: Vec<f64> = (0..repeat)
            .map(|_| {
                let t0 = Instant::now();
                f();
                t0.elapsed().as_secs_f64()
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[repeat / 2]
    };
    let t_sim = time(&|| {
        simulate_loop(&cfg, &truth, &exc, None).unwrap();
    });
    if simulation_only {
        println!("one simulation {t_sim:.3} s");
        return;
    }
    let cols = Consistent::a_columns();
    let mut cfg_fast = cfg.clone();
    // As CLOE iterates after the guess: with the implicit law every derivative of a tick's first
    // stage serves its four stages, else the state Jacobians once per tick.
    cfg_fast.state_jacobians = if implicit {
        rss6_ident::StateJacobians::FirstStage
    } else {
        rss6_ident::StateJacobians::PerTick
    };
    if exact_only || per_tick_recorded_only {
        // Only the exact (or per-tick) sensitivities from a recording (for a profiler).
        let (_, rec) = simulate_loop_recording(&cfg, &truth, &exc).unwrap();
        let (c, what) = if exact_only {
            (&cfg, "exact")
        } else {
            (&cfg_fast, "per-tick")
        };
        let t_e = time(&|| {
            simulate_loop_from(c, &truth, &exc, &cols, rec.clone()).unwrap();
        });
        println!(
            "{what} ones from a recording {t_e:.3} s = {:.2} × one simulation",
            t_e / t_sim
        );
        return;
    }
    if per_tick_only {
        // Alternating: a plain simulation; the per-tick sensitivities as `simulate_loop` runs
        // them (a primal run first when the stages are evaluated ahead); a recording primal run
        // and the per-tick sensitivities taken from it, as CLOE runs a Jacobian after a trial;
        // the exact sensitivities from another recording, as CLOE computes them at its stop.
        let mut t = [vec![], vec![], vec![], vec![], vec![]];
        for _ in 0..repeat {
            let t0 = Instant::now();
            simulate_loop(&cfg, &truth, &exc, None).unwrap();
            t[0].push(t0.elapsed().as_secs_f64());
            let t0 = Instant::now();
            simulate_loop(&cfg_fast, &truth, &exc, Some(&cols)).unwrap();
            t[1].push(t0.elapsed().as_secs_f64());
            let t0 = Instant::now();
            let (_, rec) = simulate_loop_recording(&cfg, &truth, &exc).unwrap();
            t[2].push(t0.elapsed().as_secs_f64());
            let t0 = Instant::now();
            simulate_loop_from(&cfg_fast, &truth, &exc, &cols, rec).unwrap();
            t[3].push(t0.elapsed().as_secs_f64());
            let (_, rec) = simulate_loop_recording(&cfg, &truth, &exc).unwrap();
            let t0 = Instant::now();
            simulate_loop_from(&cfg, &truth, &exc, &cols, rec).unwrap();
            t[4].push(t0.elapsed().as_secs_f64());
        }
        let [s, f, r, g, e] = t.map(|mut v| {
            v.sort_by(f64::total_cmp);
            v[repeat / 2]
        });
        println!(
            "{secs} s run, {} rayon threads, medians of {repeat}: simulation {s:.3} s; per-tick sensitivities (49) {f:.3} s = {:.2} ×; recording simulation {r:.3} s, per-tick sensitivities from it {g:.3} s = {:.2} ×, exact ones from a recording {e:.3} s = {:.2} ×",
            rayon::current_num_threads(),
            f / s,
            g / s,
            e / s
        );
        return;
    }
    let t_jac = time(&|| {
        simulate_loop(&cfg, &truth, &exc, Some(&cols)).unwrap();
    });
    let t_jac12 = time(&|| {
        simulate_loop(&cfg, &truth, &exc, Some(&cols[..12])).unwrap();
    });
    let t_fast = time(&|| {
        simulate_loop(&cfg_fast, &truth, &exc, Some(&cols)).unwrap();
    });
    let law = if implicit {
        "implicit stick–slip"
    } else {
        "sign"
    };
    let how = if sequential {
        "stage derivatives in turn".to_string()
    } else {
        format!(
            "stage derivatives ahead on {} rayon threads",
            rayon::current_num_threads()
        )
    };
    println!(
        "{secs} s run at 1 kHz ({} ticks), {law} friction, {how}",
        (secs * 1e3) as usize
    );
    println!("  simulation:                      {t_sim:.3} s");
    println!(
        "  simulation + sensitivities (49): {t_jac:.3} s  = {:.1} × one simulation",
        t_jac / t_sim
    );
    println!(
        "  simulation + sensitivities (12): {t_jac12:.3} s  = {:.1} × one simulation",
        t_jac12 / t_sim
    );
    println!(
        "  simulation + sensitivities (49), state Jacobians per tick: {t_fast:.3} s  = {:.1} × one simulation",
        t_fast / t_sim
    );
    let run = simulate_loop(&cfg, &truth, &exc, None).unwrap();
    // Table 4.1 camera noise on χ_m (seeded).
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let np = Normal::new(0.0, 0.0096e-3).unwrap();
    let na = Normal::new(0.0, 0.0261_f64.to_radians()).unwrap();
    let measured = run
        .chi
        .iter()
        .map(|c| {
            rss6_core::Vec6::from_fn(|i, _| {
                c[i] + if i < 3 {
                    np.sample(&mut rng)
                } else {
                    na.sample(&mut rng)
                }
            })
        })
        .collect();
    let data = CloeData { t: run.t, measured };
    let names: Vec<String> = ["platform.Sxx", "platform.Syy", "platform.Szz", "li", "ld"]
        .iter()
        .map(|s| s.to_string())
        .chain((1..=6).map(|i| format!("fv{i}")))
        .collect();
    let cons = Consistent::new(&truth).unwrap();
    let all = Consistent::names();
    let psi: Vec<f64> = cons
        .psi(&truth)
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if names.contains(&all[k]) {
                p + (1.0_f64 + 0.3 * if k % 2 == 0 { 1.0 } else { -1.0 }).ln()
            } else {
                *p
            }
        })
        .collect();
    let guess = cons.params(&psi);
    for per_tick in [false, true] {
        let opts = CloeOptions {
            parameters: Some(names.clone()),
            per_tick_jacobians: per_tick,
            ..CloeOptions::default()
        };
        let t0 = Instant::now();
        match cloe(&data, &cfg, &exc, &guess, &opts) {
            Ok(r) => println!(
                "  CLOE of 11 quantities (Table 4.1 noise, ±30 % start, per-tick Jacobians {per_tick}): {:.2} s, {} iterations, {} plain simulations, cost {:.3e} → {:.3e}, reduced χ² {:.3}",
                t0.elapsed().as_secs_f64(),
                r.iterations,
                r.simulations,
                r.cost_history[0],
                r.cost_history.last().unwrap(),
                r.reduced_chi2,
            ),
            Err(e) => println!("  CLOE failed after {:.2} s: {e}", t0.elapsed().as_secs_f64()),
        }
    }
}
