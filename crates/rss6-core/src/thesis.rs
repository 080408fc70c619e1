//! The numbers the thesis publishes (Li 2020), in one place. Every other crate, the benches and the
//! Python package (through `rss6._rss6.thesis_tables()` and `rss6.thesis`) read them from here.
//!
//! Units: SI (m, rad, kg, s) unless a constant's doc says otherwise; Tables 6.1/6.2 keep the thesis's
//! printed units (mm and 10⁻³ rad) so they compare digit for digit. Pose-indexed arrays follow
//! χ = [x, y, z, α, β, γ] (the thesis prints some tables in the order γ, β, α; they are reordered here).
//! Values the thesis does not print (the DSMC gains and the Kalman process noise of §6.5, the robot's
//! dimensions) are not here: they are rss6's own and live with the code that tunes them.

use core::f64::consts::PI;

// ---- Table 4.1: noise of the measurements (1σ) ----

/// Table 4.1: potentiometer (joint angle) reading noise κ, in bits.
pub const KAPPA_NOISE_BITS: f64 = 0.2233;
/// Table 4.1: camera pose position noise per component x, y, z (m); printed as 0.0096 mm.
pub const POSE_POSITION_NOISE: f64 = 0.0096e-3;
/// Table 4.1: camera pose angle noise per Euler angle α, β, γ, in degrees as printed.
pub const POSE_ANGLE_NOISE_DEG: f64 = 0.0261;
/// Table 4.1: camera pose angle noise per Euler angle α, β, γ (rad); 0.0261°.
pub const POSE_ANGLE_NOISE: f64 = POSE_ANGLE_NOISE_DEG * PI / 180.0;

// ---- Table 4.2: standard deviations of the simulated parameter errors ----

/// Table 4.2: σ of the length and position errors b_I1 … b_I48 (m); printed as 1 mm.
pub const SIGMA_LENGTH: f64 = 1e-3;
/// Table 4.2: σ of the potentiometer gain errors b_I49 … b_I54 (rad/bit).
pub const SIGMA_ETA: f64 = 5e-5;
/// Table 4.2: σ of the potentiometer offset errors Δθ, b_I55 … b_I60 (rad).
pub const SIGMA_DTHETA: f64 = 0.05;
/// Table 4.2: σ of the external position errors of ᴼχ_C and ᴱχ_t (m); printed as 0.5 mm.
pub const SIGMA_EXT_POSITION: f64 = 0.5e-3;
/// Table 4.2: σ of the external angle errors of ᴼχ_C and ᴱχ_t (rad).
pub const SIGMA_EXT_ANGLE: f64 = 0.017;

// ---- Tables 4.3 and 4.4: calibration in simulation ----

/// One of Tables 4.3/4.4: the error norms before and after a simulated calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationNorms {
    /// ‖b^c − b^n‖₂ (before, after); the thesis prints it without units (mixed m, rad/bit, rad).
    pub param_error: (f64, f64),
    /// Σ_l ‖Φ^c − Φ^n‖₂ over the configurations (before, after).
    pub residual: (f64, f64),
    /// Number of calibration configurations (34 implicit, 22 RPBA).
    pub configurations: u32,
    /// Gauss–Newton iterations the thesis reports (11 implicit, 4 RPBA).
    pub iterations: u32,
}

/// Table 4.3: implicit calibration (72 error parameters, 34 configurations, 11 iterations).
pub const TABLE_4_3_IMPLICIT: CalibrationNorms = CalibrationNorms {
    param_error: (3.273, 0.8197),
    residual: (0.00109929, 2.94235e-05),
    configurations: 34,
    iterations: 11,
};

/// Table 4.4: relative-pose-based calibration RPBA (66 error parameters, 22 configurations, 4 iterations).
pub const TABLE_4_4_RPBA: CalibrationNorms = CalibrationNorms {
    param_error: (3.1630, 0.6616),
    residual: (0.00542206, 2.38881e-05),
    configurations: 22,
    iterations: 4,
};

// ---- Table 4.5: RMS relative pose errors in simulation, [x, y, z, α, β, γ] (m, rad) ----

