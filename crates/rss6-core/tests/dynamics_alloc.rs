//! Zero heap allocations in the dynamics hot paths, counted by an instrumented `#[global_allocator]`.
//!
//! Runs without libtest (`harness = false` in Cargo.toml): the counter is process-wide, and libtest's own
//! threads allocate now and then (seen once under heavy load), which would make the count flaky.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use rss6_core::*;
use stats_alloc::{Region, StatsAlloc, INSTRUMENTED_SYSTEM};
use std::alloc::System;
use std::hint::black_box;

#[global_allocator]
static GLOBAL: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Runs `f` and returns the number of allocations (incl. reallocations) it made.
fn allocations(f: impl FnOnce()) -> usize {
    let region = Region::new(GLOBAL);
    f();
    let s = region.change();
    s.allocations + s.reallocations
}

fn dynamics_hot_paths_do_not_allocate() {
    assert!(
        allocations(|| drop(black_box(vec![1u8; 64]))) > 0,
        "allocation counter is not counting"
    );
    let kp = KinematicParams::perturbed(&[2e-4; N_KIN_ERRORS]);
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.2; 6];
    dp.viscous = [0.05; 6];
    let pose = Vec6::new(0.012, -0.015, 0.128, 0.03, -0.04, 0.02);
    let pose_dot = Vec6::new(0.1, -0.2, 0.05, 0.3, 0.1, -0.2);
    let pose_ddot = Vec6::new(1.0, 0.5, -0.3, -2.0, 1.0, 0.4);
    let g_tilt = Vec3::new(0.1, 0.0, -9.8);
    let mut sink = 0.0;
    let n = allocations(|| {
        for _ in 0..5 {
            let p = black_box(&pose);
            sink += mass_matrix(&kp, &dp, p).unwrap()[(0, 0)];
            sink += coriolis(&kp, &dp, p, &pose_dot).unwrap()[(1, 2)];
            sink += gravity(&kp, &dp, p).unwrap()[2];
            sink += gravity_with(&kp, &dp, p, &g_tilt).unwrap()[2];
            sink += friction(&kp, &dp, p, &pose_dot).unwrap()[3];
            let tau = inverse_dynamics(&kp, &dp, p, &pose_dot, &pose_ddot).unwrap();
            sink += tau[0];
            sink += inverse_dynamics_with_gravity(&kp, &dp, p, &pose_dot, &pose_ddot, &g_tilt)
                .unwrap()[1];
            sink += forward_dynamics(&kp, &dp, p, &pose_dot, &tau).unwrap()[4];
            sink +=
                forward_dynamics_with_gravity(&kp, &dp, p, &pose_dot, &tau, &g_tilt).unwrap()[4];
            let t = dynamics_terms(&kp, &dp, p, &pose_dot).unwrap();
            sink += t.m[(2, 2)] + t.c[(0, 1)] + t.g[2] + t.f[0] + t.j_theta[(0, 0)];
            sink += regressor(&kp, p, &pose_dot, &pose_ddot).unwrap()[(0, 4)];
            let req = JacobianRequest {
                state: true,
                rate_step: Some(1e-3),
                ..JacobianRequest::default()
            };
            let env = Environment::default();
            let mut fj = ForwardJacobians::default();
            forward_dynamics_jacobians_with_env(&kp, &dp, p, &pose_dot, &tau, &env, &req, &mut fj)
                .unwrap();
            sink += fj.d_params[(0, 4)] + fj.d_rates.unwrap()[(1, 1)];
            // The per-tick path: one-sided steps, a column mask.
            let one = JacobianRequest {
                one_sided_step: Some(1e-7),
                param_columns: 0x00ff_00ff,
                ..req
            };
            forward_dynamics_jacobians_with_env(&kp, &dp, p, &pose_dot, &tau, &env, &one, &mut fj)
                .unwrap();
            sink += fj.d_params[(0, 4)] + fj.d_state.unwrap().0[(1, 1)];
            sink += implicit_friction(&kp, &dp, p, &pose_dot, &tau, &env, 1e-3)
                .unwrap()
                .torque[0];
            sink += regressor_tau_g(&kp, p, &pose_dot, &pose_ddot).unwrap()[(2, 0)];
            let legs = leg_jacobians(&kp, p, &pose_dot).unwrap();
            sink += legs[3].j_b_dot[(4, 4)] + legs[2].j_a_dot[(0, 0)];
            let s = ModelState { pose: *p, pose_dot };
            sink += rk4_step(&kp, &dp, &s, &tau, 1e-3).unwrap().pose[0];
            sink += rk4_step_implicit_friction(&kp, &dp, &s, &tau, 1e-3, &env, None)
                .unwrap()
                .0
                .pose[1];
            let mut last = 0.0;
            sink += rk4_step_implicit_friction_observed(
                &kp,
                &dp,
                &s,
                &tau,
                1e-3,
                &env,
                None,
                |p, _, _, _| last = p[0],
            )
            .unwrap()
            .0
            .pose[1]
                + last;
            let theta = ik(&kp, p).unwrap();
            sink += forward_dynamics_by_joint_rates_from(
                &kp,
                &dp,
                p,
                &pose_dot,
                &env,
                Some(&theta),
                |td| tau - td,
            )
            .unwrap()[1];
            sink += forward_dynamics_by_joint_rates(&kp, &dp, p, &pose_dot, &env, |td| tau - td)
                .unwrap()[2];
            sink += kinetic_energy(&kp, &dp, p, &pose_dot).unwrap();
            sink += potential_energy_with_gravity(&kp, &dp, p, &GRAVITY).unwrap();
            sink += joint_friction_smooth(&dp, &pose_dot, 1e-3)[0];
            sink += mass_matrix_twist(&kp, &dp, p).unwrap()[(1, 1)];
            sink += coriolis_twist(&kp, &dp, p, &pose_dot).unwrap()[(3, 4)];
            sink += gravity_twist(&kp, &dp, p, &GRAVITY).unwrap()[2];
            sink += friction_twist(&kp, &dp, p, &pose_dot).unwrap()[0];
            sink += ModelState::at_rest(p).pose[2];
            // with a load fixed to the platform
            let env = Environment::with_gravity(g_tilt).with_load(PlatformLoad::new(
                2.0,
                Vec3::new(0.05, 0.02, 0.03),
                Mat3::identity() * 2e-3,
            ));
            sink += env.load.map_or(0.0, |l| l.inertia_about_e()[(0, 0)]);
            sink += env
                .load
                .map_or(Ok(()), |l| l.validate())
                .map_or(1.0, |_| 0.0);
            let tau_l =
                inverse_dynamics_with_env(&kp, &dp, p, &pose_dot, &pose_ddot, &env).unwrap();
            sink += tau_l[2];
            sink += forward_dynamics_with_env(&kp, &dp, p, &pose_dot, &tau_l, &env).unwrap()[1];
            sink += mass_matrix_with_env(&kp, &dp, p, &env).unwrap()[(3, 3)];
            let t = dynamics_terms_with_env(&kp, &dp, p, &pose_dot, &env).unwrap();
            sink += t.m[(2, 2)] + t.c[(0, 4)] + t.g[3];
            sink += gravity_with_env(&kp, &dp, p, &env).unwrap()[4];
            sink += rk4_step_with_env(&kp, &dp, &s, &tau_l, 1e-3, &env)
                .unwrap()
                .pose[1];
            sink += kinetic_energy_with_env(&kp, &dp, p, &pose_dot, &env).unwrap();
            sink += potential_energy_with_env(&kp, &dp, p, &env).unwrap();
            // error paths too
            let far = Vec6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0);
            sink += inverse_dynamics(&kp, &dp, &far, &pose_dot, &pose_ddot).map_or(1.0, |_| 0.0);
        }
    });
    black_box(sink);
    assert_eq!(n, 0, "dynamics hot paths allocated {n} times");
}

fn main() {
    dynamics_hot_paths_do_not_allocate();
    println!("test dynamics_hot_paths_do_not_allocate ... ok");
    println!("1 passed, 0 failed");
}
