//! Short-round timing shared by the `*_cpu` examples: many rounds of `n` calls, each shorter than a
//! scheduler time slice, so the fastest round ran undisturbed even on a loaded machine.

use std::time::Instant;

/// Runs `rounds` rounds of `n` calls of `op`; prints a Markdown row with the median and the fastest
/// round's time per call (ns).
pub(crate) fn measure(name: &str, rounds: usize, n: usize, mut op: impl FnMut(usize)) {
    let mut per_call: Vec<f64> = (0..rounds)
        .map(|_| {
            let t0 = Instant::now();
            for k in 0..n {
                op(k);
            }
            t0.elapsed().as_secs_f64() * 1e9 / n as f64
        })
        .collect();
    per_call.sort_by(f64::total_cmp);
    println!(
        "| {name} | {:.0} | {:.0} |",
        per_call[rounds / 2],
        per_call[0]
    );
}