/// Table 4.5, χ_u,e: RMS relative pose error with the uncalibrated parameters (m, rad).
pub const TABLE_4_5_UNCALIBRATED: [f64; 6] = [3.4e-3, 3.8e-3, 4.5e-3, 0.0037, 0.0060, 0.0033];
/// Table 4.5, χ_I,e: RMS relative pose error after implicit calibration (m, rad).
pub const TABLE_4_5_IMPLICIT: [f64; 6] = [3.1e-3, 4.9e-3, 4.2e-3, 9.6e-4, 7.9e-4, 0.0012];
/// Table 4.5, χ_R,e: RMS relative pose error after RPBA (m, rad).
pub const TABLE_4_5_RPBA: [f64; 6] = [0.053e-3, 0.039e-3, 0.018e-3, 6.7e-5, 1.6e-4, 9.7e-5];

// ---- Table 5.1: initial (manufacturer) dynamic parameters, [m, I_x, I_y, I_z] (kg, kg·m²) ----

/// Table 5.1: end-effector platform [m_p, I_xp, I_yp, I_zp] (kg, kg·m²).
pub const TABLE_5_1_PLATFORM: [f64; 4] = [24.0, 17.8e-2, 17.8e-2, 35.0e-2];
/// Table 5.1: each wrench (crank) [m_w, I_xw, I_yw, I_zw] (kg, kg·m²); I_z about the revolute axis.
pub const TABLE_5_1_WRENCH: [f64; 4] = [68.5e-2, 22.9e-5, 22.9e-5, 60.5e-5];
/// Table 5.1: each link [m_l, I_xl, I_yl, I_zl] (kg, kg·m²); I_z about the link axis.
pub const TABLE_5_1_LINK: [f64; 4] = [1.31, 52.3e-5, 52.3e-5, 21.3e-4];

// ---- Table 5.2: the built-in joint PID (eq. 5.5 / 6.14) and the identified joint friction ----

/// Table 5.2: initial gains [l_p, l_i, l_d] of the drive's built-in PID, in the drive's own command
/// units (the thesis does not state them; they are not N·m/rad, see `rss6_ctrl::PidGains`).
pub const TABLE_5_2_PID_INITIAL: [f64; 3] = [10.0, 12.0, 0.1];
/// Table 5.2: identified gains [l_p, l_i, l_d] of the built-in PID (drive units), used in §6.5.
pub const TABLE_5_2_PID_IDENTIFIED: [f64; 3] = [10.5, 11.4, 0.164];
/// Table 5.2: identified Coulomb friction f_c,1 … f_c,6 of the revolute joints (initial value 0).
pub const TABLE_5_2_COULOMB: [f64; 6] = [0.104, 0.111, 0.0336, 0.147, 0.104, 0.0828];
/// Table 5.2: identified viscous friction f_v,1 … f_v,6 of the revolute joints (initial value 0).
pub const TABLE_5_2_VISCOUS: [f64; 6] = [0.148, 0.187, 0.0993, 0.854, 0.0803, 0.0349];

// ---- Table 5.2: identified masses and inertias; Tables 5.3–5.5: identification results ----

