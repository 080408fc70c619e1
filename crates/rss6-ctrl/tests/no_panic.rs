//! No panic for any finite input: every public constructor and step/update function of rss6-ctrl is
//! driven with random finite values (zeros of both signs, negatives, ±1e300, ±f64::MAX, subnormals,
//! arbitrary normals, and plausible values near home so the deep paths run too). A case fails only if
//! a call panics; errors and NaN outputs for absurd input are fine. 10 000 cases per block.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6, N_DYN, N_KIN_ERRORS};
use rss6_ctrl::servo::{run, Plant};
use rss6_ctrl::{
    discrete_noise, input_response, sat, transition, CartesianPidGains, CommandGuard,
    CommandLimits, Dsmc, DsmcGains, Fourier, JointPid, JointSpaceGains, KalmanConfig, Kcsc, Kjsc,
    PidGains, PoseEstimate, PoseKalman, Reference, Scheme, Servo, ServoConfig, Sinusoid,
    TorqueToPosition, Trajectory, VisualPid,
};

const CASES: u32 = 10_000;

fn config() -> ProptestConfig {
    ProptestConfig::with_cases(CASES)
}

/// Any finite f64, biased toward the values that break arithmetic.
fn wild() -> impl Strategy<Value = f64> {
    use proptest::num::f64 as f;
    prop_oneof![
        4 => -2.0..2.0f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(1e300),
        1 => Just(-1e300),
        1 => Just(f64::MAX),
        1 => Just(f64::MIN),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(5e-324),
        1 => Just(-5e-324),
        3 => f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO,
    ]
}

/// A non-negative finite f64 (so validation passes often and the steps run).
fn wild_pos() -> impl Strategy<Value = f64> {
    wild().prop_map(f64::abs)
}

fn wild6() -> impl Strategy<Value = Vec6> {
    proptest::array::uniform6(wild()).prop_map(Vec6::from)
}

fn wild6_pos() -> impl Strategy<Value = Vec6> {
    proptest::array::uniform6(wild_pos()).prop_map(Vec6::from)
}

/// Near home half the time (so IK, Jacobians and dynamics succeed), wild otherwise.
fn pose() -> impl Strategy<Value = Vec6> {
    prop_oneof![
        proptest::array::uniform6(-0.03..0.03f64).prop_map(|d| home_pose() + Vec6::from(d)),
        wild6(),
    ]
}

fn small6() -> impl Strategy<Value = Vec6> {
    prop_oneof![
        proptest::array::uniform6(-0.5..0.5f64).prop_map(Vec6::from),
        wild6()
    ]
}

fn reference() -> impl Strategy<Value = Reference> {
    (pose(), small6(), small6()).prop_map(|(pose, pose_dot, pose_ddot)| Reference {
        pose,
        pose_dot,
        pose_ddot,
    })
}

fn estimate() -> impl Strategy<Value = PoseEstimate> {
    (pose(), small6(), small6()).prop_map(|(pose, pose_dot, pose_ddot)| PoseEstimate {
        pose,
        pose_dot,
        pose_ddot,
    })
}

/// The nominal robot, or one with errors of any size (wild ones fail validation or IK).
fn kinematics() -> impl Strategy<Value = KinematicParams> {
    prop_oneof![
        Just(KinematicParams::nominal()),
        proptest::collection::vec(-1e-3..1e-3f64, N_KIN_ERRORS).prop_map(|b| {
            let mut a = [0.0; N_KIN_ERRORS];
            a.copy_from_slice(&b);
            KinematicParams::perturbed(&a)
        }),
        proptest::collection::vec(wild(), N_KIN_ERRORS).prop_map(|b| {
            let mut a = [0.0; N_KIN_ERRORS];
            a.copy_from_slice(&b);
            KinematicParams::perturbed(&a)
        }),
    ]
}

fn dynamics() -> impl Strategy<Value = DynamicParams> {
    prop_oneof![
        Just(DynamicParams::nominal()),
        proptest::collection::vec(wild_pos(), N_DYN).prop_map(|x| {
            let mut a = [0.0; N_DYN];
            a.copy_from_slice(&x);
            DynamicParams::from_vector(&a)
        }),
    ]
}

fn pid_gains() -> impl Strategy<Value = PidGains> {
    prop_oneof![
        Just(PidGains::tuned()),
        (wild(), wild(), wild()).prop_map(|(lp, li, ld)| PidGains { lp, li, ld }),
        (wild_pos(), wild_pos(), wild_pos()).prop_map(|(lp, li, ld)| PidGains { lp, li, ld }),
    ]
}

