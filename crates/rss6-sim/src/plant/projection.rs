//! The plant's projections onto the mechanism: loop closure of positions after every rapier step
//! (mass-weighted), and the optional velocity projection with its symplectic position step
//! (`SolverConfig::velocity_projection`, docs/sim.md).

use super::{dv, RapierPhysics};
use rapier3d_f64::glamx::{DMat3, DQuat, DVec3};
use rapier3d_f64::prelude::*;
use rss6_core::{Vec6, LEGS};

/// Jacobian of the six loop equations with respect to (φ_1..φ_6, δp, δr).
pub(super) type LoopJacobian = ::nalgebra::SMatrix<f64, LEGS, 12>;

/// Where the mechanism is: platform pose, crank angles, link poses.
#[derive(Debug, Clone, Copy)]
pub(super) struct Configuration {
    pub(super) platform: Pose,
    pub(super) phi: [f64; LEGS],
    pub(super) links: [Pose; LEGS],
}

impl RapierPhysics {
    /// The six loop-closure equations g_i = |A_i − T_i| − ℓ_i and their Jacobian with respect to
    /// (φ_1..φ_6, δp, δr): wrench angles about their axes, platform translation and small rotation
    /// (world frame), for wrench angles `phi` and platform pose (`p`, `q`).
    fn loop_equations(&self, phi: &[f64; LEGS], p: DVec3, q: DQuat) -> ([f64; LEGS], LoopJacobian) {
        let mut g = [0.0; LEGS];
        let mut jac = LoopJacobian::zeros();
        for (i, leg) in self.legs.iter().enumerate() {
            let b = dv(&self.kp.base_joints[i]);
            let lw = self.kp.wrench_lengths[i];
            let arm = lw * DVec3::new(phi[i].cos(), phi[i].sin(), 0.0);
            let r_a = q * leg.a_in_platform;
            let d = p + r_a - (b + arm);
            let len = d.length();
            let u = if len > 0.0 { d / len } else { DVec3::Z };
            g[i] = len - 2.0 * leg.half_link;
            jac[(i, i)] = -u.dot(DVec3::Z.cross(arm));
            let ru = r_a.cross(u);
            for k in 0..3 {
                jac[(i, LEGS + k)] = u[k];
                jac[(i, LEGS + 3 + k)] = ru[k];
            }
        }
        (g, jac)
    }

    /// The mass-weighted minimum-norm correction δ = −W⁻¹Jᵀ(JW⁻¹Jᵀ)⁻¹r that zeroes J·δ + r.
    fn weighted_correction(
        &self,
        jac: &LoopJacobian,
        r: &[f64; LEGS],
        w_rot: &DMat3,
    ) -> Option<[f64; 12]> {
        let mut wjt = jac.transpose(); // 12 × 6, becomes W⁻¹Jᵀ
        for c in 0..LEGS {
            for i in 0..LEGS {
                wjt[(i, c)] *= self.inv_wrench_inertia[i];
            }
            for k in 0..3 {
                wjt[(LEGS + k, c)] *= self.inv_platform_mass;
            }
            let w = DVec3::new(wjt[(9, c)], wjt[(10, c)], wjt[(11, c)]);
            let w = *w_rot * w;
            for k in 0..3 {
                wjt[(9 + k, c)] = w[k];
            }
        }
        let a = jac * wjt;
        let chol = a.cholesky()?;
        let lambda = chol.solve(&Vec6::from_column_slice(r));
        let delta = -(wjt * lambda);
        let mut out = [0.0; 12];
        out.copy_from_slice(delta.as_slice());
        Some(out)
    }