/// Table 5.2: identified platform [m, I_x, I_y, I_z] (kg, kg·m²) as printed. Its moments violate the
/// triangle inequality (I_x + I_y < I_z): `rss6_ident::table_5_2_truth` lowers I_z for a physical body.
pub const TABLE_5_2_PLATFORM: [f64; 4] = [23.5, 16.1e-2, 14.4e-2, 33.7e-2];
/// Table 5.2: identified wrench i [m, I_z] (kg, kg·m²); I_x, I_y are not identified.
pub const TABLE_5_2_WRENCHES: [[f64; 2]; 6] = [
    [67.1e-2, 69.4e-5],
    [68.7e-2, 10.0e-5],
    [68.0e-2, 22.6e-5],
    [67.7e-2, 76.0e-5],
    [68.3e-2, 44.1e-5],
    [68.4e-2, 69.6e-5],
];
/// Table 5.2: identified link i [m, I_x, I_y] (kg, kg·m²); I_z is not identified.
pub const TABLE_5_2_LINKS: [[f64; 3]; 6] = [
    [1.33, 63.0e-5, 68.4e-5],
    [1.32, 60.7e-5, 71.8e-5],
    [1.25, 22.4e-5, 35.5e-5],
    [1.24, 12.9e-5, 39.2e-5],
    [1.33, 30.7e-5, 49.7e-5],
    [1.34, 47.0e-5, 50.9e-5],
];
/// Table 5.3: RMS pose error on the identification trajectory before identification
/// [x, y, z, α, β, γ] (m, rad).
pub const TABLE_5_3_BEFORE: [f64; 6] = [1.26e-3, 1.16e-3, 1.55e-3, 2.52e-3, 3.58e-3, 2.80e-3];
/// Table 5.3: the same after identification (m, rad).
pub const TABLE_5_3_AFTER: [f64; 6] = [0.408e-3, 0.235e-3, 0.494e-3, 0.956e-3, 0.797e-3, 0.725e-3];
/// Table 5.4: RMS pose error of the identified model on ten validation trajectories, one row per
/// trajectory [x, y, z, α, β, γ] (m, rad).
pub const TABLE_5_4: [[f64; 6]; 10] = [
    [0.517e-3, 0.384e-3, 0.709e-3, 1.091e-3, 0.963e-3, 0.966e-3],
    [0.273e-3, 0.410e-3, 0.522e-3, 1.157e-3, 1.071e-3, 0.932e-3],
    [0.381e-3, 0.403e-3, 0.600e-3, 1.242e-3, 0.830e-3, 1.143e-3],
    [0.341e-3, 0.511e-3, 0.617e-3, 1.136e-3, 0.814e-3, 1.161e-3],
    [0.322e-3, 0.394e-3, 0.464e-3, 1.219e-3, 0.877e-3, 0.835e-3],
    [0.310e-3, 0.301e-3, 0.441e-3, 1.195e-3, 1.111e-3, 1.040e-3],
    [0.360e-3, 0.402e-3, 0.455e-3, 1.263e-3, 1.176e-3, 1.024e-3],
    [0.418e-3, 0.483e-3, 0.460e-3, 1.251e-3, 1.211e-3, 1.015e-3],
    [0.342e-3, 0.510e-3, 0.557e-3, 1.411e-3, 1.156e-3, 0.711e-3],
    [0.318e-3, 0.379e-3, 0.473e-3, 1.219e-3, 1.023e-3, 0.905e-3],
];
/// Table 5.5: variation of each identified value over re-identifications, in percent as printed,
/// by name ("platform.m", …, "wrench1.Iz", "link1.Iy", "fc1", "fv1", "lp", "li", "ld").
pub const TABLE_5_5_PERCENT: [(&str, f64); 49] = [
    ("platform.m", 0.48),
    ("platform.Ix", 5.0),
    ("platform.Iy", 24.9),
    ("platform.Iz", 8.6),
    ("wrench1.m", 0.56),
    ("wrench1.Iz", 6.6),
    ("wrench2.m", 1.5),
    ("wrench2.Iz", 1.4),
    ("wrench3.m", 3.4),
    ("wrench3.Iz", 5.0),
    ("wrench4.m", 3.7),
    ("wrench4.Iz", 3.8),
    ("wrench5.m", 6.6),
    ("wrench5.Iz", 6.6),
    ("wrench6.m", 0.79),
    ("wrench6.Iz", 1.7),
    ("link1.m", 4.1),
    ("link1.Ix", 0.04),
    ("link1.Iy", 0.11),
    ("link2.m", 5.2),
    ("link2.Ix", 0.05),
    ("link2.Iy", 0.12),
    ("link3.m", 20.9),
    ("link3.Ix", 0.09),
    ("link3.Iy", 0.17),
    ("link4.m", 19.1),
    ("link4.Ix", 0.16),
    ("link4.Iy", 0.06),
    ("link5.m", 10.1),
    ("link5.Ix", 0.15),
    ("link5.Iy", 0.01),
    ("link6.m", 12.9),
    ("link6.Ix", 0.17),
    ("link6.Iy", 0.02),
    ("fc1", 15.9),
    ("fv1", 11.7),
    ("fc2", 21.4),
    ("fv2", 13.9),
    ("fc3", 9.0),
    ("fv3", 16.4),
    ("fc4", 17.8),
    ("fv4", 15.2),
    ("fc5", 15.1),
    ("fv5", 21.8),
    ("fc6", 23.4),
    ("fv6", 13.0),
    ("lp", 2.82),
    ("li", 0.44),
    ("ld", 3.7),
];

