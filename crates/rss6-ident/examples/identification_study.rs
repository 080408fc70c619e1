//! CLOE (thesis §5.3) on the rapier plant: the Table 5.2 analog and a Table 5.4 analog.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
//!
//! ```text
//! cargo run --release -p rss6-ident --example identification_study [-- --seed 0 --validate 3 --soft 1]
//! cargo run --release -p rss6-ident --example identification_study -- --signal 1 [--soft 3]
//! ```
//! The plant's truth is [`table_5_2_truth`] (its drive filters the derivative with T_f = 5 ms,
//! camera noise of Table 4.1). The model starts from Table 5.1 (`DynamicParams::nominal`), small
//! positive friction and the tuned nominal gains, and models the drive the same way with Coulomb
//! friction smoothed at ε = 0.5 rad/s. An exciting trajectory (5 harmonics of 0.1 Hz, 10 s, the
//! best of 96 random feasible candidates by O_in) is run once on the plant; CLOE estimates every
//! identifiable quantity; `--validate N` then runs N other random feasible trajectories on the plant
//! and compares the RMS of χ_m − χ_s per axis before (initial model) and after.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::PidGains;
use rss6_exp::{ident, Externals, Record};
use rss6_ident::{
    cloe, simulate_loop, table_5_2_truth, CloeData, CloeOptions, Consistent, Excitation,
    ExcitationLimits, ExcitationProblem, LoopConfig, LoopParams,
};
use rss6_sim::{CmmConfig, Plant, RobotSim, SimConfig};
use std::time::Instant;

const T_F: f64 = 5e-3;
const EPS: f64 = 0.5;
const HARMONICS: usize = 5;
const F0: f64 = 0.1;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The best of `n` random feasible at-rest trajectories by O_in (or the first feasible one when
/// `best` is false).
fn random_excitation(seed: u64, n: usize, best: bool) -> Excitation {
    let kp = KinematicParams::nominal();
    let k = Excitation::free_per_axis(HARMONICS);
    let problem = ExcitationProblem {
        kp,
        limits: ExcitationLimits::default(),
        harmonics: HARMONICS,
        f0: F0,
        start: home_pose(),
        columns: (0..rss6_core::N_DYN).collect(),
        samples: 200,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for _round in 0..50 {
        let pop: Vec<Vec<f64>> = (0..n)
            .map(|_| {
                (0..6 * k)
                    .map(|j| {
                        let amp = if j < 3 * k { 0.002 } else { 0.008 };
                        rng.random_range(-amp..amp)
                    })
                    .collect()
            })
            .collect();
        let scores = if best {
            problem.objectives(&pop)
        } else {
            pop.par_iter()
                .map(|x| {
                    let e = Excitation::at_rest(HARMONICS, F0, &home_pose(), x).unwrap();
                    if e.check(&kp, &problem.limits).is_none() {
                        -1.0
                    } else {
                        1.0
                    }
                })
                .collect()
        };
        if let Some((i, s)) = scores
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(i, s)| (i, *s))
        {
            if s < 0.0 {
                return Excitation::at_rest(HARMONICS, F0, &home_pose(), &pop[i]).unwrap();
            }
        }
    }
    panic!("no feasible excitation found");
}

fn plant_config(truth: &LoopParams, seed: u64) -> SimConfig {
    let mut sc = SimConfig::new(KinematicParams::nominal(), truth.dynamics, truth.pid);
    sc.drive_derivative_filter = T_F;
    sc.cmm = CmmConfig::table_4_1();
    sc.seed = seed;
    sc
}

/// Runs the identification loop on the plant and returns the measured frames.
fn collect(truth: &LoopParams, exc: &Excitation, seed: u64) -> CloeData {
    let sc = plant_config(truth, seed);
    let ext = Externals {
        sensor_in_base: sc.sensor_in_base,
        target_in_effector: sc.target_in_effector,
    };
    let mut plant = Plant::new(sc).unwrap();
    plant.reset(&home_pose()).unwrap();
    let mut spec = ident::IdentSpec::new(KinematicParams::nominal(), ext);
    spec.duration = exc.period();
    let mut recs: Vec<Record> = Vec::new();
    ident::run(&mut plant, &spec, exc, &mut recs).unwrap();
    let (t, measured) = recs
        .iter()
        .filter_map(|r| r.camera.map(|c| (r.t, c)))
        .unzip();
    CloeData { t, measured }
}

fn loop_config(duration: f64) -> LoopConfig {
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), duration);
    cfg.derivative_filter = T_F;
    cfg.friction_smoothing = EPS;
    cfg
}

fn rms(data: &CloeData, cfg: &LoopConfig, a: &LoopParams, exc: &Excitation) -> Vec6 {
    let run = simulate_loop(cfg, a, exc, None).unwrap();
    let mut sq = Vec6::zeros();
    let mut n = 0.0;
    for (t, m) in data.t.iter().zip(&data.measured) {
        if let Some(k) = run.t.iter().position(|s| (s - t).abs() < 0.5e-3) {
            sq += (m - run.chi[k]).map(|v| v * v);
            n += 1.0;
        }
    }
    (sq / n).map(f64::sqrt)
}

fn fmt6(v: &Vec6) -> String {
    format!(
        "{:6.3} {:6.3} {:6.3} mm  {:6.3} {:6.3} {:6.3} mrad",
        v[0] * 1e3,
        v[1] * 1e3,
        v[2] * 1e3,
        v[3] * 1e3,
        v[4] * 1e3,
        v[5] * 1e3
    )
}

