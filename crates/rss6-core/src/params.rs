//! Read-only robot parameters (the "Model" of the Model/Data split): [`KinematicParams`] with the
//! 60-parameter error model of eq. 4.3, and [`DynamicParams`] with the 64-vector Ξ of eq. 5.1.
//!
//! # The nominal geometry
//!
//! The thesis does not print the robot's dimensions, so the nominal geometry is derived from the facts
//! it does state (docs/kinematics.md, "The nominal geometry"):
//!
//! * three motor pairs, pair k centred at azimuth θ0 ∈ {−60°, 180°, 60°}; leg i of a pair sits at
//!   B_i = R_z(θ0_i)·[0.138, ±0.023, 0] m (base radius 0.138 m, half-spacing 0.023 m tangential);
//! * radial cranks of length l_TB = 0.100 m, so at θ = 0 the wrench points along θ0_i
//!   (eq. 3.18: T_i = B_i + l_TB·[cos(θ_i + θ0_i), sin(θ_i + θ0_i), 0]);
//! * platform joints A'_i = 0.196·[cos(θ0_i ± 38°), sin(θ0_i ± 38°), 0] m in the end-effector frame,
//!   with the same sign as the leg's tangential offset;
//! * home pose χ = [0, 0, 0.115, 0, 0, 0] ↔ θ = 0: each link length is *defined* as |A_i − T_i| at
//!   home (≈ 0.1725 m), which makes the home fact exact rather than approximate;
//! * with this choice (w_i × l_i)·ẑ at home is +0.1·0.0977 for the odd legs (1, 3, 5, positive offset)
//!   and −0.1·0.0977 for the even legs: the sign pattern [+, −, +, −, +, −] of diag J_a1;
//! * three-fold symmetry about z holds by construction; the platform radius 0.196 m and a 24 kg
//!   platform are consistent with Table 5.1's I_x = I_y = 0.178, I_z = 0.350 kg·m² (a uniform disc of
//!   radius r has I_z = m r²/2: r ≈ 0.17 m, inside the joint circle).
//!
//! Potentiometers: η = π/4096 rad/bit (a 12-bit reading spanning 180°) so that Table 4.2's
//! σ_η = 5·10⁻⁵ rad/bit is ≈ 6.5 % of nominal (±3σ ≈ ±20 %, as §4.4.3 says), and Δθ = 0 nominal.
//! The tests in `tests/nominal.rs` check every one of these facts.

use crate::error::{check_finite, CoreError, Result};
use crate::thesis;
use crate::types::{Vec3, LEGS};
use core::f64::consts::PI;
use libm::{cos, sin};

/// Number of kinematic error parameters b (eq. 4.3).
pub const N_KIN_ERRORS: usize = 60;
/// Number of dynamic parameters Ξ (eq. 5.1).
pub const N_DYN: usize = 64;

/// Nominal home height of the end-effector frame above the base plane (m).
pub const HOME_Z: f64 = 0.115;
/// Nominal wrench home directions θ0 (rad): [−60, −60, 180, 180, 60, 60]°.
pub const THETA0_DEG: [f64; LEGS] = [-60.0, -60.0, 180.0, 180.0, 60.0, 60.0];
/// Nominal base radius of the motor-pair centres (m).
pub const BASE_RADIUS: f64 = 0.138;
/// Nominal tangential half-spacing of a motor pair (m).
pub const PAIR_HALF_SPACING: f64 = 0.023;
/// Nominal wrench (crank) length l_TB (m).
pub const WRENCH_LENGTH: f64 = 0.100;
/// Nominal platform joint radius (m).
pub const PLATFORM_RADIUS: f64 = 0.196;
/// Nominal azimuth offset of the platform joints from their pair centre (deg).
pub const PLATFORM_HALF_ANGLE_DEG: f64 = 38.0;
/// Nominal potentiometer gain η (rad/bit).
pub const ETA_NOMINAL: f64 = PI / 4096.0;

/// Home pose χ = [0, 0, 0.115, 0, 0, 0].
pub fn home_pose() -> crate::types::Vec6 {
    crate::types::Vec6::new(0.0, 0.0, HOME_Z, 0.0, 0.0, 0.0)
}

/// Tangential side of leg i within its motor pair: +1 for legs 1, 3, 5 and −1 for 2, 4, 6.
pub const fn leg_side(i: usize) -> f64 {
    if i % 2 == 0 {
        1.0
    } else {
        -1.0
    }
}

/// Kinematic parameters of one 6-RSS robot (all in the base frame unless noted; SI units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinematicParams {
    /// B_i: revolute-joint centres in the base frame (m). The wrench circles lie in z = B_i.z.
    pub base_joints: [Vec3; LEGS],
    /// A'_i: platform spherical-joint centres in the end-effector frame ΣE (m).
    pub platform_joints: [Vec3; LEGS],
    /// l_TB,i: wrench (crank) lengths (m).
    pub wrench_lengths: [f64; LEGS],
    /// l_AT,i: link lengths (m).
    pub link_lengths: [f64; LEGS],
    /// θ0_i: wrench home directions (rad), azimuth of T_i − B_i at θ_i = 0 (eq. 3.18).
    pub theta0: [f64; LEGS],
    /// η_i: potentiometer gains (rad/bit), θ = η κ + Δθ (eq. 4.2).
    pub eta: [f64; LEGS],
    /// Δθ_i: potentiometer offsets (rad) (eq. 4.2).
    pub dtheta: [f64; LEGS],
}

