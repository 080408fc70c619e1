//! Kalman filter on the camera pose (§6.4.1, eq. 6.15–6.18): a third-order integrator per pose axis.
//!
//! Each axis i has the state S_i = [χ_i, χ̇_i, χ̈_i] with Ṡ = A S + W, y = C S + e_n (eq. 6.16),
//! A = [[0,1,0],[0,0,1],[0,0,0]], C = [1,0,0]. The thesis writes the continuous-time filter (eq. 6.17–6.18);
//! the camera delivers samples, so rss6 runs the *exact discrete-time equivalent* at whatever interval
//! elapsed since the previous step:
//!
//! * Φ(Δt) = e^{AΔt} = [[1, Δt, Δt²/2], [0, 1, Δt], [0, 0, 1]],
//! * Q_d(Δt) = ∫₀^Δt Φ(s) Q_c Φ(s)ᵀ ds for Q_c = diag(q_χ, q_χ̇, q_χ̈) (closed form in [`discrete_noise`]),
//! * R_d = σ² per frame (the camera's per-sample variance, Table 4.1).
//!
//! A missing frame is a predict-only step. With `steady_state = true` the gain is the converged gain of
//! the Riccati recursion at `nominal_dt` (computed once at construction with a bounded iteration count)
//! and the covariance is not propagated — cheaper and deterministic; the variable-Δt prediction is kept.

use crate::error::{all_finite, check_dt, CtrlError, Result};
use nalgebra::{Matrix3, Vector3};
use rss6_core::{thesis, Vec6};

/// Iteration bound of the steady-state Riccati recursion (converges in a few hundred at 30 Hz).
pub const RICCATI_MAX_ITERATIONS: u32 = 20_000;

/// Tuning of the pose Kalman filter. Indices follow χ = [x, y, z, α, β, γ].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KalmanConfig {
    /// Spectral density of the white jerk driving χ̈ (Q_c(2,2)); m²/s⁵ for x, y, z and rad²/s⁵ for α, β, γ.
    pub q_jerk: Vec6,
    /// Spectral density of white noise on the velocity equation (Q_c(1,1)), m²/s³ or rad²/s³; 0 for the
    /// pure third-order integrator.
    pub q_vel: Vec6,
    /// Variance of one camera sample R (m² or rad²); Table 4.1: (0.0096 mm)², (0.0261°)².
    pub r: Vec6,
    /// Initial standard deviations of [χ, χ̇, χ̈] (same for every axis; m or rad, per s, per s²).
    pub p0_std: [f64; 3],
    /// Camera period used for the steady-state gain (s), 0.033 in the thesis.
    pub nominal_dt: f64,
    /// Use the precomputed steady-state gain instead of propagating the covariance.
    pub steady_state: bool,
}

impl KalmanConfig {
    /// rss6's servo tuning: the camera noise of Table 4.1 ([`rss6_core::thesis`]) and the control period
    /// of §6.5, with *our* jerk densities (1e-2 m²/s⁵, 3 rad²/s⁵; the thesis tunes Q_c but does not print
    /// it): little lag, so the DSMC's 30 Hz velocity loop stays stable; noise reduction is modest (see
    /// docs/control.md). Lower `q_jerk` smooths more and lags more.
    pub fn tuned() -> Self {
        let sp = thesis::POSE_POSITION_NOISE;
        let sa = thesis::POSE_ANGLE_NOISE;
        KalmanConfig {
            q_jerk: Vec6::new(1e-2, 1e-2, 1e-2, 3.0, 3.0, 3.0),
            q_vel: Vec6::zeros(),
            r: Vec6::new(sp * sp, sp * sp, sp * sp, sa * sa, sa * sa, sa * sa),
            p0_std: [1e-3, 1e-2, 1e-1],
            nominal_dt: thesis::CONTROL_PERIOD,
            steady_state: false,
        }
    }

