//! Property tests (proptest) of the dynamics round trips and identities over the workspace box
//! (±20 mm, ±0.05 rad around home), arbitrary rates, accelerations, torques and parameters.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use proptest::prelude::*;
use rss6_core::*;

fn vec6(lin: f64, ang: f64) -> impl Strategy<Value = Vec6> {
    (
        -lin..=lin,
        -lin..=lin,
        -lin..=lin,
        -ang..=ang,
        -ang..=ang,
        -ang..=ang,
    )
        .prop_map(|(a, b, c, d, e, f)| Vec6::new(a, b, c, d, e, f))
}

fn pose() -> impl Strategy<Value = Vec6> {
    vec6(0.02, 0.05).prop_map(|d| home_pose() + d)
}

/// Ξ scaled entry-wise by 0.5..1.5 around Table 5.1, friction in [0, 0.5].
fn params() -> impl Strategy<Value = DynamicParams> {
    (
        proptest::collection::vec(0.5f64..1.5, 52),
        proptest::collection::vec(0.0f64..0.5, 12),
    )
        .prop_map(|(s, f)| {
            let mut x = DynamicParams::nominal().to_vector();
            for (v, k) in x.iter_mut().zip(s.iter()) {
                *v *= k;
            }
            for (v, k) in x.iter_mut().skip(52).zip(f.iter()) {
                *v = *k;
            }
            DynamicParams::from_vector(&x)
        })
}

