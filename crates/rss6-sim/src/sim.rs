//! The robot as a sampled system: a [`Physics`] engine (rapier plant or analytic twin) wrapped with
//! the built-in joint PID, the drive train (optional gear backlash), the potentiometers and the optical
//! CMM. One call of [`RobotSim::step_joint_command`] is one 1 kHz joint-loop tick.
//!
//! Joint commands are in the **nominal** joint convention, as on the real robot: the drive tracks the
//! potentiometer reading κ_cmd = (θ_cmd − Δθ_nom)/η_nom, i.e. the PID error is
//! e = θ_cmd − (η_nom κ + Δθ_nom), so the physical angle reached is η_true κ_cmd + Δθ_true (eq. 4.2).

use crate::effects::{build_effects, Backlash, Effect, EffectSetup, EffectSpec};
use crate::error::{Result, SimError};
use crate::sensors::{CmmConfig, OpticalCmm, Potentiometers, POT_NOISE_BITS};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{
    compose, euler_from_rotation, home_pose, ik, pose_inverse, DynamicParams, KinematicParams,
    Mat3, Vec3, Vec6, LEGS,
};
use rss6_ctrl::{JointPid, PidGains};
use serde::{Deserialize, Serialize};

/// How the link is attached to the wrench tip T_i.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum TJoint {
    /// Spherical joint (S–S link): joint forces pass through the link axis, the link's spin stays at
    /// rest (Assumption 2). The default.
    #[default]
    Spherical,
    /// Universal joint (relative rotation about the link axis locked): couples the link's spin to the
    /// wrench's rotation, violating Assumption 2. For the demonstration only.
    Universal,
}

/// Physics-engine settings of the rapier plant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolverConfig {
    /// Constraint-solver iterations per step (rapier `num_solver_iterations`).
    pub iterations: usize,
    /// Warm-start impulse joints from the previous step (rapier `warmstart_joints`).
    pub warmstart_joints: bool,
    /// Joint at T_i.
    pub t_joint: TJoint,
    /// PGS iterations inside each solver iteration (rapier `num_internal_pgs_iterations`).
    pub pgs_iterations: usize,
    /// Position-stabilisation iterations inside each solver iteration (rapier
    /// `num_internal_stabilization_iterations`).
    pub stabilization_iterations: usize,
    /// Build each leg's wrench and link as a reduced-coordinate multibody (exact revolute and T
    /// joints) and close the loops at A_i with impulse joints; otherwise all 18 joints are impulse
    /// joints.
    pub multibody_legs: bool,
    /// After every rapier step, project the mechanism back onto its loop constraints (positions and
    /// velocities, mass-weighted, see `docs/sim.md`): removes the solver's residual loop gap so fewer
    /// iterations suffice. Ignored with `multibody_legs`.
    #[serde(default)]
    pub projection: bool,
    /// After the position projection, replace every body's velocity by its mass-weighted projection
    /// onto the mechanism's velocities at the start-of-step configuration and the positions by one
    /// symplectic-Euler step with them (Gauss's principle: the solver's unconverged constraint
    /// impulses drop out). Makes the plant respond to torques as the loaded mechanism does at the
    /// default 4 iterations — with `implicit_friction` it follows the twin to 3.4 µm under Table
    /// 5.2's friction (736 µm without) — but its frictionless floor against the twin is 0.020 mm /
    /// 0.051 mrad (default 0.020 mm / 0.021 mrad; 48 iterations 0.0005 mm / 0.0011 mrad: rapier's
    /// iterations are TGS substeps). Needs `projection` and spherical T joints; off by default.
    #[serde(default)]
    pub velocity_projection: bool,
}

impl Default for SolverConfig {
    /// The settings that meet the accuracy targets (see `docs/sim.md`).
    fn default() -> Self {
        SolverConfig {
            iterations: 4,
            warmstart_joints: false,
            t_joint: TJoint::Spherical,
            pgs_iterations: 2,
            stabilization_iterations: 1,
            multibody_legs: false,
            projection: true,
            velocity_projection: false,
        }
    }
}

