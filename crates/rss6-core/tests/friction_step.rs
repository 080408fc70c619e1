//! The implicit friction step: sticks below f_c, obeys Coulomb + viscous friction when it slips,
//! and its predicted rates are those of the forward dynamics with the friction torque held.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::thesis::{TABLE_5_2_COULOMB, TABLE_5_2_VISCOUS};
use rss6_core::*;

const DT: f64 = 1e-3;

/// Table 5.2's friction in N·m (its drive unit taken as 40 N·m, as rss6-ident's truth does).
fn with_friction() -> DynamicParams {
    let mut dp = DynamicParams::nominal();
    for i in 0..LEGS {
        dp.coulomb[i] = TABLE_5_2_COULOMB[i] * 40.0;
        dp.viscous[i] = TABLE_5_2_VISCOUS[i] * 40.0;
    }
    dp
}

fn holding_torque(kp: &KinematicParams, dp: &DynamicParams, pose: &Vec6) -> Vec6 {
    let mut nf = *dp;
    nf.coulomb = [0.0; LEGS];
    nf.viscous = [0.0; LEGS];
    inverse_dynamics(kp, &nf, pose, &Vec6::zeros(), &Vec6::zeros()).unwrap()
}

#[test]
fn below_coulomb_every_joint_sticks() {
    let (kp, dp, pose) = (KinematicParams::nominal(), with_friction(), home_pose());
    let env = Environment::default();
    // The holding torque plus 90 % of f_c, alternating in sign.
    let tau = holding_torque(&kp, &dp, &pose)
        + Vec6::from_fn(|i, _| 0.9 * dp.coulomb[i] * if i % 2 == 0 { 1.0 } else { -1.0 });
    let f = implicit_friction(&kp, &dp, &pose, &Vec6::zeros(), &tau, &env, DT).unwrap();
    assert!(f.exact);
    assert_eq!(f.stuck, [true; LEGS], "{f:?}");
    assert_eq!(f.rate, Vec6::zeros());
    for i in 0..LEGS {
        assert!(f.torque[i].abs() <= dp.coulomb[i] * (1.0 + 1e-9));
    }
    // Held over the tick, τ_a − τ_f leaves the robot at rest: χ̈ = 0.
    let mut nf = dp;
    nf.coulomb = [0.0; LEGS];
    nf.viscous = [0.0; LEGS];
    let acc = forward_dynamics(&kp, &nf, &pose, &Vec6::zeros(), &(tau - f.torque)).unwrap();
    assert!(acc.amax() < 1e-9, "{acc}");
}

#[test]
fn a_slipping_joint_obeys_the_friction_law_and_the_dynamics() {
    let (kp, dp) = (KinematicParams::nominal(), with_friction());
    let pose = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03);
    let env = Environment::default();
    // Joint 1 pushed well past f_c, the others held.
    let mut tau = holding_torque(&kp, &dp, &pose);
    tau[0] += 4.0 * dp.coulomb[0];
    let f = implicit_friction(&kp, &dp, &pose, &Vec6::zeros(), &tau, &env, DT).unwrap();
    assert!(f.exact);
    assert!(!f.stuck[0] && f.rate[0] > 0.0, "{f:?}");
    let w = f.rate;
    for i in 0..LEGS {
        if f.stuck[i] {
            assert!(f.torque[i].abs() <= dp.coulomb[i] * (1.0 + 1e-9));
        } else {
            let law = dp.coulomb[i] * w[i].signum() + dp.viscous[i] * w[i];
            assert!(
                (f.torque[i] - law).abs() < 1e-9 * dp.coulomb[i],
                "joint {i}"
            );
        }
    }
    // From rest, w = dt J_θ χ̈ with χ̈ the forward dynamics of τ_a − τ_f (an independent path).
    let mut nf = dp;
    nf.coulomb = [0.0; LEGS];
    nf.viscous = [0.0; LEGS];
    let acc = forward_dynamics(&kp, &nf, &pose, &Vec6::zeros(), &(tau - f.torque)).unwrap();
    let w_fd = jacobian_theta(&kp, &pose).unwrap() * acc * DT;
    assert!(
        (w - w_fd).amax() < 1e-12 * (1.0 + w.amax()),
        "{w} vs {w_fd}"
    );
}