    /// Smoother tuning for a filter that is told the commanded acceleration ([`PoseKalman::set_input`],
    /// `ServoConfig::kalman_model_input`): q_jerk = 1e-3 m²/s⁵ for x, y, z (10× below [`Self::tuned`]) and
    /// 1 rad²/s⁵ for α, β, γ (3× below). With the DSMC's model acceleration as input the filter lags only the
    /// model residual, so this tuning keeps the loop stable where the same q without the input does not
    /// (docs/control.md, "Kalman filter in the loop").
    pub fn model_aided() -> Self {
        KalmanConfig {
            q_jerk: Vec6::new(1e-3, 1e-3, 1e-3, 1.0, 1.0, 1.0),
            ..Self::tuned()
        }
    }

    /// Tuning of [`crate::ServoConfig::low_noise`] (model input, hold compensation and potentiometer rate):
    /// q_jerk = 1e-4 m²/s⁵ for x, y, z (100× below [`Self::tuned`]) and 0.1 rad²/s⁵ for α, β, γ (30×
    /// below). Without those servo options this tuning lags too much for the DSMC loop.
    pub fn low_noise() -> Self {
        KalmanConfig {
            q_jerk: Vec6::new(1e-4, 1e-4, 1e-4, 0.1, 0.1, 0.1),
            ..Self::tuned()
        }
    }

    /// Smoothing tuning for monitoring/logging, not for closing a loop: q_jerk 1e-5 × [`Self::tuned`]
    /// (1e-7 m²/s⁵, 3e-5 rad²/s⁵). On the Experiment 1 and 2 references with Table 4.1 noise it tracks χ̇
    /// on all six axes (tests/kalman.rs); inside the DSMC loop it destabilises the rotational loop.
    pub fn smoothing() -> Self {
        let t = Self::tuned();
        KalmanConfig {
            q_jerk: t.q_jerk * 1e-5,
            ..t
        }
    }

    /// Checks finiteness and signs.
    pub fn validate(&self) -> Result<()> {
        if !(all_finite(self.q_jerk.as_slice())
            && all_finite(self.q_vel.as_slice())
            && all_finite(self.r.as_slice())
            && all_finite(&self.p0_std))
        {
            return Err(CtrlError::NonFinite);
        }
        if self
            .q_jerk
            .iter()
            .chain(self.q_vel.iter())
            .any(|&q| q < 0.0)
        {
            return Err(CtrlError::InvalidParameter(
                "Kalman process noise must be >= 0",
            ));
        }
        if self.r.iter().any(|&r| r <= 0.0) {
            return Err(CtrlError::InvalidParameter(
                "Kalman measurement variance must be > 0",
            ));
        }
        check_dt(self.nominal_dt)
    }
}

/// Filter output: χ_m, χ̇_m, χ̈_m (eq. 6.19–6.20 use the first two).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseEstimate {
    /// Filtered pose χ_m (m, rad).
    pub pose: Vec6,
    /// Pose rate χ̇_m (m/s, rad/s).
    pub pose_dot: Vec6,
    /// Pose acceleration χ̈_m (m/s², rad/s²).
    pub pose_ddot: Vec6,
}

/// Response Γ(Δt) = ∫₀^Δt e^{As} B ds = [Δt²/2, Δt, 0] of the state to a known acceleration input held
/// constant over Δt (B = [0, 1, 0]ᵀ: the input adds to χ̈, the third state is the unexplained residual).
pub fn input_response(dt: f64) -> Vector3<f64> {
    Vector3::new(0.5 * dt * dt, dt, 0.0)
}

/// State transition Φ(Δt) = e^{AΔt} of the third-order integrator.
pub fn transition(dt: f64) -> Matrix3<f64> {
    Matrix3::new(1.0, dt, 0.5 * dt * dt, 0.0, 1.0, dt, 0.0, 0.0, 1.0)
}

