//! Typed faults and validated constructors: a singular J_θ and time running backwards each latch their
//! own reason; constructors refuse the values that used to make a later step panic or return NaN.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use rss6_core::{
    home_pose, ik, jacobian_theta, DynamicParams, KinematicParams, Vec3, Vec6, HOME_Z, LEGS,
};
use rss6_ctrl::{
    sat, CartesianPidGains, CtrlError, Dsmc, DsmcGains, FaultReason, JointPid, JointSpaceGains,
    Kcsc, Kjsc, PidGains, PoseEstimate, Reference, Scheme, Servo, ServoConfig, TorqueToPosition,
};

/// A robot whose six platform joints all sit at the end-effector origin: every leg can still close
/// (the links are as long as at home), J_a1 is regular, but the rows of J_a2 lose their a_i × l_i half,
/// so J_θ = J_ad J_s has three zero columns at every pose.
fn collapsed_platform() -> KinematicParams {
    let mut kp = KinematicParams::nominal();
    let centre = Vec3::new(0.0, 0.0, HOME_Z);
    for i in 0..LEGS {
        kp.platform_joints[i] = Vec3::zeros();
        let tip = kp.base_joints[i]
            + kp.wrench_lengths[i] * Vec3::new(kp.theta0[i].cos(), kp.theta0[i].sin(), 0.0);
        kp.link_lengths[i] = (centre - tip).norm();
    }
    kp
}

fn at_rest(pose: &Vec6) -> PoseEstimate {
    PoseEstimate {
        pose: *pose,
        pose_dot: Vec6::zeros(),
        pose_ddot: Vec6::zeros(),
    }
}

#[test]
fn collapsed_platform_is_reachable_with_a_singular_j_theta() {
    let kp = collapsed_platform();
    kp.validate().unwrap();
    ik(&kp, &home_pose()).unwrap();
    let j = jacobian_theta(&kp, &home_pose()).unwrap();
    assert!(j.column(3).amax() == 0.0 && j.column(4).amax() == 0.0 && j.column(5).amax() == 0.0);
}

#[test]
fn dsmc_reports_a_singular_j_theta_as_such() {
    let kp = collapsed_platform();
    let mut dsmc = Dsmc::new(kp, DynamicParams::nominal(), DsmcGains::tuned()).unwrap();
    let home = home_pose();
    let err = dsmc
        .step(&Reference::hold(&home), &at_rest(&home), 0.033)
        .unwrap_err();
    assert_eq!(err, CtrlError::Faulted(FaultReason::SingularJacobian));
    assert_eq!(dsmc.fault(), Some(FaultReason::SingularJacobian));
    assert_eq!(dsmc.holding_torque(&home), Err(CtrlError::SingularJacobian));
    assert_eq!(dsmc.hold_stiffness(&home), Err(CtrlError::SingularJacobian));
}

#[test]
fn servo_latches_a_singular_j_theta() {
    let kp = collapsed_platform();
    let home = home_pose();
    let dsmc = Dsmc::new(kp, DynamicParams::nominal(), DsmcGains::tuned()).unwrap();
    let kappa = kp.reading_from_theta(&ik(&kp, &home).unwrap());
    let mut servo = Servo::new(
        kp,
        ServoConfig::tuned(),
        Scheme::Dsmc(dsmc),
        &home,
        &kappa,
        0.0,
    )
    .unwrap();
    let err = servo
        .tick(0.0, &Reference::hold(&home), Some(&home), &kappa)
        .unwrap_err();
    assert_eq!(err, CtrlError::Faulted(FaultReason::SingularJacobian));
    assert_eq!(servo.fault(), Some(FaultReason::SingularJacobian));
}

fn kcsc_servo(t0: f64) -> (Servo, Vec6) {
    let kp = KinematicParams::nominal();
    let home = home_pose();
    let kappa = kp.reading_from_theta(&ik(&kp, &home).unwrap());
    let kcsc = Kcsc::new(kp, CartesianPidGains::thesis(), &Vec6::zeros()).unwrap();
    let servo = Servo::new(
        kp,
        ServoConfig::tuned(),
        Scheme::Kcsc(kcsc),
        &home,
        &kappa,
        t0,
    )
    .unwrap();
    (servo, kappa)
}

