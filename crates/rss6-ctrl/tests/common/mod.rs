//! Closed-loop tests run on the experiment layer (rss6-exp): the analytic-model twin of rss6-sim (rss6-core
//! forward dynamics + RK4 at 1 kHz, the drive's PID on 500 Hz potentiometers with Table 4.1 noise, a
//! 30 Hz camera with Table 4.1 pose noise), seen through [`rss6_exp::View`] as the real robot is, and
//! driven by [`rss6_exp::servo::track`]. This file only sets experiments up and reduces their records.
#![allow(
    dead_code,
    unreachable_pub,
    missing_docs,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rss6_core::{jacobian_theta, thesis, DynamicParams, KinematicParams, Vec6, N_KIN_ERRORS};
use rss6_ctrl::{DsmcGains, PidGains, Scheme, ServoConfig, Trajectory};
use rss6_exp::servo::{track, Controller, ServoSpec, Tuning};
use rss6_exp::{Convention, Externals, Flow, Observer, Record, View};
use rss6_sim::{CmmConfig, ModelSim, RobotSim, SimConfig};

pub use rss6_exp::servo::Controller as Which;

#[derive(Debug, Clone, Copy)]
pub struct Noise {
    pub camera: bool,
    pub potentiometer: bool,
}

/// The model twin of a robot with kinematics `kp_true`, at rest at `start`, with Table 4.1 noise where
/// `noise` asks for it and a camera latency of `latency_ticks` ms.
pub fn model_sim(
    kp_true: KinematicParams,
    dp: DynamicParams,
    start: &Vec6,
    noise: Noise,
    seed: u64,
    latency_ticks: u64,
) -> ModelSim {
    let mut cfg = SimConfig::new(kp_true, dp, PidGains::tuned());
    cfg.seed = seed;
    cfg.cmm = CmmConfig::table_4_1();
    if !noise.camera {
        cfg.cmm.pose_noise = Some([0.0, 0.0]);
    }
    if !noise.potentiometer {
        cfg.pot_noise = 0.0;
    }
    cfg.cmm.latency = latency_ticks as f64 * cfg.dt;
    // The target at the end-effector origin: Table 4.1's noise is then the noise of χ_E (a target offset
    // turns angle noise into position noise through its lever arm).
    cfg.target_in_effector = Vec6::zeros();
    let mut sim = ModelSim::new(cfg).unwrap();
    sim.reset(start).unwrap();
    sim
}

/// The twin as a controller sees it: frames through its true external parameters, commands in the
/// drive's convention.
pub type Rig = View<ModelSim>;

pub fn rig(
    kp_true: KinematicParams,
    dp: DynamicParams,
    start: &Vec6,
    noise: Noise,
    seed: u64,
) -> Rig {
    let sim = model_sim(kp_true, dp, start, noise, seed, 0);
    let truth = RobotSim::truth(&sim);
    let ext = Externals {
        sensor_in_base: truth.sensor_in_base,
        target_in_effector: truth.target_in_effector,
    };
    View::new(sim, ext, KinematicParams::nominal(), Convention::Drive)
}

/// Table 4.2 error sizes drawn once (seeded).
pub fn table_4_2_errors(seed: u64) -> [f64; N_KIN_ERRORS] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut b = [0.0; N_KIN_ERRORS];
    for (k, x) in b.iter_mut().enumerate() {
        let sd = match k {
            0..=47 => thesis::SIGMA_LENGTH,
            48..=53 => thesis::SIGMA_ETA,
            _ => thesis::SIGMA_DTHETA,
        };
        *x = Normal::new(0.0, sd).unwrap().sample(&mut rng);
    }
    b
}

/// The controller `which` on the nominal model, starting at `theta0`.
pub fn scheme(which: Which, theta0: &Vec6, dsmc: DsmcGains) -> Scheme {
    let kp = KinematicParams::nominal();
    rss6_exp::servo::scheme(which, &kp, &DynamicParams::nominal(), &dsmc, theta0).unwrap()
}

/// Per-run statistics (errors against the TRUE pose).
#[derive(Debug, Clone, Default)]
pub struct Stats {
    pub n: usize,
    pub sq: [f64; 6],
    pub abs: [f64; 6],
    pub pos_sq: f64,
    pub ang_sq: f64,
    /// Kalman: squared camera error, squared estimate error, squared velocity error, squared velocity.
    pub kf_n: usize,
    pub cam_sq: [f64; 6],
    pub est_sq: [f64; 6],
    pub vel_err_sq: [f64; 6],
    pub vel_sq: [f64; 6],
    pub first_fault: Option<(f64, rss6_ctrl::FaultReason)>,
    /// Monitor filter ([`Setup::monitor`]) after [`MONITOR_FROM`] s: frames, squared camera error, squared
    /// estimate error, squared velocity error, squared velocity; the servo's filter over the same frames.
    pub mon_n: usize,
    pub mon_cam_sq: [f64; 6],
    pub mon_est_sq: [f64; 6],
    pub mon_vel_err_sq: [f64; 6],
    pub mon_vel_sq: [f64; 6],
    pub mon_servo_est_sq: [f64; 6],
    pub mon_servo_vel_err_sq: [f64; 6],
    /// Per-frame error trace (t, e = χ_d − χ_true).
    pub trace: Vec<(f64, Vec6)>,
    /// Per-frame true sliding variable F = ė + λe and the DSMC's own F.
    pub sliding: Vec<(f64, Vec6, Vec6)>,
}

