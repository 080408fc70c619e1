//! Kalman filter: exact discretisation, noise reduction, velocity tracking, predict-only, steady state.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use nalgebra::Matrix3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rss6_core::{home_pose, Vec6};
use rss6_ctrl::{discrete_noise, transition, CtrlError, KalmanConfig, PoseKalman};

#[test]
fn discrete_noise_is_the_integral_of_phi_q_phi_t() {
    let (dt, qv, qj) = (0.041, 0.7, 3.0);
    let qc = Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0, qv, qj));
    // Composite Simpson with 2000 intervals.
    let n = 2000;
    let h = dt / n as f64;
    let mut acc = Matrix3::zeros();
    for k in 0..=n {
        let s = k as f64 * h;
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        let phi = transition(s);
        acc += phi * qc * phi.transpose() * w;
    }
    acc *= h / 3.0;
    let exact = discrete_noise(dt, qv, qj);
    assert!(
        (acc - exact).amax() < 1e-12 * exact.amax().max(1.0),
        "{acc} vs {exact}"
    );
    // Φ(a)Φ(b) = Φ(a+b).
    assert!((transition(0.01) * transition(0.02) - transition(0.03)).amax() < 1e-15);
}

struct Signal;
impl Signal {
    fn at(t: f64) -> (Vec6, Vec6) {
        let w = 0.5;
        let amp = Vec6::new(0.01, 0.008, 0.006, 0.03, 0.03, 0.03);
        let p = amp * (w * t).sin() + Vec6::new(0.0, 0.0, 0.115, 0.0, 0.0, 0.0);
        let v = amp * (w * (w * t).cos());
        (p, v)
    }
}

fn rms(xs: &[f64]) -> f64 {
    (xs.iter().map(|x| x * x).sum::<f64>() / xs.len() as f64).sqrt()
}

fn run_filter(config: KalmanConfig, seed: u64) -> ([f64; 6], [f64; 6], [f64; 6], [f64; 6]) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sd = config.r.map(f64::sqrt);
    let jitter = Normal::new(0.0, 0.002).unwrap();
    let mut kf = PoseKalman::new(config, &Signal::at(0.0).0).unwrap();
    let (mut t, mut raw_err, mut est_err, mut vel_err, mut vel) = (
        0.0,
        vec![vec![]; 6],
        vec![vec![]; 6],
        vec![vec![]; 6],
        vec![vec![]; 6],
    );
    for k in 0..1500 {
        let dt = 0.033 + jitter.sample(&mut rng);
        t += dt;
        let (p, v) = Signal::at(t);
        let z = Vec6::from_fn(|i, _| p[i] + Normal::new(0.0, sd[i]).unwrap().sample(&mut rng));
        let est = kf.step(dt, Some(&z)).unwrap();
        if k > 150 {
            for i in 0..6 {
                raw_err[i].push(z[i] - p[i]);
                est_err[i].push(est.pose[i] - p[i]);
                vel_err[i].push(est.pose_dot[i] - v[i]);
                vel[i].push(v[i]);
            }
        }
    }
    let f = |x: &Vec<Vec<f64>>| core::array::from_fn(|i| rms(&x[i]));
    (f(&raw_err), f(&est_err), f(&vel_err), f(&vel))
}

#[test]
fn filter_lowers_noise_and_tracks_velocity() {
    // The servo tuning (little lag, used in the loop) and a smoothing tuning with 1000× less process
    // noise. Thresholds per group [translation, rotation]: pose-noise ratio and velocity-error ratio.
    let servo = KalmanConfig::tuned();
    let smooth = KalmanConfig {
        q_jerk: servo.q_jerk * 1e-3,
        ..servo
    };
    // The servo tuning does not track angular rates on this slow motion (0.0261° noise differenced at 30 Hz
    // is ≈ 0.02 rad/s, above the 0.015 rad/s signal): no velocity bound for its rotation axes.
    let cases = [
        ("servo", servo, [1.0, 1.0], [0.2, f64::INFINITY]),
        ("smooth", smooth, [0.8, 0.8], [0.1, 0.25]),
    ];
    for (name, base, noise_ratio, vel_ratio) in cases {
        for steady in [false, true] {
            let config = KalmanConfig {
                steady_state: steady,
                ..base
            };
            let (raw, est, vel_err, vel) = run_filter(config, 7);
            for i in 0..6 {
                let (n, v) = (est[i] / raw[i], vel_err[i] / vel[i]);
                println!("{name} steady={steady} axis {i}: est/raw {n:.3}, velocity error/velocity {v:.3}");
                assert!(
                    n < noise_ratio[i / 3],
                    "{name} steady={steady} axis {i}: noise ratio {n}"
                );
                assert!(
                    v < vel_ratio[i / 3],
                    "{name} steady={steady} axis {i}: velocity ratio {v}"
                );
            }
        }
    }
}

