//! The two calibration methods of §4.3 and their Levenberg–Marquardt solver.
//!
//! * [`implicit`]: leg-closure residuals Φ_I (eq. 4.10) with ᴼM_E^l = ᴼM_C·ᶜM_t^l·ᵗM_E (eq. 4.12);
//!   60 kinematic + 12 external parameters (ᴼχ_C, ᴱχ_t), cost eq. 4.13.
//! * [`rpba`]: relative-pose residuals Φ_R = L(ᶜM_t⁰⁻¹ᶜM_t^l) − L(ᴱM_t⁻¹·ᴼM_E⁰⁻¹·ᴼM_E^l·ᴱM_t)
//!   (eq. 4.16–4.18) with forward kinematics inside; 60 + 6 parameters (ᴱχ_t), cost eq. 4.19.
//!
//! Both are solved by Levenberg–Marquardt (eq. 4.14 / 4.20 are its undamped Gauss–Newton case) with
//! analytic Jacobians: the FK derivative comes from implicit differentiation of the leg closure,
//! dχ/db = −(∂Φ/∂χ)⁻¹ ∂Φ/∂b. The finite differences of eq. 4.25 remain available
//! ([`JacobianMode::FiniteDifference`]) and are used by the tests to check the analytic Jacobian.
//! Parameters are scaled by their Table 4.2 σ, and steps are restricted to the complement of the 10
//! gauge directions (see [`crate::model`]): the minimum-norm fix of the frame choice.

mod noise;
mod options;
mod problem;
mod result;
mod solver;

pub use noise::MeasurementNoise;
pub use options::{CalibrationOptions, Convergence, JacobianMode, Progress};
pub use result::{CalibrationResult, DroppedConfiguration, RejectedConfiguration};

use crate::data::CalibrationData;
use crate::error::{IdentError, Method, Result};
use crate::model::{Layout, N_GAUGE};
use nalgebra::{DMatrix, DVector};
use problem::{usable, Problem};
use rss6_core::{KinematicParams, Vec6};
use solver::solve;

/// Minimum number of configurations (including configuration 0) each method needs: every
/// configuration gives 6 equations, RPBA loses one configuration to the reference, and the
/// identifiable parameter count is the total minus the 10 gauge directions.
pub fn min_configurations(method: Method) -> usize {
    let free = Layout::new(method, KinematicParams::nominal()).n() - N_GAUGE;
    let per = free.div_ceil(6);
    match method {
        Method::Rpba => per + 1,
        Method::Implicit => per,
    }
}

/// The parameter vector x = [b; (ᴼχ_C); ᴱχ_t] of `method` for parameters `kp` measured from
/// `reference` (b = kp − reference). `sensor` is ignored for RPBA.
pub fn parameter_vector(
    method: Method,
    reference: &KinematicParams,
    kp: &KinematicParams,
    sensor: Option<&Vec6>,
    target: &Vec6,
) -> DVector<f64> {
    Layout::new(method, *reference).pack(kp, sensor, target)
}

/// RPBA (eq. 4.16–4.21) from `data`, starting at kinematic parameters `kp` and the target pose
/// `opts.target_guess` (ᴱχ_t, m/rad; e.g. the nominal target definition).
///
/// Configuration 0 is the reference. Configurations with NaN or missing frames, or where FK fails at
/// the starting parameters, are dropped and reported in [`CalibrationResult::dropped`]; a bad
/// configuration 0 is an error.
pub fn rpba(
    data: &CalibrationData,
    kp: &KinematicParams,
    opts: &CalibrationOptions,
) -> Result<CalibrationResult> {
    rpba_with_progress(data, kp, opts, &mut |_| {})
}

/// [`rpba`] with a progress callback after every LM iteration.
pub fn rpba_with_progress(
    data: &CalibrationData,
    kp: &KinematicParams,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let layout = Layout::new(Method::Rpba, *kp);
    let x0 = layout.pack(kp, None, &Vec6::from(opts.target_guess));
    solve(layout, data, x0, opts, progress)
}

/// Implicit calibration (eq. 4.10–4.15) from `data`, starting at `kp`, the rough sensor pose
/// `sensor_pose_guess` (ᴼχ_C) and `opts.target_guess` (ᴱχ_t). Configuration 0 is used like the
/// others.
pub fn implicit(
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor_pose_guess: &Vec6,
    opts: &CalibrationOptions,
) -> Result<CalibrationResult> {
    implicit_with_progress(data, kp, sensor_pose_guess, opts, &mut |_| {})
}