#[test]
fn servo_faults_when_time_runs_backwards() {
    let (mut servo, kappa) = kcsc_servo(1.0);
    let hold = Reference::hold(&home_pose());
    servo.tick(1.0, &hold, Some(&home_pose()), &kappa).unwrap();
    servo.tick(1.001, &hold, None, &kappa).unwrap();
    // The same instant again is allowed (a repeated stamp, not a reversal) …
    servo.tick(1.001, &hold, None, &kappa).unwrap();
    // … an earlier one is not, with or without a camera frame.
    let err = servo
        .tick(1.0005, &hold, Some(&home_pose()), &kappa)
        .unwrap_err();
    match err {
        CtrlError::Faulted(FaultReason::TimeWentBackwards { by }) => {
            assert!((by - 0.0005).abs() < 1e-12, "{by}");
        }
        other => panic!("expected TimeWentBackwards, got {other:?}"),
    }
    // Latched until reset; reset at an earlier time restarts the clock there.
    assert!(servo.tick(1.002, &hold, None, &kappa).is_err());
    servo.reset(0.5, &home_pose()).unwrap();
    servo.tick(0.5, &hold, Some(&home_pose()), &kappa).unwrap();
}

#[test]
fn servo_faults_on_a_first_tick_before_its_start_time() {
    let (mut servo, kappa) = kcsc_servo(2.0);
    let err = servo
        .tick(1.9, &Reference::hold(&home_pose()), None, &kappa)
        .unwrap_err();
    assert!(
        matches!(
            err,
            CtrlError::Faulted(FaultReason::TimeWentBackwards { .. })
        ),
        "{err:?}"
    );
}

#[test]
fn joint_pid_refuses_what_would_make_it_panic_or_divide_by_zero() {
    let g = PidGains::tuned();
    assert!(matches!(
        JointPid::new(g, 0.0, 30.0),
        Err(CtrlError::InvalidTimeStep(_))
    ));
    assert!(matches!(
        JointPid::new(g, -1e-3, 30.0),
        Err(CtrlError::InvalidTimeStep(_))
    ));
    for lim in [0.0, -1.0, f64::NAN] {
        assert!(matches!(
            JointPid::new(g, 1e-3, lim),
            Err(CtrlError::InvalidParameter(_))
        ));
    }
    let negative = PidGains { lp: -1.0, ..g };
    assert!(matches!(
        JointPid::new(negative, 1e-3, 30.0),
        Err(CtrlError::InvalidParameter(_))
    ));
    // An unlimited drive is fine.
    let mut pid = JointPid::new(g, 1e-3, f64::INFINITY).unwrap();
    assert!(pid
        .step(&Vec6::repeat(1.0), &Vec6::zeros())
        .iter()
        .all(|t| t.is_finite()));
    // The converter also needs l_p + l_d > 0 to invert the law.
    let integral_only = PidGains {
        lp: 0.0,
        li: 1.0,
        ld: 0.0,
    };
    assert!(JointPid::new(integral_only, 1e-3, 30.0).is_ok());
    assert!(matches!(
        TorqueToPosition::new(integral_only, 1e-3, 30.0),
        Err(CtrlError::InvalidParameter(_))
    ));
}

#[test]
fn kinematic_controllers_refuse_a_negative_integral_limit() {
    let kp = KinematicParams::nominal();
    let cart = CartesianPidGains {
        integral_limit: Vec6::repeat(-0.1),
        ..CartesianPidGains::thesis()
    };
    assert!(matches!(
        Kcsc::new(kp, cart, &Vec6::zeros()),
        Err(CtrlError::InvalidParameter(_))
    ));
    let joint = JointSpaceGains {
        integral_limit: -1.0,
        ..JointSpaceGains::from_visual_pid()
    };
    assert!(matches!(
        Kjsc::new(kp, joint, &Vec6::zeros()),
        Err(CtrlError::InvalidParameter(_))
    ));
    let nan = JointSpaceGains {
        kd: f64::NAN,
        ..JointSpaceGains::from_visual_pid()
    };
    assert!(matches!(
        Kjsc::new(kp, nan, &Vec6::zeros()),
        Err(CtrlError::NonFinite)
    ));
}

#[test]
fn sat_without_a_boundary_layer_is_the_sign() {
    assert_eq!(sat(3.0, 0.0), 1.0);
    assert_eq!(sat(-1e-300, 0.0), -1.0);
    assert_eq!(sat(0.0, 0.0), 0.0);
    assert_eq!(sat(0.5, -1.0), 1.0);
    assert_eq!(sat(1.0, f64::MIN_POSITIVE), 1.0);
    assert_eq!(sat(0.0, f64::MIN_POSITIVE), 0.0);
}
