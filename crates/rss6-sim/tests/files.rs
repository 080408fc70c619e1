//! MCAP run logs (round trip, killed run, truncated file) and TOML parameter files.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{DynamicParams, KinematicParams};
use rss6_ctrl::PidGains;
use rss6_sim::{
    load_dynamic_params, load_kinematic_params, load_pid_gains, read_log, save_dynamic_params,
    save_kinematic_params, save_pid_gains, ExcitingTrajectory, McapLogger, Plant, RobotSim,
    SimConfig, SimError, TickRecord,
};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name)
}

/// Runs the plant for `ticks` and returns what was logged.
fn run(ticks: usize, mut log: impl FnMut(&TickRecord)) {
    let mut plant = Plant::new(SimConfig::nominal()).unwrap();
    let traj = ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    for k in 0..ticks {
        let cmd = traj.joint_command(&nominal, k as f64 * 1e-3).unwrap();
        plant.step_joint_command(&cmd).unwrap();
        log(&TickRecord {
            time: plant.time(),
            theta_cmd: cmd,
            kappa: plant.potentiometers(),
            torque: plant.torques(),
            true_pose: plant.true_pose(),
            camera: plant.camera(),
        });
    }
}

#[test]
fn mcap_round_trip() {
    let path = tmp("round_trip.mcap");
    let mut logger = McapLogger::create(&path).unwrap();
    let mut records = Vec::new();
    run(400, |r| {
        logger.log(r).unwrap();
        records.push(*r);
    });
    logger.finish().unwrap();
    let log = read_log(&path).unwrap();
    assert!(log.complete);
    assert_eq!(log.true_pose.len(), 400);
    assert_eq!(log.readings.len(), 400);
    assert_eq!(log.commands.len(), 400);
    assert_eq!(log.torques.len(), 400);
    let frames: Vec<_> = records
        .iter()
        .filter_map(|r| r.camera.map(|c| (r.time, c)))
        .collect();
    assert_eq!(log.camera.len(), frames.len());
    assert!(frames.len() >= 12);
    for (r, (t, p)) in records.iter().zip(&log.true_pose) {
        assert!((r.time - t).abs() < 1e-9);
        assert!(
            (r.true_pose - p).amax() < 1e-12,
            "pose {} vs {}",
            r.true_pose,
            p
        );
    }
    for ((t0, c0), (t1, c1)) in frames.iter().zip(&log.camera) {
        assert!((t0 - t1).abs() < 1e-9 && (c0 - c1).amax() < 1e-12);
    }
    for (r, (_, k)) in records.iter().zip(&log.readings) {
        assert_eq!(r.kappa, *k);
    }
    for (r, (_, c)) in records.iter().zip(&log.commands) {
        assert_eq!(r.theta_cmd, *c);
    }
    for (r, (_, tau)) in records.iter().zip(&log.torques) {
        assert_eq!(r.torque, *tau);
    }
}

#[test]
fn a_killed_run_is_readable_up_to_its_last_finished_chunk() {
    let path = tmp("killed.mcap");
    let file = std::fs::File::create(&path).unwrap();
    // Unbuffered file and 4 KiB chunks: every finished chunk is on disk at once.
    let mut logger = McapLogger::new(file, 4096).unwrap();
    let mut n = 0;
    run(300, |r| {
        logger.log(r).unwrap();
        n += 1;
    });
    // The process dies: no finish, no drop.
    std::mem::forget(logger);
    let log = read_log(&path).unwrap();
    assert!(!log.complete);
    assert!(
        !log.true_pose.is_empty() && log.true_pose.len() < n,
        "{} of {n}",
        log.true_pose.len()
    );
    // What was read is a prefix of the run, in order.
    for w in log.true_pose.windows(2) {
        assert!(w[1].0 > w[0].0);
    }
    assert!((log.true_pose[0].0 - 1e-3).abs() < 1e-9);
}

