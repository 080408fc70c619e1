//! Every hidden effect changes the plant the way its physics says (one test per effect).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{
    home_pose, ik, inverse_dynamics_with_gravity, DynamicParams, KinematicParams, LegGeometry,
    Vec3, Vec6,
};
use rss6_sim::{EffectSpec, ExcitingTrajectory, ModelSim, Plant, RobotSim, SimConfig};

fn quiet(effects: Vec<EffectSpec>) -> Plant {
    let mut cfg = SimConfig::nominal();
    cfg.pot_noise = 0.0;
    cfg.cmm.pixel_noise = 0.0;
    cfg.effects = effects;
    Plant::new(cfg).unwrap()
}

/// Holds the home pose for 1.5 s; returns the mean PID torque over the last 0.3 s and the lowest
/// platform height seen.
fn hold_home(plant: &mut Plant) -> (Vec6, f64) {
    let cmd = ik(&KinematicParams::nominal(), &home_pose()).unwrap();
    let (mut sum, mut zmin) = (Vec6::zeros(), f64::INFINITY);
    for k in 0..1500 {
        plant.step_joint_command(&cmd).unwrap();
        zmin = zmin.min(plant.true_pose()[2]);
        if k >= 1200 {
            sum += plant.torques();
        }
    }
    (sum / 300.0, zmin)
}

#[test]
fn joint_friction_dissipates_the_predicted_power() {
    let (fc, fv) = (1.0, 0.5);
    let traj = ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    let mut work = [0.0; 2];
    let mut predicted = 0.0;
    for (j, effects) in [
        vec![],
        vec![EffectSpec::new(
            "joint_friction",
            &[("coulomb", fc), ("viscous", fv)],
        )],
    ]
    .into_iter()
    .enumerate()
    {
        let mut plant = quiet(effects);
        for k in 0..2500 {
            plant
                .step_joint_command(&traj.joint_command(&nominal, k as f64 * 1e-3).unwrap())
                .unwrap();
            if k >= 500 {
                let thd = plant.true_theta_dot();
                work[j] += plant.torques().dot(&thd) * 1e-3;
                if j == 1 {
                    predicted += thd.iter().map(|w| fc * w.abs() + fv * w * w).sum::<f64>() * 1e-3;
                }
            }
        }
    }
    let extra = work[1] - work[0];
    println!(
        "actuator work: {:.3} J without, {:.3} J with friction; predicted loss {predicted:.3} J",
        work[0], work[1]
    );
    assert!(
        predicted > 0.5,
        "the trajectory should move the joints ({predicted} J)"
    );
    assert!(
        (extra / predicted - 1.0).abs() < 0.25,
        "extra work {extra} J vs friction loss {predicted} J"
    );
}

#[test]
fn backlash_opens_a_dead_band_on_the_loaded_flank() {
    let width = 0.01;
    let mut plant = quiet(vec![EffectSpec::new(
        "backlash",
        &[("width", width), ("stiffness", 5000.0)],
    )]);
    let (tau, _) = hold_home(&mut plant);
    let gap = plant.drive_theta() - plant.true_theta();
    println!("backlash: drive − wrench = {gap:.5?} rad, torque {tau:.3?}");
    for i in 0..6 {
        // The rotor rests against the flank the torque pushes on: |gap| = width/2 + τ/k.
        let expected = tau[i].signum() * (0.5 * width + tau[i].abs() / 5000.0);
        assert!(
            (gap[i] - expected).abs() < 0.1 * width,
            "joint {i}: gap {} vs {expected}",
            gap[i]
        );
    }
    let mut plain = quiet(vec![]);
    hold_home(&mut plain);
    assert!((plain.drive_theta() - plain.true_theta()).amax() < 1e-12);
    // The dead band shows up in the pose: the drive holds its angle but the wrench lags by width/2.
    let err = (plant.true_pose() - plain.true_pose())
        .fixed_rows::<3>(0)
        .norm();
    assert!(err > 1e-4, "backlash should move the platform ({err} m)");
}