#[test]
fn predict_only_extrapolates_constant_acceleration() {
    let config = KalmanConfig::tuned();
    let mut kf = PoseKalman::new(config, &Vec6::zeros()).unwrap();
    let traj = |t: f64| Vec6::repeat(0.001 + 0.002 * t + 0.5 * 0.003 * t * t);
    let mut t = 0.0;
    for _ in 0..300 {
        t += 0.033;
        kf.step(0.033, Some(&traj(t))).unwrap();
    }
    // Three missing frames, then compare with the truth.
    for _ in 0..3 {
        t += 0.033;
        kf.step(0.033, None).unwrap();
    }
    let est = kf.estimate();
    assert!(
        (est.pose - traj(t)).amax() < 1e-7,
        "{} vs {}",
        est.pose,
        traj(t)
    );
    assert!((est.pose_dot - Vec6::repeat(0.002 + 0.003 * t)).amax() < 1e-5);
    assert!((est.pose_ddot - Vec6::repeat(0.003)).amax() < 1e-3);
}

#[test]
fn steady_state_gain_is_the_limit_of_the_riccati_recursion() {
    let config = KalmanConfig::tuned();
    let kf = PoseKalman::new(config, &Vec6::zeros()).unwrap();
    let k_ss = kf.steady_state_gains();
    // Run the covariance filter long enough and read its gain from the estimate response to a unit
    // innovation: with zero state, a measurement z gives s = K z.
    let mut full = PoseKalman::new(config, &Vec6::zeros()).unwrap();
    for _ in 0..2000 {
        full.step(config.nominal_dt, Some(&Vec6::zeros())).unwrap();
    }
    let est = full
        .step(config.nominal_dt, Some(&Vec6::repeat(1.0)))
        .unwrap();
    for i in 0..6 {
        assert!(
            (est.pose[i] - k_ss[i][0]).abs() < 1e-9,
            "axis {i}: {} vs {}",
            est.pose[i],
            k_ss[i][0]
        );
        assert!((est.pose_dot[i] - k_ss[i][1]).abs() < 1e-7 * k_ss[i][1].abs().max(1.0));
        assert!(k_ss[i][0] > 0.0 && k_ss[i][0] < 1.0);
    }
}

#[test]
fn nan_measurement_is_refused_and_state_kept() {
    let mut kf = PoseKalman::new(KalmanConfig::tuned(), &Vec6::repeat(0.1)).unwrap();
    let before = kf.estimate();
    let mut z = Vec6::repeat(0.1);
    z[4] = f64::NAN;
    assert_eq!(kf.step(0.033, Some(&z)), Err(CtrlError::NonFinite));
    assert_eq!(kf.estimate(), before);
    assert!(matches!(
        kf.step(0.0, None),
        Err(CtrlError::InvalidTimeStep(_))
    ));
    assert!(matches!(
        kf.step(f64::INFINITY, None),
        Err(CtrlError::InvalidTimeStep(_))
    ));
}

/// Open-loop filter on the Experiment 1 and 2 references (the true motion is the reference) with the Table
/// 4.1 camera noise at 30 Hz (±2 ms jitter), after 5 s of convergence. Returns per axis
/// (est/raw pose noise, velocity rms error / rms velocity).
fn run_on_trajectory(
    config: KalmanConfig,
    traj: &dyn rss6_ctrl::Trajectory,
    seconds: f64,
    seed: u64,
) -> [(f64, f64); 6] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let sd = config.r.map(f64::sqrt);
    let jitter = Normal::new(0.0, 0.002).unwrap();
    let mut kf = PoseKalman::new(config, &traj.sample(0.0).pose).unwrap();
    let mut acc = [[0.0; 4]; 6];
    let mut t = 0.0;
    while t < seconds {
        let dt = 0.033 + jitter.sample(&mut rng);
        t += dt;
        let r = traj.sample(t);
        let z = Vec6::from_fn(|i, _| r.pose[i] + Normal::new(0.0, sd[i]).unwrap().sample(&mut rng));
        let est = kf.step(dt, Some(&z)).unwrap();
        if t > 5.0 {
            for i in 0..6 {
                acc[i][0] += (z[i] - r.pose[i]).powi(2);
                acc[i][1] += (est.pose[i] - r.pose[i]).powi(2);
                acc[i][2] += (est.pose_dot[i] - r.pose_dot[i]).powi(2);
                acc[i][3] += r.pose_dot[i].powi(2);
            }
        }
    }
    core::array::from_fn(|i| {
        let a = acc[i];
        ((a[1] / a[0]).sqrt(), (a[2] / a[3]).sqrt())
    })
}

