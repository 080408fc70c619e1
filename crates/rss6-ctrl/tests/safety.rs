//! Command guard and the servo's fault paths (NaN measurement, missing frames, stroke).

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use rss6_core::{home_pose, KinematicParams, Vec6};
use rss6_ctrl::{
    CartesianPidGains, CommandGuard, CommandLimits, CtrlError, FaultReason, Kcsc, Reference,
    Scheme, Servo, ServoConfig,
};

#[test]
fn commands_beyond_the_stroke_are_clamped_and_rate_limited() {
    let limits = CommandLimits::nominal();
    let mut g = CommandGuard::new(limits, &Vec6::zeros()).unwrap();
    let far = Vec6::new(5.0, -5.0, 0.0, 0.0, 0.0, 0.0);
    let dt = 1e-3;
    let first = g.apply(&far, dt).unwrap();
    assert!(first.rate_limited && first.stroke_limited);
    assert!((first.command[0] - limits.max_rate * dt).abs() < 1e-15);
    let mut last = first.command;
    for _ in 0..2000 {
        last = g.apply(&far, dt).unwrap().command;
    }
    assert_eq!(last[0], limits.max[0]);
    assert_eq!(last[1], limits.min[1]);
    // NaN is refused and the last command stays.
    let mut bad = far;
    bad[3] = f64::NAN;
    assert_eq!(
        g.apply(&bad, dt),
        Err(CtrlError::Faulted(FaultReason::NonFiniteCommand))
    );
    assert_eq!(g.last_command(), last);
}

fn kcsc_servo(stale_after: f64) -> Servo {
    let kp = KinematicParams::nominal();
    let kcsc = Kcsc::new(kp, CartesianPidGains::thesis(), &Vec6::zeros()).unwrap();
    let config = ServoConfig {
        stale_after,
        ..ServoConfig::tuned()
    };
    let kappa = kp.reading_from_theta(&Vec6::zeros());
    Servo::new(kp, config, Scheme::Kcsc(kcsc), &home_pose(), &kappa, 0.0).unwrap()
}

#[test]
fn nan_measurement_latches_a_fault_and_holds_the_command() {
    let mut s = kcsc_servo(0.2);
    let kappa = KinematicParams::nominal().reading_from_theta(&Vec6::zeros());
    let reference = Reference::hold(&(home_pose() + Vec6::new(0.005, 0.0, 0.0, 0.0, 0.0, 0.0)));
    let mut held = Vec6::zeros();
    for k in 0..100 {
        let t = k as f64 * 1e-3;
        let frame = (k % 33 == 0).then(home_pose);
        held = s
            .tick(t, &reference, frame.as_ref(), &kappa)
            .unwrap()
            .theta_cmd;
    }
    assert!(
        held.amax() > 0.0,
        "the servo must be commanding something before the fault"
    );
    let mut bad = home_pose();
    bad[0] = f64::NAN;
    let r = s.tick(0.1, &reference, Some(&bad), &kappa);
    assert_eq!(
        r,
        Err(CtrlError::Faulted(FaultReason::NonFiniteMeasurement))
    );
    assert_eq!(s.fault(), Some(FaultReason::NonFiniteMeasurement));
    assert_eq!(s.held_command(), held);
    // Stays faulted on good data, command held.
    let r = s.tick(0.101, &reference, Some(&home_pose()), &kappa);
    assert_eq!(
        r,
        Err(CtrlError::Faulted(FaultReason::NonFiniteMeasurement))
    );
    assert_eq!(s.held_command(), held);
}

#[test]
fn missing_frames_predict_then_fault_when_stale() {
    let mut s = kcsc_servo(0.15);
    let kappa = KinematicParams::nominal().reading_from_theta(&Vec6::zeros());
    let reference = Reference::hold(&home_pose());
    let mut predicted = 0;
    let mut fault_at = None;
    for k in 0..400 {
        let t = k as f64 * 1e-3;
        // Frames until 50 ms, then the camera goes silent.
        let frame = (k % 33 == 0 && k <= 50).then(home_pose);
        match s.tick(t, &reference, frame.as_ref(), &kappa) {
            Ok(o) => {
                if o.estimate.is_some() && !o.frame && k > 0 {
                    predicted += 1;
                }
            }
            Err(CtrlError::Faulted(FaultReason::StaleCamera { age })) => {
                fault_at = Some((t, age));
                break;
            }
            Err(e) => panic!("unexpected {e:?}"),
        }
    }
    let (t, age) = fault_at.expect("stale camera must fault");
    assert!(
        predicted >= 2,
        "missing frames must be predicted over first ({predicted})"
    );
    assert!(age > 0.15 && age < 0.152, "age {age}");
    assert!((t - 0.033 - age).abs() < 1e-9);
    assert!(matches!(s.fault(), Some(FaultReason::StaleCamera { .. })));
}

#[test]
fn nan_potentiometer_faults() {
    let mut s = kcsc_servo(0.2);
    let mut kappa = KinematicParams::nominal().reading_from_theta(&Vec6::zeros());
    kappa[2] = f64::INFINITY;
    let r = s.tick(
        0.0,
        &Reference::hold(&home_pose()),
        Some(&home_pose()),
        &kappa,
    );
    assert_eq!(r, Err(CtrlError::Faulted(FaultReason::NonFiniteJoint)));
}