/// Everything that defines a simulated robot. Fields not in the Python call shape have defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// True kinematic parameters (possibly perturbed).
    pub kinematics: KinematicParams,
    /// True dynamic parameters (masses, inertias, joint friction).
    pub dynamics: DynamicParams,
    /// True gains of the built-in joint PID.
    pub pid: PidGains,
    /// Joint-loop period (s), 1e-3 (1 kHz).
    pub dt: f64,
    /// PID torque limit per joint (N·m).
    pub torque_limit: f64,
    /// Time constant T_f (s) of the drive's derivative filter
    /// ([`rss6_ctrl::JointPid::with_derivative_filter`]); 0 = the thesis's unfiltered law (default).
    pub drive_derivative_filter: f64,
    /// Velocity scale ε (rad/s) of the model twin's Coulomb friction f_c tanh(θ̇/ε) inside its RK4
    /// stages; 0 = the thesis's f_c sign(θ̇) (default). The rapier plant ignores it.
    pub friction_smoothing: f64,
    /// The shared friction law in plant and twin: Coulomb + viscous friction stepped implicitly
    /// per tick ([`rss6_core::implicit_friction`], stick–slip, held over the tick with the drive
    /// torque) on each simulator's own state. Off (default): the plant's Coulomb friction is a rapier
    /// velocity motor bounded by f_c with an explicit viscous torque, the twin's is
    /// `friction_smoothing`'s. Exclusive with `friction_smoothing` > 0. The plant meets the twin
    /// with it only when its solver converges (≈ 48 iterations, see `docs/sim.md`).
    pub implicit_friction: bool,
    /// Seed of every random stream (sensor noise).
    pub seed: u64,
    /// The nominal parameters that define the joint-command convention (η_nom, Δθ_nom).
    pub nominal: KinematicParams,
    /// Potentiometer noise std (bit), Table 4.1.
    pub pot_noise: f64,
    /// Potentiometer sampling period (s), 1/500 Hz.
    pub pot_period: f64,
    /// The optical CMM.
    pub cmm: CmmConfig,
    /// ᴼχ_C: the sensor frame in the base frame (calibration's external parameters).
    pub sensor_in_base: Vec6,
    /// ᴱχ_t: the target frame in the end-effector frame.
    pub target_in_effector: Vec6,
    /// Hidden effects.
    pub effects: Vec<EffectSpec>,
    /// rapier settings (ignored by the model twin).
    pub solver: SolverConfig,
}

impl SimConfig {
    /// A configuration with the given truth and defaults elsewhere.
    pub fn new(kinematics: KinematicParams, dynamics: DynamicParams, pid: PidGains) -> Self {
        SimConfig {
            kinematics,
            dynamics,
            pid,
            dt: 1e-3,
            torque_limit: DEFAULT_TORQUE_LIMIT,
            drive_derivative_filter: 0.0,
            friction_smoothing: 0.0,
            implicit_friction: false,
            seed: 0,
            nominal: KinematicParams::nominal(),
            pot_noise: POT_NOISE_BITS,
            pot_period: 2e-3,
            cmm: CmmConfig::c_track(),
            sensor_in_base: default_sensor_in_base(),
            target_in_effector: default_target_in_effector(),
            effects: Vec::new(),
            solver: SolverConfig::default(),
        }
    }

    /// The nominal robot, nominal dynamics and nominal PID.
    pub fn nominal() -> Self {
        Self::new(
            KinematicParams::nominal(),
            DynamicParams::nominal(),
            PidGains::tuned(),
        )
    }

