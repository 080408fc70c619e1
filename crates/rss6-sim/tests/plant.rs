//! The rapier plant: static accuracy, the joint-command convention, Assumption 2, sensor statistics
//! (Table 4.1), camera rate and latency, truth hiding.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::{fk, home_pose, ik, thesis, FkOptions, KinematicParams, Vec6, N_KIN_ERRORS};
use rss6_sim::{
    EffectSpec, Plant, RobotSim, SimConfig, TJoint, CMM_ANGLE_NOISE, CMM_POSITION_NOISE,
    POT_NOISE_BITS,
};

/// A robot with Table 4.2-sized errors (uniform within ±1σ).
fn perturbed(seed: u64) -> KinematicParams {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut b = [0.0; N_KIN_ERRORS];
    for (k, x) in b.iter_mut().enumerate() {
        let s = match k {
            0..=47 => thesis::SIGMA_LENGTH,
            48..=53 => thesis::SIGMA_ETA,
            _ => thesis::SIGMA_DTHETA,
        };
        *x = s * (rng.random::<f64>() * 2.0 - 1.0);
    }
    KinematicParams::perturbed(&b)
}

fn hold(plant: &mut Plant, cmd: &Vec6, ticks: usize) {
    for _ in 0..ticks {
        plant.step_joint_command(cmd).unwrap();
    }
}

#[test]
fn at_rest_the_true_pose_is_fk_of_the_true_joint_angles() {
    let kp = perturbed(3);
    let mut cfg = SimConfig::nominal();
    cfg.kinematics = kp;
    let mut plant = Plant::new(cfg).unwrap();
    let pose = Vec6::new(0.008, -0.006, 0.122, 0.02, -0.015, 0.03);
    plant.reset(&pose).unwrap();
    let cmd = ik(&KinematicParams::nominal(), &pose).unwrap();
    hold(&mut plant, &cmd, 1500);
    let sol = fk(
        &kp,
        &plant.true_theta(),
        &plant.true_pose(),
        &FkOptions::default(),
    )
    .unwrap();
    let (dp, da) = rss6_sim::pose_distance(&sol.pose, &plant.true_pose());
    println!(
        "static: |Δp| = {:.3} µm, |Δφ| = {:.3} µrad",
        dp * 1e6,
        da * 1e6
    );
    assert!(dp <= 10e-6, "true pose differs from FK(true θ) by {dp} m");
    assert!(da <= 1e-4, "orientation differs by {da} rad");
}

#[test]
fn reset_places_the_true_robot_and_commands_use_the_nominal_convention() {
    let kp = perturbed(5);
    let nominal = KinematicParams::nominal();
    let mut cfg = SimConfig::nominal();
    cfg.kinematics = kp;
    cfg.pot_noise = 0.0;
    let mut plant = Plant::new(cfg).unwrap();
    let pose = Vec6::new(-0.005, 0.004, 0.118, -0.01, 0.02, -0.02);
    plant.reset(&pose).unwrap();
    assert!((plant.true_pose() - pose).amax() < 1e-9);
    assert!((plant.true_theta() - ik(&kp, &pose).unwrap()).amax() < 1e-9);
    // Hold a nominal-convention command: the physical angle reached is η_true κ_cmd + Δθ_true.
    let cmd = Vec6::new(0.05, -0.04, 0.03, 0.02, -0.05, 0.01);
    hold(&mut plant, &cmd, 1500);
    let kappa_cmd = nominal.reading_from_theta(&cmd);
    let expected = kp.theta_from_reading(&kappa_cmd);
    let err = (plant.true_theta() - expected).amax();
    let naive = (plant.true_theta() - cmd).amax();
    println!("convention: |θ − (η κ_cmd + Δθ)| = {err:.2e} rad, |θ − θ_cmd| = {naive:.2e} rad");
    assert!(
        err < 2e-4,
        "physical angle {err} rad away from η_true κ_cmd + Δθ_true"
    );
    assert!(
        naive > 5e-3,
        "the perturbed robot should not reach θ_cmd itself"
    );
}

#[test]
fn spherical_links_do_not_spin_universal_ones_do() {
    // Assumption 2: with S–S links the joint forces pass through the link axis, so an axisymmetric
    // link's spin stays at rest; a universal joint at T_i drags the spin along with the wrench.
    let traj = rss6_sim::ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    let mut spins = Vec::new();
    for tj in [TJoint::Spherical, TJoint::Universal] {
        let mut cfg = SimConfig::nominal();
        cfg.solver.t_joint = tj;
        let mut plant = Plant::new(cfg).unwrap();
        let mut spin: f64 = 0.0;
        for k in 0..1500 {
            plant
                .step_joint_command(&traj.joint_command(&nominal, k as f64 * 1e-3).unwrap())
                .unwrap();
            spin = plant
                .link_spin_rates()
                .iter()
                .fold(spin, |m, s| m.max(s.abs()));
        }
        spins.push(spin);
    }
    println!(
        "max link spin: spherical {:.3e} rad/s, universal {:.3e} rad/s",
        spins[0], spins[1]
    );
    assert!(
        spins[0] < 1e-2,
        "spherical links spin at {} rad/s",
        spins[0]
    );
    assert!(
        spins[1] > 100.0 * spins[0] && spins[1] > 0.05,
        "universal joint did not couple spin"
    );
}

