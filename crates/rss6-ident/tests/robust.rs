//! Calibration that is never silently wrong (issue 12): faulty configurations are left out, gross
//! outliers are rejected and named, and data no model explains raise `IdentError::Calibration`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{KinematicParams, Vec6};
use rss6_exp::dwell::DwellFault;
use rss6_ident::*;

fn nominal() -> KinematicParams {
    KinematicParams::nominal()
}

/// A robot drawn from Table 4.2 and its noisy data (2 s dwells) at `n` + 1 configurations.
fn robot_data(seed: u64, n: usize) -> (TrueRobot, CalibrationData) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth = TrueRobot::draw(&nominal(), &mut rng);
    let mut src = AnalyticRobot::new(truth, nominal(), NoiseModel::default(), seed + 100);
    let mut thetas = vec![Vec6::zeros()];
    thetas.extend(test_configurations(n, seed + 7, (-0.45, 0.45)));
    (truth, collect(&mut src, &thetas, 2.0).unwrap())
}

/// Table 4.5 met on 40 test configurations drawn where the data were taken.
fn meets(result: &CalibrationResult, truth: &TrueRobot, table: &[f64; 6]) -> bool {
    let e = relative_pose_errors(
        &result.params,
        &result.target_in_effector,
        truth,
        &nominal(),
        40,
        9,
        (-0.45, 0.45),
    )
    .unwrap();
    (0..6).all(|k| e.rms[k] <= table[k])
}

fn sensor_guess(truth: &TrueRobot) -> Vec6 {
    perturb_external(&truth.sensor_in_base, &mut ChaCha8Rng::seed_from_u64(3))
}

/// Both methods with their Table 4.5 row; implicit starts at `sensor_guess`.
const METHODS: [(Method, [f64; 6]); 2] = [
    (Method::Rpba, TABLE_4_5_RPBA),
    (Method::Implicit, TABLE_4_5_IMPLICIT),
];

fn calibrate(
    method: Method,
    data: &CalibrationData,
    truth: &TrueRobot,
    opts: &CalibrationOptions,
) -> std::result::Result<CalibrationResult, IdentError> {
    match method {
        Method::Rpba => rpba(data, &nominal(), opts),
        Method::Implicit => implicit(data, &nominal(), &sensor_guess(truth), opts),
    }
}

#[test]
fn an_unreached_configuration_is_excluded_by_default_and_named_if_included() {
    let (truth, mut data) = robot_data(21, 22);
    // what an unreached dwell looks like: joint 3 reads 60 bit (2.6°) off its command, flagged
    let bad = 6;
    data.configurations[bad].kappa[2] -= 60.0;
    data.configurations[bad].fault = Some(DwellFault::Unreached {
        joint: 2,
        error_bits: -60.0,
        tolerance_bits: 2.0,
    });
    let r = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap();
    assert!(!r.used.contains(&bad));
    let d = r.dropped.iter().find(|d| d.index == bad).unwrap();
    assert!(d.reason.contains("not reached"), "{}", d.reason);
    assert!(r.rejected.is_empty(), "{:?}", r.rejected);
    assert!(meets(&r, &truth, &TABLE_4_5_RPBA));

    // Included on purpose: a 2.6° joint error is partly absorbed by the offsets and smears over
    // every residual (median normalised residual ≈ 300), so no single configuration stands out
    // and the fit statistic (≈ 1200) fails. The solver then refits without each configuration in
    // turn: without this one the fit is accepted, so it is rejected and named (its residual under
    // that fit: 3.1·10⁴ against the threshold 9). Until the thirty-fifth session the solver
    // returned no model here and named it first in the CalibrationError.
    let opts = CalibrationOptions {
        include_faulty: true,
        ..CalibrationOptions::default()
    };
    let r = rpba(&data, &nominal(), &opts).unwrap();
    let rejected: Vec<usize> = r.rejected.iter().map(|c| c.index).collect();
    assert_eq!(rejected, vec![bad]);
    assert!(r.rejected[0].normalized_residual > r.rejected[0].threshold);
    assert!(meets(&r, &truth, &TABLE_4_5_RPBA));
}

