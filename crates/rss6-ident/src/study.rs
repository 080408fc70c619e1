//! The simulation study of §4.4.3 (Tables 4.3–4.5), repeated over random robots in parallel (rayon).

use crate::calibrate::{implicit, parameter_vector, residual_norm_sum, rpba, CalibrationOptions};
use crate::data::{collect, RobotSource};
use crate::error::{Method, Result};
use crate::generator::{perturb_external, AnalyticRobot, NoiseModel, TrueRobot};
use crate::model::gauge_aligned_error;
use crate::validate::relative_pose_errors;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use rss6_core::{KinematicParams, Vec6};

/// Options of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyOptions {
    /// Number of random true robots (≥ 20 for the reported table).
    pub robots: usize,
    /// Master seed: robot r uses seeds derived from `seed + r`.
    pub seed: u64,
    /// RPBA configurations (rad, nominal convention; element 0 = initial configuration).
    pub rpba_thetas: Vec<Vec6>,
    /// Implicit configurations (element 0 = initial configuration).
    pub implicit_thetas: Vec<Vec6>,
    /// Dwell per configuration (s); noise is averaged over it (thesis: 2 s).
    pub dwell: f64,
    /// Measurement noise (Table 4.1).
    pub noise: NoiseModel,
    /// Number of random test configurations for Table 4.5 (thesis: 100).
    pub test_configurations: usize,
    /// Stroke (rad) the test configurations are drawn from.
    pub stroke: (f64, f64),
    /// Solver options for both methods.
    pub solver: CalibrationOptions,
    /// Nominal ᴱχ_t: the starting guess of both methods and the uncalibrated model's target
    /// ([`crate::NOMINAL_TARGET_IN_EFFECTOR`] for the analytic generator, the simulator's default on the plant).
    pub target_nominal: [f64; 6],
}

/// One robot's results: Tables 4.3, 4.4 and 4.5 entries.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyRow {
    /// Robot index.
    pub robot: usize,
    /// Table 4.3: gauge-aligned ‖S⁻¹(b_I − b_I^n)‖ (Table 4.2 σ units) before / after implicit.
    pub implicit_param_error: (f64, f64),
    /// Same, unscaled SI norm (m, rad/bit, rad mixed) before / after.
    pub implicit_param_error_si: (f64, f64),
    /// Table 4.3: Σ_l ‖Φ_I^l‖ (m) before / after / at the true parameters.
    pub implicit_residual: (f64, f64, f64),
    /// Table 4.4: gauge-aligned ‖S⁻¹(b_R − b_R^n)‖ before / after RPBA.
    pub rpba_param_error: (f64, f64),
    /// Same, unscaled SI norm.
    pub rpba_param_error_si: (f64, f64),
    /// Table 4.4: Σ_l ‖Φ_R^l‖ (mixed m/rad) before / after / at the true parameters.
    pub rpba_residual: (f64, f64, f64),
    /// Table 4.5: RMS relative pose errors [x, y, z, α, β, γ] (m, rad), uncalibrated.
    pub rms_uncalibrated: [f64; 6],
    /// Table 4.5, implicit.
    pub rms_implicit: [f64; 6],
    /// Table 4.5, RPBA.
    pub rms_rpba: [f64; 6],
    /// Table 4.5, implicit with ᴼχ_C held at its rough guess (not estimated): the thesis's setting.
    pub rms_implicit_fixed_sensor: [f64; 6],
    /// LM iterations (implicit, RPBA).
    pub iterations: (usize, usize),
    /// Jacobian ranks at the solution (implicit of 72, RPBA of 66).
    pub ranks: (usize, usize),
}

