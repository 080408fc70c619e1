//! Calibration on data from the rapier plant (its PID, potentiometers and stereo CMM).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{KinematicParams, Vec6};
use rss6_ident::*;

#[test]
fn rpba_on_rapier_plant_data_improves_relative_accuracy() {
    let nominal = KinematicParams::nominal();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let (mut source, truth) = random_plant(&nominal, &mut rng, 4).unwrap();
    source.spec.move_time = 0.6;
    source.spec.settle_time = 0.4;
    let mut thetas = vec![Vec6::zeros()];
    thetas.extend(test_configurations(13, 5, (-0.4, 0.4)));
    let data = collect(&mut source, &thetas, 1.0).unwrap();
    assert!(data
        .configurations
        .iter()
        .all(|c| c.camera_frames >= 25 && c.kappa_samples == 500));
    let opts = CalibrationOptions {
        target_guess: plant_nominal_target().into(),
        ..Default::default()
    };
    let r = rpba(&data, &nominal, &opts).unwrap();
    assert_eq!(r.rank, 56);
    let stroke = (-0.4, 0.4);
    let cal = relative_pose_errors(
        &r.params,
        &r.target_in_effector,
        &truth,
        &nominal,
        40,
        1,
        stroke,
    )
    .unwrap();
    let unc = relative_pose_errors(
        &nominal,
        &plant_nominal_target(),
        &truth,
        &nominal,
        40,
        1,
        stroke,
    )
    .unwrap();
    for k in 0..6 {
        assert!(
            cal.rms[k] * 20.0 < unc.rms[k],
            "axis {k}: calibrated {:?} vs uncalibrated {:?}",
            cal.rms,
            unc.rms
        );
    }
}
