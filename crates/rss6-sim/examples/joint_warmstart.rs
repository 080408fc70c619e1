//! Minimal rapier3d-f64 reproduction: `IntegrationParameters::warmstart_joints` changes nothing.
//! A chain of `n` bodies (1 kg links, last body `heavy` kg, 0.2 m apart) hangs at rest under gravity
//! from a fixed base on spherical impulse joints, starting exactly closed; we print the largest joint
//! anchor separation after 1, 10 and 1000 steps (dt = 1 ms) with joint warm-starting off, with
//! `warmstart_joints = true` (bit-identical to off), and with a public-API emulation of warm
//! starting: last step's joint forces, rebuilt from `ImpulseJoint::impulses`, applied as external
//! forces at the anchors (coefficient 1 and 0.5). See `docs/rapier_warmstart.md`.
//!
//! `cargo run --release -p rss6-sim --example joint_warmstart`
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rapier3d_f64::glamx::DVec3;
use rapier3d_f64::prelude::*;

struct Chain {
    world: PhysicsWorld,
    joints: Vec<(
        ImpulseJointHandle,
        RigidBodyHandle,
        RigidBodyHandle,
        DVec3,
        DVec3,
    )>,
    /// Feed-forward joint forces (N, on body 1 of each joint, world frame) of the public-API
    /// warm start, and its coefficient (None: off).
    ff: Vec<DVec3>,
    ff_coeff: Option<f64>,
}

/// The world-frame impulse (on body 1) that rapier's three locked linear rows of a spherical joint
/// applied, from the per-row impulses it stores in `ImpulseJoint::impulses` (a per-substep
/// impulse, N·s). The rows are mass-orthogonalised by rapier (modified Gram–Schmidt in the metric
/// K = (1/m₁ + 1/m₂)·1 − [r₁]ₓI₁⁻¹[r₁]ₓ − [r₂]ₓI₂⁻¹[r₂]ₓ, `JointConstraintHelper::finalize_constraints`),
/// so the stored numbers are coordinates in that orthogonalised basis, not in the joint frame.
fn spherical_impulse(b1: &RigidBody, b2: &RigidBody, a1: DVec3, a2: DVec3, imp: &[f64]) -> DVec3 {
    let x1 = b1.position().transform_point(a1);
    let x2 = b2.position().transform_point(a2);
    let (m1, m2) = (b1.mass_properties(), b2.mass_properties());
    let r1 = x1 - m1.world_com;
    let r2 = x2 - m2.world_com;
    let imsum = m1.effective_inv_mass + m2.effective_inv_mass;
    let k = |a: DVec3, b: DVec3| {
        a.dot(imsum * b)
            + (m1.effective_world_inv_inertia * r1.cross(a)).dot(r1.cross(b))
            + (m2.effective_world_inv_inertia * r2.cross(a)).dot(r2.cross(b))
    };
    let rot = *b1.rotation();
    let mut e = [rot * DVec3::X, rot * DVec3::Y, rot * DVec3::Z];
    for j in 0..3 {
        let djj = k(e[j], e[j]);
        for i in (j + 1)..3 {
            let c = k(e[i], e[j]) / djj;
            e[i] -= e[j] * c;
        }
    }
    e[0] * imp[0] + e[1] * imp[1] + e[2] * imp[2]
}

/// `n` bodies hanging in a vertical line, each 0.2 m long; the last one has mass `heavy`.
fn chain(
    n: usize,
    heavy: f64,
    warm: bool,
    ff_coeff: Option<f64>,
    iterations: usize,
    pgs: usize,
) -> Chain {
    let mut w = PhysicsWorld::new();
    w.gravity = DVec3::new(0.0, 0.0, -9.81);
    w.integration_parameters.dt = 1e-3;
    w.integration_parameters.num_solver_iterations = iterations;
    w.integration_parameters.num_internal_pgs_iterations = pgs;
    w.integration_parameters.warmstart_joints = warm;
    let base = w.insert_body(RigidBodyBuilder::fixed());
    let half = 0.1;
    let mut parent = base;
    let mut parent_anchor = DVec3::ZERO;
    let mut joints = Vec::new();
    for k in 0..n {
        let m = if k + 1 == n { heavy } else { 1.0 };
        let centre = DVec3::new(0.0, 0.0, -((2 * k + 1) as f64) * half);
        let body = w.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(centre)
                .additional_mass_properties(MassProperties::new(
                    DVec3::ZERO,
                    m,
                    DVec3::splat(0.01 * m),
                ))
                .can_sleep(false),
        );
        let a2 = DVec3::new(0.0, 0.0, half);
        let j = SphericalJointBuilder::new()
            .local_anchor1(parent_anchor)
            .local_anchor2(a2)
            .contacts_enabled(false);
        let h = w.insert_impulse_joint(parent, body, j);
        joints.push((h, parent, body, parent_anchor, a2));
        parent = body;
        parent_anchor = DVec3::new(0.0, 0.0, -half);
    }
    Chain {
        world: w,
        ff: vec![DVec3::ZERO; joints.len()],
        joints,
        ff_coeff,
    }
}