/// A physical load: 0.1–5 kg, centre of mass within ±0.1 m of E, inertia A Aᵀ (SPD, full).
fn load() -> impl Strategy<Value = PlatformLoad> {
    (
        0.1f64..5.0,
        vec6(0.1, 0.1),
        proptest::array::uniform9(-0.05f64..0.05),
    )
        .prop_map(|(m, c, a)| {
            let a = Mat3::from_column_slice(&a);
            PlatformLoad::new(m, Vec3::new(c[0], c[1], c[2]), a * a.transpose())
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn rate_dependent_torques_are_the_two_calls_bit_for_bit(
        p in pose(), pd in vec6(0.2, 1.0), tau in vec6(5.0, 5.0), dp in params(), l in load(),
        eps in prop_oneof![Just(1e-3), 1e-4..1.0f64]
    ) {
        // The smoothed Coulomb law as the twin and CLOE apply it, with and without a load.
        let kp = KinematicParams::nominal();
        let law = |td: &Vec6| Vec6::from_fn(|i, _| tau[i] - dp.coulomb[i] * (td[i] / eps).tanh());
        for env in [Environment::default(), Environment::default().with_load(l)] {
            let two = forward_dynamics_with_env(
                &kp, &dp, &p, &pd, &law(&(jacobian_theta(&kp, &p).unwrap() * pd)), &env,
            ).unwrap();
            let one = forward_dynamics_by_joint_rates(&kp, &dp, &p, &pd, &env, law).unwrap();
            prop_assert_eq!(one, two);
            // From the angles of an IK of the pose (no IK): the same bits.
            let theta = ik(&kp, &p).unwrap();
            let from =
                forward_dynamics_by_joint_rates_from(&kp, &dp, &p, &pd, &env, Some(&theta), law);
            prop_assert_eq!(from.unwrap(), two);
            // Angles of another pose (the legs do not close) are refused, not used.
            let mut other = p;
            other[2] += 0.01;
            let stale = ik(&kp, &other).unwrap();
            let r = forward_dynamics_by_joint_rates_from(&kp, &dp, &p, &pd, &env, Some(&stale), law);
            prop_assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{:?}", r);
        }
    }

    #[test]
    fn inverse_of_forward_is_identity_with_load(
        p in pose(), pd in vec6(0.2, 1.0), dtau in vec6(5.0, 5.0), dp in params(), l in load()
    ) {
        let kp = KinematicParams::nominal();
        let env = Environment::default().with_load(l);
        let z = Vec6::zeros();
        let tau = inverse_dynamics_with_env(&kp, &dp, &p, &z, &z, &env).unwrap() + dtau;
        let acc = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau, &env).unwrap();
        let back = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &acc, &env).unwrap();
        prop_assert!((back - tau).amax() <= 1e-10 * tau.amax(), "{} vs {}", back, tau);
    }

    #[test]
    fn mass_matrix_with_load_is_spd(p in pose(), pd in vec6(0.2, 1.0), dp in params(), l in load()) {
        let kp = KinematicParams::nominal();
        let env = Environment::default().with_load(l);
        let m = mass_matrix_with_env(&kp, &dp, &p, &env).unwrap();
        prop_assert!((m - m.transpose()).amax() <= 1e-14 * m.amax());
        prop_assert!(m.cholesky().is_some());
        prop_assert!(kinetic_energy_with_env(&kp, &dp, &p, &pd, &env).unwrap()
            >= kinetic_energy(&kp, &dp, &p, &pd).unwrap() - 1e-15);
    }

    #[test]
    fn inverse_of_forward_is_identity(
        p in pose(), pd in vec6(0.2, 1.0), dtau in vec6(5.0, 5.0), dp in params()
    ) {
        let kp = KinematicParams::nominal();
        let tau = inverse_dynamics(&kp, &dp, &p, &Vec6::zeros(), &Vec6::zeros()).unwrap() + dtau;
        let acc = forward_dynamics(&kp, &dp, &p, &pd, &tau).unwrap();
        let back = inverse_dynamics(&kp, &dp, &p, &pd, &acc).unwrap();
        prop_assert!((back - tau).amax() <= 1e-10 * tau.amax(), "{} vs {}", back, tau);
    }

    #[test]
    fn regressor_is_linear_form_of_inverse_dynamics(
        p in pose(), pd in vec6(0.2, 1.0), pdd in vec6(2.0, 10.0), dp in params()
    ) {
        let kp = KinematicParams::nominal();
        let xi = nalgebra::SVector::<f64, 64>::from_column_slice(&dp.to_vector());
        let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let gamma = regressor(&kp, &p, &pd, &pdd).unwrap();
        prop_assert!((gamma * xi - tau).amax() <= 1e-10 * tau.amax().max(1.0));
    }

    #[test]
    fn mass_matrix_is_spd_and_energy_positive(p in pose(), pd in vec6(0.2, 1.0), dp in params()) {
        let kp = KinematicParams::nominal();
        let m = mass_matrix(&kp, &dp, &p).unwrap();
        prop_assert!((m - m.transpose()).amax() <= 1e-14 * m.amax());
        prop_assert!(m.cholesky().is_some());
        let t = kinetic_energy(&kp, &dp, &p, &pd).unwrap();
        prop_assert!(t >= 0.0);
    }

    #[test]
    fn coriolis_matrix_is_skew_against_mdot(p in pose(), pd in vec6(0.2, 1.0), x in vec6(1.0, 1.0)) {
        // xᵀ C̃ x = ½ xᵀ Ṁ̃ x, Ṁ̃ by a 4th-order central difference along χ̇
        let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
        let m = |t: f64| mass_matrix(&kp, &dp, &(p + pd * t)).unwrap();
        let h = 1e-4;
        let m_dot = ((m(h) - m(-h)) * 8.0 - (m(2.0 * h) - m(-2.0 * h))) / (12.0 * h);
        let c = coriolis(&kp, &dp, &p, &pd).unwrap();
        let xa = x.abs();
        let scale = xa.dot(&((m_dot.abs() + c.abs() * 2.0) * xa));
        prop_assert!((x.dot(&(m_dot * x)) - 2.0 * x.dot(&(c * x))).abs() <= 1e-9 * scale);
    }

    #[test]
    fn forward_dynamics_state_jacobians_from_the_inverse_dynamics_derivatives(
        p in pose(), pd in vec6(0.2, 1.0), tau in vec6(5.0, 5.0), dp in params()
    ) {
        // ∂χ̈/∂x = −M̃⁻¹J_θᵀ ∂τ/∂x (implicit function theorem) against central differences of the
        // forward dynamics itself (Coulomb off: its sign is held in one and not the other).
        let kp = KinematicParams::nominal();
        let mut dp = dp;
        dp.coulomb = [0.0; 6];
        let env = Environment::default();
        let a = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau, &env).unwrap();
        let (dtp, dtv) =
            inverse_dynamics_derivatives_with_env(&kp, &dp, &p, &pd, &a, &env).unwrap();
        let ft = mass_matrix(&kp, &dp, &p).unwrap().cholesky().unwrap()
            .solve(&jacobian_theta(&kp, &p).unwrap().transpose());
        let (fp, fv) = (-(ft * dtp), -(ft * dtv));
        for k in 0..6 {
            let e = Vec6::from_fn(|i, _| if i == k { 1.0 } else { 0.0 });
            let f = |x: &Vec6, v: &Vec6| forward_dynamics_with_env(&kp, &dp, x, v, &tau, &env).unwrap();
            let cp = (f(&(p + e * 1e-6), &pd) - f(&(p - e * 1e-6), &pd)) / 2e-6;
            let cv = (f(&p, &(pd + e * 1e-2)) - f(&p, &(pd - e * 1e-2))) / 2e-2;
            let ep = (fp.column(k) - cp).amax() / cp.amax().max(1.0);
            let ev = (fv.column(k) - cv).amax() / cv.amax().max(1.0);
            prop_assert!(ep <= STATE_JACOBIAN_TOL && ev <= STATE_JACOBIAN_TOL, "column {k}: {ep:.2e} {ev:.2e}");
        }
    }

    #[test]
    fn one_call_jacobians_equal_the_separate_calls(
        p in pose(), pd in vec6(0.2, 1.0), tau in vec6(5.0, 5.0), dp in params()
    ) {
        // forward_dynamics_jacobians_with_env against forward dynamics, J_θ, M̃⁻¹J_θᵀ, the regressor
        // and the inverse-dynamics derivatives called one by one, and its rate derivative against
        // central differences of J_ad(χ)ν.
        let kp = KinematicParams::nominal();
        let env = Environment::default();
        let h = 1e-3;
        let req = JacobianRequest { state: true, rate_step: Some(h), ..JacobianRequest::default() };
        let mut fj = ForwardJacobians::default();
        forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &req, &mut fj).unwrap();
        let a = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau, &env).unwrap();
        prop_assert_eq!(fj.pose_ddot, a);
        let j = jacobian_theta(&kp, &p).unwrap();
        let ft = mass_matrix(&kp, &dp, &p).unwrap().cholesky().unwrap().solve(&j.transpose());
        let gamma = regressor(&kp, &p, &pd, &a).unwrap();
        let (dtp, dtv) =
            inverse_dynamics_derivatives_with_env(&kp, &dp, &p, &pd, &a, &env).unwrap();
        let (fp, fv) = fj.d_state.unwrap();
        let rel = |x: f64, scale: f64| x / scale.max(1e-300);
        let errs = [
            rel((fj.j_theta - j).amax(), j.amax()),
            rel((fj.d_torque - ft).amax(), ft.amax()),
            rel((fj.d_params + ft * gamma).amax(), (ft * gamma).amax()),
            rel((fp + ft * dtp).amax(), (ft * dtp).amax()),
            rel((fv + ft * dtv).amax(), (ft * dtv).amax()),
        ];
        let js = twist_jacobian(&p);
        let nu = js * pd + (js * a + twist_jacobian_dot(&p, &pd) * pd) * h;
        let mut cd = Mat6::zeros();
        for k in 0..6 {
            let e = Vec6::from_fn(|i, _| if i == k { 1e-6 } else { 0.0 });
            let jp = jacobian_ad(&kp, &(p + e)).unwrap();
            let jm = jacobian_ad(&kp, &(p - e)).unwrap();
            cd.set_column(k, &((jp - jm) * nu / 2e-6));
        }
        let er = rel((fj.d_rates.unwrap() - cd).amax(), cd.amax());
        prop_assert!(errs.iter().all(|&e| e <= ONE_CALL_TOL) && er <= RATE_TOL, "{errs:?} {er:.2e}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn one_sided_state_jacobians_and_masked_columns(
        p in pose(), pd in vec6(0.2, 1.0), tau in vec6(5.0, 5.0), dp in params(), mask in any::<u64>()
    ) {
        // The one-sided state Jacobians (the per-tick sensitivities' steps) against the exact
        // ones, and a column mask: the requested columns of ∂χ̈/∂Ξ equal the full call's bit for
        // bit, the others are zero.
        let kp = KinematicParams::nominal();
        let env = Environment::default();
        let exact = JacobianRequest { state: true, rate_step: Some(1e-3), ..JacobianRequest::default() };
        let one = JacobianRequest {
            one_sided_step: Some(1e-7), param_columns: mask, ..exact
        };
        let (mut fc, mut fo) = (ForwardJacobians::default(), ForwardJacobians::default());
        forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &exact, &mut fc).unwrap();
        forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &one, &mut fo).unwrap();
        let rel = |a: &Mat6, b: &Mat6| (a - b).amax() / b.amax().max(1e-300);
        let ((cp, cv), (op, ov)) = (fc.d_state.unwrap(), fo.d_state.unwrap());
        let errs = [rel(&op, &cp), rel(&ov, &cv), rel(&fo.d_rates.unwrap(), &fc.d_rates.unwrap())];
        prop_assert!(errs.iter().all(|&e| e <= ONE_SIDED_TOL), "{:.2e} {:.2e} {:.2e}", errs[0], errs[1], errs[2]);
        prop_assert_eq!(fo.pose_ddot, fc.pose_ddot);
        prop_assert_eq!(fo.d_torque, fc.d_torque);
        for c in 0..N_DYN {
            let want = if mask >> c & 1 == 1 { fc.d_params.column(c).into_owned() } else { Vec6::zeros() };
            prop_assert_eq!(fo.d_params.column(c).into_owned(), want, "column {}", c);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn known_angles_and_acceleration_change_no_bit(
        p in pose(), pd in vec6(0.2, 1.0), tau in vec6(5.0, 5.0), dp in params(), mask in any::<u64>()
    ) {
        // With θ = IK(χ) and χ̈ = the forward dynamics' given, every output is the one computed
        // without them, bit for bit: exact and one-sided state Jacobians, any column mask, and
        // without state Jacobians.
        let kp = KinematicParams::nominal();
        let env = Environment::default();
        let theta = ik(&kp, &p).unwrap();
        let a = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau, &env).unwrap();
        let bits = |f: &ForwardJacobians| format!("{:?}", (
            f.pose_ddot.map(f64::to_bits), f.j_theta.map(f64::to_bits), f.d_torque.map(f64::to_bits),
            f.d_params.map(f64::to_bits), f.d_state.map(|(x, y)| (x.map(f64::to_bits), y.map(f64::to_bits))),
            f.d_rates.map(|x| x.map(f64::to_bits)),
        ));
        for (state, one_sided) in [(true, None), (true, Some(1e-7)), (false, None)] {
            let plain = JacobianRequest {
                state, rate_step: Some(1e-3), one_sided_step: one_sided, param_columns: mask,
                ..JacobianRequest::default()
            };
            let known = JacobianRequest { theta: Some(theta), pose_ddot: Some(a), ..plain };
            let (mut f0, mut f1) = (ForwardJacobians::default(), ForwardJacobians::default());
            forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &plain, &mut f0).unwrap();
            forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &known, &mut f1).unwrap();
            prop_assert_eq!(bits(&f0), bits(&f1));
            prop_assert!(f0.d_params.amax() > 0.0 || mask & 0xf == 0);
        }
    }
}

