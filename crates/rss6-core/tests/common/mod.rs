//! Helpers shared by the kinematics test binaries (random poses of the documented box, perturbed robots).
#![allow(dead_code, unreachable_pub)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::{KinematicParams, PoseBox, Vec6, N_KIN_ERRORS};

pub use rss6_core::thesis::{SIGMA_DTHETA, SIGMA_ETA, SIGMA_LENGTH};

/// A deterministic RNG.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// A standard normal sample (Box–Muller).
pub fn normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * u2).cos()
}

/// A random error vector b with Table 4.2 standard deviations (eq. 4.3 order).
pub fn table_4_2_errors(rng: &mut ChaCha8Rng) -> [f64; N_KIN_ERRORS] {
    let mut b = [0.0; N_KIN_ERRORS];
    for (k, bk) in b.iter_mut().enumerate() {
        let sigma = match k {
            0..=47 => SIGMA_LENGTH,
            48..=53 => SIGMA_ETA,
            _ => SIGMA_DTHETA,
        };
        *bk = sigma * normal(rng);
    }
    b
}

/// A perturbed robot with Table 4.2 error sizes.
pub fn perturbed_robot(rng: &mut ChaCha8Rng) -> KinematicParams {
    KinematicParams::perturbed(&table_4_2_errors(rng))
}

/// A uniform random pose of `bx`.
pub fn random_pose(rng: &mut ChaCha8Rng, bx: &PoseBox) -> Vec6 {
    let u = Vec6::from_fn(|_, _| rng.random_range(-1.0..=1.0));
    bx.point(&u)
}

/// The 3⁶ = 729 grid poses of `bx` with u ∈ {−1, 0, 1}⁶ (all vertices, face and edge centres).
pub fn grid3(bx: &PoseBox) -> impl Iterator<Item = Vec6> + '_ {
    (0..729u32).map(move |mut idx| {
        let mut u = Vec6::zeros();
        for uk in u.iter_mut() {
            *uk = f64::from(idx % 3) - 1.0;
            idx /= 3;
        }
        bx.point(&u)
    })
}