// ---- §5.6.2: the outer visual-servoing PID (eq. 5.4) ----

/// §5.6.2: proportional gain k_p of the outer visual PID (eq. 5.4), every axis (dimensionless).
pub const VISUAL_PID_KP: f64 = 0.3;
/// §5.6.2: integral gain k_i of the outer visual PID (1/s), every axis.
pub const VISUAL_PID_KI: f64 = 2.4;
/// §5.6.2: derivative gain k_d of the outer visual PID (s), every axis.
pub const VISUAL_PID_KD: f64 = 0.001;

// ---- §6.5: the tracking experiments ----

/// §6.5.1: control period = optical CMM sampling period (s), 30 Hz.
pub const CONTROL_PERIOD: f64 = 0.033;
/// §6.5.1: angular frequency of Experiment 1's sinusoids (rad/s).
pub const EXPERIMENT1_OMEGA: f64 = 0.5;
/// §6.5.2: fundamental frequency ω0 of Experiment 2's Fourier series (rad/s).
pub const EXPERIMENT2_OMEGA0: f64 = 0.15;
/// §6.5.2: number of harmonics n of Experiment 2's Fourier series.
pub const EXPERIMENT2_HARMONICS: usize = 5;

/// One of Tables 6.1/6.2, rows KJSC, KCSC, DSMC (see [`TRACKING_SCHEMES`]), columns
/// [x, y, z, α, β, γ] in the printed units: mm for x, y, z and 10⁻³ rad for α, β, γ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackingTable {
    /// Root-mean-square tracking error per scheme (mm, 10⁻³ rad).
    pub rmse: [[f64; 6]; 3],
    /// Mean absolute tracking error per scheme (mm, 10⁻³ rad).
    pub mae: [[f64; 6]; 3],
}

/// Row names of [`TrackingTable`].
pub const TRACKING_SCHEMES: [&str; 3] = ["KJSC", "KCSC", "DSMC"];

/// Table 6.1: Experiment 1 (sinusoids), RMSE and MAE of KJSC, KCSC, DSMC (mm, 10⁻³ rad).
pub const TABLE_6_1: TrackingTable = TrackingTable {
    rmse: [
        [2.8, 3.4, 2.1, 14.8, 14.0, 14.6],
        [1.1, 1.5, 1.2, 3.2, 3.8, 3.5],
        [0.44, 1.4, 0.63, 1.1, 2.1, 1.6],
    ],
    mae: [
        [2.5, 2.7, 1.8, 12.5, 12.4, 14.2],
        [0.97, 1.1, 1.0, 2.8, 3.3, 3.1],
        [0.36, 0.61, 0.46, 0.92, 1.7, 1.3],
    ],
};

/// Table 6.2: Experiment 2 (Fourier series), RMSE and MAE of KJSC, KCSC, DSMC (mm, 10⁻³ rad).
pub const TABLE_6_2: TrackingTable = TrackingTable {
    rmse: [
        [3.2, 3.2, 3.1, 13.9, 9.4, 14.5],
        [1.2, 1.5, 1.9, 4.5, 3.6, 2.9],
        [0.60, 1.1, 1.3, 3.4, 2.8, 2.5],
    ],
    mae: [
        [2.9, 2.7, 2.6, 11.3, 7.4, 13.7],
        [0.96, 1.0, 1.3, 3.0, 2.4, 1.8],
        [0.33, 0.54, 0.57, 1.4, 1.6, 1.0],
    ],
};
