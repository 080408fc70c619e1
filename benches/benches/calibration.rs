//! Criterion benches of the rss6-ident calibration (target, issue 12: RPBA with 66 parameters and
//! 22 configurations ≤ 10 ms, noise weighting and outlier handling included).
//!
//! `cargo bench -p rss6-benches --bench calibration -- --warm-up-time 1 --measurement-time 2`
#![allow(missing_docs, clippy::unwrap_used)]
use criterion::{criterion_group, criterion_main, Criterion};
use rand_chacha::rand_core::SeedableRng;
use rss6_core::{KinematicParams, Vec6};
use rss6_ident::*;
use std::hint::black_box;

fn data(n: usize) -> (KinematicParams, TrueRobot, CalibrationData) {
    let nominal = KinematicParams::nominal();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let truth = TrueRobot::draw(&nominal, &mut rng);
    let mut src = AnalyticRobot::new(truth, nominal, NoiseModel::default(), 2);
    let mut thetas = vec![Vec6::zeros()];
    thetas.extend(test_configurations(n, 3, (-0.45, 0.45)));
    (nominal, truth, collect(&mut src, &thetas, 2.0).unwrap())
}

fn bench_calibration(c: &mut Criterion) {
    let (nominal, truth, d) = data(22);
    let opts = CalibrationOptions::default();
    let r = rpba(&d, &nominal, &opts).unwrap();
    assert_eq!((r.parameter_count, r.used.len()), (66, 23));
    c.bench_function("rpba_66_params_22_configurations", |b| {
        b.iter(|| rpba(black_box(&d), black_box(&nominal), &opts).unwrap())
    });
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let guess = perturb_external(&truth.sensor_in_base, &mut rng);
    let (_, _, d34) = data(34);
    c.bench_function("implicit_72_params_34_configurations", |b| {
        b.iter(|| implicit(black_box(&d34), black_box(&nominal), &guess, &opts).unwrap())
    });
}

criterion_group!(benches, bench_calibration);
criterion_main!(benches);
