//! The analytic-model "robot" for closed-loop tests: rss6-core forward dynamics + RK4 at 1 kHz, the
//! drive's [`JointPid`] on potentiometer readings (500 Hz, 0.2233 bit noise), a 30 Hz camera with the
//! Table 4.1 noise, and kinematics that may differ from the controllers' nominal model (Table 4.2 sizes).
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
use rss6_core::{
    ik, rk4_step, thesis, CoreError, DynamicParams, KinematicParams, ModelState, Vec6, N_KIN_ERRORS,
};
use rss6_ctrl::servo::{run, TickRecord};
use rss6_ctrl::{
    CartesianPidGains, Dsmc, DsmcGains, JointPid, JointSpaceGains, Kcsc, Kjsc, PidGains, Plant,
    Scheme, Servo, ServoConfig, Trajectory,
};

/// Table 4.1 camera noise (1σ): position (m), angle (rad).
pub const CAMERA_SIGMA: [f64; 2] = [thesis::POSE_POSITION_NOISE, thesis::POSE_ANGLE_NOISE];
/// Table 4.1 potentiometer noise (1σ, bits).
pub const POT_SIGMA: f64 = thesis::KAPPA_NOISE_BITS;

#[derive(Debug, Clone, Copy)]
pub struct Noise {
    pub camera: bool,
    pub potentiometer: bool,
}

pub struct ModelPlant {
    pub kp_true: KinematicParams,
    pub kp_nominal: KinematicParams,
    pub dp: DynamicParams,
    pub pid: JointPid,
    pub state: ModelState,
    pub tick: u64,
    pub dt: f64,
    pub camera_every: u64,
    pub pot_every: u64,
    /// Frames are delivered this many ticks after exposure.
    pub camera_latency_ticks: u64,
    in_flight: std::collections::VecDeque<(u64, Vec6)>,
    noise: Noise,
    kappa: Vec6,
    pending_frame: Option<Vec6>,
    rng: ChaCha8Rng,
}

impl ModelPlant {
    pub fn new(
        kp_true: KinematicParams,
        dp: DynamicParams,
        start: &Vec6,
        noise: Noise,
        seed: u64,
    ) -> Self {
        let mut p = ModelPlant {
            kp_true,
            kp_nominal: KinematicParams::nominal(),
            dp,
            pid: JointPid::new(PidGains::tuned(), 1e-3, 30.0).unwrap(),
            state: ModelState {
                pose: *start,
                pose_dot: Vec6::zeros(),
            },
            tick: 0,
            dt: 1e-3,
            camera_every: 33,
            pot_every: 2,
            camera_latency_ticks: 0,
            in_flight: std::collections::VecDeque::with_capacity(8),
            noise,
            kappa: Vec6::zeros(),
            pending_frame: None,
            rng: ChaCha8Rng::seed_from_u64(seed),
        };
        p.sample_potentiometers();
        p.sample_camera();
        p
    }

    pub fn time(&self) -> f64 {
        self.tick as f64 * self.dt
    }

    pub fn true_theta(&self) -> Vec6 {
        ik(&self.kp_true, &self.state.pose).expect("plant left its workspace")
    }

    fn sample_potentiometers(&mut self) {
        let theta = self.true_theta();
        let mut kappa = self.kp_true.reading_from_theta(&theta);
        if self.noise.potentiometer {
            let n = Normal::new(0.0, POT_SIGMA).unwrap();
            for k in kappa.iter_mut() {
                *k += n.sample(&mut self.rng);
            }
        }
        self.kappa = kappa;
    }

    fn sample_camera(&mut self) {
        let mut z = self.state.pose;
        if self.noise.camera {
            for i in 0..6 {
                let s = CAMERA_SIGMA[i / 3];
                z[i] += Normal::new(0.0, s).unwrap().sample(&mut self.rng);
            }
        }
        self.in_flight
            .push_back((self.tick + self.camera_latency_ticks, z));
        self.deliver();
    }

    fn deliver(&mut self) {
        while let Some(&(due, z)) = self.in_flight.front() {
            if due > self.tick {
                break;
            }
            self.in_flight.pop_front();
            self.pending_frame = Some(z);
        }
    }
}

impl Plant for ModelPlant {
    type Error = CoreError;

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<(), CoreError> {
        // The drive's PID works on the nominal-convention angle of its own potentiometer reading.
        let theta_meas = self.kp_nominal.theta_from_reading(&self.kappa);
        let tau = self.pid.step(theta_cmd, &theta_meas);
        self.state = rk4_step(&self.kp_true, &self.dp, &self.state, &tau, self.dt)?;
        self.tick += 1;
        if self.tick % self.pot_every == 0 {
            self.sample_potentiometers();
        }
        if self.tick % self.camera_every == 0 {
            self.sample_camera();
        }
        self.deliver();
        Ok(())
    }

    fn camera(&mut self) -> Option<Vec6> {
        self.pending_frame.take()
    }