impl Stats {
    pub fn rmse(&self, i: usize) -> f64 {
        (self.sq[i] / self.n as f64).sqrt()
    }
    pub fn mae(&self, i: usize) -> f64 {
        self.abs[i] / self.n as f64
    }
    pub fn pos_rmse(&self) -> f64 {
        (self.pos_sq / self.n as f64).sqrt()
    }
    pub fn ang_rmse(&self) -> f64 {
        (self.ang_sq / self.n as f64).sqrt()
    }
}

pub struct Setup {
    pub kp_true: KinematicParams,
    pub noise: Noise,
    pub seconds: f64,
    pub seed: u64,
    pub config: ServoConfig,
    pub dsmc: DsmcGains,
    /// Camera latency of the plant (ticks of 1 ms).
    pub latency_ticks: u64,
    /// A second filter run on the same camera frames beside the loop (not used by the controller).
    pub monitor: Option<rss6_ctrl::KalmanConfig>,
}

/// Start (s) of the monitor statistics (after the initial step has settled).
pub const MONITOR_FROM: f64 = 2.0;

impl Setup {
    pub fn new(kp_true: KinematicParams, noise: Noise, seconds: f64, seed: u64) -> Self {
        Setup {
            kp_true,
            noise,
            seconds,
            seed,
            config: ServoConfig::tuned(),
            dsmc: DsmcGains::tuned(),
            latency_ticks: 0,
            monitor: None,
        }
    }
}

/// Reduces the records of a run to [`Stats`].
struct StatsObserver {
    kp_true: KinematicParams,
    lambda: Vec6,
    monitor: Option<(rss6_ctrl::PoseKalman, f64)>,
    st: Stats,
}

impl Observer for StatsObserver {
    fn record(&mut self, r: &Record) -> Flow {
        let (Some(truth), Some(reference)) = (r.truth, r.reference) else {
            return Flow::Continue;
        };
        let st = &mut self.st;
        let e = reference.pose - truth.pose;
        for i in 0..6 {
            st.sq[i] += e[i] * e[i];
            st.abs[i] += e[i].abs();
        }
        st.pos_sq += e.fixed_rows::<3>(0).norm_squared();
        st.ang_sq += e.fixed_rows::<3>(3).norm_squared();
        st.n += 1;
        let Some(z) = r.camera else {
            return Flow::Continue;
        };
        // The true pose rate: θ̇ = J_θ χ̇ (eq. 5.3) on the true kinematics.
        let j = jacobian_theta(&self.kp_true, &truth.pose).unwrap();
        let v_true = j.lu().solve(&truth.theta_dot).unwrap();
        if let Some(est) = r.estimate {
            for i in 0..6 {
                st.cam_sq[i] += (z[i] - truth.pose[i]).powi(2);
                st.est_sq[i] += (est.pose[i] - truth.pose[i]).powi(2);
                st.vel_err_sq[i] += (est.pose_dot[i] - v_true[i]).powi(2);
                st.vel_sq[i] += v_true[i].powi(2);
            }
            st.kf_n += 1;
            if let Some((mf, last_t)) = self.monitor.as_mut() {
                let m = mf.step((r.t - *last_t).max(1e-6), Some(&z)).unwrap();
                *last_t = r.t;
                if r.t > MONITOR_FROM {
                    for i in 0..6 {
                        st.mon_cam_sq[i] += (z[i] - truth.pose[i]).powi(2);
                        st.mon_est_sq[i] += (m.pose[i] - truth.pose[i]).powi(2);
                        st.mon_vel_err_sq[i] += (m.pose_dot[i] - v_true[i]).powi(2);
                        st.mon_vel_sq[i] += v_true[i].powi(2);
                        st.mon_servo_est_sq[i] += (est.pose[i] - truth.pose[i]).powi(2);
                        st.mon_servo_vel_err_sq[i] += (est.pose_dot[i] - v_true[i]).powi(2);
                    }
                    st.mon_n += 1;
                }
            }
        }
        let f_true = (reference.pose_dot - v_true) + self.lambda.component_mul(&e);
        let f_ctrl = r.dsmc.map(|d| d.1).unwrap_or(Vec6::zeros());
        st.sliding.push((r.t, f_true, f_ctrl));
        st.trace.push((r.t, e));
        Flow::Continue
    }
}

/// Runs one scheme on the model twin along `traj`, starting at rest at home, through the experiment
/// layer's servo runner.
pub fn run_scheme(which: Which, traj: &dyn Trajectory, setup: &Setup) -> Stats {
    let start = rss6_core::home_pose();
    let sim = model_sim(
        setup.kp_true,
        DynamicParams::nominal(),
        &start,
        setup.noise,
        setup.seed,
        setup.latency_ticks,
    );
    let truth = RobotSim::truth(&sim);
    let ext = Externals {
        sensor_in_base: truth.sensor_in_base,
        target_in_effector: truth.target_in_effector,
    };
    let kp = KinematicParams::nominal();
    let mut spec = ServoSpec::new(which, Tuning::Tuned, kp, DynamicParams::nominal(), ext).unwrap();
    spec.config = setup.config;
    spec.dsmc = setup.dsmc;
    spec.duration = setup.seconds;
    let mut obs = StatsObserver {
        kp_true: setup.kp_true,
        lambda: setup.dsmc.lambda,
        monitor: setup
            .monitor
            .map(|c| (rss6_ctrl::PoseKalman::new(c, &start).unwrap(), 0.0_f64)),
        st: Stats::default(),
    };
    let outcome = track(sim, &spec, traj, &mut obs).unwrap();
    obs.st.first_fault = outcome.first_fault;
    obs.st
}

/// Shown so the compiler sees the controller type used (Which is an alias of it).
pub fn controller_name(c: Controller) -> &'static str {
    c.name()
}