    /// Checks ranges.
    pub fn validate(&self) -> Result<()> {
        self.kinematics.validate()?;
        self.nominal.validate()?;
        self.dynamics.validate()?;
        self.cmm.validate()?;
        let pid = self.pid.to_array();
        if !(self.dt > 0.0 && self.dt <= 0.01) {
            return Err(SimError::InvalidConfig(format!(
                "dt must be in (0, 0.01] s, got {}",
                self.dt
            )));
        }
        if self.torque_limit.is_nan()
            || self.torque_limit <= 0.0
            || pid.iter().any(|g| !g.is_finite())
        {
            return Err(SimError::InvalidConfig(
                "torque limit must be > 0, gains finite".into(),
            ));
        }
        if !(self.pot_noise >= 0.0 && self.pot_period >= self.dt) {
            return Err(SimError::InvalidConfig(
                "potentiometer noise >= 0, period >= dt".into(),
            ));
        }
        if self.solver.iterations == 0 {
            return Err(SimError::InvalidConfig(
                "solver iterations must be >= 1".into(),
            ));
        }
        for (name, v) in [
            ("drive derivative filter", self.drive_derivative_filter),
            ("friction smoothing", self.friction_smoothing),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::InvalidConfig(format!(
                    "{name} must be finite and >= 0, got {v}"
                )));
            }
        }
        if self.implicit_friction && self.friction_smoothing > 0.0 {
            return Err(SimError::InvalidConfig(
                "implicit friction and friction smoothing exclude each other".into(),
            ));
        }
        Ok(())
    }
}

/// Default PID torque limit (N·m).
pub const DEFAULT_TORQUE_LIMIT: f64 = 30.0;

/// Default ᴼχ_C: the sensor 2.05 m from the robot (up and to the side), its z axis looking at the
/// platform, its y axis pointing down as far as possible.
pub fn default_sensor_in_base() -> Vec6 {
    let aim = Vec3::new(0.0, 0.0, 0.16);
    let dir = Vec3::new(1.5, -1.0, 0.9).normalize();
    let origin = aim + 2.05 * dir;
    let z = -dir;
    let down = Vec3::new(0.0, 0.0, -1.0);
    let y = (down - z * down.dot(&z)).normalize();
    let x = y.cross(&z);
    let r = Mat3::from_columns(&[x, y, z]);
    let e = euler_from_rotation(&r);
    Vec6::new(origin[0], origin[1], origin[2], e[0], e[1], e[2])
}

/// Default ᴱχ_t: a target raised 4.5 cm above the platform centre, slightly offset and turned.
pub fn default_target_in_effector() -> Vec6 {
    Vec6::new(0.02, -0.015, 0.045, 0.05, -0.04, 0.3)
}

/// The plant's secret truth (calibration and identification try to recover it).
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    /// True kinematic parameters.
    pub kinematics: KinematicParams,
    /// True dynamic parameters.
    pub dynamics: DynamicParams,
    /// True PID gains.
    pub pid: PidGains,
    /// ᴼχ_C (m, rad).
    pub sensor_in_base: Vec6,
    /// ᴱχ_t (m, rad).
    pub target_in_effector: Vec6,
    /// The hidden effects that are on, with their parameters.
    pub effects: Vec<EffectSpec>,
}

