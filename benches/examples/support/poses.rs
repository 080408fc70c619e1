//! Deterministic pose sets shared by the kinematics bench and the `fk_iterations` example: a Halton
//! sequence over the documented box (no RNG dependency) and a smooth 1 kHz Lissajous path through it.

use rss6_core::{PoseBox, Vec6};

/// Radical inverse of `i` in `base` (the Halton sequence), in [0, 1).
fn radical_inverse(mut i: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f64;
        r += f * (i % base) as f64;
        i /= base;
    }
    r
}

/// `n` poses of the documented box from a 6-D Halton sequence (bases 2, 3, 5, 7, 11, 13).
pub(crate) fn box_poses(n: usize) -> Vec<Vec6> {
    let bx = PoseBox::documented();
    const BASES: [u64; 6] = [2, 3, 5, 7, 11, 13];
    (1..=n as u64)
        .map(|i| {
            bx.point(&Vec6::from_fn(|k, _| {
                2.0 * radical_inverse(i, BASES[k]) - 1.0
            }))
        })
        .collect()
}

/// `n` samples at 1 kHz of a Lissajous path spanning the documented box (periods 1.4–3.6 s).
pub(crate) fn smooth_path(n: usize) -> Vec<Vec6> {
    let bx = PoseBox::documented();
    const W: [f64; 6] = [4.4, 5.2, 2.8, 6.8, 3.6, 7.6]; // rad/s
    (0..n)
        .map(|k| {
            let t = k as f64 * 1e-3;
            bx.point(&Vec6::from_fn(|j, _| (W[j] * t + j as f64).sin()))
        })
        .collect()
}