#[test]
fn camera_latency_effect_delays_every_frame() {
    let mut plant = quiet(vec![EffectSpec::new(
        "camera_latency",
        &[("latency", 0.03)],
    )]);
    assert!((plant.camera_latency() - 0.03).abs() < 1e-12);
    let traj = ExcitingTrajectory::default();
    let nominal = KinematicParams::nominal();
    let mut history = vec![plant.true_camera_pose()];
    let mut first = None;
    for k in 0..800 {
        plant
            .step_joint_command(&traj.joint_command(&nominal, k as f64 * 1e-3).unwrap())
            .unwrap();
        history.push(plant.true_camera_pose());
        if let Some(c) = plant.camera() {
            first.get_or_insert(plant.time());
            let now = history.len() - 1;
            assert!(
                (c - history[now - 30]).amax() < 1e-8,
                "frame is not 30 ms old"
            );
        }
    }
    let first = first.unwrap();
    assert!((first - 0.03).abs() < 1e-9, "first frame at {first}");
}

#[test]
fn payload_sags_needs_more_torque_and_shifts_the_pattern() {
    let (m, com) = (5.0, Vec3::new(0.06, 0.0, 0.03));
    let mut plain = quiet(vec![]);
    let (tau0, z0) = hold_home(&mut plain);
    let mut loaded = quiet(vec![EffectSpec::new(
        "payload",
        &[("mass", m), ("x", com[0]), ("y", com[1]), ("z", com[2])],
    )]);
    let (tau1, z1) = hold_home(&mut loaded);
    // Statics: τ = J_ad⁻ᵀ F_E with F_E the wrench that holds the payload at E (eq. 3.30 duality).
    let geom = LegGeometry::at_pose(&KinematicParams::nominal(), &home_pose()).unwrap();
    let up = Vec3::new(0.0, 0.0, m * 9.81);
    let f_e = Vec6::new(up[0], up[1], up[2], 0.0, 0.0, 0.0)
        + Vec6::from_iterator(
            [0.0, 0.0, 0.0]
                .into_iter()
                .chain(com.cross(&up).iter().copied()),
        );
    let expected = geom.j_ad().unwrap().transpose().lu().solve(&f_e).unwrap();
    let got = tau1 - tau0;
    println!(
        "payload: Δτ = {got:.3?}, statics predict {expected:.3?}; sag {:.3} mm",
        (z0 - z1) * 1e3
    );
    assert!(
        (got - expected).norm() < 0.05 * expected.norm(),
        "Δτ {got} vs {expected}"
    );
    assert!(tau1.norm() > tau0.norm(), "a payload needs more torque");
    assert!(
        z1 < z0 - 1e-5,
        "the platform should sag more under load ({z0} → {z1})"
    );
    // The COM offset in +x shifts the load between legs: the pattern is not a uniform scaling.
    let ratio: Vec<f64> = (0..6).map(|i| tau1[i] / tau0[i]).collect();
    let spread = ratio.iter().cloned().fold(f64::MIN, f64::max)
        - ratio.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread > 0.05, "torque ratios {ratio:?}");
}

#[test]
fn base_tilt_changes_the_gravity_torque_pattern_as_the_model_says() {
    let (roll, pitch) = (0.08, -0.05);
    let mut plain = quiet(vec![]);
    let (tau0, _) = hold_home(&mut plain);
    let mut tilted = quiet(vec![EffectSpec::new(
        "base_tilt",
        &[("roll", roll), ("pitch", pitch)],
    )]);
    let (tau1, _) = hold_home(&mut tilted);
    let kp = KinematicParams::nominal();
    let dp = DynamicParams::nominal();
    let z = Vec6::zeros();
    let model0 =
        inverse_dynamics_with_gravity(&kp, &dp, &home_pose(), &z, &z, &Vec3::new(0.0, 0.0, -9.81))
            .unwrap();
    let model1 =
        inverse_dynamics_with_gravity(&kp, &dp, &home_pose(), &z, &z, &tilted.gravity()).unwrap();
    println!(
        "tilt: plant {tau1:.3?} model {model1:.3?}; untilted plant {tau0:.3?} model {model0:.3?}"
    );
    assert!(
        (tau0 - model0).norm() < 0.01 * model0.norm(),
        "untilted statics differ from the model"
    );
    assert!(
        (tau1 - model1).norm() < 0.01 * model1.norm(),
        "tilted statics differ from the model"
    );
    assert!(
        (tau1 - tau0).norm() > 0.05 * tau0.norm(),
        "tilt should change the torque pattern"
    );
}

