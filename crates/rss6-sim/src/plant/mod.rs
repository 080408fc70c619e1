//! The rapier3d-f64 plant: the "real robot" of every experiment (the thesis used SimMechanics, §5.6.1).
//!
//! Bodies: a fixed base; 6 wrenches on revolute joints about +z at B_i; 6 links joined to the wrench
//! tips T_i and to the platform at A_i; the platform. Each body's centre of mass is its geometric
//! centre (Assumption 1) and its principal inertia comes from the true [`DynamicParams`]
//! (wrench frame: x along B→T, z along the revolute axis; link frame: z along T→A; platform = ΣE).
//! Gravity −z (or tilted by the `base_tilt` effect). The six closed loops are impulse joints (rapier
//! multibodies cannot close loops), so rapier holds them only to its solver's tolerance (≈ 50 µm at
//! the default 4 iterations); a post-step projection onto the loop constraints
//! ([`crate::SolverConfig::projection`], on by default) closes them after every tick. Both gaps are
//! reported ([`Physics::loop_closure_error`], [`Physics::solver_gap`]) and tested.
//!
//! Joint friction: by default Coulomb friction f_c is a velocity motor on each revolute joint with
//! target speed 0 and force bound f_c (it sticks, to the solver's tolerance) and viscous friction
//! −f_v θ̇ an applied torque. With [`SimConfig::implicit_friction`] it is the law the twin shares:
//! Coulomb + viscous friction stepped implicitly per tick ([`rss6_core::implicit_friction`] on the
//! plant's own state, true parameters and environment; a joint sticks while its drive torque is
//! below f_c), held over the tick with the drive torque. That law predicts the step with the
//! model's dynamics, so the plant follows it only when rapier's step converges: measured with
//! Table 5.2's friction over 4 s, plant − twin ≤ 1.5 µm at 48 solver iterations, 54 µm at 32,
//! 176 µm at 16 and 666 µm at the default 4 (docs/sim.md). Actuator torques are applied to the wrench bodies (`add_torque`, cleared every tick); the
//! reaction goes into the fixed base.

mod projection;

use crate::effects::EffectSetup;
use crate::error::{Result, SimError};
use crate::sim::{total_friction, Physics, Robot, SimConfig, TJoint};
use rapier3d_f64::glamx::{DMat3, DQuat, DVec3};
use rapier3d_f64::prelude::*;
use rss6_core::{
    euler_from_rotation, implicit_friction, jacobian_theta, pose_rotation, wrap_angle, wrench_tips,
    CoreError, DynamicParams, Environment, KinematicParams, Mat3, SingularKind, Vec3, Vec6, LEGS,
};

fn dv(v: &Vec3) -> DVec3 {
    DVec3::new(v[0], v[1], v[2])
}

fn nv(v: DVec3) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

fn quat_from(r: &Mat3) -> DQuat {
    let mut a = [0.0; 9];
    a.copy_from_slice(r.as_slice()); // column-major, as glam expects
    DQuat::from_mat3(&DMat3::from_cols_array(&a)).normalize()
}

fn mat_from(q: DQuat) -> Mat3 {
    let m = DMat3::from_quat(q).to_cols_array();
    Mat3::from_column_slice(&m)
}

#[derive(Debug, Clone, Copy)]
struct Leg {
    wrench: RigidBodyHandle,
    link: RigidBodyHandle,
    /// Anchor of the T joint in the wrench frame and in the link frame.
    t_in_wrench: DVec3,
    t_in_link: DVec3,
    /// Anchor of the A joint in the link frame and in the platform frame.
    a_in_link: DVec3,
    a_in_platform: DVec3,
    /// Unit link axis in the link frame (z).
    half_link: f64,
}

/// The rapier world of the plant.
pub struct RapierPhysics {
    kp: KinematicParams,
    dp: DynamicParams,
    setup: EffectSetup,
    coulomb: [f64; LEGS],
    viscous: [f64; LEGS],
    implicit_friction: bool,
    /// Gravity and payload of the implicit friction step.
    env: Environment,
    t_joint: TJoint,
    multibody: bool,
    projection: bool,
    velocity_projection: bool,
    /// Loop gap left by the rapier step before the projection (m).
    solver_gap: f64,
    /// Implicit friction solves that hit their sweep bound.
    inexact_friction: u64,
    /// Projection metric: inverse inertia of each wrench about its axis (1/(kg·m²)), inverse
    /// platform mass (1/kg) and platform inertia in ΣE (kg·m²), each with half of every link lumped
    /// at its ends.
    inv_wrench_inertia: [f64; LEGS],
    inv_platform_mass: f64,
    platform_inertia: DMat3,
    world: PhysicsWorld,
    legs: Vec<Leg>,
    platform: RigidBodyHandle,
}