#[test]
fn sensor_noise_matches_table_4_1_and_camera_rate_is_as_set() {
    let mut plant = Plant::new(SimConfig::nominal()).unwrap();
    let kp = KinematicParams::nominal();
    let cmd = ik(&kp, &home_pose()).unwrap();
    let (mut pot_res, mut cam_res, mut frame_times) = (Vec::new(), Vec::new(), Vec::new());
    // 11 s: ≥ 330 camera frames, 5500 potentiometer samples.
    for k in 0..11_000u64 {
        let theta_before = plant.drive_theta();
        plant.step_joint_command(&cmd).unwrap();
        if k % 2 == 0 {
            let truth = kp.reading_from_theta(&theta_before);
            pot_res.push(plant.potentiometers() - truth);
        }
        if let Some(c) = plant.camera() {
            frame_times.push(plant.time());
            cam_res.push(c - plant.true_camera_pose());
        }
    }
    let rms = |v: &[Vec6], r: std::ops::Range<usize>| {
        let n = v.len() as f64;
        let per_axis: Vec<f64> = r
            .map(|i| (v.iter().map(|x| x[i] * x[i]).sum::<f64>() / n).sqrt())
            .collect();
        (per_axis.iter().map(|s| s * s).sum::<f64>() / per_axis.len() as f64).sqrt()
    };
    let pot = rms(&pot_res, 0..6);
    let (pos, ang) = (rms(&cam_res, 0..3), rms(&cam_res, 3..6));
    println!(
        "frames {}: pot std {:.4} bit, pose std {:.4} mm {:.4} deg",
        cam_res.len(),
        pot,
        pos * 1e3,
        ang.to_degrees()
    );
    assert!(cam_res.len() >= 300);
    assert!((pot / POT_NOISE_BITS - 1.0).abs() < 0.2, "pot noise {pot}");
    assert!(
        (pos / CMM_POSITION_NOISE - 1.0).abs() < 0.2,
        "position noise {pos}"
    );
    assert!(
        (ang / CMM_ANGLE_NOISE - 1.0).abs() < 0.2,
        "angle noise {ang}"
    );
    // Rate: frames every 33 ms (±1 tick of the 1 kHz clock).
    let gaps: Vec<f64> = frame_times.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(
        gaps.iter().all(|g| (g - 0.033).abs() <= 1.001e-3),
        "frame gaps {gaps:?}"
    );
    let rate =
        (frame_times.len() - 1) as f64 / (frame_times[frame_times.len() - 1] - frame_times[0]);
    assert!((29.0..=31.0).contains(&rate), "camera rate {rate} Hz");
}

#[test]
fn configured_camera_latency_delays_frames() {
    let mut cfg = SimConfig::nominal();
    cfg.cmm.latency = 0.02;
    cfg.cmm.pixel_noise = 0.0; // so the delayed frame can be matched exactly
    let mut plant = Plant::new(cfg).unwrap();
    let traj = rss6_sim::ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    let mut history = vec![plant.true_camera_pose()];
    let mut checked = 0;
    for k in 0..1000 {
        plant
            .step_joint_command(&traj.joint_command(&nominal, k as f64 * 1e-3).unwrap())
            .unwrap();
        history.push(plant.true_camera_pose());
        if let Some(c) = plant.camera() {
            let t = plant.time();
            assert!(t >= 0.02 - 1e-9, "frame before the latency elapsed: {t}");
            let now = history.len() - 1;
            let then = now - 20;
            let (lag, fresh) = ((c - history[then]).amax(), (c - history[now]).amax());
            assert!(
                lag < 1e-8,
                "frame at {t} is not the pose 20 ms earlier ({lag})"
            );
            if t > 0.2 {
                assert!(
                    fresh > 1e-6,
                    "the delayed frame should differ from the current pose"
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 25);
}

#[test]
fn outputs_do_not_reveal_effects_but_truth_does() {
    let mut cfg = SimConfig::nominal();
    cfg.effects = vec![EffectSpec::new("payload", &[("mass", 2.0), ("x", 0.03)])];
    let plant = Plant::new(cfg).unwrap();
    let shown = format!("{plant:?}");
    assert!(
        !shown.contains("payload") && !shown.contains("mass"),
        "{shown}"
    );
    let truth = plant.truth();
    assert_eq!(truth.effects.len(), 1);
    assert_eq!(truth.effects[0].name, "payload");
    assert_eq!(truth.effects[0].params["mass"], 2.0);
    assert_ne!(truth.sensor_in_base, Vec6::zeros());
    assert_ne!(truth.target_in_effector, Vec6::zeros());
}

#[test]
fn frames_with_reflectors_out_of_view_are_dropped_not_fatal() {
    let mut cfg = SimConfig::nominal();
    // A 1e6 px lens sees only a few millimetres: the reflectors fall outside the images.
    for cam in cfg.cmm.cameras.iter_mut() {
        cam.focal = 1e6;
    }
    let mut plant = Plant::new(cfg).unwrap();
    let cmd = ik(&KinematicParams::nominal(), &home_pose()).unwrap();
    for _ in 0..200 {
        plant.step_joint_command(&cmd).unwrap();
        assert!(plant.camera().is_none());
    }
    assert!(plant.dropped_camera_frames() >= 6);
}