impl KinematicParams {
    /// The nominal robot (see the module docs for the derivation).
    pub fn nominal() -> Self {
        let mut base_joints = [Vec3::zeros(); LEGS];
        let mut platform_joints = [Vec3::zeros(); LEGS];
        let mut link_lengths = [0.0; LEGS];
        let mut theta0 = [0.0; LEGS];
        let half = PLATFORM_HALF_ANGLE_DEG.to_radians();
        for i in 0..LEGS {
            let th0 = THETA0_DEG[i].to_radians();
            let s = leg_side(i);
            let (c0, s0) = (cos(th0), sin(th0));
            // R_z(θ0)·[BASE_RADIUS, s·PAIR_HALF_SPACING, 0]
            let b = Vec3::new(
                c0 * BASE_RADIUS - s0 * s * PAIR_HALF_SPACING,
                s0 * BASE_RADIUS + c0 * s * PAIR_HALF_SPACING,
                0.0,
            );
            let a = Vec3::new(
                PLATFORM_RADIUS * cos(th0 + s * half),
                PLATFORM_RADIUS * sin(th0 + s * half),
                0.0,
            );
            let t = b + WRENCH_LENGTH * Vec3::new(c0, s0, 0.0);
            let a_home = a + Vec3::new(0.0, 0.0, HOME_Z);
            base_joints[i] = b;
            platform_joints[i] = a;
            link_lengths[i] = (a_home - t).norm();
            theta0[i] = th0;
        }
        KinematicParams {
            base_joints,
            platform_joints,
            wrench_lengths: [WRENCH_LENGTH; LEGS],
            link_lengths,
            theta0,
            eta: [ETA_NOMINAL; LEGS],
            dtheta: [0.0; LEGS],
        }
    }

    /// The nominal robot with the 60 error parameters `b` added (order of docs/architecture.md / eq. 4.3):
    /// ΔA'_1..6 (x, y, z each), ΔB_1..6, Δl_AT,1..6, Δl_TB,1..6, Δη_1..6, Δθ_1..6.
    pub fn perturbed(b: &[f64; N_KIN_ERRORS]) -> Self {
        Self::nominal().with_errors(b)
    }

    /// These parameters with the error vector `b` added (same order as [`Self::perturbed`]).
    pub fn with_errors(&self, b: &[f64; N_KIN_ERRORS]) -> Self {
        let mut p = *self;
        for i in 0..LEGS {
            for k in 0..3 {
                p.platform_joints[i][k] += b[3 * i + k];
                p.base_joints[i][k] += b[18 + 3 * i + k];
            }
            p.link_lengths[i] += b[36 + i];
            p.wrench_lengths[i] += b[42 + i];
            p.eta[i] += b[48 + i];
            p.dtheta[i] += b[54 + i];
        }
        p
    }

    /// The error vector b with `self == reference.with_errors(&b)`.
    pub fn errors_from(&self, reference: &Self) -> [f64; N_KIN_ERRORS] {
        let mut b = [0.0; N_KIN_ERRORS];
        for i in 0..LEGS {
            for k in 0..3 {
                b[3 * i + k] = self.platform_joints[i][k] - reference.platform_joints[i][k];
                b[18 + 3 * i + k] = self.base_joints[i][k] - reference.base_joints[i][k];
            }
            b[36 + i] = self.link_lengths[i] - reference.link_lengths[i];
            b[42 + i] = self.wrench_lengths[i] - reference.wrench_lengths[i];
            b[48 + i] = self.eta[i] - reference.eta[i];
            b[54 + i] = self.dtheta[i] - reference.dtheta[i];
        }
        b
    }

    /// Checks that every value is finite, lengths and gains are positive.
    pub fn validate(&self) -> Result<()> {
        for i in 0..LEGS {
            check_finite(self.base_joints[i].as_slice())?;
            check_finite(self.platform_joints[i].as_slice())?;
        }
        check_finite(&self.wrench_lengths)?;
        check_finite(&self.link_lengths)?;
        check_finite(&self.theta0)?;
        check_finite(&self.eta)?;
        check_finite(&self.dtheta)?;
        if self.wrench_lengths.iter().any(|&l| l <= 0.0) {
            return Err(CoreError::InvalidParameter("wrench length must be > 0"));
        }
        if self.link_lengths.iter().any(|&l| l <= 0.0) {
            return Err(CoreError::InvalidParameter("link length must be > 0"));
        }
        if self.eta.contains(&0.0) {
            return Err(CoreError::InvalidParameter(
                "potentiometer gain eta must be non-zero",
            ));
        }
        Ok(())
    }