/// The call shape shared by the rapier plant and the analytic twin (and any future robot).
pub trait RobotSim {
    /// Places the true robot at rest at `pose` (IK of the true kinematics), clears the PID and
    /// sensor queues, sets time to 0.
    fn reset(&mut self, pose: &Vec6) -> Result<()>;
    /// One joint-loop tick with the command θ_cmd (rad, nominal convention).
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()>;
    /// The true platform pose χ (m, rad).
    fn true_pose(&self) -> Vec6;
    /// The true physical joint angles θ (rad).
    fn true_theta(&self) -> Vec6;
    /// Simulated time (s).
    fn time(&self) -> f64;
    /// ᶜχ_t if a CMM frame became available on the last tick, else None.
    fn camera(&self) -> Option<Vec6>;
    /// The latest potentiometer readings κ (bit).
    fn potentiometers(&self) -> Vec6;
    /// The joint torques the PID applied on the last tick (N·m).
    fn torques(&self) -> Vec6;
    /// The secret truth.
    fn truth(&self) -> Truth;
    /// Largest loop-closure gap after the last tick (m); 0 for an exact model.
    fn loop_closure_error(&self) -> f64 {
        0.0
    }
    /// Largest gap the physics engine's solver left in the last tick before any post-step
    /// projection (m); 0 for an exact model.
    fn solver_gap(&self) -> f64 {
        0.0
    }
    /// Ticks whose implicit friction solve stopped at its sweep bound instead of converging
    /// exactly ([`rss6_core::FrictionStep::exact`]); 0 expected, 0 without `implicit_friction`.
    fn inexact_friction_steps(&self) -> u64 {
        0
    }
}

/// A rigid-body engine that the robot wrapper drives.
pub trait Physics: Send {
    /// Puts the mechanism at rest at platform pose `pose` with physical joint angles `theta`.
    fn place(&mut self, pose: &Vec6, theta: &Vec6) -> Result<()>;
    /// Advances one tick with wrench torques τ (N·m) about +z (joint friction is the engine's job).
    fn advance(&mut self, tau: &Vec6) -> Result<()>;
    /// Platform pose χ.
    fn pose(&self) -> Vec6;
    /// Physical joint angles θ (rad).
    fn theta(&self) -> Vec6;
    /// Joint rates θ̇ (rad/s).
    fn theta_dot(&self) -> Vec6;
    /// Largest gap between joint anchors that should coincide (m); 0 for an exact model.
    fn loop_closure_error(&self) -> f64;
    /// The gap the engine's constraint solver left in the last tick before any post-step
    /// projection (m); the same as [`Physics::loop_closure_error`] for engines without one.
    fn solver_gap(&self) -> f64 {
        self.loop_closure_error()
    }
    /// See [`RobotSim::inexact_friction_steps`].
    fn inexact_friction_steps(&self) -> u64 {
        0
    }
}

#[derive(Debug, Clone, Copy)]
struct Rotor {
    theta: f64,
    omega: f64,
}

/// A simulated robot: physics + PID + drive train + sensors. See `Plant` (feature `rapier`) and
/// [`crate::ModelSim`].
pub struct Robot<P: Physics> {
    pub(crate) physics: P,
    cfg: SimConfig,
    effects: Vec<Box<dyn Effect>>,
    setup: EffectSetup,
    pid: JointPid,
    pots: Potentiometers,
    cmm: OpticalCmm,
    rotors: Option<[Rotor; LEGS]>,
    tick: u64,
    last_tau: Vec6,
}

impl<P: Physics> std::fmt::Debug for Robot<P> {
    // Deliberately silent about effects and truth.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Robot")
            .field("time", &self.time())
            .finish_non_exhaustive()
    }
}

impl<P: Physics> Robot<P> {
    /// Wraps a physics engine (already built from `cfg` and `setup`).
    pub(crate) fn assemble(
        cfg: SimConfig,
        effects: Vec<Box<dyn Effect>>,
        setup: EffectSetup,
        physics: P,
    ) -> Result<Self> {
        let pid = JointPid::new(cfg.pid, cfg.dt, cfg.torque_limit)
            .and_then(|p| p.with_derivative_filter(cfg.drive_derivative_filter))
            .map_err(|e| SimError::InvalidConfig(format!("drive PID: {e}")))?;
        let period_ticks = (cfg.pot_period / cfg.dt).round().max(1.0) as u64;
        let pots = Potentiometers::new(
            cfg.kinematics.eta,
            cfg.kinematics.dtheta,
            cfg.pot_noise,
            period_ticks,
            ChaCha8Rng::seed_from_u64(cfg.seed),
        )?
        .with_drift(setup.dtheta_drift, cfg.dt);
        let mut cam_rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        cam_rng.set_stream(1);
        let cmm = OpticalCmm::new(cfg.cmm.clone(), setup.extra_camera_latency, cam_rng);
        let mut r = Robot {
            physics,
            cfg,
            effects,
            setup,
            pid,
            pots,
            cmm,
            rotors: None,
            tick: 0,
            last_tau: Vec6::zeros(),
        };
        r.reset(&home_pose())?;
        Ok(r)
    }