/// Exact discrete process noise Q_d(Δt) = ∫₀^Δt Φ(s) diag(0, q_vel, q_jerk) Φ(s)ᵀ ds.
pub fn discrete_noise(dt: f64, q_vel: f64, q_jerk: f64) -> Matrix3<f64> {
    let t2 = dt * dt;
    let t3 = t2 * dt;
    let t4 = t3 * dt;
    let t5 = t4 * dt;
    let jerk = Matrix3::new(
        t5 / 20.0,
        t4 / 8.0,
        t3 / 6.0,
        t4 / 8.0,
        t3 / 3.0,
        t2 / 2.0,
        t3 / 6.0,
        t2 / 2.0,
        dt,
    );
    let vel = Matrix3::new(t3 / 3.0, t2 / 2.0, 0.0, t2 / 2.0, dt, 0.0, 0.0, 0.0, 0.0);
    jerk * q_jerk + vel * q_vel
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    s: Vector3<f64>,
    p: Matrix3<f64>,
    k_ss: Vector3<f64>,
    q_vel: f64,
    q_jerk: f64,
    r: f64,
    /// Known acceleration input u (held constant over the prediction interval).
    u: f64,
}

impl Axis {
    fn predict(&mut self, dt: f64, covariance: bool) {
        let phi = transition(dt);
        self.s = phi * self.s + input_response(dt) * self.u;
        if covariance {
            self.p = phi * self.p * phi.transpose() + discrete_noise(dt, self.q_vel, self.q_jerk);
        }
    }

    fn gain(&self) -> Vector3<f64> {
        let s = self.p[(0, 0)] + self.r;
        self.p.column(0) / s
    }

    /// Measurement update of the rate and acceleration states (H = [0, 1, 0], pose gain 0) with variance
    /// `r_v`; the Joseph form keeps P exact for this suboptimal gain.
    fn update_rate(&mut self, z: f64, r_v: f64) {
        let s = self.p[(1, 1)] + r_v;
        let mut k: Vector3<f64> = self.p.column(1) / s;
        // The pose is left to the camera (see `PoseKalman::update_rate`).
        k[0] = 0.0;
        let innovation = z - self.s[1];
        self.s += k * innovation;
        let mut ikh = Matrix3::<f64>::identity();
        for i in 0..3 {
            ikh[(i, 1)] -= k[i];
        }
        self.p = ikh * self.p * ikh.transpose() + k * k.transpose() * r_v;
    }

    /// Measurement update; Joseph form keeps P symmetric positive semidefinite.
    fn update(&mut self, z: f64, steady: bool) {
        let k = if steady { self.k_ss } else { self.gain() };
        let innovation = z - self.s[0];
        self.s += k * innovation;
        if !steady {
            let mut ikh = Matrix3::<f64>::identity();
            for i in 0..3 {
                ikh[(i, 0)] -= k[i];
            }
            self.p = ikh * self.p * ikh.transpose() + k * k.transpose() * self.r;
        }
    }
}

/// Six independent third-order Kalman filters, one per pose axis. Fixed size, no heap; `Clone` (not
/// `Copy`, so `let f = filter;` cannot silently fork the state).
#[derive(Debug, Clone, PartialEq)]
pub struct PoseKalman {
    config: KalmanConfig,
    axes: [Axis; 6],
    p0: Matrix3<f64>,
}

impl PoseKalman {
    /// A filter started at `initial_pose` with zero velocity and acceleration (eq. 6.17: Ŝ(0) = E[S(0)]).
    /// Computes the steady-state gains (bounded Riccati iteration) when the config asks for them.
    pub fn new(config: KalmanConfig, initial_pose: &Vec6) -> Result<Self> {
        config.validate()?;
        if !all_finite(initial_pose.as_slice()) {
            return Err(CtrlError::NonFinite);
        }
        let [a, b, c] = config.p0_std;
        let p0 = Matrix3::from_diagonal(&Vector3::new(a * a, b * b, c * c));
        let mut axes = [Axis {
            s: Vector3::zeros(),
            p: p0,
            k_ss: Vector3::zeros(),
            q_vel: 0.0,
            q_jerk: 0.0,
            r: 1.0,
            u: 0.0,
        }; 6];
        for (i, ax) in axes.iter_mut().enumerate() {
            ax.q_vel = config.q_vel[i];
            ax.q_jerk = config.q_jerk[i];
            ax.r = config.r[i];
            ax.k_ss = steady_state_gain(ax, config.nominal_dt);
        }
        let mut f = PoseKalman { config, axes, p0 };
        f.reset(initial_pose);
        Ok(f)
    }

