//! Relative-pose accuracy test of §4.4.3 (procedure steps 1–4 under Table 4.4; Table 4.5).
//!
//! 1. n random test relative configurations M_n^l (target frame relative to the initial
//!    configuration) are drawn: random joint vectors inside the stroke, mapped through the nominal
//!    model (eq. 4.17).
//! 2. For a model (kinematic parameters and ᴱχ_t) and the initial readings κ⁰, ᴼM_E⁰ = FK_model(κ⁰).
//! 3. The commanded readings are κ^l = IK_model(ᴼM_E⁰·ᴱM_t·M_n^l·ᴱM_t⁻¹).
//! 4. The true robot executes κ^l; its realised relative pose M^l (eq. 4.17 with the true parameters)
//!    is compared with M_n^l: error = L(M^l) − L(M_n^l).

use crate::closure::fk_reading;
use crate::error::{IdentError, Result};
use crate::generator::TrueRobot;
use crate::se3::{iso, pose_difference};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::{home_pose, ik, isometry_to_pose, KinematicParams, Vec6};

/// Relative pose errors of one model on the test configurations.
#[derive(Debug, Clone, PartialEq)]
pub struct RelativePoseErrors {
    /// RMS per axis [x, y, z, α, β, γ] (m, rad).
    pub rms: [f64; 6],
    /// Per-configuration errors L(M^l) − L(M_n^l).
    pub errors: Vec<Vec6>,
    /// Test configurations the model or the true robot could not execute (IK/FK failure).
    pub skipped: usize,
}

/// Random test configurations: joint vectors uniform in `stroke` (rad, nominal convention).
pub fn test_configurations(n: usize, seed: u64, stroke: (f64, f64)) -> Vec<Vec6> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| Vec6::from_fn(|_, _| rng.random_range(stroke.0..stroke.1)))
        .collect()
}

/// [`relative_pose_errors`] of a calibration result on `truth`, with its starting parameters as the
/// nominal model and the test configurations drawn inside [`crate::stroke`] of them.
pub fn result_relative_pose_errors(
    result: &crate::CalibrationResult,
    truth: &TrueRobot,
    n: usize,
    seed: u64,
) -> Result<RelativePoseErrors> {
    let stroke = crate::stroke(&result.reference)?;
    relative_pose_errors(
        &result.params,
        &result.target_in_effector,
        truth,
        &result.reference,
        n,
        seed,
        stroke,
    )
}

/// RMS relative pose errors (Table 4.5) of the model (`params`, `target_in_effector`) on the true
/// robot, over `n` random test configurations drawn with `seed` inside `stroke` (rad). The initial
/// configuration is θ = 0 in the convention of `nominal`.
pub fn relative_pose_errors(
    params: &KinematicParams,
    target_in_effector: &Vec6,
    truth: &TrueRobot,
    nominal: &KinematicParams,
    n: usize,
    seed: u64,
    stroke: (f64, f64),
) -> Result<RelativePoseErrors> {
    if n == 0 || stroke.0.is_nan() || stroke.1.is_nan() || stroke.0 >= stroke.1 {
        return Err(IdentError::InvalidInput(format!(
            "need n > 0 and a non-empty stroke (n {n}, stroke {stroke:?})"
        )));
    }
    let kappa0 = nominal.reading_from_theta(&Vec6::zeros());
    let nominal_target = crate::generator::NOMINAL_TARGET_IN_EFFECTOR.into();
    let fk = |kp: &KinematicParams, kappa: &Vec6| fk_reading(kp, kappa, &home_pose());
    let e0_nom = fk(nominal, &kappa0)?;
    let e0_model = fk(params, &kappa0)?;
    let e0_true = truth.pose_from_reading(&kappa0, &home_pose())?;
    let mt_nom = iso(&nominal_target);
    let mt_model = iso(target_in_effector);
    let mt_true = iso(&truth.target_in_effector);
    let mut errors = Vec::with_capacity(n);
    let mut skipped = 0;
    for theta in test_configurations(n, seed, stroke) {
        // step 1: nominal relative configuration M_n
        let Ok(el_nom) = fk(nominal, &nominal.reading_from_theta(&theta)) else {
            skipped += 1;
            continue;
        };
        let m_n = (iso(&e0_nom) * mt_nom).inverse() * iso(&el_nom) * mt_nom;
        // steps 2–3: model command
        let el_cmd = isometry_to_pose(&(iso(&e0_model) * mt_model * m_n * mt_model.inverse()));
        let Ok(theta_model) = ik(params, &el_cmd) else {
            skipped += 1;
            continue;
        };
        let kappa = params.reading_from_theta(&theta_model);
        // step 4: the true robot executes it
        let Ok(el_true) = truth.pose_from_reading(&kappa, &el_cmd) else {
            skipped += 1;
            continue;
        };
        let m = (iso(&e0_true) * mt_true).inverse() * iso(&el_true) * mt_true;
        errors.push(pose_difference(
            &isometry_to_pose(&m),
            &isometry_to_pose(&m_n),
        ));
    }
    if errors.len() * 2 < n {
        return Err(IdentError::InvalidInput(format!(
            "only {} of {n} test configurations could be executed",
            errors.len()
        )));
    }
    let mut rms = [0.0; 6];
    for (k, r) in rms.iter_mut().enumerate() {
        *r = (errors.iter().map(|e| e[k] * e[k]).sum::<f64>() / errors.len() as f64).sqrt();
    }
    Ok(RelativePoseErrors {
        rms,
        errors,
        skipped,
    })
}