impl std::fmt::Debug for RapierPhysics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RapierPhysics").finish_non_exhaustive()
    }
}

impl RapierPhysics {
    /// An (unplaced) plant world for `cfg` with the effect hooks `setup`.
    pub fn new(cfg: &SimConfig, setup: &EffectSetup) -> Self {
        let (coulomb, viscous) = total_friction(&cfg.dynamics, setup);
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = cfg.dt;
        world.integration_parameters.num_solver_iterations = cfg.solver.iterations;
        world.integration_parameters.warmstart_joints = cfg.solver.warmstart_joints;
        world.integration_parameters.num_internal_pgs_iterations = cfg.solver.pgs_iterations.max(1);
        world
            .integration_parameters
            .num_internal_stabilization_iterations = cfg.solver.stabilization_iterations;
        RapierPhysics {
            kp: cfg.kinematics,
            dp: cfg.dynamics,
            setup: *setup,
            coulomb,
            viscous,
            implicit_friction: cfg.implicit_friction,
            env: setup.environment(),
            t_joint: cfg.solver.t_joint,
            multibody: cfg.solver.multibody_legs,
            projection: cfg.solver.projection && !cfg.solver.multibody_legs,
            velocity_projection: cfg.solver.velocity_projection
                && cfg.solver.t_joint == TJoint::Spherical
                && !cfg.solver.multibody_legs,
            solver_gap: 0.0,
            inexact_friction: 0,
            inv_wrench_inertia: [0.0; LEGS],
            inv_platform_mass: 0.0,
            platform_inertia: DMat3::IDENTITY,
            world,
            legs: Vec::new(),
            platform: RigidBodyHandle::invalid(),
        }
    }