    /// Validates the config and builds the effects.
    pub(crate) fn prepare(cfg: &SimConfig) -> Result<(Vec<Box<dyn Effect>>, EffectSetup)> {
        cfg.validate()?;
        build_effects(&cfg.effects)
    }

    /// The configuration (contains the truth: do not show it to estimators).
    pub fn config(&self) -> &SimConfig {
        &self.cfg
    }

    /// Largest loop-closure gap of the physics (m).
    pub fn loop_closure_error(&self) -> f64 {
        self.physics.loop_closure_error()
    }

    /// Loop gap the constraint solver left in the last tick before the post-step projection (m);
    /// see [`SolverConfig::projection`].
    pub fn solver_gap(&self) -> f64 {
        self.physics.solver_gap()
    }

    /// The true ᶜχ_t now (no noise, no latency).
    pub fn true_camera_pose(&self) -> Vec6 {
        camera_pose_of(&self.cfg, &self.physics.pose())
    }

    /// Joint rates θ̇ (rad/s).
    pub fn true_theta_dot(&self) -> Vec6 {
        self.physics.theta_dot()
    }

    /// The drive-side (potentiometer-side) joint angles (rad): equal to [`RobotSim::true_theta`]
    /// unless there is gear backlash.
    pub fn drive_theta(&self) -> Vec6 {
        match &self.rotors {
            Some(r) => Vec6::from_fn(|i, _| r[i].theta),
            None => self.physics.theta(),
        }
    }

    /// CMM frames dropped because the target could not be measured (reflector out of view).
    pub fn dropped_camera_frames(&self) -> u64 {
        self.cmm.dropped()
    }

    /// Total CMM latency (s).
    pub fn camera_latency(&self) -> f64 {
        self.cmm.latency()
    }

    /// The drive's built-in joint PID (its integral and derivative memory).
    pub fn drive_pid(&self) -> &JointPid {
        &self.pid
    }

    /// The gravity vector acting on the robot (m/s², base frame): part of the truth.
    pub fn gravity(&self) -> Vec3 {
        self.setup.gravity
    }

    fn backlash(&self) -> Option<Backlash> {
        self.setup.backlash
    }
}

