//! # rss6-ident
//!
//! Offline kinematic calibration of 6-RSS parallel robots from an optical CMM (Li 2020, chapter 4):
//! the implicit method (eq. 4.10–4.15) and the relative-pose-based algorithm RPBA (eq. 4.16–4.21),
//! solved by Levenberg–Marquardt with analytic Jacobians; identifiability and gauge analysis
//! (§4.3.4); the observability index O1 (eq. 4.23) with the configuration selection of §4.4.2 and the
//! actuator stroke of §4.4.1; the relative-pose accuracy test of §4.4.3 (Table 4.5).
//!
//! Symbols follow the thesis: ᴼχ_C is the sensor (camera) pose in the base frame ("sensor_in_base"),
//! ᴱχ_t the target (reflector) frame in the end-effector frame ("target_in_effector"), ᶜχ_t the
//! measured target pose in the sensor frame, κ potentiometer readings (bits), b the 60 kinematic error
//! parameters in docs/architecture.md order. Units are SI (m, rad). See `docs/calibration.md`.
#![forbid(unsafe_code)]
#![allow(non_snake_case)]

mod calibrate;
mod cloe;
mod closure;
mod data;
mod error;
mod excitation;
mod generator;
mod model;
mod plant;
mod se3;
mod selection;
mod study;
mod validate;

pub use crate::calibrate::{
    gauge_directions, implicit, implicit_with_progress, min_configurations, parameter_vector,
    residual_norm_sum, residuals_and_jacobian, rpba, rpba_with_progress, CalibrationOptions,
    CalibrationResult, Convergence, DroppedConfiguration, JacobianMode, MeasurementNoise, Progress,
    RejectedConfiguration,
};
pub use crate::cloe::{
    cloe, cloe_observed, output_observability, parameter_names as loop_parameter_names,
    simulate as simulate_loop, simulate_from as simulate_loop_from,
    simulate_recording as simulate_loop_recording, table_5_2_truth, Alias, CloeData, CloeOptions,
    CloeResult, CloeStop, Consistent, LoopConfig, LoopParams, LoopRun, OutputObservability,
    Recording, StateJacobians, DRIVE_UNIT_TO_NM, HAC_LAGS, N_A, N_PSI, SETTLE_STEPS,
};
pub use crate::data::{
    collect, collect_with_progress, CalibrationData, ConfigurationData, RobotSource,
};
pub use crate::error::{IdentError, Method, Result};
pub use crate::excitation::{
    aliases, base_columns, observability_of, Excitation, ExcitationLimits, ExcitationProblem,
    Violation, PIVOT_TIE,
};
pub use crate::generator::{
    perturb_external, AnalyticRobot, NoiseModel, TrueRobot, NOMINAL_SENSOR_IN_BASE,
    NOMINAL_TARGET_IN_EFFECTOR,
};
pub use crate::model::{
    gauge_aligned_error, parameter_names, parameter_scale, GAUGE_DESCRIPTIONS, N_GAUGE,
    SIGMA_DTHETA, SIGMA_ETA, SIGMA_EXT_ANGLE, SIGMA_EXT_POSITION, SIGMA_LENGTH,
};
pub use crate::plant::{plant_nominal_target, plant_with_kinematics, random_plant, sim_source};
pub use crate::selection::{
    observability_index, select_configurations, select_configurations_with, stroke, stroke_margin,
    stroke_with, SelectionOptions, SelectionReport, StrokeOptions,
};

pub use crate::study::{
    mean_p95, run_plant_robot, run_plant_robustness, run_robot, run_robot_with_source, run_study,
    MethodOutcome, Outcome, RobotDraw, RobustnessRow, StudyOptions, StudyRow, TABLE_4_5_IMPLICIT,
    TABLE_4_5_RPBA,
};
pub use crate::validate::{
    relative_pose_errors, result_relative_pose_errors, test_configurations, RelativePoseErrors,
};