#[test]
fn a_camera_pose_shifted_by_5_mm_is_rejected_and_named() {
    let (truth, mut data) = robot_data(22, 34);
    let bad = 9;
    if let Some(p) = data.configurations[bad].sensor_pose.as_mut() {
        p[0] += 5e-3;
    }
    let opts = CalibrationOptions::default();
    for (method, table) in METHODS {
        let r = calibrate(method, &data, &truth, &opts).unwrap();
        assert_eq!(r.rejected.len(), 1, "{method}: {:?}", r.rejected);
        assert_eq!(r.rejected[0].index, bad);
        assert!(
            r.rejected[0].normalized_residual > r.rejected[0].threshold,
            "{:?}",
            r.rejected
        );
        assert!(!r.used.contains(&bad));
        assert!(r.convergence.converged());
        // measured fit statistic after rejection: RPBA 0.96, implicit 1.02; bounds ≈ 3× / ÷3
        assert!(
            r.fit_statistic > 0.3 && r.fit_statistic < 3.0,
            "{method}: fit statistic {}",
            r.fit_statistic
        );
        assert_eq!(
            r.normalized_residuals.len(),
            r.used.len() - usize::from(method == Method::Rpba)
        );
        assert!(meets(&r, &truth, &table), "{method}");
    }
}

#[test]
fn a_gross_outlier_costs_only_its_own_configuration() {
    // One camera pose 5 mm–5 cm off among 35. A gross error pulls the least-squares fit toward
    // itself: Levenberg–Marquardt may not converge and its own residual need not stand out, so
    // the fit used to be refused (10 of these 32 cases: "did not converge" or "inconsistent with
    // the noise model") or good configurations were rejected before it. Refitting without each
    // configuration in turn when the fit fails (`deletion_outlier`), and testing rejected
    // configurations again against the accepted fit, leaves exactly the bad one out: 32 of 32.
    for seed in [22u64, 23, 24, 25] {
        for shift in [5e-3, 1e-2, 2e-2, 5e-2] {
            let (truth, mut data) = robot_data(seed, 34);
            let bad = 9;
            if let Some(p) = data.configurations[bad].sensor_pose.as_mut() {
                p[0] += shift;
            }
            let opts = CalibrationOptions::default();
            for (method, table) in METHODS {
                let r = calibrate(method, &data, &truth, &opts)
                    .unwrap_or_else(|e| panic!("seed {seed}, {shift} m, {method}: {e}"));
                let rejected: Vec<usize> = r.rejected.iter().map(|c| c.index).collect();
                assert_eq!(rejected, vec![bad], "seed {seed}, {shift} m, {method}");
                assert_eq!(r.used.len(), data.configurations.len() - 1);
                assert!(
                    meets(&r, &truth, &table),
                    "seed {seed}, {shift} m, {method}"
                );
            }
        }
    }
}

#[test]
fn data_no_model_explains_raise_calibration_error() {
    let (truth, mut data) = robot_data(23, 34);
    // scramble: every configuration gets its neighbour's camera pose
    let poses: Vec<_> = data.configurations.iter().map(|c| c.sensor_pose).collect();
    let n = poses.len();
    for (l, c) in data.configurations.iter_mut().enumerate() {
        c.sensor_pose = poses[(l + 1) % n];
    }
    let opts = CalibrationOptions::default();
    for (method, _) in METHODS {
        match calibrate(method, &data, &truth, &opts) {
            Err(IdentError::Calibration {
                method: m,
                configurations,
                fit_statistic,
                ..
            }) => {
                assert_eq!(m, method);
                assert!(!configurations.is_empty());
                assert!(configurations.iter().all(|&c| c < n), "{configurations:?}");
                assert!(fit_statistic > opts.max_fit_statistic, "{fit_statistic}");
            }
            other => panic!("{method}: expected a CalibrationError, got {other:?}"),
        }
    }
}