/// [`implicit`] with a progress callback after every LM iteration.
pub fn implicit_with_progress(
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor_pose_guess: &Vec6,
    opts: &CalibrationOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<CalibrationResult> {
    let layout = Layout::new(Method::Implicit, *kp);
    let x0 = layout.pack(kp, Some(sensor_pose_guess), &Vec6::from(opts.target_guess));
    solve(layout, data, x0, opts, progress)
}

/// Σ_l ‖Φ^l‖₂ (unweighted, SI units) for `data` at the given parameters: the second row of
/// Tables 4.3 (implicit, m) and 4.4 (RPBA, mixed m/rad). Unusable configurations are skipped.
pub fn residual_norm_sum(
    method: Method,
    data: &CalibrationData,
    kp: &KinematicParams,
    sensor: Option<&Vec6>,
    target: &Vec6,
) -> Result<f64> {
    let layout = Layout::new(method, *kp);
    let x = layout.pack(kp, sensor, target);
    let u = usable(data, false);
    if u.len() < 2 {
        return Err(IdentError::InvalidInput("no usable configurations".into()));
    }
    let opts = CalibrationOptions {
        pose_weights: [1.0; 6],
        leg_weight: 1.0,
        ..CalibrationOptions::default()
    };
    let mut p = Problem::new(layout, u.kappa, u.cam, &opts);
    let e = p
        .eval(&x, false)
        .map_err(|(config, source)| IdentError::Fk { config, source })?;
    Ok(e.r
        .as_slice()
        .chunks(6)
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .sum())
}

/// Residuals and Jacobian of `method` at parameter vector `x` (see [`parameter_vector`]) for the
/// usable configurations of `data`, with the fixed Table 4.1 weights (no noise whitening). Exposed for identifiability studies and
/// for checking the analytic Jacobian against eq. 4.25.
pub fn residuals_and_jacobian(
    method: Method,
    data: &CalibrationData,
    reference: &KinematicParams,
    x: &DVector<f64>,
    mode: JacobianMode,
) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let layout = Layout::new(method, *reference);
    if x.len() != layout.n() {
        return Err(IdentError::InvalidInput(format!(
            "parameter vector has {} entries, {method} needs {}",
            x.len(),
            layout.n()
        )));
    }
    let u = usable(data, false);
    if u.len() < 2 {
        return Err(IdentError::InvalidInput(
            "fewer than 2 usable configurations".into(),
        ));
    }
    let mut p = Problem::new(layout, u.kappa, u.cam, &CalibrationOptions::default());
    p.eval_full(x, mode).map_err(|(l, source)| IdentError::Fk {
        config: u.index[l],
        source,
    })
}

/// The 10 gauge directions (columns, unscaled parameter units) of `method` at parameter vector `x`.
pub fn gauge_directions(
    method: Method,
    reference: &KinematicParams,
    x: &DVector<f64>,
) -> DMatrix<f64> {
    Layout::new(method, *reference).gauge_basis(x)
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::data::collect;
    use crate::generator::{AnalyticRobot, NoiseModel, TrueRobot};
    use rand::SeedableRng;

    /// The gauge claim of `model.rs` is exact, not first-order: finite frame changes leave every
    /// residual unchanged.
    #[test]
    fn residuals_are_invariant_under_finite_gauge_transformations() {
        let nominal = KinematicParams::nominal();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let truth = TrueRobot::draw(&nominal, &mut rng);
        let mut src = AnalyticRobot::new(truth, nominal, NoiseModel::default(), 5);
        let mut thetas = vec![Vec6::zeros()];
        thetas.extend(crate::validate::test_configurations(8, 1, (-0.4, 0.4)));
        let data = collect(&mut src, &thetas, 2.0).unwrap();
        let g = [
            0.01, -0.02, 0.005, 0.03, 0.004, -0.003, 0.01, 0.02, -0.01, 0.05,
        ];
        for method in [Method::Rpba, Method::Implicit] {
            let layout = Layout::new(method, nominal);
            let x = layout.pack(
                &truth.kp,
                Some(&truth.sensor_in_base),
                &truth.target_in_effector,
            );
            let xg = layout.apply_gauge(&x, &g);
            assert!(
                (&xg - &x).amax() > 1e-3,
                "the gauge must actually move the parameters"
            );
            let u = usable(&data, false);
            let mut p = Problem::new(layout, u.kappa, u.cam, &CalibrationOptions::default());
            let r = p.eval(&x, false).unwrap().r;
            let rg = p.eval(&xg, false).unwrap().r;
            assert!(
                (&r - &rg).amax() < 1e-6 * r.amax(),
                "{method}: {}",
                (&r - &rg).amax()
            );
        }
    }
}