    /// Rebuilds every body and joint at rest in the configuration (χ, θ).
    fn build(&mut self, pose: &Vec6, theta: &Vec6) {
        let params = self.world.integration_parameters;
        let mut w = PhysicsWorld::new();
        w.integration_parameters = params;
        w.gravity = dv(&self.setup.gravity);
        let kp = &self.kp;
        let base = w.insert_body(RigidBodyBuilder::fixed());

        // Platform: body frame = ΣE, COM at E (+ payload).
        let r_p = pose_rotation(pose);
        let e = Vec3::new(pose[0], pose[1], pose[2]);
        let pb = &self.dp.platform;
        let mut mprops = MassProperties::new(DVec3::ZERO, pb.mass, dv(&pb.inertia));
        if let Some(pl) = self.setup.payload {
            mprops += MassProperties::new(dv(&pl.com), pl.mass, DVec3::splat(pl.inertia));
        }
        let platform = w.insert_body(
            RigidBodyBuilder::dynamic()
                .pose(Pose::from_parts(dv(&e), quat_from(&r_p)))
                .additional_mass_properties(mprops)
                .can_sleep(false),
        );

        // Projection metric (see `project`): half of each link's mass lumped at T_i and A_i.
        let mut m_total = pb.mass;
        let mut i_plat = DMat3::from_diagonal(dv(&pb.inertia));
        let point = |m: f64, c: DVec3| {
            m * (DMat3::from_diagonal(DVec3::splat(c.length_squared()))
                - DMat3::from_cols(c * c.x, c * c.y, c * c.z))
        };
        if let Some(pl) = self.setup.payload {
            m_total += pl.mass;
            i_plat += DMat3::from_diagonal(DVec3::splat(pl.inertia)) + point(pl.mass, dv(&pl.com));
        }
        for i in 0..LEGS {
            let half = 0.5 * self.dp.links[i].mass;
            m_total += half;
            i_plat += point(half, dv(&kp.platform_joints[i]));
            let wb = &self.dp.wrenches[i];
            let lw = kp.wrench_lengths[i];
            let i_axis = wb.inertia[2] + wb.mass * 0.25 * lw * lw + half * lw * lw;
            self.inv_wrench_inertia[i] = if i_axis > 0.0 { 1.0 / i_axis } else { 0.0 };
        }
        self.inv_platform_mass = if m_total > 0.0 { 1.0 / m_total } else { 0.0 };
        self.platform_inertia = i_plat;

        let tips = wrench_tips(kp, theta);
        let mut legs = Vec::with_capacity(LEGS);
        for i in 0..LEGS {
            let b = kp.base_joints[i];
            let t = tips[i];
            let a = r_p * kp.platform_joints[i] + e;
            let lw = kp.wrench_lengths[i];
            let phi = theta[i] + kp.theta0[i];
            let q_w = DQuat::from_rotation_z(phi);
            let wb = &self.dp.wrenches[i];
            let wrench = w.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(Pose::from_parts(dv(&(0.5 * (b + t))), q_w))
                    .additional_mass_properties(MassProperties::new(
                        DVec3::ZERO,
                        wb.mass,
                        dv(&wb.inertia),
                    ))
                    .can_sleep(false),
            );
            let u = (a - t).normalize();
            let q_l = DQuat::from_rotation_arc(DVec3::Z, dv(&u));
            let lb = &self.dp.links[i];
            let link = w.insert_body(
                RigidBodyBuilder::dynamic()
                    .pose(Pose::from_parts(dv(&(0.5 * (t + a))), q_l))
                    .additional_mass_properties(MassProperties::new(
                        DVec3::ZERO,
                        lb.mass,
                        dv(&lb.inertia),
                    ))
                    .can_sleep(false),
            );
            let half_link = 0.5 * (a - t).norm();
            let leg = Leg {
                wrench,
                link,
                t_in_wrench: DVec3::new(0.5 * lw, 0.0, 0.0),
                t_in_link: DVec3::new(0.0, 0.0, -half_link),
                a_in_link: DVec3::new(0.0, 0.0, half_link),
                a_in_platform: dv(&kp.platform_joints[i]),
                half_link,
            };
            // Revolute joint about +z at B_i.
            let mut rev = RevoluteJointBuilder::new(DVec3::Z)
                .local_anchor1(dv(&b))
                .local_anchor2(DVec3::new(-0.5 * lw, 0.0, 0.0))
                .contacts_enabled(false);
            if !self.implicit_friction && self.coulomb[i] > 0.0 {
                rev = rev
                    .motor_model(MotorModel::ForceBased)
                    .motor_velocity(0.0, 1.0e6)
                    .motor_max_force(self.coulomb[i]);
            }
            if self.multibody {
                w.insert_multibody_joint(base, wrench, rev);
            } else {
                w.insert_impulse_joint(base, wrench, rev);
            }
            // Joint at T_i.
            let tj: GenericJoint = match self.t_joint {
                TJoint::Spherical => SphericalJointBuilder::new()
                    .local_anchor1(leg.t_in_wrench)
                    .local_anchor2(leg.t_in_link)
                    .contacts_enabled(false)
                    .into(),
                TJoint::Universal => {
                    // Joint frames with x along the link axis, identical at build time; locking
                    // ANG_X forbids relative rotation about the link axis.
                    let f_link = DQuat::from_rotation_y(-std::f64::consts::FRAC_PI_2);
                    let f_wrench = q_w.inverse() * q_l * f_link;
                    GenericJointBuilder::new(JointAxesMask::LIN_AXES | JointAxesMask::ANG_X)
                        .local_frame1(Pose::from_parts(leg.t_in_wrench, f_wrench))
                        .local_frame2(Pose::from_parts(leg.t_in_link, f_link))
                        .contacts_enabled(false)
                        .build()
                }
            };
            if self.multibody {
                w.insert_multibody_joint(wrench, link, tj);
            } else {
                w.insert_impulse_joint(wrench, link, tj);
            }
            // Spherical joint at A_i.
            let aj = SphericalJointBuilder::new()
                .local_anchor1(leg.a_in_link)
                .local_anchor2(leg.a_in_platform)
                .contacts_enabled(false);
            w.insert_impulse_joint(link, platform, aj);
            legs.push(leg);
        }
        self.world = w;
        self.legs = legs;
        self.platform = platform;
    }

    /// Spin rate of each link about its own axis (rad/s): ω·û. Zero under Assumption 2.
    pub fn link_spin_rates(&self) -> [f64; LEGS] {
        core::array::from_fn(|i| match self.legs.get(i) {
            Some(l) => {
                let body = &self.world.bodies[l.link];
                let axis = body.rotation() * DVec3::Z;
                body.angvel().dot(axis)
            }
            None => 0.0,
        })
    }

    /// Length of link i between its two joint anchors as the bodies sit now (m).
    pub fn link_half_length(&self, i: usize) -> Option<f64> {
        self.legs.get(i).map(|l| l.half_link)
    }

    /// τ_f of the shared law ([`rss6_core::implicit_friction`]) on the plant's own state (χ from
    /// the platform, χ̇ from the wrench rates θ̇), its true friction and environment.
    fn implicit_friction_torque(&mut self, tau: &Vec6, thd: &Vec6) -> Result<Vec6> {
        let pose = self.pose();
        let pose_dot = jacobian_theta(&self.kp, &pose)?
            .lu()
            .solve(thd)
            .ok_or(SimError::Core(CoreError::Singular(SingularKind::TypeII)))?;
        let mut dp = self.dp;
        dp.coulomb = self.coulomb;
        dp.viscous = self.viscous;
        let dt = self.world.integration_parameters.dt;
        let f = implicit_friction(&self.kp, &dp, &pose, &pose_dot, tau, &self.env, dt)?;
        self.inexact_friction += u64::from(!f.exact);
        Ok(f.torque)
    }

    fn platform_body(&self) -> &RigidBody {
        &self.world.bodies[self.platform]
    }
}

