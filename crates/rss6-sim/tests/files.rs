//! TOML parameter files (the MCAP log format is rss6-exp's, tested there).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{DynamicParams, KinematicParams};
use rss6_ctrl::PidGains;
use rss6_sim::{
    load_dynamic_params, load_kinematic_params, load_pid_gains, save_dynamic_params,
    save_kinematic_params, save_pid_gains, Plant, RobotSim, SimConfig, SimError,
};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name)
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