    fn potentiometers(&self) -> Vec6 {
        self.kappa
    }

    fn time(&self) -> f64 {
        ModelPlant::time(self)
    }
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

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Which {
    Dsmc,
    Kcsc,
    Kjsc,
}

pub fn scheme(which: Which, theta0: &Vec6, dsmc: DsmcGains) -> Scheme {
    let kp = KinematicParams::nominal();
    match which {
        Which::Dsmc => Scheme::Dsmc(Dsmc::new(kp, DynamicParams::nominal(), dsmc).unwrap()),
        Which::Kcsc => Scheme::Kcsc(Kcsc::new(kp, CartesianPidGains::thesis(), theta0).unwrap()),
        Which::Kjsc => {
            Scheme::Kjsc(Kjsc::new(kp, JointSpaceGains::from_visual_pid(), theta0).unwrap())
        }
    }
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
    /// Per-tick error trace (t, e = χ_d − χ_true) sampled at camera frames.
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

/// Runs one scheme on the analytic plant along `traj`, starting at rest at home.
pub fn run_scheme(which: Which, traj: &dyn Trajectory, setup: &Setup) -> Stats {
    let start = rss6_core::home_pose();
    let mut plant = ModelPlant::new(
        setup.kp_true,
        DynamicParams::nominal(),
        &start,
        setup.noise,
        setup.seed,
    );
    plant.camera_latency_ticks = setup.latency_ticks;
    let kp = KinematicParams::nominal();
    let kappa0 = plant.potentiometers();
    let theta0 = kp.theta_from_reading(&kappa0);
    let mut servo = Servo::new(
        kp,
        setup.config,
        scheme(which, &theta0, setup.dsmc),
        &start,
        &kappa0,
        0.0,
    )
    .unwrap();
    let lambda = setup.dsmc.lambda;
    let mut st = Stats::default();
    let ticks = (setup.seconds / 1e-3).round() as u32;
    let mut prev = plant.state;
    let mut monitor = setup
        .monitor
        .map(|c| (rss6_ctrl::PoseKalman::new(c, &start).unwrap(), 0.0_f64));
    let summary = run(
        &mut plant,
        &mut servo,
        traj,
        0.0,
        ticks,
        |rec: &TickRecord, p: &ModelPlant| {
            // Error at the start of the tick: reference at t vs the true pose at t. The plant has already
            // stepped, so compare with the reference at the plant's new time instead.
            let t = p.time();
            let r = traj.sample(t);
            let e = r.pose - p.state.pose;
            for i in 0..6 {
                st.sq[i] += e[i] * e[i];
                st.abs[i] += e[i].abs();
            }
            st.pos_sq += e.fixed_rows::<3>(0).norm_squared();
            st.ang_sq += e.fixed_rows::<3>(3).norm_squared();
            st.n += 1;
            if let (Some(z), Some(tick)) = (rec.camera, rec.tick) {
                // The frame and the estimate are for rec.t, when the true state was `prev`.
                if let Some(est) = tick.estimate {
                    let v_true = prev.pose_dot;
                    for i in 0..6 {
                        st.cam_sq[i] += (z[i] - prev.pose[i]).powi(2);
                        st.est_sq[i] += (est.pose[i] - prev.pose[i]).powi(2);
                        st.vel_err_sq[i] += (est.pose_dot[i] - v_true[i]).powi(2);
                        st.vel_sq[i] += v_true[i].powi(2);
                    }
                    st.kf_n += 1;
                    if let Some((mf, last_t)) = monitor.as_mut() {
                        let m = mf.step((rec.t - *last_t).max(1e-6), Some(&z)).unwrap();
                        *last_t = rec.t;
                        if rec.t > MONITOR_FROM {
                            for i in 0..6 {
                                st.mon_cam_sq[i] += (z[i] - prev.pose[i]).powi(2);
                                st.mon_est_sq[i] += (m.pose[i] - prev.pose[i]).powi(2);
                                st.mon_vel_err_sq[i] += (m.pose_dot[i] - v_true[i]).powi(2);
                                st.mon_vel_sq[i] += v_true[i].powi(2);
                                st.mon_servo_est_sq[i] += (est.pose[i] - prev.pose[i]).powi(2);
                                st.mon_servo_vel_err_sq[i] += (est.pose_dot[i] - v_true[i]).powi(2);
                            }
                            st.mon_n += 1;
                        }
                    }
                }
            }
            prev = p.state;
            if rec.tick.map(|x| x.frame).unwrap_or(false) {
                let f_true = (r.pose_dot - p.state.pose_dot) + lambda.component_mul(&e);
                let f_ctrl = rec
                    .tick
                    .and_then(|x| x.dsmc)
                    .map(|d| d.1)
                    .unwrap_or(Vec6::zeros());
                st.sliding.push((t, f_true, f_ctrl));
                st.trace.push((t, e));
            }
        },
    )
    .unwrap();
    st.first_fault = summary.first_fault;
    st
}