impl Physics for RapierPhysics {
    fn place(&mut self, pose: &Vec6, theta: &Vec6) -> Result<()> {
        self.build(pose, theta);
        Ok(())
    }

    fn advance(&mut self, tau: &Vec6) -> Result<()> {
        let thd = self.theta_dot();
        let joint_tau = if self.implicit_friction && self.legs.len() == LEGS {
            tau - self.implicit_friction_torque(tau, &thd)?
        } else {
            Vec6::from_fn(|i, _| tau[i] - self.viscous[i] * thd[i])
        };
        for (i, leg) in self.legs.iter().enumerate() {
            let body = &mut self.world.bodies[leg.wrench];
            body.reset_torques(false);
            body.add_torque(DVec3::new(0.0, 0.0, joint_tau[i]), true);
        }
        let before = self.configuration();
        self.world.step();
        self.solver_gap = self.loop_closure_error();
        if self.projection {
            self.project();
            if self.velocity_projection {
                self.project_velocities(&before);
                self.integrate_positions(&before);
            }
        }
        Ok(())
    }

    fn pose(&self) -> Vec6 {
        let b = self.platform_body();
        let e = nv(b.translation());
        let eul = euler_from_rotation(&mat_from(*b.rotation()));
        Vec6::new(e[0], e[1], e[2], eul[0], eul[1], eul[2])
    }

    fn theta(&self) -> Vec6 {
        let mut th = Vec6::zeros();
        for (i, leg) in self.legs.iter().enumerate() {
            let x = self.world.bodies[leg.wrench].rotation() * DVec3::X;
            th[i] = wrap_angle(x.y.atan2(x.x) - self.kp.theta0[i]);
        }
        th
    }

    fn theta_dot(&self) -> Vec6 {
        let mut v = Vec6::zeros();
        for (i, leg) in self.legs.iter().enumerate() {
            v[i] = self.world.bodies[leg.wrench].angvel().z;
        }
        v
    }

    fn inexact_friction_steps(&self) -> u64 {
        self.inexact_friction
    }

    fn solver_gap(&self) -> f64 {
        self.solver_gap
    }

    fn loop_closure_error(&self) -> f64 {
        let bodies = &self.world.bodies;
        let p = bodies[self.platform].position();
        let mut worst: f64 = 0.0;
        for leg in &self.legs {
            let pw = bodies[leg.wrench].position();
            let pl = bodies[leg.link].position();
            let dt = pw.transform_point(leg.t_in_wrench) - pl.transform_point(leg.t_in_link);
            let da = pl.transform_point(leg.a_in_link) - p.transform_point(leg.a_in_platform);
            worst = worst.max(dt.length()).max(da.length());
        }
        worst
    }
}

/// The rapier plant with the built-in PID and sensors: the "real robot".
pub type Plant = Robot<RapierPhysics>;

impl Robot<RapierPhysics> {
    /// Builds the plant from a full configuration, placed at the home pose.
    pub fn new(cfg: SimConfig) -> Result<Self> {
        let (effects, setup) = Self::prepare(&cfg)?;
        let physics = RapierPhysics::new(&cfg, &setup);
        Self::assemble(cfg, effects, setup, physics)
    }

    /// Link spin rates about their own axes (rad/s) — Assumption 2 check.
    pub fn link_spin_rates(&self) -> [f64; LEGS] {
        self.physics.link_spin_rates()
    }

    /// Fails if the loops have come apart by more than `tolerance` (m).
    pub fn check_loops(&self, tolerance: f64) -> Result<()> {
        let e = self.physics.loop_closure_error();
        if e.is_finite() && e <= tolerance {
            Ok(())
        } else {
            Err(SimError::Diverged {
                time: crate::RobotSim::time(self),
                message: format!("loop-closure gap {e:.3e} m > {tolerance:.3e} m"),
            })
        }
    }
}
