//! Dynamic sliding-mode controller DSMC (§6.4.2, eq. 6.19–6.28).
//!
//! e = χ_d − χ_m, ė = χ̇_d − χ̇_m (eq. 6.19–6.20), F = ė + λe (eq. 6.21),
//! χ̇_r = χ̇_d + λe, χ̈_r = χ̈_d + λė (eq. 6.24),
//! τ_m = M̃0(χ_m) χ̈_r + C̃0(χ_m, χ̇_m) χ̇_r + G̃0(χ_m) + τ̃_f0 (eq. 6.26),
//! J_sᵀ J_adᵀ τ_a = τ_m + K_p F + K_i ∫F dt + K_r sat(F/ε) (eq. 6.25, 6.27),
//!
//! with M̃0, C̃0, G̃0, τ̃_f0 from rss6-core on the controller's model (nominal or identified parameters) and
//! τ_a solved from J_θᵀ τ_a = u (J_θ = J_ad J_s, LU, no inverse formed).
//!
//! **Boundary layer.** Eq. 6.28 defines sat(F_i) = F_i for |F_i| ≤ ε and sgn(F_i) otherwise, which jumps
//! from ±ε to ±1 at |F_i| = ε (and is not even dimensionally uniform). rss6 uses the continuous boundary
//! layer sat(F_i/ε) = clamp(F_i/ε, −1, 1): identical to sgn outside the layer, the linear high-gain
//! K_r/ε inside, no jump. The Lyapunov argument of eq. 6.35–6.36 only uses the outside-the-layer branch,
//! so Theorem 1's ultimate bound |F_i| ≤ ε is unchanged.

use crate::error::{all_finite, CtrlError, FaultLatch, FaultReason, Result};
use crate::kalman::PoseEstimate;
use crate::trajectory::Reference;
use rss6_core::{
    dynamics_terms, CoreError, DynamicParams, KinematicParams, Mat6, SingularKind, Vec6,
};

/// DSMC gains, diagonal per pose axis (x, y, z in SI translational units, α, β, γ in rotational ones).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DsmcGains {
    /// λ of the sliding surface (1/s), eq. 6.21.
    pub lambda: Vec6,
    /// K_p (N·s/m for x, y, z; N·m·s/rad for α, β, γ), eq. 6.25.
    pub kp: Vec6,
    /// K_i (N/m, N·m/rad), eq. 6.25.
    pub ki: Vec6,
    /// K_r (N, N·m), eq. 6.27.
    pub kr: Vec6,
    /// Boundary-layer half-width ε (m/s, rad/s), eq. 6.28.
    pub epsilon: Vec6,
    /// Anti-windup bound on |∫F dt| (m, rad).
    pub integral_limit: Vec6,
}

impl DsmcGains {
    /// Gains tuned on the analytic model of the nominal robot at a 30 Hz camera rate (docs/control.md).
    pub fn tuned() -> Self {
        DsmcGains {
            lambda: Vec6::repeat(6.0),
            kp: Vec6::new(150.0, 150.0, 150.0, 1.5, 1.5, 1.5),
            ki: Vec6::new(750.0, 750.0, 750.0, 7.5, 7.5, 7.5),
            kr: Vec6::new(2.0, 2.0, 2.0, 0.02, 0.02, 0.02),
            epsilon: Vec6::new(2e-2, 2e-2, 2e-2, 2e-2, 2e-2, 2e-2),
            integral_limit: Vec6::new(0.5, 0.5, 0.5, 5.0, 5.0, 5.0),
        }
    }

    /// Gains of the low-noise servo ([`crate::ServoConfig::low_noise`]): [`Self::tuned`] with a stiffer
    /// orientation loop, λ = 9 /s, K_p = 3 N·m·s/rad, K_i = 15 N·m/rad for α, β, γ (translation unchanged).
    /// With the hold compensation the orientation loop no longer fights the held-torque instability, and
    /// the stiffer loop halves the orientation RMSE (docs/control.md).
    pub fn low_noise() -> Self {
        let t = Self::tuned();
        DsmcGains {
            lambda: Vec6::new(6.0, 6.0, 6.0, 9.0, 9.0, 9.0),
            kp: Vec6::new(150.0, 150.0, 150.0, 3.0, 3.0, 3.0),
            ki: Vec6::new(750.0, 750.0, 750.0, 15.0, 15.0, 15.0),
            ..t
        }
    }

    /// Checks finiteness, λ, K ≥ 0 and ε > 0.
    pub fn validate(&self) -> Result<()> {
        let all = [
            self.lambda,
            self.kp,
            self.ki,
            self.kr,
            self.epsilon,
            self.integral_limit,
        ];
        if !all.iter().all(|v| all_finite(v.as_slice())) {
            return Err(CtrlError::NonFinite);
        }
        if all.iter().any(|v| v.iter().any(|&x| x < 0.0)) {
            return Err(CtrlError::InvalidParameter("DSMC gains must be >= 0"));
        }
        if self.epsilon.iter().any(|&x| x <= 0.0) {
            return Err(CtrlError::InvalidParameter(
                "DSMC boundary layer epsilon must be > 0",
            ));
        }
        Ok(())
    }
}

