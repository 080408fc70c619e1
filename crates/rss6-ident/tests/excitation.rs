//! Exciting trajectories (§5.4): rest at both ends, feasibility checks, identifiable columns, O_in.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::{home_pose, KinematicParams, Vec6};
use rss6_ctrl::Trajectory;
use rss6_ident::{aliases, base_columns, Excitation, ExcitationLimits};

fn random_free(n: usize, scale: [f64; 2], seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let k = Excitation::free_per_axis(n);
    (0..6 * k)
        .map(|j| {
            let s = if j / k < 3 { scale[0] } else { scale[1] };
            s * rng.random_range(-1.0..1.0)
        })
        .collect()
}

#[test]
fn an_at_rest_trajectory_starts_and_ends_at_rest_at_its_pose() {
    let start = Vec6::new(0.002, -0.003, 0.116, 0.01, -0.02, 0.005);
    let e = Excitation::at_rest(5, 0.1, &start, &random_free(5, [0.01, 0.05], 1)).unwrap();
    for t in [0.0, e.period()] {
        let r = e.at(t);
        assert!(
            (r.pose - start).amax() < 1e-15,
            "t = {t}: {}",
            (r.pose - start).amax()
        );
        assert!(r.pose_dot.amax() < 1e-15);
        assert!(r.pose_ddot.amax() < 1e-14);
    }
    // The derivatives are those of the pose (central differences, h = 1e-5 s).
    let (t, h) = (3.3, 1e-5);
    let (a, b, c) = (e.at(t - h), e.at(t), e.at(t + h));
    assert!(((c.pose - a.pose) / (2.0 * h) - b.pose_dot).amax() < 1e-8);
    assert!(((c.pose_dot - a.pose_dot) / (2.0 * h) - b.pose_ddot).amax() < 1e-7);
    // The reference repeats with the period (a run of several periods excites every one), and
    // holds the start at rest before t = 0.
    for t in [1.3, 4.1] {
        let (first, third) = (e.sample(t), e.sample(t + 2.0 * e.period()));
        assert!((third.pose - first.pose).amax() < 1e-12, "t = {t}");
        assert!((third.pose_dot - first.pose_dot).amax() < 1e-10, "t = {t}");
        assert!(
            (first.pose - start).amax() > 1e-4,
            "t = {t}: the trajectory moves"
        );
    }
    let before = e.sample(-1.0);
    assert_eq!(before.pose_dot, Vec6::zeros());
    assert!((before.pose - start).amax() < 1e-15);
    assert!(Excitation::at_rest(1, 0.1, &start, &[]).is_err());
    assert!(Excitation::at_rest(5, 0.1, &start, &[0.0; 5]).is_err());
}

#[test]
fn the_checks_name_the_violated_constraint_and_its_time() {
    let kp = KinematicParams::nominal();
    let limits = ExcitationLimits::default();
    let n = 5;
    let still = Excitation::at_rest(
        n,
        0.1,
        &home_pose(),
        &vec![0.0; 6 * Excitation::free_per_axis(n)],
    )
    .unwrap();
    assert_eq!(still.check(&kp, &limits), None);
    let gentle =
        Excitation::at_rest(n, 0.1, &home_pose(), &random_free(n, [0.0005, 0.002], 2)).unwrap();
    assert_eq!(gentle.check(&kp, &limits), None);
    // Large rotations leave the stroke (with its margin) somewhere in the period.
    let wild = Excitation::at_rest(n, 0.1, &home_pose(), &random_free(n, [0.0, 0.5], 3)).unwrap();
    let v = wild.check(&kp, &limits).expect("must be infeasible");
    assert!(v.time > 0.0 && v.time < wild.period());
    assert!(v.excess > 0.0);
    println!("wild trajectory: {v}");
    // A tight acceleration limit is named as such.
    let tight = ExcitationLimits {
        max_acceleration: Vec6::repeat(1e-6),
        ..limits
    };
    assert_eq!(
        gentle.check(&kp, &tight).unwrap().constraint,
        "acceleration"
    );
    let slow = ExcitationLimits {
        max_joint_rate: 1e-6,
        ..limits
    };
    assert_eq!(gentle.check(&kp, &slow).unwrap().constraint, "joint rate");
}