    /// Joint angles from potentiometer readings: θ_i = η_i κ_i + Δθ_i (eq. 4.2). κ in bits.
    pub fn theta_from_reading(&self, kappa: &crate::types::Vec6) -> crate::types::Vec6 {
        crate::types::Vec6::from_fn(|i, _| self.eta[i] * kappa[i] + self.dtheta[i])
    }

    /// Potentiometer readings from joint angles: κ_i = (θ_i − Δθ_i)/η_i (inverse of eq. 4.2).
    pub fn reading_from_theta(&self, theta: &crate::types::Vec6) -> crate::types::Vec6 {
        crate::types::Vec6::from_fn(|i, _| (theta[i] - self.dtheta[i]) / self.eta[i])
    }
}

/// Mass and principal moments of one symmetric rigid body (Assumption 1), about its centre of mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Mass m (kg).
    pub mass: f64,
    /// Principal moments [I_x, I_y, I_z] (kg·m²) in the body frame.
    pub inertia: Vec3,
}

impl Body {
    /// A body from its mass and principal moments.
    pub const fn new(mass: f64, ix: f64, iy: f64, iz: f64) -> Self {
        Body {
            mass,
            inertia: Vec3::new(ix, iy, iz),
        }
    }

    /// A body from `[m, I_x, I_y, I_z]` (kg, kg·m²), the layout of Table 5.1 ([`crate::thesis`]).
    pub const fn from_array(x: &[f64; 4]) -> Self {
        Self::new(x[0], x[1], x[2], x[3])
    }
}

/// Dynamic parameters Ξ (eq. 5.1): platform, wrenches, links, joint friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicParams {
    /// The end-effector platform; its centre of mass is the origin of ΣE, its principal axes ΣE's.
    pub platform: Body,
    /// Wrench i; centre of mass at the midpoint of B_i T_i; I_z is the moment about the revolute axis.
    pub wrenches: [Body; LEGS],
    /// Link i; centre of mass at the midpoint of T_i A_i; I_z is about the link axis.
    pub links: [Body; LEGS],
    /// Coulomb friction f_c,i of revolute joint i (N·m) (eq. 3.48).
    pub coulomb: [f64; LEGS],
    /// Viscous friction f_v,i of revolute joint i (N·m·s/rad) (eq. 3.48).
    pub viscous: [f64; LEGS],
}

impl DynamicParams {
    /// Table 5.1 (manufacturer values), friction zero.
    pub fn nominal() -> Self {
        DynamicParams {
            platform: Body::from_array(&thesis::TABLE_5_1_PLATFORM),
            wrenches: [Body::from_array(&thesis::TABLE_5_1_WRENCH); LEGS],
            links: [Body::from_array(&thesis::TABLE_5_1_LINK); LEGS],
            coulomb: [0.0; LEGS],
            viscous: [0.0; LEGS],
        }
    }

    /// Ξ (64) in the order of docs/architecture.md: [m, Ix, Iy, Iz] for the platform, wrenches 1..6, links 1..6,
    /// then f_c,1..6, f_v,1..6. No validation: identification explores non-physical values too.
    pub fn from_vector(x: &[f64; N_DYN]) -> Self {
        let body = |k: usize| Body::new(x[4 * k], x[4 * k + 1], x[4 * k + 2], x[4 * k + 3]);
        let mut p = Self::nominal();
        p.platform = body(0);
        for i in 0..LEGS {
            p.wrenches[i] = body(1 + i);
            p.links[i] = body(7 + i);
            p.coulomb[i] = x[52 + i];
            p.viscous[i] = x[58 + i];
        }
        p
    }

    /// The 64-vector Ξ; inverse of [`Self::from_vector`].
    pub fn to_vector(&self) -> [f64; N_DYN] {
        let mut x = [0.0; N_DYN];
        let mut put = |k: usize, b: &Body| {
            x[4 * k] = b.mass;
            x[4 * k + 1] = b.inertia[0];
            x[4 * k + 2] = b.inertia[1];
            x[4 * k + 3] = b.inertia[2];
        };
        put(0, &self.platform);
        for i in 0..LEGS {
            put(1 + i, &self.wrenches[i]);
            put(7 + i, &self.links[i]);
        }
        x[52..58].copy_from_slice(&self.coulomb);
        x[58..64].copy_from_slice(&self.viscous);
        x
    }

    /// Checks finiteness, positive masses, non-negative inertias and friction.
    pub fn validate(&self) -> Result<()> {
        check_finite(&self.to_vector())?;
        let bodies = core::iter::once(&self.platform)
            .chain(self.wrenches.iter())
            .chain(self.links.iter());
        for b in bodies {
            if b.mass <= 0.0 {
                return Err(CoreError::InvalidParameter("body mass must be > 0"));
            }
            if b.inertia.iter().any(|&i| i < 0.0) {
                return Err(CoreError::InvalidParameter(
                    "moments of inertia must be >= 0",
                ));
            }
        }
        if self
            .coulomb
            .iter()
            .chain(self.viscous.iter())
            .any(|&f| f < 0.0)
        {
            return Err(CoreError::InvalidParameter(
                "friction coefficients must be >= 0",
            ));
        }
        Ok(())
    }
}