    /// Restarts at `pose` with zero rates and the initial covariance.
    pub fn reset(&mut self, pose: &Vec6) {
        for (i, ax) in self.axes.iter_mut().enumerate() {
            ax.s = Vector3::new(pose[i], 0.0, 0.0);
            ax.p = self.p0;
            ax.u = 0.0;
        }
    }

    /// The configuration.
    pub fn config(&self) -> &KalmanConfig {
        &self.config
    }

    /// The steady-state gains K = [k_χ, k_χ̇, k_χ̈] per axis at `nominal_dt`.
    pub fn steady_state_gains(&self) -> [[f64; 3]; 6] {
        let mut out = [[0.0; 3]; 6];
        for (o, ax) in out.iter_mut().zip(self.axes.iter()) {
            *o = [ax.k_ss[0], ax.k_ss[1], ax.k_ss[2]];
        }
        out
    }

    /// Posterior variance of the pose estimate per axis (m², rad²); meaningless with `steady_state`.
    pub fn pose_variance(&self) -> Vec6 {
        Vec6::from_fn(|i, _| self.axes.get(i).map_or(f64::NAN, |a| a.p[(0, 0)]))
    }

    /// The current estimate without stepping (χ̈_m = known input + estimated residual).
    pub fn estimate(&self) -> PoseEstimate {
        let get = |k: usize| Vec6::from_fn(|i, _| self.axes.get(i).map_or(f64::NAN, |a| a.s[k]));
        PoseEstimate {
            pose: get(0),
            pose_dot: get(1),
            pose_ddot: get(2) + self.input(),
        }
    }

    /// The known acceleration input u (m/s², rad/s²) currently applied in the prediction.
    pub fn input(&self) -> Vec6 {
        Vec6::from_fn(|i, _| self.axes.get(i).map_or(f64::NAN, |a| a.u))
    }

    /// Sets the known acceleration input u (m/s², rad/s²) used by the following predictions until it is set
    /// again: the model becomes χ̈ = u + r with the third state r the unexplained residual (still driven by
    /// white jerk). With u = 0 (the default, and after [`PoseKalman::reset`]) this is the thesis's filter.
    /// A controller that knows the acceleration it commands (the DSMC, [`crate::DsmcOutput::accel_model`])
    /// passes it here; the filter then lags only the residual, not the commanded motion, so a smoother tuning
    /// does not add phase lag to the control loop (separation principle).
    ///
    /// Errors: [`CtrlError::NonFinite`] (input left unchanged).
    pub fn set_input(&mut self, accel: &Vec6) -> Result<()> {
        if !all_finite(accel.as_slice()) {
            return Err(CtrlError::NonFinite);
        }
        for (i, ax) in self.axes.iter_mut().enumerate() {
            ax.u = accel[i];
        }
        Ok(())
    }

    /// The estimate extrapolated `ahead` seconds (≥ 0) with Φ(ahead), without changing the filter: used to
    /// bring a latency-delayed estimate to the present.
    pub fn predicted(&self, ahead: f64) -> PoseEstimate {
        let phi = transition(ahead.max(0.0));
        let s = |i: usize| {
            self.axes.get(i).map_or(Vector3::repeat(f64::NAN), |a| {
                phi * a.s + input_response(ahead.max(0.0)) * a.u
            })
        };
        let mut out = self.estimate();
        let u = self.input();
        for i in 0..6 {
            let x = s(i);
            out.pose[i] = x[0];
            out.pose_dot[i] = x[1];
            out.pose_ddot[i] = x[2] + u[i];
        }
        out
    }