#[test]
fn bad_input_is_a_typed_error() {
    let (kp, dp, pose) = (KinematicParams::nominal(), with_friction(), home_pose());
    let env = Environment::default();
    let z = Vec6::zeros();
    assert!(matches!(
        implicit_friction(&kp, &dp, &pose, &z, &z, &env, 0.0),
        Err(CoreError::InvalidParameter(_))
    ));
    let nan = Vec6::from_element(f64::NAN);
    assert_eq!(
        implicit_friction(&kp, &dp, &pose, &nan, &z, &env, DT),
        Err(CoreError::NonFinite)
    );
}

/// The one-call tick equals `implicit_friction` then RK4 of the friction-free model, bit for bit,
/// with and without the angles of the last IK, while joints slip, stick and reverse; its observed
/// variant reports the four stage states the two calls' RK4 evaluates, with their IK angles and
/// accelerations.
#[test]
fn the_one_call_tick_is_the_two_calls_bit_for_bit() {
    let (kp, dp) = (KinematicParams::nominal(), with_friction());
    let mut nf = dp;
    nf.coulomb = [0.0; LEGS];
    nf.viscous = [0.0; LEGS];
    let env = Environment::with_gravity(Vec3::new(0.3, -0.2, -9.8));
    let start = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03);
    let mut s = ModelState::at_rest(&start);
    let hold = holding_torque(&kp, &dp, &start);
    let (mut stuck, mut slipping) = (0, 0);
    for k in 0..400 {
        // A torque that pushes each joint past f_c and back below it.
        let phase = k as f64 * 0.03;
        let tau = hold + Vec6::from_fn(|i, _| 2.0 * dp.coulomb[i] * (phase + i as f64).sin());
        let f = implicit_friction(&kp, &dp, &s.pose, &s.pose_dot, &tau, &env, DT).unwrap();
        let two = rk4_step_with_env(&kp, &nf, &s, &(tau - f.torque), DT, &env).unwrap();
        let theta = ik(&kp, &s.pose).unwrap();
        for known in [None, Some(&theta)] {
            let (one, g) = rk4_step_implicit_friction(&kp, &dp, &s, &tau, DT, &env, known).unwrap();
            assert_eq!(one, two, "tick {k}");
            assert_eq!(g, f, "tick {k}");
            // The observed variant: the same step, and the four stage states at which the two
            // calls' RK4 evaluates the friction-free model.
            // Each stage's IK angles and acceleration too: IK's and the forward dynamics', bit for
            // bit.
            let mut seen = Vec::new();
            let (obs, h) = rk4_step_implicit_friction_observed(
                &kp,
                &dp,
                &s,
                &tau,
                DT,
                &env,
                known,
                |p, v, th, a| seen.push([*p, *v, *th, *a].map(|x| x.map(f64::to_bits))),
            )
            .unwrap();
            assert_eq!((obs, h), (one, g), "tick {k}");
            let mut at = Vec::new();
            rk4_step_by(&s, DT, |p, v| {
                let a = forward_dynamics_with_env(&kp, &nf, p, v, &(tau - f.torque), &env)?;
                at.push([*p, *v, ik(&kp, p)?, a].map(|x| x.map(f64::to_bits)));
                Ok(a)
            })
            .unwrap();
            assert_eq!(seen, at, "tick {k}");
        }
        stuck += f.stuck.iter().filter(|&&b| b).count();
        slipping += f.stuck.iter().filter(|&&b| !b).count();
        s = two;
    }
    // Both regimes were exercised.
    assert!(
        stuck > 100 && slipping > 100,
        "{stuck} stuck, {slipping} slipping"
    );
    // Angles of an earlier pose (the start, 400 ticks back) are refused, not stepped.
    let stale = ik(&kp, &start).unwrap();
    let r = rk4_step_implicit_friction(&kp, &dp, &s, &hold, DT, &env, Some(&stale));
    assert!(matches!(r, Err(CoreError::InvalidParameter(_))), "{r:?}");
}