/// Runs `robot` (built without noise from `effects`) holding home for `steps` ticks; returns the
/// true joint angles after every tick.
fn hold_and_record<R: RobotSim>(robot: &mut R, steps: usize) -> Vec<Vec6> {
    let cmd = ik(&KinematicParams::nominal(), &home_pose()).unwrap();
    (0..steps)
        .map(|_| {
            robot.step_joint_command(&cmd).unwrap();
            robot.true_theta()
        })
        .collect()
}

/// `joint_offset_drift`: Δθ_i(t) = Δθ_i + rate·t. At the same physical state the reading differs by
/// exactly −rate·t/η_i on the drifting joint and not at all elsewhere; in closed loop the drive
/// tracks the drifting reading, so that joint's true angle moves by rate·t and the others hold.
/// Plant and model twin alike (they share the sensor model).
#[test]
fn joint_offset_drift_moves_the_reading_by_rate_t_and_nothing_else() {
    let (rate, joint, steps) = (2e-3, 2usize, 1500usize);
    let t = steps as f64 * 1e-3;
    let drift = || {
        vec![EffectSpec::new(
            "joint_offset_drift",
            &[("rate", rate), ("joint", joint as f64)],
        )]
    };
    let quiet_cfg = |effects: Vec<EffectSpec>| {
        let mut cfg = SimConfig::nominal();
        cfg.pot_noise = 0.0;
        cfg.cmm.pixel_noise = 0.0;
        cfg.effects = effects;
        cfg
    };
    let eta = KinematicParams::nominal().eta;
    fn check<R: RobotSim>(
        name: &str,
        plain: &mut R,
        drifting: &mut R,
        steps: usize,
        rate: f64,
        joint: usize,
        eta: &[f64; 6],
    ) {
        let t = steps as f64 * 1e-3;
        let a = hold_and_record(plain, steps);
        let b = hold_and_record(drifting, steps);
        // Closed loop: the drifting joint follows rate·t (after the PID catches up), the others hold.
        let (mut follow, mut others): (f64, f64) = (0.0, 0.0);
        for (k, (ta, tb)) in a.iter().zip(&b).enumerate().skip(steps / 2) {
            let d = tb - ta;
            let expected = rate * (k + 1) as f64 * 1e-3;
            follow = follow.max((d[joint] - expected).abs() / expected);
            others = others.max(
                (0..6)
                    .filter(|&i| i != joint)
                    .map(|i| d[i].abs())
                    .fold(0.0, f64::max),
            );
        }
        // Same physical state (reset places both at home; it does not rewind the sensors' age):
        // the readings differ by exactly −rate·t/η on the drifting joint.
        plain.reset(&home_pose()).unwrap();
        drifting.reset(&home_pose()).unwrap();
        assert_eq!(plain.true_theta(), drifting.true_theta());
        let dk = drifting.potentiometers() - plain.potentiometers();
        let expected = -rate * t / eta[joint];
        println!(
            "{name}: Δκ = {dk:.4?} bit (expected {expected:.4} on joint {joint}); closed loop: drifting joint vs rate·t rel. err {follow:.2e}, other joints {others:.2e} rad"
        );
        for i in 0..6 {
            let want = if i == joint { expected } else { 0.0 };
            assert!(
                (dk[i] - want).abs() <= 1e-9 * expected.abs(),
                "{name} joint {i}: {} vs {want}",
                dk[i]
            );
        }
        // ≈ 3× measured (plant and twin alike: 1.1e-3 rel., 2.2e-6 rad of rate·t = 3e-3 rad).
        assert!(follow < 3.5e-3, "{name}: drifting joint {follow}");
        assert!(others < 7e-6, "{name}: other joints moved {others} rad");
    }
    let mut p0 = Plant::new(quiet_cfg(vec![])).unwrap();
    let mut p1 = Plant::new(quiet_cfg(drift())).unwrap();
    check("plant", &mut p0, &mut p1, steps, rate, joint, &eta);
    let mut m0 = ModelSim::new(quiet_cfg(vec![])).unwrap();
    let mut m1 = ModelSim::new(quiet_cfg(drift())).unwrap();
    check("twin", &mut m0, &mut m1, steps, rate, joint, &eta);
    assert!(t > 1.0);
    // Bad parameters are refused.
    for bad in [
        vec![("joint", 1.0)],
        vec![("rate", 1e-3), ("joint", 6.0)],
        vec![("rate", 1e-3), ("speed", 1.0)],
    ] {
        assert!(rss6_sim::make_effect(&EffectSpec::new("joint_offset_drift", &bad)).is_err());
    }
}