fn limits() -> impl Strategy<Value = CommandLimits> {
    prop_oneof![
        Just(CommandLimits::nominal()),
        (wild6(), wild6(), wild()).prop_map(|(min, max, max_rate)| CommandLimits {
            min,
            max,
            max_rate
        }),
    ]
}

fn kalman_config() -> impl Strategy<Value = KalmanConfig> {
    prop_oneof![
        Just(KalmanConfig::tuned()),
        Just(KalmanConfig::low_noise()),
        (
            wild6_pos(),
            wild6_pos(),
            wild6(),
            proptest::array::uniform3(wild()),
            wild(),
            any::<bool>()
        )
            .prop_map(|(q_jerk, q_vel, r, p0_std, nominal_dt, steady_state)| {
                KalmanConfig {
                    q_jerk,
                    q_vel,
                    r,
                    p0_std,
                    nominal_dt,
                    steady_state,
                }
            }),
    ]
}

fn dsmc_gains() -> impl Strategy<Value = DsmcGains> {
    prop_oneof![
        Just(DsmcGains::tuned()),
        Just(DsmcGains::low_noise()),
        (
            wild6(),
            wild6_pos(),
            wild6_pos(),
            wild6_pos(),
            wild6(),
            wild6()
        )
            .prop_map(|(lambda, kp, ki, kr, epsilon, integral_limit)| DsmcGains {
                lambda,
                kp,
                ki,
                kr,
                epsilon,
                integral_limit
            }),
    ]
}

fn cartesian_gains() -> impl Strategy<Value = CartesianPidGains> {
    prop_oneof![
        Just(CartesianPidGains::thesis()),
        (wild6(), wild6(), wild6(), wild6()).prop_map(|(kp, ki, kd, integral_limit)| {
            CartesianPidGains {
                kp,
                ki,
                kd,
                integral_limit,
            }
        }),
    ]
}

fn joint_gains() -> impl Strategy<Value = JointSpaceGains> {
    prop_oneof![
        Just(JointSpaceGains::from_visual_pid()),
        (wild(), wild(), wild(), wild()).prop_map(|(kp, ki, kd, integral_limit)| {
            JointSpaceGains {
                kp,
                ki,
                kd,
                integral_limit,
            }
        }),
    ]
}

