//! Mean iteration counts of the two FK methods on the same pose sets (printed as Markdown):
//! the quasi-Stewart method [`rss6_core::fk`] (eq. 3.18–3.20) and Newton on θ
//! [`rss6_core::fk_theta_newton`] (Fig. 3.2), cold from home and warm along a 1 kHz path.
//!
//! `cargo run --release -p rss6-benches --example fk_iterations`
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "support/poses.rs"]
mod poses;

use rss6_core::{fk, fk_theta_newton, home_pose, ik, FkOptions, FkSolution, KinematicParams, Vec6};

type Solver = fn(&KinematicParams, &Vec6, &Vec6, &FkOptions) -> rss6_core::Result<FkSolution>;

/// (mean iterations, max iterations, max pose error) over (θ, guess, truth) triples.
fn stats(kp: &KinematicParams, solver: Solver, cases: &[(Vec6, Vec6, Vec6)]) -> (f64, u32, f64) {
    let opts = FkOptions::default();
    let (mut sum, mut max, mut err) = (0u64, 0u32, 0.0f64);
    for (theta, guess, truth) in cases {
        let s = solver(kp, theta, guess, &opts).expect("FK failed");
        sum += u64::from(s.iterations);
        max = max.max(s.iterations);
        err = err.max((s.pose - truth).amax());
    }
    (sum as f64 / cases.len() as f64, max, err)
}

fn main() {
    let kp = KinematicParams::nominal();
    let n = 10_000;
    let cold: Vec<(Vec6, Vec6, Vec6)> = poses::box_poses(n)
        .into_iter()
        .map(|p| (ik(&kp, &p).unwrap(), home_pose(), p))
        .collect();
    let path = poses::smooth_path(n + 1);
    let warm: Vec<(Vec6, Vec6, Vec6)> = path
        .windows(2)
        .map(|w| (ik(&kp, &w[1]).unwrap(), w[0], w[1]))
        .collect();
    println!("| pose set ({n} poses, nominal robot, eps_c = eps_p = 1e-13) | method | mean iterations | max iterations | max pose error |");
    println!("|---|---|---|---|---|");
    for (set, cases) in [
        ("cold: documented box, start at home", &cold),
        ("warm: 1 kHz path, start at previous", &warm),
    ] {
        for (name, solver) in [
            ("fk (quasi-Stewart)", fk as Solver),
            ("fk_theta_newton", fk_theta_newton as Solver),
        ] {
            let (mean, max, err) = stats(&kp, solver, cases);
            println!("| {set} | {name} | {mean:.3} | {max} | {err:.1e} |");
        }
    }
}
