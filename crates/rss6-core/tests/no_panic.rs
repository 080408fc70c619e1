//! No panic for any finite input: the public fallible functions of rss6-core (and the infallible ones
//! they are built from) driven with random finite values — zeros of both signs, negatives, ±1e300,
//! ±f64::MAX, subnormals, arbitrary normals, and plausible values near home so the deep paths run too.
//! A case fails only if a call panics (or `joint_friction_smooth` returns NaN); errors are fine.
//! 10 000 cases per block.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use rss6_core::*;

fn config() -> ProptestConfig {
    ProptestConfig::with_cases(10_000)
}

fn wild() -> impl Strategy<Value = f64> {
    use proptest::num::f64 as f;
    prop_oneof![
        4 => -2.0..2.0f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(1e300),
        1 => Just(-1e300),
        1 => Just(f64::MAX),
        1 => Just(f64::MIN),
        1 => Just(f64::MIN_POSITIVE),
        1 => Just(5e-324),
        1 => Just(-5e-324),
        3 => f::POSITIVE | f::NEGATIVE | f::NORMAL | f::SUBNORMAL | f::ZERO,
    ]
}

fn wild3() -> impl Strategy<Value = Vec3> {
    proptest::array::uniform3(wild()).prop_map(Vec3::from)
}

fn wild6() -> impl Strategy<Value = Vec6> {
    proptest::array::uniform6(wild()).prop_map(Vec6::from)
}

fn pose() -> impl Strategy<Value = Vec6> {
    prop_oneof![
        proptest::array::uniform6(-0.03..0.03f64).prop_map(|d| home_pose() + Vec6::from(d)),
        wild6(),
    ]
}

fn rate() -> impl Strategy<Value = Vec6> {
    prop_oneof![
        proptest::array::uniform6(-1.0..1.0f64).prop_map(Vec6::from),
        wild6()
    ]
}

fn gravity_vec() -> impl Strategy<Value = Vec3> {
    prop_oneof![Just(GRAVITY), wild3()]
}

fn kinematics() -> impl Strategy<Value = KinematicParams> {
    let errors = |s: BoxedStrategy<f64>| {
        proptest::collection::vec(s, N_KIN_ERRORS).prop_map(|b| {
            let mut a = [0.0; N_KIN_ERRORS];
            a.copy_from_slice(&b);
            KinematicParams::perturbed(&a)
        })
    };
    prop_oneof![
        Just(KinematicParams::nominal()),
        errors((-1e-3..1e-3f64).boxed()),
        errors(wild().boxed()),
    ]
}

fn dynamics() -> impl Strategy<Value = DynamicParams> {
    prop_oneof![
        Just(DynamicParams::nominal()),
        proptest::collection::vec(wild(), N_DYN).prop_map(|x| {
            let mut a = [0.0; N_DYN];
            a.copy_from_slice(&x);
            DynamicParams::from_vector(&a)
        }),
    ]
}

/// A load: the sim test's offset load, or wild mass, centre of mass and inertia entries.
fn load() -> impl Strategy<Value = PlatformLoad> {
    prop_oneof![
        Just(PlatformLoad::new(
            2.0,
            Vec3::new(0.05, 0.02, 0.03),
            Mat3::identity() * 2e-3
        )),
        (wild(), wild3(), proptest::array::uniform9(wild()))
            .prop_map(|(m, c, i)| { PlatformLoad::new(m, c, Mat3::from_column_slice(&i)) }),
    ]
}

fn environment() -> impl Strategy<Value = Environment> {
    (gravity_vec(), proptest::option::of(load())).prop_map(|(g, l)| Environment {
        gravity: g,
        load: l,
    })
}