/// Largest relative difference allowed between the one-sided state Jacobians (pose step 10⁻⁷) and
/// the exact ones (∂χ̈/∂χ, ∂χ̈/∂χ̇, the rates' pose derivative): worst measured 6.1·10⁻⁶ over the
/// 128 cases against the exact tangents (4.2·10⁻⁶ against central differences through the IK,
/// before them); ≈ 2.4× that.
const ONE_SIDED_TOL: f64 = 1.5e-5;

/// Largest relative difference allowed between the one-call derivatives and the separate calls
/// (the same quantities by other roundings, e.g. M̃⁻¹J_θᵀ = J_s⁻¹M⁻¹J_adᵀ): measured 5.6·10⁻¹⁵
/// over the 128 cases, in ∂χ̈/∂χ since the one call maps the force tangents by M̃⁻¹J_θᵀJ_adᵀ⁻¹
/// directly and takes the rigid torque from its forward dynamics (eighteenth session; 1.6·10⁻¹⁵
/// through J_adᵀ⁻¹ and a second Newton–Euler pass before); 3× that.
const ONE_CALL_TOL: f64 = 1.7e-14;

/// The same for the rate derivative (the call's exact tangent) against central differences of
/// J_ad(χ)ν through the IK: measured 8.6·10⁻¹⁰ over the 128 cases, the reference's own error
/// (rounding ε/h ≈ 2·10⁻¹⁰ at h = 10⁻⁶, amplified); 2.2·10⁻¹¹ when the call differenced through the
/// IK as the reference does. ≈ 3× the 8.6·10⁻¹⁰.
const RATE_TOL: f64 = 2.5e-9;

/// Largest relative difference allowed between the state Jacobians (exact tangents) and central
/// differences of the forward dynamics: measured 2.3·10⁻⁹ (χ columns, the reference's own error;
/// the χ̇ columns 3.7·10⁻¹³) over the 128 cases (2.5·10⁻⁹ and 6.4·10⁻¹³ when the call differenced
/// through the IK too); ≈ 3× the 2.5·10⁻⁹.
const STATE_JACOBIAN_TOL: f64 = 7.5e-9;