/// Positive, plausible time steps half the time, wild ones otherwise.
fn dt() -> impl Strategy<Value = f64> {
    prop_oneof![1e-4..0.1f64, wild()]
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn joint_pid(g in pid_gains(), step in dt(), lim in wild(), t_f in wild(),
                 io in proptest::collection::vec((small6(), small6()), 1..4)) {
        if let Ok(mut pid) = JointPid::new(g, step, lim).and_then(|p| p.with_derivative_filter(t_f)) {
            for (cmd, meas) in &io {
                let _ = pid.step(cmd, meas);
            }
            let _ = (pid.integral(), pid.prev_error(), pid.dt(), pid.torque_limit(), pid.gains());
            let _ = (pid.prev_derivative(), pid.derivative_filter());
            pid.reset();
        }
    }

    #[test]
    fn converter_and_guard(g in pid_gains(), step in dt(), lim in wild(), l in limits(),
                           initial in small6(), mirror in any::<bool>(), t_f in wild(),
                           io in proptest::collection::vec((wild6(), small6(), small6()), 1..4)) {
        let conv = if mirror {
            JointPid::new(g, step, lim)
                .and_then(|p| p.with_derivative_filter(t_f))
                .and_then(|p| TorqueToPosition::mirroring(&p))
        } else {
            TorqueToPosition::new(g, step, lim)
        };
        let guard = CommandGuard::new(l, &initial);
        if let (Ok(mut conv), Ok(mut guard)) = (conv, guard) {
            for (tau, theta, cmd) in &io {
                let _ = conv.error_for_torque(tau);
                let _ = conv.step(tau, theta, &mut guard);
                let _ = conv.observe(cmd, theta);
                let _ = guard.apply(cmd, step);
            }
            guard.reset(&initial);
            conv.reset();
        }
    }

    #[test]
    fn command_guard(l in limits(), initial in wild6(),
                     io in proptest::collection::vec((wild6(), dt()), 1..5)) {
        if let Ok(mut guard) = CommandGuard::new(l, &initial) {
            for (req, step) in &io {
                let _ = guard.apply(req, *step);
                guard.reset(req);
            }
            let _ = guard.last_command();
        }
    }

    #[test]
    fn kalman(c in kalman_config(), start in pose(), ahead in wild(),
              io in proptest::collection::vec(
                  (dt(), proptest::option::of(pose()), small6(), wild6(), small6()), 1..4)) {
        let _ = (transition(ahead), discrete_noise(ahead, c.q_vel[0], c.q_jerk[0]),
                 input_response(ahead));
        if let Ok(mut kf) = PoseKalman::new(c, &start) {
            for (step, z, rate, var, input) in &io {
                let _ = kf.step(*step, z.as_ref());
                let _ = kf.update_rate(rate, var);
                let _ = kf.set_input(input);
                let _ = kf.predicted(ahead);
            }
            let _ = (kf.estimate(), kf.pose_variance(), kf.steady_state_gains(), kf.input());
            kf.reset(&start);
        }
    }

    #[test]
    fn dsmc(kp in kinematics(), dp in dynamics(), g in dsmc_gains(),
            io in proptest::collection::vec((reference(), estimate(), dt()), 1..3)) {
        let _ = sat(io[0].1.pose[0], g.epsilon[0]);
        let _ = g.validate();
        if let Ok(mut d) = Dsmc::new(kp, dp, g) {
            for (r, e, step) in &io {
                let _ = d.step(r, e, *step);
                let _ = d.holding_torque(&e.pose);
            }
            let _ = d.hold_stiffness(&io[0].1.pose);
            let _ = (d.fault(), d.last_output(), d.integral());
            d.reset();
        }
    }

    #[test]
    fn kcsc_and_visual_pid(kp in kinematics(), g in cartesian_gains(), bias in small6(),
                           io in proptest::collection::vec((reference(), estimate(), dt()), 1..4)) {
        if let Ok(mut k) = Kcsc::new(kp, g, &bias) {
            for (r, e, step) in &io {
                let _ = k.step(r, e, *step);
            }
            k.reset();
        }
        if let Ok(mut v) = VisualPid::new(kp, g, &bias) {
            for (r, e, step) in &io {
                let _ = v.step(r, &e.pose, &e.pose_dot, *step);
            }
            v.reset();
        }
    }

    #[test]
    fn kjsc(kp in kinematics(), g in joint_gains(), bias in small6(),
            io in proptest::collection::vec((reference(), small6(), dt()), 1..4)) {
        if let Ok(mut k) = Kjsc::new(kp, g, &bias) {
            for (r, theta, step) in &io {
                let _ = k.step(r, theta, *step);
            }
            k.reset();
        }
    }

    #[test]
    fn trajectories(center in wild6(), amplitude in wild6(), phase in wild6(), omega in wild(),
                    s in proptest::array::uniform6(proptest::array::uniform3(wild())),
                    c in proptest::array::uniform6(proptest::array::uniform3(wild())),
                    t in wild(), f in wild(), eps in wild()) {
        let sin = Sinusoid { center, amplitude, phase, omega };
        let _ = sin.sample(t).is_finite();
        let four = Fourier::<3> { s, c, offset: center, omega0: omega };
        let _ = four.sample(t);
        let _ = Reference::hold(&center).sample(t);
        let _ = (Sinusoid::experiment1().sample(t), Fourier::experiment2().sample(t));
        prop_assert!(!sat(f, eps).is_nan());
    }
}

/// A [`ServoConfig`] mixing the presets with wild values field by field.
fn servo_config() -> impl Strategy<Value = ServoConfig> {
    (
        prop_oneof![Just(ServoConfig::tuned()), Just(ServoConfig::low_noise())],
        proptest::option::of((dt(), dt(), dt(), wild())),
        proptest::option::of((limits(), kalman_config())),
        proptest::option::of((
            any::<bool>(),
            any::<bool>(),
            proptest::option::of(wild()),
            wild6(),
        )),
        proptest::option::of((pid_gains(), wild())),
    )
        .prop_map(|(base, rates, parts, flags, pid)| {
            let mut c = base;
            if let Some((j, f, s, l)) = rates {
                (c.joint_dt, c.frame_period, c.stale_after, c.camera_latency) = (j, f, s, l);
            }
            if let Some((l, k)) = parts {
                (c.limits, c.kalman) = (l, k);
            }
            if let Some((m, h, p, e)) = flags {
                c.kalman_model_input = m;
                c.hold_compensation = h;
                c.potentiometer_rate = p;
                c.potentiometer_rate_scale_error = e;
            }
            if let Some((g, t)) = pid {
                (c.pid, c.torque_limit) = (g, t);
            }
            c
        })
}