fn fk_options() -> impl Strategy<Value = FkOptions> {
    prop_oneof![
        Just(FkOptions::default()),
        (wild(), wild(), 0u32..50).prop_map(|(eps_c, eps_p, max_iterations)| FkOptions {
            eps_c,
            eps_p,
            max_iterations
        }),
    ]
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn params(kp in kinematics(), dp in dynamics(), v in wild6(), reference in kinematics()) {
        let _ = kp.validate();
        let _ = dp.validate();
        let _ = (kp.theta_from_reading(&v), kp.reading_from_theta(&v), kp.errors_from(&reference));
        let _ = DynamicParams::from_vector(&dp.to_vector());
    }

    #[test]
    fn pose_functions(p in pose(), pd in rate(), pdd in rate(), q in pose(), a in wild(), b in wild()) {
        let _ = check_pose(&p);
        let _ = twist_jacobian_inverse(&p);
        let _ = (twist_jacobian(&p), twist_jacobian_dot(&p, &pd), twist(&p, &pd), twist_dot(&p, &pd, &pdd));
        let _ = (compose(&p, &q), pose_inverse(&p), pose_rotation(&p), rotation(a, b, a));
        let _ = euler_from_rotation(&pose_rotation(&p));
        let _ = (euler_rate_jacobian(a, b), euler_rate_jacobian_dot(a, b, a, b), wrap_angle(a));
        let _ = isometry_to_pose(&pose_to_isometry(&p));
    }

    #[test]
    fn inverse_kinematics(kp in kinematics(), p in pose(), leg in 0usize..8, a in wild3(), th in rate()) {
        let _ = ik(&kp, &p);
        let _ = ik_reading(&kp, &p);
        let _ = ik_leg(&kp, leg, &a);
        let _ = (platform_joints_in_base(&kp, &p), wrench_tips(&kp, &th));
    }

    #[test]
    fn forward_kinematics(kp in kinematics(), th in rate(), guess in pose(), opts in fk_options()) {
        let _ = fk(&kp, &th, &guess, &opts);
        let _ = fk_theta_newton(&kp, &th, &guess, &opts);
    }

    #[test]
    fn jacobians(kp in kinematics(), p in pose(), pd in rate(), th in rate()) {
        let _ = (jacobian_a1(&kp, &p), jacobian_a2(&kp, &p), jacobian_ad(&kp, &p));
        let _ = jacobian_theta(&kp, &p);
        let _ = jacobian_stewart(&kp, &p, &wrench_tips(&kp, &th));
        let _ = leg_jacobians(&kp, &p, &pd);
        if let Ok(geo) = LegGeometry::at_pose(&kp, &p) {
            let _ = (geo.j_a1(), geo.j_a2(), geo.j_ad(), geo.j_theta());
            let _ = leg_jacobians_from_geometry(&geo, &pd);
            let _ = (type_i_check(&geo), type_ii_check(&geo), homeomorphism_check(&geo));
        }
        let geo = LegGeometry::from_pose_and_theta(&kp, &p, &th);
        let _ = (geo.j_ad(), type_ii_check(&geo), homeomorphism_check(&geo));
        let _ = singularity_check(&kp, &p);
    }

    #[test]
    fn dynamics_functions(kp in kinematics(), dp in dynamics(), p in pose(), pd in rate(),
                          pdd in rate(), g in gravity_vec(), eps in wild()) {
        let _ = (mass_matrix(&kp, &dp, &p), coriolis(&kp, &dp, &p, &pd), gravity(&kp, &dp, &p));
        let _ = (gravity_with(&kp, &dp, &p, &g), friction(&kp, &dp, &p, &pd));
        let _ = (mass_matrix_twist(&kp, &dp, &p), coriolis_twist(&kp, &dp, &p, &pd));
        let _ = (gravity_twist(&kp, &dp, &p, &g), friction_twist(&kp, &dp, &p, &pd));
        let _ = inverse_dynamics(&kp, &dp, &p, &pd, &pdd);
        let _ = inverse_dynamics_with_gravity(&kp, &dp, &p, &pd, &pdd, &g);
        let _ = forward_dynamics(&kp, &dp, &p, &pd, &pdd);
        let _ = forward_dynamics_with_gravity(&kp, &dp, &p, &pd, &pdd, &g);
        let _ = dynamics_terms(&kp, &dp, &p, &pd);
        let _ = dynamics_terms_with_gravity(&kp, &dp, &p, &pd, &g);
        let _ = kinetic_energy(&kp, &dp, &p, &pd);
        let _ = potential_energy_with_gravity(&kp, &dp, &p, &g);
        let _ = (platform_inertia(&pose_rotation(&p), &dp.platform), joint_friction(&dp, &pd));
        let _ = (wrench_axial_inertia(&dp.wrenches[0]), link_transverse_inertia(&dp.links[0]));
        // Moderate parameters and rates never give a NaN friction, whatever ε (ε ≤ 0: the sign).
        let moderate = dp.to_vector().iter().all(|x| x.abs() <= 1e150) && pd.amax() <= 1e150;
        let f = joint_friction_smooth(&dp, &pd, eps);
        prop_assert!(!moderate || f.iter().all(|x| !x.is_nan()), "{f} at eps = {eps}");
    }

    #[test]
    fn dynamics_with_env(kp in kinematics(), dp in dynamics(), p in pose(), pd in rate(),
                         pdd in rate(), env in environment(), l in load(), h in wild(), k in wild()) {
        let _ = l.validate();
        let _ = (l.inertia_about_e(), PlatformLoad::point(l.mass, l.com));
        let _ = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &pdd, &env);
        let _ = inverse_dynamics_derivatives_with_env(&kp, &dp, &p, &pd, &pdd, &env);
        let _ = forward_dynamics_with_env(&kp, &dp, &p, &pd, &pdd, &env);
        // A rate-dependent torque, errors as the two calls give them.
        let two = jacobian_theta(&kp, &p).and_then(|j| {
            forward_dynamics_with_env(&kp, &dp, &p, &pd, &(pdd - j * pd), &env)
        });
        let one = forward_dynamics_by_joint_rates(&kp, &dp, &p, &pd, &env, |td| pdd - td);
        prop_assert_eq!(one.map(|a| a.map(f64::to_bits)), two.map(|a| a.map(f64::to_bits)));
        // From the angles of an IK of the pose: the same bits; from any angles: no panic.
        if let Ok(theta) = ik(&kp, &p) {
            let from = forward_dynamics_by_joint_rates_from(
                &kp, &dp, &p, &pd, &env, Some(&theta), |td| pdd - td);
            prop_assert_eq!(from.map(|a| a.map(f64::to_bits)), one.map(|a| a.map(f64::to_bits)));
        }
        let _ = forward_dynamics_by_joint_rates_from(&kp, &dp, &p, &pd, &env, Some(&pdd), |td| td * h);
        // Known angles and acceleration: any values, no panic.
        for (one_sided, known) in [(false, false), (true, false), (false, true)] {
            let req = JacobianRequest {
                state: true, rate_step: Some(h), one_sided_step: one_sided.then_some(h), param_columns: k.to_bits(),
                theta: known.then_some(pdd), pose_ddot: known.then_some(pd * h),
            };
            let mut fj = ForwardJacobians::default();
            let _ = forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &pdd, &env, &req, &mut fj);
        }
        let _ = mass_matrix_with_env(&kp, &dp, &p, &env);
        let _ = dynamics_terms_with_env(&kp, &dp, &p, &pd, &env);
        let _ = gravity_with_env(&kp, &dp, &p, &env);
        let _ = kinetic_energy_with_env(&kp, &dp, &p, &pd, &env);
        let _ = potential_energy_with_env(&kp, &dp, &p, &env);
    }

    #[test]
    fn integration(kp in kinematics(), dp in dynamics(), p in pose(), pd in rate(), tau in rate(),
                   dt in prop_oneof![1e-4..1e-2f64, wild()], g in gravity_vec()) {
        let s = ModelState { pose: p, pose_dot: pd };
        let _ = rk4_step(&kp, &dp, &s, &tau, dt);
        let _ = rk4_step_with_gravity(&kp, &dp, &ModelState::at_rest(&p), &tau, dt, &g);
    }

    #[test]
    fn integration_with_env(kp in kinematics(), dp in dynamics(), p in pose(), pd in rate(),
                            tau in rate(), dt in prop_oneof![1e-4..1e-2f64, wild()],
                            env in environment()) {
        let _ = rk4_step_with_env(&kp, &dp, &ModelState { pose: p, pose_dot: pd }, &tau, dt, &env);
    }

    #[test]
    fn implicit_friction_step(kp in kinematics(), dp in dynamics(), p in pose(), pd in rate(),
                              tau in rate(), dt in prop_oneof![1e-4..1e-2f64, wild()],
                              env in environment()) {
        if let Ok(f) = implicit_friction(&kp, &dp, &p, &pd, &tau, &env, dt) {
            // A returned step is finite and never more sweeps than its bound.
            prop_assert!(f.sweeps <= 400);
            prop_assert!(!f.exact || f.torque.iter().all(|x| x.is_finite()));
        }
        let s = ModelState { pose: p, pose_dot: pd };
        let theta = ik(&kp, &p).ok();
        let plain = rk4_step_implicit_friction(&kp, &dp, &s, &tau, dt, &env, theta.as_ref());
        let mut stages = 0;
        let observed = rk4_step_implicit_friction_observed(
            &kp, &dp, &s, &tau, dt, &env, theta.as_ref(), |_, _, _, _| stages += 1);
        // The same outcome, bit for bit (errors too); four stages observed when it succeeds.
        prop_assert_eq!(format!("{plain:?}"), format!("{observed:?}"));
        prop_assert!(observed.is_err() || stages == 4);
    }

    #[test]
    fn regressors(kp in kinematics(), p in pose(), pd in rate(), pdd in rate(), g in gravity_vec()) {
        let _ = regressor(&kp, &p, &pd, &pdd);
        let _ = regressor_with_gravity(&kp, &p, &pd, &pdd, &g);
        let _ = regressor_tau_g(&kp, &p, &pd, &pdd);
    }

    #[test]
    fn workspace_scans(kp in kinematics(), c in pose(), hw in wild6(), n in prop_oneof![Just(2u32), 0u32..40],
                       m in wild(), cond in wild(), h in wild()) {
        let bx = PoseBox { center: c, half_width: hw };
        let _ = (bx.contains(&c), bx.point(&hw));
        let limits = BoxLimits { min_type_i_margin: m, max_condition: cond, homeomorphism_c: h };
        // Only n = 2 runs a scan (64 poses); 0, 1 and ≥ 17 are refused; larger grids are checked by
        // tests/workspace.rs.
        let n = if n <= 2 { n } else { n.max(17) };
        let _ = scan_box(&kp, &bx, n, &limits);
        let _ = verify_box(&kp, &bx, n, &limits);
    }
}

/// `joint_friction_smooth` at ε = 0 is `joint_friction` (the sign), not 0/0 = NaN.
#[test]
fn smooth_friction_without_a_transition_is_the_sign() {
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.1; LEGS];
    dp.viscous = [0.2; LEGS];
    let rates = Vec6::new(0.0, -0.0, 1e-300, -2.0, 5e-324, 3.0);
    let f0 = joint_friction_smooth(&dp, &rates, 0.0);
    assert_eq!(f0, joint_friction(&dp, &rates));
    assert!(f0.iter().all(|x| x.is_finite()));
    assert_eq!(joint_friction_smooth(&dp, &rates, -1.0), f0);
    let tiny = joint_friction_smooth(&dp, &rates, f64::MIN_POSITIVE);
    assert!(tiny.iter().all(|x| x.is_finite()));
}