    /// Post-step projection of the positions onto the loop constraints (post-stabilisation, as in
    /// Cline & Pai 2003). The wrenches are put back on their revolute axes; the wrench angles and
    /// the platform pose move by the smallest mass-weighted step that makes every |A_i − T_i| equal
    /// its link length (Newton, at most 4 iterations, to 1e-13 m); each link is then set exactly
    /// between its two joints and its angular velocity turned with it (its spin about its own axis
    /// kept). Velocities are otherwise left as the solver made them (projecting them too with this
    /// lumped metric made the plant–twin agreement worse). Uses only the bodies' joint anchors, not
    /// the analytic model.
    pub(super) fn project(&mut self) {
        if self.legs.len() != LEGS {
            return;
        }
        let mut phi = [0.0; LEGS];
        for (i, leg) in self.legs.iter().enumerate() {
            let x = self.world.bodies[leg.wrench].rotation() * DVec3::X;
            phi[i] = x.y.atan2(x.x);
        }
        let pb = &self.world.bodies[self.platform];
        let mut p = pb.translation();
        let mut q = *pb.rotation();
        for _ in 0..4 {
            let (g, jac) = self.loop_equations(&phi, p, q);
            if g.iter().all(|e| e.abs() < 1e-13) {
                break;
            }
            let r = DMat3::from_quat(q);
            let inv_inertia = (r * self.platform_inertia * r.transpose()).inverse();
            let Some(d) = self.weighted_correction(&jac, &g, &inv_inertia) else {
                return;
            };
            for (f, di) in phi.iter_mut().zip(d) {
                *f += di;
            }
            p += DVec3::new(d[6], d[7], d[8]);
            q = (DQuat::from_scaled_axis(DVec3::new(d[9], d[10], d[11])) * q).normalize();
        }

        let bodies = &mut self.world.bodies;
        bodies[self.platform].set_position(Pose::from_parts(p, q), false);
        for (i, leg) in self.legs.iter().enumerate() {
            let b = dv(&self.kp.base_joints[i]);
            let lw = self.kp.wrench_lengths[i];
            let dir = DVec3::new(phi[i].cos(), phi[i].sin(), 0.0);
            let t = b + lw * dir;
            bodies[leg.wrench].set_position(
                Pose::from_parts(b + 0.5 * lw * dir, DQuat::from_rotation_z(phi[i])),
                false,
            );
            let a = p + q * leg.a_in_platform;
            let d = a - t;
            if d.length() <= 0.0 {
                continue;
            }
            let link = &mut bodies[leg.link];
            let q_old = *link.rotation();
            let turn = DQuat::from_rotation_arc(q_old * DVec3::Z, d.normalize());
            link.set_position(
                Pose::from_parts(0.5 * (t + a), (turn * q_old).normalize()),
                false,
            );
            // Turn the angular velocity with the body, so the spin about the link axis is kept
            // (otherwise each step moves a little of the swing rate into the spin).
            let w = turn * link.angvel();
            link.set_angvel(w, false);
        }
    }

    /// Replaces every body's velocity by the mass-weighted (M-orthogonal) projection of rapier's
    /// end-of-step velocities onto the mechanism's 6 degrees of freedom at the configuration `at`
    /// before the step (the platform twist; each link keeps its spin about its own axis; spherical
    /// T joints only). By Gauss's principle the solver's unconverged or stabilising impulses, which
    /// lie in the constraint directions, drop out. Geometry, masses and inertias are rapier's own
    /// (no model code). With [`Self::integrate_positions`] the step becomes one symplectic-Euler
    /// step of the mechanism with rapier's forces (see `SolverConfig::velocity_projection`).
    pub(super) fn project_velocities(&mut self, at: &Configuration) {
        if self.legs.len() != LEGS {
            return;
        }
        let bodies = &self.world.bodies;
        let pb = &bodies[self.platform];
        let e = at.platform.translation;
        let q = at.platform.rotation;
        let com = |rb: &RigidBody, pose: &Pose| {
            pose.transform_point(rb.mass_properties().local_mprops.local_com)
        };
        // Per body: COM, the velocity map of each unit twist (linear at COM, angular), mass,
        // world inertia, rapier's velocity.
        struct Body {
            lin: [DVec3; 6],
            ang: [DVec3; 6],
            mass: f64,
            inertia: DMat3,
            u_lin: DVec3,
            u_ang: DVec3,
            /// Link axis (unit) whose spin is kept, or zero.
            axis: DVec3,
        }
        let unit = |j: usize| -> (DVec3, DVec3) {
            let mut ve = DVec3::ZERO;
            let mut w = DVec3::ZERO;
            if j < 3 {
                ve[j] = 1.0;
            } else {
                w[j - 3] = 1.0;
            }
            (ve, w)
        };
        let world_inertia = |rb: &RigidBody, rot: DQuat| {
            let r = DMat3::from_quat(rot);
            r * rb
                .mass_properties()
                .local_mprops
                .reconstruct_inertia_matrix()
                * r.transpose()
        };
        let mut list: Vec<Body> = Vec::with_capacity(1 + 2 * LEGS);
        let c_p = com(pb, &at.platform);
        let mut plat = Body {
            lin: [DVec3::ZERO; 6],
            ang: [DVec3::ZERO; 6],
            mass: pb.mass(),
            inertia: world_inertia(pb, q),
            u_lin: pb.linvel(),
            u_ang: pb.angvel(),
            axis: DVec3::ZERO,
        };
        for j in 0..6 {
            let (ve, w) = unit(j);
            plat.lin[j] = ve + w.cross(c_p - e);
            plat.ang[j] = w;
        }
        list.push(plat);
        for (i, leg) in self.legs.iter().enumerate() {
            let b = dv(&self.kp.base_joints[i]);
            let wb = &bodies[leg.wrench];
            let lb = &bodies[leg.link];
            let wrench_pose = Pose::from_parts(
                dv(&self.kp.base_joints[i])
                    + 0.5
                        * self.kp.wrench_lengths[i]
                        * DVec3::new(at.phi[i].cos(), at.phi[i].sin(), 0.0),
                DQuat::from_rotation_z(at.phi[i]),
            );
            let t = wrench_pose.transform_point(leg.t_in_wrench);
            let a = e + q * leg.a_in_platform;
            let d = a - t;
            let n = DVec3::Z.cross(t - b);
            let denom = n.dot(d);
            if denom.abs() < 1e-12 * d.length_squared() || d.length_squared() <= 0.0 {
                return; // a singular leg: leave rapier's velocities
            }
            let c_w = com(wb, &wrench_pose);
            let c_l = com(lb, &at.links[i]);
            let mut wr = Body {
                lin: [DVec3::ZERO; 6],
                ang: [DVec3::ZERO; 6],
                mass: wb.mass(),
                inertia: world_inertia(wb, wrench_pose.rotation),
                u_lin: wb.linvel(),
                u_ang: wb.angvel(),
                axis: DVec3::ZERO,
            };
            let mut li = Body {
                lin: [DVec3::ZERO; 6],
                ang: [DVec3::ZERO; 6],
                mass: lb.mass(),
                inertia: world_inertia(lb, at.links[i].rotation),
                u_lin: lb.linvel(),
                u_ang: lb.angvel(),
                axis: d.normalize(),
            };
            for j in 0..6 {
                let (ve, w) = unit(j);
                let v_a = ve + w.cross(a - e);
                let rate = v_a.dot(d) / denom;
                wr.ang[j] = DVec3::Z * rate;
                wr.lin[j] = (DVec3::Z * rate).cross(c_w - b);
                let v_t = n * rate;
                let w_l = d.cross(v_a - v_t) / d.length_squared();
                li.ang[j] = w_l;
                li.lin[j] = v_t + w_l.cross(c_l - t);
            }
            list.push(wr);
            list.push(li);
        }
        let mut g = nalgebra::Matrix6::<f64>::zeros();
        let mut h = nalgebra::Vector6::<f64>::zeros();
        let perp = |x: DVec3, axis: DVec3| x - axis * axis.dot(x);
        for bd in &list {
            let u_ang = perp(bd.u_ang, bd.axis);
            for j in 0..6 {
                let ij = bd.inertia * perp(bd.ang[j], bd.axis);
                h[j] += bd.mass * bd.lin[j].dot(bd.u_lin) + ij.dot(u_ang);
                for k in 0..6 {
                    g[(j, k)] +=
                        bd.mass * bd.lin[j].dot(bd.lin[k]) + ij.dot(perp(bd.ang[k], bd.axis));
                }
            }
        }
        let Some(v) = g.cholesky().map(|c| c.solve(&h)) else {
            return;
        };
        if !v.iter().all(|x| x.is_finite()) {
            return;
        }
        let handles: Vec<RigidBodyHandle> = std::iter::once(self.platform)
            .chain(self.legs.iter().flat_map(|l| [l.wrench, l.link]))
            .collect();
        for (bd, hnd) in list.iter().zip(handles) {
            let mut lin = DVec3::ZERO;
            let mut ang = bd.axis * bd.axis.dot(bd.u_ang);
            for j in 0..6 {
                lin += bd.lin[j] * v[j];
                ang += bd.ang[j] * v[j];
            }
            let rb = &mut self.world.bodies[hnd];
            rb.set_linvel(lin, false);
            rb.set_angvel(ang, false);
        }
    }