#[test]
fn a_truncated_file_is_readable_up_to_the_cut() {
    let path = tmp("full.mcap");
    let file = std::fs::File::create(&path).unwrap();
    let mut logger = McapLogger::new(file, 8192).unwrap();
    let mut records = Vec::new();
    run(300, |r| {
        logger.log(r).unwrap();
        records.push(*r);
    });
    logger.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut previous = 0;
    for frac in [0.3, 0.6, 0.9] {
        let cut = tmp("cut.mcap");
        std::fs::write(&cut, &bytes[..(bytes.len() as f64 * frac) as usize]).unwrap();
        let log = read_log(&cut).unwrap();
        assert!(!log.complete);
        let n = log.true_pose.len();
        assert!(n >= previous && n < records.len(), "{frac}: {n}");
        for (r, (_, p)) in records.iter().zip(&log.true_pose) {
            assert!((r.true_pose - p).amax() < 1e-12);
        }
        previous = n;
    }
    assert!(previous > 0);
}

#[test]
fn parameter_files_round_trip_and_bad_files_give_clear_errors() {
    let mut b = [0.0; 60];
    b[0] = 1e-3;
    b[50] = 2e-5;
    b[57] = -0.03;
    let kp = KinematicParams::perturbed(&b);
    let mut dp = DynamicParams::nominal();
    dp.coulomb[2] = 0.4;
    dp.links[4].mass = 1.5;
    let pid = PidGains {
        lp: 350.0,
        li: 1800.0,
        ld: 3.5,
    };
    let (pk, pd, pp) = (tmp("kin.toml"), tmp("dyn.toml"), tmp("pid.toml"));
    save_kinematic_params(&pk, &kp).unwrap();
    save_dynamic_params(&pd, &dp).unwrap();
    save_pid_gains(&pp, &pid).unwrap();
    assert_eq!(load_kinematic_params(&pk).unwrap(), kp);
    assert_eq!(load_dynamic_params(&pd).unwrap(), dp);
    assert_eq!(load_pid_gains(&pp).unwrap(), pid);
    let text = std::fs::read_to_string(&pk).unwrap();
    for key in [
        "base_joints",
        "platform_joints",
        "wrench_lengths",
        "link_lengths",
        "theta0",
        "eta",
        "dtheta",
    ] {
        assert!(text.contains(key), "missing key {key}");
    }
    // Corrupt, truncated, wrong shape, unknown key, invalid value.
    let bad = tmp("bad.toml");
    for (content, needle) in [
        ("this is not toml ][", "invalid parameter file"),
        (&text[..text.len() / 2], "invalid parameter file"),
        (
            &text.replace("link_lengths = [", "link_lengths = [1.0, "),
            "invalid length 7",
        ),
        (
            &text.replace("link_lengths = [", "link_lengths = [\"a\", "),
            "invalid parameter file",
        ),
        (&format!("{text}\nextra = 1\n"), "unknown field"),
    ] {
        std::fs::write(&bad, content).unwrap();
        let e = load_kinematic_params(&bad).unwrap_err();
        assert!(matches!(e, SimError::ParamFile { .. }), "{e}");
        assert!(
            e.to_string().contains(needle) && e.to_string().contains("bad.toml"),
            "{e}"
        );
    }
    let missing = load_kinematic_params(&tmp("does_not_exist.toml")).unwrap_err();
    assert!(matches!(missing, SimError::Io { .. }), "{missing}");
    let mut neg = dp;
    neg.platform.mass = -1.0;
    save_dynamic_params(&pd, &neg).unwrap();
    assert!(matches!(
        load_dynamic_params(&pd).unwrap_err(),
        SimError::ParamFile { .. }
    ));
}

#[test]
fn the_truth_record_is_written_only_when_asked_and_round_trips() {
    let mut cfg = SimConfig::nominal();
    cfg.effects = vec![
        rss6_sim::EffectSpec::new("base_tilt", &[("roll", 0.02)]),
        rss6_sim::EffectSpec::new("camera_latency", &[("latency", 0.01)]),
    ];
    let plant = Plant::new(cfg).unwrap();
    let path = tmp("truth.toml");
    rss6_sim::save_truth(&path, &plant.truth()).unwrap();
    let back = rss6_sim::load_truth(&path).unwrap();
    assert_eq!(back, plant.truth());
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("base_tilt") && text.contains("sensor_in_base"));
}
