//! The servo loop: camera latency compensation, and restart after a fault with the converter still in
//! step with the drive's PID.

#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

mod common;

use common::*;
use rss6_core::{home_pose, DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::servo::run;
use rss6_ctrl::{DsmcGains, FaultReason, Plant, Servo, ServoConfig, Sinusoid, Trajectory};

#[test]
fn latency_compensation_helps_with_a_late_camera() {
    let traj = Sinusoid::experiment1();
    let mut rows = vec![];
    for (plant_ms, assumed) in [(0, 0.0), (25, 0.0), (25, 0.025)] {
        let mut setup = Setup::new(
            KinematicParams::perturbed(&table_4_2_errors(42)),
            Noise {
                camera: true,
                potentiometer: true,
            },
            10.0,
            1,
        );
        setup.latency_ticks = plant_ms;
        setup.config.camera_latency = assumed;
        let s = run_scheme(Which::Dsmc, &traj, &setup);
        assert!(s.first_fault.is_none(), "{:?}", s.first_fault);
        println!(
            "camera latency {plant_ms} ms, servo assumes {:.0} ms: position RMSE {:.3} mm, orientation {:.3} mrad",
            assumed * 1e3,
            s.pos_rmse() * 1e3,
            s.ang_rmse() * 1e3
        );
        rows.push(s);
    }
    assert!(
        rows[2].pos_rmse() < rows[1].pos_rmse(),
        "compensation must lower the position RMSE"
    );
    assert!(
        rows[2].ang_rmse() < rows[1].ang_rmse(),
        "compensation must lower the orientation RMSE"
    );
}

#[test]
fn restart_after_a_fault_is_bumpless_and_the_shadow_tracks_the_drive() {
    let start = home_pose();
    let kp = KinematicParams::nominal();
    let mut plant = rig(
        KinematicParams::perturbed(&table_4_2_errors(7)),
        DynamicParams::nominal(),
        &start,
        Noise {
            camera: true,
            potentiometer: true,
        },
        3,
    );
    let kappa0 = plant.potentiometers();
    let theta0 = kp.theta_from_reading(&kappa0);
    let mut servo = Servo::new(
        kp,
        ServoConfig::tuned(),
        scheme(Which::Dsmc, &theta0, DsmcGains::tuned()),
        &start,
        &kappa0,
        0.0,
    )
    .unwrap();
    let traj = Sinusoid::experiment1();
    // 2 s of tracking.
    run(&mut plant, &mut servo, &traj, 0.0, 2000, |_, _| {}).unwrap();
    assert!(servo.fault().is_none());
    // A NaN frame: the servo faults and holds; the plant keeps running 0.5 s on the held command.
    let t = rss6_ctrl::Plant::time(&plant);
    let mut bad = plant.robot.model_state().pose;
    bad[2] = f64::NAN;
    let held = servo.held_command();
    let r = servo.tick(t, &traj.sample(t), Some(&bad), &plant.potentiometers());
    assert!(r.is_err());
    assert_eq!(servo.fault(), Some(FaultReason::NonFiniteMeasurement));
    plant.step_joint_command(&servo.held_command()).unwrap();
    let mut cmds = vec![];
    run(&mut plant, &mut servo, &traj, 0.0, 500, |rec, _| {
        cmds.push(rec.theta_cmd)
    })
    .unwrap();
    assert!(
        cmds.iter().all(|c| *c == held),
        "the held command must not move while faulted"
    );
    assert_eq!(
        *servo.converter().shadow(),
        *plant.robot.drive_pid(),
        "shadow drifted from the drive during the fault"
    );
    // Restart at the camera's pose: the first commands continue from the held one (rate limit) and the
    // tracking error comes back down.
    servo
        .reset(
            rss6_ctrl::Plant::time(&plant),
            &plant.robot.model_state().pose,
        )
        .unwrap();
    let mut first = None;
    let mut late_err: f64 = 0.0;
    run(&mut plant, &mut servo, &traj, 0.0, 3000, |rec, p| {
        first.get_or_insert(rec.theta_cmd);
        if rec.t > 4.5 {
            let e = traj.sample(rss6_ctrl::Plant::time(p)).pose - p.robot.model_state().pose;
            late_err = late_err.max(e.fixed_rows::<3>(0).amax());
        }
    })
    .unwrap();
    assert!(servo.fault().is_none(), "{:?}", servo.fault());
    let jump = (first.unwrap() - held).amax();
    assert!(
        jump <= ServoConfig::tuned().limits.max_rate * 1e-3 + 1e-15,
        "bump {jump} rad"
    );
    assert_eq!(*servo.converter().shadow(), *plant.robot.drive_pid());
    println!(
        "after restart: max position error over the last 0.5 s {:.3} mm",
        late_err * 1e3
    );
    assert!(
        late_err < 1e-3,
        "tracking did not recover after the restart: {late_err} m"
    );
    let _ = Vec6::zeros();
}

/// The low-noise options are checked at construction.
#[test]
fn low_noise_config_is_validated() {
    let kp = KinematicParams::nominal();
    let plant = rig(
        kp,
        DynamicParams::nominal(),
        &home_pose(),
        Noise {
            camera: false,
            potentiometer: false,
        },
        0,
    );
    let kappa0 = <Rig as Plant>::potentiometers(&plant);
    let theta0 = kp.theta_from_reading(&kappa0);
    let make = |config: ServoConfig| {
        Servo::new(
            kp,
            config,
            scheme(Which::Dsmc, &theta0, DsmcGains::low_noise()),
            &home_pose(),
            &kappa0,
            0.0,
        )
    };
    assert!(make(ServoConfig::low_noise()).is_ok());
    let mut c = ServoConfig::low_noise();
    c.kalman.steady_state = true;
    assert!(matches!(
        make(c),
        Err(rss6_ctrl::CtrlError::InvalidParameter(_))
    ));
    let mut c = ServoConfig::low_noise();
    c.potentiometer_rate = Some(f64::NAN);
    assert!(matches!(
        make(c),
        Err(rss6_ctrl::CtrlError::InvalidParameter(_))
    ));
    let mut c = ServoConfig::low_noise();
    c.potentiometer_rate_scale_error[3] = -1.0;
    assert!(matches!(
        make(c),
        Err(rss6_ctrl::CtrlError::InvalidParameter(_))
    ));
}