#[test]
fn smoothing_tuning_tracks_all_six_rates_on_experiments_1_and_2() {
    let e1 = rss6_ctrl::Sinusoid::experiment1();
    let e2 = rss6_ctrl::Fourier::experiment2();
    let trajs: [(&str, &dyn rss6_ctrl::Trajectory, f64); 2] =
        [("Exp. 1", &e1, 30.0), ("Exp. 2", &e2, 45.0)];
    for (name, traj, seconds) in trajs {
        for (cname, config) in [
            ("thesis", KalmanConfig::tuned()),
            ("model_aided", KalmanConfig::model_aided()),
            ("smoothing", KalmanConfig::smoothing()),
        ] {
            let r = run_on_trajectory(config, traj, seconds, 11);
            let line: Vec<String> = r.iter().map(|(n, v)| format!("{n:.2}/{v:.2}")).collect();
            println!("{name} {cname:<12} est/raw noise / velocity error ratio per axis: {line:?}");
            if cname == "smoothing" {
                for (i, (n, v)) in r.iter().enumerate() {
                    assert!(*n < 0.8, "{name} axis {i}: noise ratio {n}");
                    assert!(*v < 0.3, "{name} axis {i}: velocity ratio {v}");
                }
            }
        }
    }
}

#[test]
fn known_input_removes_the_lag_of_a_smooth_filter() {
    // A pose driven by a known, fast-changing acceleration (square wave, 2 Hz) plus Table 4.1 noise: with the
    // input the smoothing filter's velocity error is the noise floor; without it, the lag dominates.
    let config = KalmanConfig::smoothing();
    let sd = config.r.map(f64::sqrt);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let run = |with_input: bool, rng: &mut ChaCha8Rng| {
        let mut kf = PoseKalman::new(config, &Vec6::zeros()).unwrap();
        let (mut p, mut v) = (Vec6::zeros(), Vec6::zeros());
        let (mut err, mut n) = (0.0, 0);
        let dt = 0.033;
        for k in 0..600 {
            let a = Vec6::repeat(if (k / 8) % 2 == 0 { 0.05 } else { -0.05 });
            if with_input {
                kf.set_input(&a).unwrap();
            }
            p += v * dt + a * (0.5 * dt * dt);
            v += a * dt;
            let z = Vec6::from_fn(|i, _| p[i] + Normal::new(0.0, sd[i]).unwrap().sample(rng));
            let est = kf.step(dt, Some(&z)).unwrap();
            if k > 100 {
                err += (est.pose_dot - v).norm_squared();
                n += 1;
            }
        }
        (err / n as f64).sqrt()
    };
    let with = run(true, &mut rng);
    let without = run(false, &mut rng);
    println!("velocity rms error: with input {with:.3e}, without {without:.3e}");
    assert!(with < 0.2 * without, "{with} vs {without}");
    let mut kf = PoseKalman::new(config, &Vec6::zeros()).unwrap();
    assert_eq!(
        kf.set_input(&Vec6::repeat(f64::NAN)),
        Err(CtrlError::NonFinite)
    );
    assert_eq!(kf.input(), Vec6::zeros());
}

/// A rate measurement pulls χ̇ toward it in proportion to the variances and shrinks its variance; bad
/// input is refused with the state untouched; steady-state filters have no covariance to update.
#[test]
fn rate_measurement_updates_the_velocity() {
    let mut kf = PoseKalman::new(KalmanConfig::tuned(), &home_pose()).unwrap();
    for _ in 0..30 {
        kf.step(0.033, Some(&home_pose())).unwrap();
    }
    let before = kf.clone();
    let v = Vec6::new(0.01, -0.02, 0.005, 0.03, -0.01, 0.02);
    let est = kf.update_rate(&v, &Vec6::repeat(1e-12)).unwrap();
    assert_eq!(est.pose, before.estimate().pose, "the pose is the camera's");
    assert!(
        (est.pose_dot - v).amax() < 1e-3 * v.amax(),
        "{} vs {v}",
        est.pose_dot
    );
    // An uninformative measurement changes little.
    let mut kf2 = before.clone();
    let est2 = kf2.update_rate(&v, &Vec6::repeat(1e6)).unwrap();
    assert!((est2.pose_dot - before.estimate().pose_dot).amax() < 1e-6);
    // Refused input leaves the state untouched.
    let mut kf3 = before.clone();
    let mut bad = v;
    bad[2] = f64::NAN;
    assert!(matches!(
        kf3.update_rate(&bad, &Vec6::repeat(1e-6)),
        Err(CtrlError::NonFinite)
    ));
    assert!(matches!(
        kf3.update_rate(&v, &Vec6::repeat(0.0)),
        Err(CtrlError::InvalidParameter(_))
    ));
    assert_eq!(kf3, before);
    let mut ss = PoseKalman::new(
        KalmanConfig {
            steady_state: true,
            ..KalmanConfig::tuned()
        },
        &home_pose(),
    )
    .unwrap();
    assert!(matches!(
        ss.update_rate(&v, &Vec6::repeat(1e-6)),
        Err(CtrlError::InvalidParameter(_))
    ));
}