/// Runs the study for one robot: draw the truth, collect both data sets from the analytic generator,
/// calibrate with both methods, evaluate Tables 4.3–4.5.
pub fn run_robot(nominal: &KinematicParams, opts: &StudyOptions, robot: usize) -> Result<StudyRow> {
    let seed = opts
        .seed
        .wrapping_add(robot as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth = TrueRobot::draw(nominal, &mut rng);
    let mut source = AnalyticRobot::new(truth, *nominal, opts.noise, seed ^ 0xDA7A);
    run_robot_with_source(nominal, opts, robot, &truth, &mut source, &mut rng)
}

/// [`run_robot`] with any data source whose truth is known (e.g. the rapier plant).
pub fn run_robot_with_source(
    nominal: &KinematicParams,
    opts: &StudyOptions,
    robot: usize,
    truth: &TrueRobot,
    source: &mut dyn RobotSource,
    rng: &mut ChaCha8Rng,
) -> Result<StudyRow> {
    let data_r = collect(source, &opts.rpba_thetas, opts.dwell)?;
    let data_i = collect(source, &opts.implicit_thetas, opts.dwell)?;
    let target0 = Vec6::from(opts.target_nominal);
    let sensor_guess = perturb_external(&truth.sensor_in_base, rng);
    let solver = CalibrationOptions {
        target_guess: target0.into(),
        ..opts.solver
    };
    let res_i = implicit(&data_i, nominal, &sensor_guess, &solver)?;
    let res_r = rpba(&data_r, nominal, &solver)?;
    let res_if = implicit(
        &data_i,
        nominal,
        &sensor_guess,
        &CalibrationOptions {
            fix_sensor_pose: true,
            // ᴼχ_C held at a guess that is off by Table 4.2's external sizes cannot explain the data to
            // within the noise (fit statistic 6–40 on the analytic generator): the thesis's setting is
            // misspecified by design, so this variant is evaluated without the consistency check.
            max_fit_statistic: f64::INFINITY,
            max_rejections: 0,
            ..solver
        },
    )?;

    let param_errors = |method: Method,
                        sensor0: Option<&Vec6>,
                        kp: &KinematicParams,
                        sensor: Option<&Vec6>,
                        target: &Vec6| {
        let x_true = parameter_vector(
            method,
            nominal,
            &truth.kp,
            Some(&truth.sensor_in_base),
            &truth.target_in_effector,
        );
        let x0 = parameter_vector(method, nominal, nominal, sensor0, &target0);
        let x1 = parameter_vector(method, nominal, kp, sensor, target);
        let (b0, d0) = gauge_aligned_error(method, nominal, &x0, &x_true);
        let (b1, d1) = gauge_aligned_error(method, nominal, &x1, &x_true);
        ((b0, b1), (d0.norm(), d1.norm()))
    };
    let (implicit_param_error, implicit_param_error_si) = param_errors(
        Method::Implicit,
        Some(&sensor_guess),
        &res_i.params,
        res_i.sensor_in_base.as_ref(),
        &res_i.target_in_effector,
    );
    let (rpba_param_error, rpba_param_error_si) = param_errors(
        Method::Rpba,
        None,
        &res_r.params,
        None,
        &res_r.target_in_effector,
    );
    let implicit_residual = (
        residual_norm_sum(
            Method::Implicit,
            &data_i,
            nominal,
            Some(&sensor_guess),
            &target0,
        )?,
        residual_norm_sum(
            Method::Implicit,
            &data_i,
            &res_i.params,
            res_i.sensor_in_base.as_ref(),
            &res_i.target_in_effector,
        )?,
        residual_norm_sum(
            Method::Implicit,
            &data_i,
            &truth.kp,
            Some(&truth.sensor_in_base),
            &truth.target_in_effector,
        )?,
    );
    let rpba_residual = (
        residual_norm_sum(Method::Rpba, &data_r, nominal, None, &target0)?,
        residual_norm_sum(
            Method::Rpba,
            &data_r,
            &res_r.params,
            None,
            &res_r.target_in_effector,
        )?,
        residual_norm_sum(
            Method::Rpba,
            &data_r,
            &truth.kp,
            None,
            &truth.target_in_effector,
        )?,
    );
    let rel = |kp: &KinematicParams, target: &Vec6| {
        relative_pose_errors(
            kp,
            target,
            truth,
            nominal,
            opts.test_configurations,
            opts.seed ^ (robot as u64) ^ 0x7E57,
            opts.stroke,
        )
        .map(|e| e.rms)
    };
    Ok(StudyRow {
        robot,
        implicit_param_error,
        implicit_param_error_si,
        implicit_residual,
        rpba_param_error,
        rpba_param_error_si,
        rpba_residual,
        rms_uncalibrated: rel(nominal, &target0)?,
        rms_implicit: rel(&res_i.params, &res_i.target_in_effector)?,
        rms_rpba: rel(&res_r.params, &res_r.target_in_effector)?,
        rms_implicit_fixed_sensor: rel(&res_if.params, &res_if.target_in_effector)?,
        iterations: (res_i.iterations, res_r.iterations),
        ranks: (res_i.rank, res_r.rank),
    })
}

/// [`run_robot`] on the rapier plant: the truth is drawn the same way (Table 4.2 around `nominal`,
/// external poses around the simulator's defaults) and the data come from the plant's PID, potentiometers
/// and stereo CMM through the experiment layer's dwell runner. Set `opts.target_nominal` to [`crate::plant_nominal_target`].
pub fn run_plant_robot(
    nominal: &KinematicParams,
    opts: &StudyOptions,
    robot: usize,
) -> Result<StudyRow> {
    let seed = opts
        .seed
        .wrapping_add(robot as u64)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut source, truth) = crate::plant::random_plant(nominal, &mut rng, seed ^ 0xDA7A)?;
    run_robot_with_source(nominal, opts, robot, &truth, &mut source, &mut rng)
}

/// Runs [`run_robot`] for robots 0..`opts.robots` in parallel.
pub fn run_study(nominal: &KinematicParams, opts: &StudyOptions) -> Vec<Result<StudyRow>> {
    (0..opts.robots)
        .into_par_iter()
        .map(|r| run_robot(nominal, opts, r))
        .collect()
}

/// Mean and 95th percentile (nearest rank) of `values`.
pub fn mean_p95(values: &[f64]) -> (f64, f64) {
    if values.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    let mut v = values.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let rank = ((0.95 * v.len() as f64).ceil() as usize).clamp(1, v.len());
    (mean, v[rank - 1])
}