fn scheme(kp: KinematicParams, which: u8, bias: &Vec6, gains: DsmcGains) -> Option<Scheme> {
    match which % 3 {
        0 => Dsmc::new(kp, DynamicParams::nominal(), gains)
            .ok()
            .map(Scheme::Dsmc),
        1 => Kcsc::new(kp, CartesianPidGains::thesis(), bias)
            .ok()
            .map(Scheme::Kcsc),
        _ => Kjsc::new(kp, JointSpaceGains::from_visual_pid(), bias)
            .ok()
            .map(Scheme::Kjsc),
    }
}

/// Readings near the nominal home configuration (θ ≈ 0 ↔ κ ≈ 0) half the time, wild otherwise.
fn kappa() -> impl Strategy<Value = Vec6> {
    prop_oneof![
        proptest::array::uniform6(-50.0..50.0f64).prop_map(Vec6::from),
        wild6()
    ]
}

/// A plant whose camera, potentiometers and clock are scripted (wild) values.
#[derive(Debug)]
struct Scripted {
    samples: Vec<(f64, Option<Vec6>, Vec6)>,
    k: usize,
}

impl Plant for Scripted {
    type Error = ();
    fn step_joint_command(&mut self, _theta_cmd: &Vec6) -> Result<(), ()> {
        self.k += 1;
        Ok(())
    }
    fn camera(&mut self) -> Option<Vec6> {
        self.samples.get(self.k).and_then(|s| s.1)
    }
    fn potentiometers(&self) -> Vec6 {
        self.samples.get(self.k).map_or(Vec6::zeros(), |s| s.2)
    }
    fn time(&self) -> f64 {
        self.samples.get(self.k).map_or(0.0, |s| s.0)
    }
}

/// Tick times: mostly increasing by a plausible joint period, sometimes wild (backwards, huge).
fn times() -> impl Strategy<Value = Vec<f64>> {
    proptest::collection::vec(prop_oneof![3 => 1e-4..0.05f64, 1 => wild()], 1..6).prop_map(|d| {
        let mut t = 0.0;
        d.iter()
            .map(|x| {
                t += x;
                t
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn servo(c in servo_config(), which in any::<u8>(), gains in dsmc_gains(), start in pose(),
             k0 in kappa(), t0 in prop_oneof![Just(0.0), wild()], ts in times(),
             frames in proptest::collection::vec(
                 (proptest::option::of(pose()), kappa(), reference()), 6),
             reset_pose in pose()) {
        let kp = KinematicParams::nominal();
        let bias = kp.theta_from_reading(&k0);
        let Some(s) = scheme(kp, which, &bias, gains) else { return Ok(()); };
        if let Ok(mut servo) = Servo::new(kp, c, s, &start, &k0, t0) {
            for (t, (z, k, r)) in ts.iter().zip(frames.iter()) {
                let _ = servo.tick(t0 + t, r, z.as_ref(), k);
            }
            let _ = (servo.fault(), servo.held_command(), servo.scheme().name());
            let _ = servo.reset(t0 + ts[0], &reset_pose);
            let _ = servo.tick(t0 + ts[0], &frames[0].2, frames[0].0.as_ref(), &frames[0].1);
        }
    }

    #[test]
    fn runner(c in servo_config(), which in any::<u8>(), start in pose(), k0 in kappa(),
              ts in times(),
              frames in proptest::collection::vec((proptest::option::of(pose()), kappa()), 6),
              traj_t0 in wild()) {
        let kp = KinematicParams::nominal();
        let bias = kp.theta_from_reading(&k0);
        let Some(s) = scheme(kp, which, &bias, DsmcGains::tuned()) else { return Ok(()); };
        if let Ok(mut servo) = Servo::new(kp, c, s, &start, &k0, 0.0) {
            let samples = ts.iter().zip(frames.iter()).map(|(t, (z, k))| (*t, *z, *k)).collect();
            let mut plant = Scripted { samples, k: 0 };
            let n = ts.len() as u32;
            let _ = run(&mut plant, &mut servo, &Sinusoid::experiment1(), traj_t0, n, |_, _| {});
        }
    }
}