/// Continuous boundary-layer saturation sat(F/ε) = clamp(F/ε, −1, 1) (replaces eq. 6.28, see module docs).
/// For ε ≤ 0 it is the limit ε → 0⁺, sgn(F) with sgn(0) = 0, so it never returns NaN for finite input.
///
/// ```
/// assert_eq!(rss6_ctrl::sat(0.01, 0.02), 0.5); // inside the layer: linear
/// assert_eq!(rss6_ctrl::sat(-3.0, 0.02), -1.0); // outside: sgn
/// assert_eq!(rss6_ctrl::sat(2e-9, 0.0), 1.0); // no layer: sgn
/// assert_eq!(rss6_ctrl::sat(0.0, 0.0), 0.0);
/// ```
pub fn sat(f: f64, epsilon: f64) -> f64 {
    if epsilon > 0.0 {
        // F/ε is ±∞ at worst for finite F (never NaN), and clamp's bounds are constants.
        (f / epsilon).clamp(-1.0, 1.0)
    } else if f > 0.0 {
        1.0
    } else if f < 0.0 {
        -1.0
    } else {
        f
    }
}

/// One DSMC step's result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DsmcOutput {
    /// Actuator torques τ_a (N·m), eq. 6.25.
    pub tau_a: Vec6,
    /// Sliding variable F = ė + λe (m/s, rad/s), eq. 6.21.
    pub sliding: Vec6,
    /// Generalised force u = J_sᵀ J_adᵀ τ_a in χ coordinates (N, N·m).
    pub generalized: Vec6,
    /// The model part τ_m (eq. 6.26).
    pub tau_model: Vec6,
    /// Every |F_i| ≤ ε_i.
    pub in_boundary_layer: bool,
    /// The acceleration the model predicts for this command,
    /// χ̈ = M̃0⁻¹(u − C̃0 χ̇_m − G̃0 − τ̃_f0) (m/s², rad/s²): the known input for
    /// [`crate::PoseKalman::set_input`].
    pub accel_model: Vec6,
}

/// The DSMC of eq. 6.25. Runs at the camera rate on the Kalman estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Dsmc {
    kp_model: KinematicParams,
    dp_model: DynamicParams,
    gains: DsmcGains,
    integral: Vec6,
    last: Option<DsmcOutput>,
    fault: FaultLatch,
}

impl Dsmc {
    /// A DSMC on the model (kinematics `kp_model`, dynamics `dp_model` = M̃0, C̃0, G̃0, τ̃_f0).
    pub fn new(
        kp_model: KinematicParams,
        dp_model: DynamicParams,
        gains: DsmcGains,
    ) -> Result<Self> {
        kp_model.validate()?;
        dp_model.validate()?;
        gains.validate()?;
        Ok(Dsmc {
            kp_model,
            dp_model,
            gains,
            integral: Vec6::zeros(),
            last: None,
            fault: FaultLatch::default(),
        })
    }

    /// Gains.
    pub fn gains(&self) -> &DsmcGains {
        &self.gains
    }

    /// The latched fault, if any.
    pub fn fault(&self) -> Option<FaultReason> {
        self.fault.get()
    }

    /// The last successful output (held while faulted).
    pub fn last_output(&self) -> Option<DsmcOutput> {
        self.last
    }

    /// ∫F dt (m, rad).
    pub fn integral(&self) -> Vec6 {
        self.integral
    }

    /// Clears the integral, the held output and the fault.
    pub fn reset(&mut self) {
        self.integral = Vec6::zeros();
        self.last = None;
        self.fault.clear();
    }

    /// Actuator torques that hold the model at rest at `pose` against gravity, τ_g = J_θ⁻ᵀ G̃0(χ) (N·m).
    ///
    /// Errors: model failures as [`CtrlError::Core`], [`CtrlError::SingularJacobian`] if J_θ cannot be
    /// factorised, [`CtrlError::NonFinite`] if the solution overflows.
    pub fn holding_torque(&self, pose: &Vec6) -> Result<Vec6> {
        let t = dynamics_terms(&self.kp_model, &self.dp_model, pose, &Vec6::zeros())?;
        match t.j_theta.transpose().lu().solve(&t.g) {
            Some(x) if all_finite(x.as_slice()) => Ok(x),
            Some(_) => Err(CtrlError::NonFinite),
            None => Err(CtrlError::SingularJacobian),
        }
    }