    /// One step: predict over `dt` (s, time since the previous step), then update with `measurement`
    /// (the camera pose χ̄_E, m and rad) if a frame arrived; `None` = predict only (missing frame).
    ///
    /// Errors (state left untouched): [`CtrlError::InvalidTimeStep`], [`CtrlError::NonFinite`] for a
    /// NaN/∞ measurement or if the step would overflow the state or covariance (e.g. a huge `dt`).
    pub fn step(&mut self, dt: f64, measurement: Option<&Vec6>) -> Result<PoseEstimate> {
        check_dt(dt)?;
        if let Some(z) = measurement {
            if !all_finite(z.as_slice()) {
                return Err(CtrlError::NonFinite);
            }
        }
        let steady = self.config.steady_state;
        let mut axes = self.axes;
        for (i, ax) in axes.iter_mut().enumerate() {
            ax.predict(dt, !steady);
            if let Some(z) = measurement {
                ax.update(z[i], steady);
            }
            if !(all_finite(ax.s.as_slice()) && all_finite(ax.p.as_slice())) {
                return Err(CtrlError::NonFinite);
            }
        }
        self.axes = axes;
        Ok(self.estimate())
    }
}

impl PoseKalman {
    /// A second, independent measurement of the pose *rate* χ̇ (m/s, rad/s) with per-axis variances
    /// `variance` ((m/s)², (rad/s)²), applied after [`PoseKalman::step`] at the same instant (scalar update
    /// with H = [0, 1, 0] per axis). It corrects χ̇ and χ̈ only: the pose state's gain is set to zero
    /// (Joseph-form covariance, exact for that gain), because a rate with a scale error (an uncalibrated
    /// potentiometer) would otherwise walk the pose away from the camera. The servo uses it for the rate
    /// the potentiometers measured over the last frame ([`crate::ServoConfig::potentiometer_rate`]).
    ///
    /// Errors (state untouched): [`CtrlError::NonFinite`], [`CtrlError::InvalidParameter`] for a variance
    /// ≤ 0 or with `steady_state` (the update needs the propagated covariance).
    pub fn update_rate(&mut self, rate: &Vec6, variance: &Vec6) -> Result<PoseEstimate> {
        if self.config.steady_state {
            return Err(CtrlError::InvalidParameter(
                "rate measurements need the propagated covariance (steady_state = false)",
            ));
        }
        if !(all_finite(rate.as_slice()) && all_finite(variance.as_slice())) {
            return Err(CtrlError::NonFinite);
        }
        if variance.iter().any(|&v| v <= 0.0) {
            return Err(CtrlError::InvalidParameter("rate variance must be > 0"));
        }
        let mut axes = self.axes;
        for (i, ax) in axes.iter_mut().enumerate() {
            ax.update_rate(rate[i], variance[i]);
            if !(all_finite(ax.s.as_slice()) && all_finite(ax.p.as_slice())) {
                return Err(CtrlError::NonFinite);
            }
        }
        self.axes = axes;
        Ok(self.estimate())
    }
}

/// Converged Kalman gain of one axis at sample time `dt` (bounded iteration; returns the last iterate).
fn steady_state_gain(axis: &Axis, dt: f64) -> Vector3<f64> {
    let mut ax = *axis;
    let mut k = Vector3::zeros();
    for _ in 0..RICCATI_MAX_ITERATIONS {
        ax.predict(dt, true);
        let k_new = ax.gain();
        ax.update(0.0, false);
        let done = (k_new - k).amax() <= 1e-12 * k_new.amax().max(1e-300);
        k = k_new;
        if done {
            break;
        }
    }
    k
}