impl Chain {
    /// One step; with the public-API warm start, last step's joint forces (scaled by the
    /// coefficient) are applied as external forces at the anchors, and the solver's stored
    /// impulses (now only the correction) are added to them afterwards.
    fn step(&mut self) {
        let Some(coeff) = self.ff_coeff else {
            self.world.step();
            return;
        };
        let bodies = &mut self.world.bodies;
        for (_, b) in bodies.iter_mut() {
            b.reset_forces(false);
        }
        for (f, (_, p, c, a1, a2)) in self.ff.iter().zip(&self.joints) {
            let x1 = bodies[*p].position().transform_point(*a1);
            let x2 = bodies[*c].position().transform_point(*a2);
            bodies[*p].add_force_at_point(*f, x1, false);
            bodies[*c].add_force_at_point(-*f, x2, false);
        }
        self.world.step();
        let h = self.world.integration_parameters.dt
            / self.world.integration_parameters.num_solver_iterations as f64;
        let b = &self.world.bodies;
        for (f, (jh, p, c, a1, a2)) in self.ff.iter_mut().zip(&self.joints) {
            let imp = self.world.impulse_joints.get(*jh).unwrap().impulses;
            let lam = spherical_impulse(&b[*p], &b[*c], *a1, *a2, &[imp[0], imp[1], imp[2]]);
            *f = (*f + lam / h) * coeff;
        }
    }
    fn gap(&self) -> f64 {
        let b = &self.world.bodies;
        self.joints
            .iter()
            .map(|(_, p, c, a1, a2)| {
                (b[*p].position().transform_point(*a1) - b[*c].position().transform_point(*a2))
                    .length()
            })
            .fold(0.0, f64::max)
    }
    /// Stored linear impulse of the first (top) joint, z component (N·s per substep).
    fn top_impulse(&self) -> f64 {
        let (h, ..) = self.joints[0];
        self.world.impulse_joints.get(h).unwrap().impulses[2]
    }
}

fn main() {
    let modes: [(&str, bool, Option<f64>); 4] = [
        ("off", false, None),
        ("warmstart_joints", true, None),
        ("force feed-forward ×1", false, Some(1.0)),
        ("force feed-forward ×0.5", false, Some(0.5)),
    ];
    println!("| bodies | last mass (kg) | iterations×PGS | warm start | gap after 1 step (µm) | after 10 | after 1000 | top joint impulses[2] after 1000 (N·s) |");
    println!("|---|---|---|---|---|---|---|---|");
    for (n, heavy) in [(1usize, 1.0), (3, 1.0), (3, 24.0), (6, 1.0)] {
        for (it, pgs) in [(1usize, 1usize), (4, 2)] {
            for (name, warm, ff) in modes {
                let mut c = chain(n, heavy, warm, ff, it, pgs);
                let mut g = [0.0; 3];
                for s in 1..=1000 {
                    c.step();
                    match s {
                        1 => g[0] = c.gap(),
                        10 => g[1] = c.gap(),
                        1000 => g[2] = c.gap(),
                        _ => {}
                    }
                }
                println!(
                    "| {n} | {heavy} | {it}×{pgs} | {name} | {:.4} | {:.4} | {:.4} | {:.6e} |",
                    g[0] * 1e6,
                    g[1] * 1e6,
                    g[2] * 1e6,
                    c.top_impulse()
                );
            }
        }
    }
}