    /// Platform pose, crank angles φ (rad, about +z at B_i) and link poses.
    pub(super) fn configuration(&self) -> Configuration {
        let mut c = Configuration {
            platform: *self.world.bodies[self.platform].position(),
            phi: [0.0; LEGS],
            links: [Pose::IDENTITY; LEGS],
        };
        for (i, leg) in self.legs.iter().enumerate() {
            let x = self.world.bodies[leg.wrench].rotation() * DVec3::X;
            c.phi[i] = x.y.atan2(x.x);
            c.links[i] = *self.world.bodies[leg.link].position();
        }
        c
    }

    /// Positions from the configuration before the step and the projected velocities (symplectic
    /// Euler on the mechanism: the engine integrated its unconverged velocities), then the loops
    /// closed again.
    pub(super) fn integrate_positions(&mut self, before: &Configuration) {
        if self.legs.len() != LEGS {
            return;
        }
        let dt = self.world.integration_parameters.dt;
        let (pose0, phi0) = (&before.platform, &before.phi);
        let pb = &self.world.bodies[self.platform];
        // Velocity of the body origin E (rapier's linvel is the COM's).
        let e = pb.translation();
        let w = pb.angvel();
        let v_e = pb.linvel() + w.cross(e - pb.center_of_mass());
        let p = pose0.translation + v_e * dt;
        let q = (DQuat::from_scaled_axis(w * dt) * pose0.rotation).normalize();
        self.world.bodies[self.platform].set_position(Pose::from_parts(p, q), false);
        for (i, leg) in self.legs.iter().enumerate() {
            let wb = &mut self.world.bodies[leg.wrench];
            let phi = phi0[i] + wb.angvel().z * dt;
            wb.set_rotation(DQuat::from_rotation_z(phi), false);
        }
        self.project();
    }
}