#[test]
fn identifiable_columns_and_observability() {
    let kp = KinematicParams::nominal();
    let n = 5;
    let e = Excitation::at_rest(n, 0.1, &home_pose(), &random_free(n, [0.0005, 0.002], 4)).unwrap();
    assert_eq!(e.check(&kp, &ExcitationLimits::default()), None);
    let h = e.stacked_regressor(&kp, 200).unwrap();
    let base = base_columns(&h, 1e-8);
    // Structural rank of the regressor with vertical gravity: 31 of 64 (docs/dynamics.md).
    println!(
        "base columns at 1e-8: {}; at the thesis's 1e-3: {}",
        base.len(),
        base_columns(&h, 1e-3).len()
    );
    assert_eq!(base.len(), 31, "{base:?}");
    // Every other column is a combination of the base ones (the regressor's structural null
    // space), and the aliases say which: measured worst misfit ≈ 1e-9 here.
    let al = aliases(&h, &base);
    assert_eq!(al.len(), 64 - 31);
    let seen: Vec<_> = al.iter().filter(|a| h.column(a.0).norm() > 0.0).collect();
    let worst = seen.iter().map(|a| a.2).fold(0.0_f64, f64::max);
    println!(
        "{} non-base columns are zero; worst alias misfit of the other {}: {worst:.2e}",
        al.len() - seen.len(),
        seen.len()
    );
    assert!(!seen.is_empty());
    assert!(worst < 1e-6, "{worst}");
    let (o1, c1) = e.observability(&kp, &base, 200).unwrap();
    // Twice the excitation: larger velocities and accelerations, better conditioned columns.
    let e2 = Excitation::at_rest(n, 0.1, &home_pose(), &random_free(n, [0.001, 0.004], 4)).unwrap();
    let (o2, c2) = e2.observability(&kp, &base, 200).unwrap();
    println!("O_in {o1:.4e} -> {o2:.4e}, cond {c1:.3e} -> {c2:.3e}");
    assert!(o1 > 0.0 && o2 > o1);
    assert!(c1.is_finite() && c1 >= 1.0);
}

#[test]
fn the_objective_prefers_feasible_and_more_exciting_candidates() {
    let kp = KinematicParams::nominal();
    let n = 5;
    let h = Excitation::at_rest(n, 0.1, &home_pose(), &random_free(n, [0.0005, 0.002], 4))
        .unwrap()
        .stacked_regressor(&kp, 100)
        .unwrap();
    let problem = rss6_ident::ExcitationProblem {
        kp,
        limits: ExcitationLimits::default(),
        harmonics: n,
        f0: 0.1,
        start: home_pose(),
        columns: base_columns(&h, 1e-8),
        samples: 100,
    };
    let pop = vec![
        random_free(n, [0.0005, 0.002], 4),
        random_free(n, [0.0007, 0.0028], 4),
        random_free(n, [0.0, 0.5], 3),
    ];
    let f = problem.objectives(&pop);
    assert!(f[0] < 0.0 && f[1] < f[0], "{f:?}");
    assert!(
        f[2] > 1.0,
        "an infeasible candidate scores above every feasible one: {f:?}"
    );
}

#[test]
fn aliases_recover_a_known_combination_and_flag_an_unseen_column() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut h = nalgebra::DMatrix::<f64>::from_fn(50, 4, |_, _| rng.random_range(-1.0..1.0));
    let combo = h.column(0) * 2.0 - h.column(1) * 0.5;
    h.set_column(2, &combo);
    h.set_column(3, &nalgebra::DVector::zeros(50));
    let base = base_columns(&h, 1e-8);
    assert_eq!(base.len(), 2, "{base:?}");
    let al = aliases(&h, &base);
    // Whichever of columns 0, 1, 2 the pivoting left out is the combination of the other two.
    let (u, c, misfit) = al.iter().find(|a| a.0 != 3).unwrap();
    assert!(*misfit < 1e-12, "{misfit}");
    let rebuilt = base
        .iter()
        .zip(c)
        .fold(nalgebra::DVector::zeros(50), |acc, (&j, &v)| {
            acc + h.column(j) * v
        });
    assert!((rebuilt - h.column(*u)).amax() < 1e-12);
    if !base.contains(&2) {
        let coef = |j: usize| c[base.iter().position(|&b| b == j).unwrap()];
        assert!((coef(0) - 2.0).abs() < 1e-10 && (coef(1) + 0.5).abs() < 1e-10);
    }
    // The zero column is seen by nothing: misfit 1, no coefficients.
    let c3 = al.iter().find(|a| a.0 == 3).unwrap();
    assert_eq!(c3.2, 1.0);
    assert!(c3.1.iter().all(|&v| v == 0.0));
}

/// The pivot's tie rule (`PIVOT_TIE`): of near-parallel columns the earliest enters the base set,
/// whatever rounding-sized changes the columns get. Four pairs (c, c + 10⁻² noise), each pair
/// nearly orthogonal to the others, at threshold 0.05: one of each pair is identifiable. Plain
/// largest-norm pivoting picks between a pair's members by their ≈ 10⁻⁴ norm difference after
/// projection, so 10⁻³ perturbations move it; the tie rule always takes 0, 2, 4, 6.
#[test]
fn of_near_parallel_columns_the_earliest_is_the_base_one() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let n = 80;
    let mut h = nalgebra::DMatrix::<f64>::zeros(n, 8);
    for p in 0..4 {
        let c = nalgebra::DVector::<f64>::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        let d = nalgebra::DVector::<f64>::from_fn(n, |_, _| rng.random_range(-1.0..1.0));
        h.set_column(2 * p, &c);
        h.set_column(2 * p + 1, &(&c + d * 1e-2));
    }
    for trial in 0..20 {
        let e = nalgebra::DMatrix::<f64>::from_fn(n, 8, |_, _| rng.random_range(-1.0..1.0));
        let hp = &h + e.component_mul(&h) * 1e-3;
        assert_eq!(base_columns(&hp, 0.05), vec![0, 2, 4, 6], "trial {trial}");
    }
}