impl<P: Physics> RobotSim for Robot<P> {
    fn loop_closure_error(&self) -> f64 {
        self.physics.loop_closure_error()
    }
    fn solver_gap(&self) -> f64 {
        self.physics.solver_gap()
    }
    fn inexact_friction_steps(&self) -> u64 {
        self.physics.inexact_friction_steps()
    }
    fn reset(&mut self, pose: &Vec6) -> Result<()> {
        let theta = ik(&self.cfg.kinematics, pose)?;
        self.physics.place(pose, &theta)?;
        self.pid.reset();
        self.tick = 0;
        self.last_tau = Vec6::zeros();
        self.rotors = self.backlash().map(|_| {
            core::array::from_fn(|i| Rotor {
                theta: theta[i],
                omega: 0.0,
            })
        });
        let drive = self.drive_theta();
        self.pots.tick(0, &drive);
        self.cmm.reset(0.0);
        let (cfg, pose) = (&self.cfg, self.physics.pose());
        self.cmm.tick(0.0, || camera_pose_of(cfg, &pose))?;
        Ok(())
    }

    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> Result<()> {
        if theta_cmd.iter().any(|x| !x.is_finite()) {
            return Err(SimError::InvalidConfig("non-finite joint command".into()));
        }
        // The drive uses the reading sampled at the end of the previous tick (or at reset): the same
        // value `potentiometers()` shows the host between ticks, so a host-side converter can mirror
        // the drive's PID exactly (rss6-ctrl's TorqueToPosition).
        let kappa = self.pots.reading();
        let nom = &self.cfg.nominal;
        let theta_meas = Vec6::from_fn(|i, _| nom.eta[i] * kappa[i] + nom.dtheta[i]);
        let tau = self.pid.step(theta_cmd, &theta_meas);
        self.last_tau = tau;
        let wrench_tau = match (self.rotors.as_mut(), self.setup.backlash) {
            (Some(rotors), Some(b)) => {
                let th = self.physics.theta();
                let thd = self.physics.theta_dot();
                let half = 0.5 * b.width;
                let dt = self.cfg.dt;
                Vec6::from_fn(|i, _| {
                    let r = &mut rotors[i];
                    let gap = r.theta - th[i];
                    let pen = if gap > half {
                        gap - half
                    } else if gap < -half {
                        gap + half
                    } else {
                        0.0
                    };
                    let tg = if pen != 0.0 {
                        b.stiffness * pen + b.damping * (r.omega - thd[i])
                    } else {
                        0.0
                    };
                    r.omega += (tau[i] - tg) / b.rotor_inertia * dt;
                    r.theta += r.omega * dt;
                    tg
                })
            }
            _ => tau,
        };
        self.physics.advance(&wrench_tau)?;
        self.tick += 1;
        let drive = self.drive_theta();
        self.pots.tick(self.tick, &drive);
        let p = self.physics.pose();
        if p.iter().any(|x| !x.is_finite()) {
            return Err(SimError::Diverged {
                time: self.time(),
                message: "non-finite pose".into(),
            });
        }
        let t = self.time();
        // The true ᶜχ_t only at the camera's captures (≈ one tick in 33).
        self.cmm.tick(t, || camera_pose_of(&self.cfg, &p))?;
        Ok(())
    }

    fn true_pose(&self) -> Vec6 {
        self.physics.pose()
    }

    fn true_theta(&self) -> Vec6 {
        self.physics.theta()
    }

    fn time(&self) -> f64 {
        self.tick as f64 * self.cfg.dt
    }

    fn camera(&self) -> Option<Vec6> {
        self.cmm.output()
    }

    fn potentiometers(&self) -> Vec6 {
        self.pots.reading()
    }

    fn torques(&self) -> Vec6 {
        self.last_tau
    }

    fn truth(&self) -> Truth {
        Truth {
            kinematics: self.cfg.kinematics,
            dynamics: self.cfg.dynamics,
            pid: self.cfg.pid,
            sensor_in_base: self.cfg.sensor_in_base,
            target_in_effector: self.cfg.target_in_effector,
            effects: self
                .effects
                .iter()
                .map(|e| EffectSpec {
                    name: e.name().to_string(),
                    params: e.params(),
                })
                .collect(),
        }
    }
}

/// The true ᶜχ_t of the effector pose `pose` (ᴼχ_E) through `cfg`'s ᴼχ_C and ᴱχ_t.
fn camera_pose_of(cfg: &SimConfig, pose: &Vec6) -> Vec6 {
    compose(
        &pose_inverse(&cfg.sensor_in_base),
        &compose(pose, &cfg.target_in_effector),
    )
}

/// Friction of the truth plus the friction effect, per joint: (f_c, f_v).
pub(crate) fn total_friction(
    dp: &DynamicParams,
    setup: &EffectSetup,
) -> ([f64; LEGS], [f64; LEGS]) {
    (
        core::array::from_fn(|i| dp.coulomb[i] + setup.extra_coulomb[i]),
        core::array::from_fn(|i| dp.viscous[i] + setup.extra_viscous[i]),
    )
}
