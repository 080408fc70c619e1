//! The collection checks of the dwell runner on the analytic-model twin: a command the robot cannot
//! reach and a platform that moves during the dwell are flagged with a typed fault; a lost target
//! aborts with a typed error.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use rss6_core::{DynamicParams, KinematicParams, Vec6};
use rss6_ctrl::PidGains;
use rss6_exp::dwell::{DriveConvention, DwellFault, DwellSession, DwellSpec};
use rss6_exp::{ExpError, Robot, TrueState};
use rss6_sim::{ModelSim, SimConfig, Truth};

fn twin(seed: u64) -> ModelSim {
    let mut cfg = SimConfig::new(
        KinematicParams::nominal(),
        DynamicParams::nominal(),
        PidGains::tuned(),
    );
    cfg.seed = seed;
    ModelSim::new(cfg).unwrap()
}

/// The twin with a twist: joint `joint`'s command is clamped at `limit` (a joint held back, as by a
/// robot that cannot assemble further), and a sinusoid of `shake` rad at 3 Hz is added to joint 0's
/// command (a platform that does not come to rest); `blind` hides every camera frame.
struct Faulty {
    sim: ModelSim,
    joint: usize,
    limit: f64,
    shake: f64,
    blind: bool,
}

impl Robot for Faulty {
    fn dt(&self) -> f64 {
        Robot::dt(&self.sim)
    }
    fn time(&self) -> f64 {
        Robot::time(&self.sim)
    }
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> rss6_exp::Result<()> {
        let mut c = *theta_cmd;
        c[self.joint] = c[self.joint].min(self.limit);
        c[0] += self.shake * (std::f64::consts::TAU * 3.0 * Robot::time(&self.sim)).sin();
        self.sim.step_joint_command(&c)
    }
    fn camera(&mut self) -> Option<Vec6> {
        let f = Robot::camera(&mut self.sim);
        if self.blind {
            None
        } else {
            f
        }
    }
    fn potentiometers(&self) -> Vec6 {
        Robot::potentiometers(&self.sim)
    }
    fn truth(&self) -> Option<Truth> {
        Robot::truth(&self.sim)
    }
    fn true_state(&self) -> Option<TrueState> {
        Robot::true_state(&self.sim)
    }
}

fn session(limit: f64, shake: f64, blind: bool) -> DwellSession<Faulty> {
    let robot = Faulty {
        sim: twin(5),
        joint: 2,
        limit,
        shake,
        blind,
    };
    DwellSession::new(
        robot,
        Vec6::zeros(),
        DwellSpec::checked(&KinematicParams::nominal()),
    )
}

const REACHED: [f64; 6] = [0.05, -0.05, 0.05, 0.0, -0.03, 0.04];
const TOO_FAR: [f64; 6] = [0.05, -0.05, 0.20, 0.0, -0.03, 0.04];

#[test]
fn an_unreached_command_is_flagged_with_the_joint_and_its_error() {
    let mut s = session(0.1, 0.0, false);
    let ok = s.measure(&Vec6::from(REACHED), 0.5).unwrap();
    assert_eq!(ok.fault, None, "{:?}", ok.fault);
    let drive = DriveConvention::of(&KinematicParams::nominal());
    let cmd = drive.reading(&ok.theta_cmd);
    let reach = (0..6)
        .map(|i| (ok.kappa[i] - cmd[i]).abs())
        .fold(0.0, f64::max);
    // measured 0.0045 bit on the twin; bound ≈ 3× that
    assert!(reach < 0.015, "reached command off by {reach} bit");

    let far = s.measure(&Vec6::from(TOO_FAR), 0.5).unwrap();
    match far.fault {
        Some(DwellFault::Unreached {
            joint, error_bits, ..
        }) => {
            assert_eq!(joint, 2);
            // the joint stops 0.1 rad short: −0.1/η = −130.4 bit
            let expect = -0.1 / KinematicParams::nominal().eta[2];
            assert!(
                (error_bits - expect).abs() < 1.0,
                "{error_bits} vs {expect}"
            );
        }
        other => panic!("not flagged as unreached: {other:?}"),
    }
    // kept in the data, excluded by default
    assert!(far.sensor_pose.is_some() && far.defect().is_none());
    assert!(
        far.exclusion().unwrap().contains("joint 3"),
        "{:?}",
        far.exclusion()
    );
}

#[test]
fn a_platform_moving_during_the_dwell_is_flagged() {
    let mut still = session(1.0, 0.0, false);
    let c = still.measure(&Vec6::from(REACHED), 0.5).unwrap();
    assert_eq!(c.fault, None);
    // at rest: measured x 0.6 σ, z 1.9 σ (the stereo head's depth), κ 1.2 σ; the check allows 3 σ
    let std = c.sensor_pose_std.unwrap();

    assert!(
        std[0] < 3.0 * 0.0096e-3 && std[2] < 3.0 * 0.0096e-3,
        "{std:?}"
    );

    // ±0.1° at 3 Hz on joint 0 (±2.3 bit): the platform moves by tens of µm
    let mut moving = session(1.0, 0.1f64.to_radians(), false);
    let c = moving.measure(&Vec6::from(REACHED), 0.5).unwrap();
    match c.fault {
        Some(DwellFault::Moving {
            channel,
            scatter,
            tolerance,
        }) => {
            assert!(scatter > tolerance, "{channel:?}: {scatter} vs {tolerance}");
            // measured: the worst potentiometer scatters 1.6 bit (tolerance 0.67 bit)
        }
        other => panic!("not flagged as moving: {other:?}"),
    }
}

#[test]
fn a_lost_target_aborts_with_the_configuration_index() {
    let mut s = session(1.0, 0.0, false);
    s.measure(&Vec6::from(REACHED), 0.3).unwrap();
    s.robot.blind = true;
    match s.measure(&Vec6::zeros(), 0.3) {
        Err(ExpError::TargetLost { index, .. }) => assert_eq!(index, 1),
        other => panic!("{other:?}"),
    }
}