fn main() {
    let seed = arg("--seed", 0);
    let n_val = arg("--validate", 3) as usize;
    // `--soft K`: the drive's gains (truth and initial) divided by K — a softer drive lets the
    // dynamics show in the pose (see docs/identification.md).
    let soft = arg("--soft", 1) as f64;
    let mut truth = table_5_2_truth();
    truth.pid.lp /= soft;
    truth.pid.li /= soft;
    truth.pid.ld /= soft;
    let initial = |soft: f64| {
        let mut g = LoopParams {
            dynamics: DynamicParams::nominal(),
            pid: PidGains {
                lp: PidGains::tuned().lp / soft,
                li: PidGains::tuned().li / soft,
                ld: PidGains::tuned().ld / soft,
            },
        };
        g.dynamics.coulomb = [1.0; 6];
        g.dynamics.viscous = [1.0; 6];
        g
    };
    // `--signal 1`: how much the pose sees the dynamics (the model with the initial vs the true
    // parameters) against how far the plant is from the model with the true parameters.
    if arg("--signal", 0) == 1 {
        let exc = random_excitation(seed, 96, true);
        let data = collect(&truth, &exc, seed);
        let cfg = loop_config(exc.period());
        println!(
            "plant vs model(truth) rms {}",
            fmt6(&rms(&data, &cfg, &truth, &exc))
        );
        use rss6_ctrl::Trajectory;
        let dev = data
            .t
            .iter()
            .zip(&data.measured)
            .map(|(t, m)| (m - exc.sample(*t).pose).amax())
            .fold(0.0, f64::max);
        let run = simulate_loop(&cfg, &truth, &exc, None).unwrap();
        let devm = run
            .t
            .iter()
            .zip(&run.chi)
            .map(|(t, m)| (m - exc.sample(*t).pose).amax())
            .fold(0.0, f64::max);
        println!("max |χ_m − ref| plant {dev:.3e}  model {devm:.3e}");
        let g = simulate_loop(&cfg, &initial(soft), &exc, None).unwrap();
        let mut sq = Vec6::zeros();
        for (a, b) in g.chi.iter().zip(&run.chi) {
            sq += (a - b).map(|v| v * v);
        }
        println!(
            "signal: model(initial) − model(truth) rms {}",
            fmt6(&(sq / g.chi.len() as f64).map(f64::sqrt))
        );
        return;
    }
    let guess = initial(soft);

    let t0 = Instant::now();
    let exc = random_excitation(seed, 96, true);
    println!(
        "excitation: {HARMONICS} harmonics of {F0} Hz, {:.0} s ({:.1} s)",
        exc.period(),
        t0.elapsed().as_secs_f64()
    );
    let t1 = Instant::now();
    let data = collect(&truth, &exc, seed);
    println!(
        "collected {} frames on the rapier plant ({:.1} s)",
        data.t.len(),
        t1.elapsed().as_secs_f64()
    );
    let cfg = loop_config(exc.period());
    let t2 = Instant::now();
    let res = cloe(&data, &cfg, &exc, &guess, &CloeOptions::default());
    let res = match res {
        Ok(r) => r,
        Err(e) => {
            println!("CLOE failed: {e}");
            return;
        }
    };
    println!(
        "CLOE: {} iterations, {} simulations, {:.1} s, reduced χ² {:.2}",
        res.iterations,
        res.simulations,
        t2.elapsed().as_secs_f64(),
        res.reduced_chi2
    );
    println!("  rms before {}", fmt6(&res.rms_before));
    println!("  rms after  {}", fmt6(&res.rms_after));
    println!(
        "  rms truth  {}   (the model with the plant's true Ξ and gains)",
        fmt6(&rms(&data, &cfg, &truth, &exc))
    );
    let names = Consistent::names();
    let cons = Consistent::new(&guess).unwrap();
    let p_guess = cons.psi(&guess).unwrap();
    let p_truth = cons.psi(&truth).unwrap();
    println!(
        "\n  {:14} {:>10} {:>10} {:>10} {:>8}",
        "quantity", "initial", "estimate", "truth", "σ %"
    );
    for (name, s) in res.identified.iter().zip(&res.relative_std) {
        let k = names.iter().position(|n| n == name).unwrap();
        println!(
            "  {name:14} {:10.4e} {:10.4e} {:10.4e} {:8.2}{}",
            p_guess[k].exp(),
            res.psi[k].exp(),
            p_truth[k].exp(),
            100.0 * s,
            if *s > 0.1 { "  poorly identified" } else { "" }
        );
    }
    println!("  unidentifiable: {}", res.unidentifiable.join(", "));

    if n_val > 0 {
        println!("\nvalidation on {n_val} other trajectories (RMS of χ_m − χ_s):");
        for v in 0..n_val {
            let e = random_excitation(1000 + seed * 100 + v as u64, 16, false);
            let d = collect(&truth, &e, 77 + v as u64);
            let c = loop_config(e.period());
            let before = rms(&d, &c, &guess, &e);
            let after = rms(&d, &c, &res.params, &e);
            let floor = rms(&d, &c, &truth, &e);
            println!("  #{v} before {}", fmt6(&before));
            println!("     after  {}", fmt6(&after));
            println!("     truth  {}", fmt6(&floor));
        }
    }
}