    /// Joint-space hold stiffness H = ∂τ_g/∂θ = (∂τ_g/∂χ) J_θ⁻¹ at `pose` (N·m/rad), τ_g from
    /// [`Dsmc::holding_torque`], by central differences (steps 1e-6 m, 1e-5 rad; 12 model evaluations).
    ///
    /// Why: between two camera frames the DSMC's τ_a is held while the platform moves, and on the 6-RSS a
    /// constant actuator torque does not keep the generalized force constant: J_θ(χ)ᵀ τ_a − G̃0(χ) changes
    /// with χ. At home the model's α̈, β̈ grow by ≈ +190 rad/s² per rad of α, β under held gravity torques
    /// (an unstable mode at ≈ 14/s, plus ≈ 560 rad/s² per m of y → α). The servo can cancel this at the
    /// joint rate with τ = τ_a + H (θ − θ_frame) ([`crate::ServoConfig::hold_compensation`]).
    ///
    /// Errors: model failures (IK, …) as [`CtrlError::Core`], [`CtrlError::SingularJacobian`],
    /// [`CtrlError::NonFinite`].
    pub fn hold_stiffness(&self, pose: &Vec6) -> Result<Mat6> {
        let mut d = Mat6::zeros();
        for j in 0..6 {
            let h = if j < 3 { 1e-6 } else { 1e-5 };
            let mut p = *pose;
            p[j] += h;
            let a = self.holding_torque(&p)?;
            p[j] -= 2.0 * h;
            let b = self.holding_torque(&p)?;
            d.set_column(j, &((a - b) / (2.0 * h)));
        }
        let t = dynamics_terms(&self.kp_model, &self.dp_model, pose, &Vec6::zeros())?;
        // H J_θ = D  ⇔  J_θᵀ Hᵀ = Dᵀ.
        match t.j_theta.transpose().lu().solve(&d.transpose()) {
            Some(ht) if all_finite(ht.as_slice()) => Ok(ht.transpose()),
            Some(_) => Err(CtrlError::NonFinite),
            None => Err(CtrlError::SingularJacobian),
        }
    }

    /// One step `dt` (s) after the previous one (the ∫F rectangle-rule step).
    pub fn step(
        &mut self,
        reference: &Reference,
        estimate: &PoseEstimate,
        dt: f64,
    ) -> Result<DsmcOutput> {
        self.fault.admit_estimate(reference, estimate, dt)?;
        let g = &self.gains;
        let e = reference.pose - estimate.pose;
        let e_dot = reference.pose_dot - estimate.pose_dot;
        let f = e_dot + g.lambda.component_mul(&e);
        let chi_r_dot = reference.pose_dot + g.lambda.component_mul(&e);
        let chi_r_ddot = reference.pose_ddot + g.lambda.component_mul(&e_dot);
        let terms = match dynamics_terms(
            &self.kp_model,
            &self.dp_model,
            &estimate.pose,
            &estimate.pose_dot,
        ) {
            Ok(t) => t,
            Err(err) => return Err(self.fault.trip(FaultReason::Model(err))),
        };
        let tau_model = terms.m * chi_r_ddot + terms.c * chi_r_dot + terms.g + terms.f;
        let mut integral = self.integral + f * dt;
        let mut robust = Vec6::zeros();
        let mut inside = true;
        for i in 0..6 {
            // integral_limit ≥ 0 and finite (`DsmcGains::validate`): the clamp cannot panic.
            integral[i] = integral[i].clamp(-g.integral_limit[i], g.integral_limit[i]);
            robust[i] = g.kr[i] * sat(f[i], g.epsilon[i]);
            inside &= f[i].abs() <= g.epsilon[i];
        }
        let u = tau_model + g.kp.component_mul(&f) + g.ki.component_mul(&integral) + robust;
        let tau_a = match terms.j_theta.transpose().lu().solve(&u) {
            Some(t) if all_finite(t.as_slice()) => t,
            Some(_) => return Err(self.fault.trip(FaultReason::NonFiniteCommand)),
            None => return Err(self.fault.trip(FaultReason::SingularJacobian)),
        };
        let m_lu = terms.m.lu();
        let accel_model = match m_lu.solve(&(u - terms.c * estimate.pose_dot - terms.g - terms.f)) {
            Some(a) if all_finite(a.as_slice()) => a,
            Some(_) => return Err(self.fault.trip(FaultReason::NonFiniteCommand)),
            None => {
                let singular = CoreError::Singular(SingularKind::Matrix);
                return Err(self.fault.trip(FaultReason::Model(singular)));
            }
        };
        self.integral = integral;
        let out = DsmcOutput {
            accel_model,
            tau_a,
            sliding: f,
            generalized: u,
            tau_model,
            in_boundary_layer: inside,
        };
        self.last = Some(out);
        Ok(out)
    }
}
