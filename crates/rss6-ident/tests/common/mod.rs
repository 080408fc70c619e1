//! Helpers shared by the calibration integration tests (each test file is its own crate and uses
//! what it needs).
#![allow(dead_code)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{KinematicParams, Vec6};
use rss6_ident::{test_configurations, AnalyticRobot, NoiseModel, TrueRobot};

pub(crate) fn nominal() -> KinematicParams {
    KinematicParams::nominal()
}

/// The reference configuration followed by `n` fixed, well-spread configurations inside a ±25° box
/// (the computed stroke is ±31°).
pub(crate) fn configurations(n: usize, seed: u64) -> Vec<Vec6> {
    let mut t = vec![Vec6::zeros()];
    t.extend(test_configurations(n, seed, (-0.45, 0.45)));
    t
}

/// A robot drawn from the calibration prior and the analytic generator that measures it.
pub(crate) fn robot(seed: u64, noise: NoiseModel) -> (TrueRobot, AnalyticRobot) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth = TrueRobot::draw(&nominal(), &mut rng);
    (
        truth,
        AnalyticRobot::new(truth, nominal(), noise, seed + 1000),
    )
}
