//! Integration tests of the calibration methods on the analytic generator.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rss6_core::{ik, KinematicParams, Vec6};
use rss6_ident::*;

mod common;
use common::{configurations, nominal, robot};

fn truth_vector(method: Method, truth: &TrueRobot) -> nalgebra::DVector<f64> {
    parameter_vector(
        method,
        &nominal(),
        &truth.kp,
        Some(&truth.sensor_in_base),
        &truth.target_in_effector,
    )
}

#[test]
fn analytic_jacobians_match_finite_differences_eq_4_25() {
    let (truth, mut src) = robot(1, NoiseModel::default());
    let data = collect(&mut src, &configurations(12, 3), 2.0).unwrap();
    for method in [Method::Rpba, Method::Implicit] {
        // evaluate away from the truth so every term is exercised
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let other = TrueRobot::draw(&nominal(), &mut rng);
        let x = truth_vector(method, &other);
        let (r_a, j_a) =
            residuals_and_jacobian(method, &data, &nominal(), &x, JacobianMode::Analytic).unwrap();
        let (r_f, j_f) = residuals_and_jacobian(
            method,
            &data,
            &nominal(),
            &x,
            JacobianMode::FiniteDifference { epsilon: 1e-6 },
        )
        .unwrap();
        assert_eq!(r_a, r_f);
        assert_eq!(j_a.shape(), j_f.shape());
        for c in 0..j_a.ncols() {
            let a = j_a.column(c);
            let f = j_f.column(c);
            let err = (a - f).norm();
            assert!(
                err <= 2e-3 * a.norm().max(1e-12 * j_a.norm()),
                "{method} column {c} ({}): analytic {:.4e} vs FD {:.4e}, diff {err:.3e}",
                parameter_names(method)[c],
                a.norm(),
                f.norm()
            );
        }
        let _ = truth;
    }
}

#[test]
fn jacobian_null_space_is_exactly_the_ten_gauge_directions() {
    let (truth, mut src) = robot(2, NoiseModel::default());
    let data = collect(&mut src, &configurations(15, 4), 2.0).unwrap();
    for method in [Method::Rpba, Method::Implicit] {
        let x = truth_vector(method, &truth);
        let (_, j) =
            residuals_and_jacobian(method, &data, &nominal(), &x, JacobianMode::Analytic).unwrap();
        let g = gauge_directions(method, &nominal(), &x);
        assert_eq!(g.ncols(), N_GAUGE);
        let s = nalgebra::DVector::from_iterator(j.ncols(), (0..j.ncols()).map(parameter_scale));
        let js = j.clone() * nalgebra::DMatrix::from_diagonal(&s);
        let jg = &j * &g;
        // each gauge direction is annihilated (relative to the Jacobian's scale)
        for k in 0..N_GAUGE {
            let rel = jg.column(k).norm() / (js.norm() * g.column(k).component_div(&s).norm());
            assert!(rel < 1e-8, "{method} gauge {k}: |J g| relative {rel:.2e}");
        }
        // and nothing else is: rank = n − 10 with a clear gap
        let mut sv: Vec<f64> = js.singular_values().iter().copied().collect();
        sv.sort_by(|a, b| b.total_cmp(a));
        let n = j.ncols();
        assert!(
            sv[n - N_GAUGE - 1] / sv[0] > 1e-5,
            "{method}: weakest identifiable {:.2e}",
            sv[n - 11] / sv[0]
        );
        assert!(
            sv[n - N_GAUGE] / sv[0] < 1e-12,
            "{method}: gauge σ {:.2e}",
            sv[n - 10] / sv[0]
        );
    }
}

#[test]
fn noise_free_data_recover_the_true_robot_up_to_gauge() {
    let (truth, mut src) = robot(3, NoiseModel::none());
    let thetas = configurations(16, 5);
    let data = collect(&mut src, &thetas, 0.0).unwrap();
    let opts = CalibrationOptions::default();
    let r = rpba(&data, &nominal(), &opts).unwrap();
    assert_eq!(r.rank, 56);
    assert!(r.dropped.is_empty());
    let x = parameter_vector(
        Method::Rpba,
        &nominal(),
        &r.params,
        None,
        &r.target_in_effector,
    );
    let (err, _) = gauge_aligned_error(
        Method::Rpba,
        &nominal(),
        &x,
        &truth_vector(Method::Rpba, &truth),
    );
    assert!(err < 1e-6, "RPBA gauge-aligned error {err:.3e} σ");
    let e = relative_pose_errors(
        &r.params,
        &r.target_in_effector,
        &truth,
        &nominal(),
        50,
        1,
        (-0.45, 0.45),
    )
    .unwrap();
    assert!(e.rms.iter().all(|&v| v < 1e-9), "{:?}", e.rms);
    assert_eq!(r.reference, nominal());
    let e = result_relative_pose_errors(&r, &truth, 20, 3).unwrap();
    assert!(
        e.rms.iter().all(|&v| v < 1e-9) && e.errors.len() + e.skipped == 20,
        "{:?}",
        e.rms
    );

    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let guess = perturb_external(&truth.sensor_in_base, &mut rng);
    let ri = implicit(&data, &nominal(), &guess, &opts).unwrap();
    assert_eq!(ri.rank, 62);
    let x = parameter_vector(
        Method::Implicit,
        &nominal(),
        &ri.params,
        ri.sensor_in_base.as_ref(),
        &ri.target_in_effector,
    );
    let (err, _) = gauge_aligned_error(
        Method::Implicit,
        &nominal(),
        &x,
        &truth_vector(Method::Implicit, &truth),
    );
    assert!(err < 1e-6, "implicit gauge-aligned error {err:.3e} σ");
    // the cost history is monotone and ends near zero
    assert!(ri.cost_history.windows(2).all(|w| w[1] <= w[0]));
    assert!(*r.cost_history.last().unwrap() < 1e-12 * r.cost_history[0]);
}

#[test]
fn light_study_meets_table_4_5_for_rpba_and_improves_both_methods() {
    let opts = StudyOptions {
        robots: 3,
        seed: 11,
        rpba_thetas: configurations(22, 21),
        implicit_thetas: configurations(34, 22),
        dwell: 2.0,
        noise: NoiseModel::default(),
        test_configurations: 40,
        stroke: (-0.45, 0.45),
        solver: CalibrationOptions::default(),
        target_nominal: NOMINAL_TARGET_IN_EFFECTOR,
    };
    let thesis = rss6_core::thesis::TABLE_4_5_RPBA;
    for row in run_study(&nominal(), &opts) {
        let row = row.unwrap();
        for k in 0..6 {
            assert!(
                row.rms_rpba[k] <= thesis[k],
                "robot {} axis {k}: {:?}",
                row.robot,
                row.rms_rpba
            );
            assert!(row.rms_rpba[k] * 50.0 < row.rms_uncalibrated[k], "{row:?}");
            assert!(
                row.rms_implicit[k] * 50.0 < row.rms_uncalibrated[k],
                "{row:?}"
            );
        }
        assert!(
            row.rpba_param_error.1 < 0.2 * row.rpba_param_error.0,
            "{row:?}"
        );
        assert!(
            row.implicit_param_error.1 < 0.5 * row.implicit_param_error.0,
            "{row:?}"
        );
        assert_eq!(row.ranks, (62, 56));
    }
}

#[test]
fn too_few_configurations_names_the_count_needed() {
    let (_, mut src) = robot(4, NoiseModel::default());
    assert_eq!(min_configurations(Method::Rpba), 11);
    assert_eq!(min_configurations(Method::Implicit), 11);
    let data = collect(&mut src, &configurations(9, 6), 2.0).unwrap();
    let err = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap_err();
    match &err {
        IdentError::TooFewConfigurations { got, needed, .. } => {
            assert_eq!((*got, *needed), (10, 11));
        }
        e => panic!("unexpected {e}"),
    }
    assert!(err.to_string().contains("need at least 11"), "{err}");
    let err = implicit(
        &data,
        &nominal(),
        &NOMINAL_SENSOR_IN_BASE.into(),
        &CalibrationOptions::default(),
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            IdentError::TooFewConfigurations {
                got: 10,
                needed: 11,
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn nan_and_missing_frames_are_dropped_and_reported() {
    let (truth, mut src) = robot(5, NoiseModel::default());
    let mut data = collect(&mut src, &configurations(16, 7), 2.0).unwrap();
    data.configurations[3].kappa[2] = f64::NAN;
    data.configurations[7].sensor_pose = None;
    if let Some(p) = data.configurations[9].sensor_pose.as_mut() {
        p[4] = f64::INFINITY;
    }
    let r = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap();
    let idx: Vec<usize> = r.dropped.iter().map(|d| d.index).collect();
    assert_eq!(idx, vec![3, 7, 9]);
    assert!(r.dropped[1].reason.contains("no camera frame"));
    assert!(!r.used.contains(&3) && r.used.len() == 14);
    let e = relative_pose_errors(
        &r.params,
        &r.target_in_effector,
        &truth,
        &nominal(),
        30,
        2,
        (-0.45, 0.45),
    )
    .unwrap();
    assert!(
        e.rms[0] < rss6_core::thesis::TABLE_4_5_RPBA[0],
        "{:?}",
        e.rms
    );

    // a bad reference configuration is an error, not a silent drop
    data.configurations[0].sensor_pose = None;
    let err = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap_err();
    assert!(matches!(err, IdentError::BadReference(_)), "{err}");
}

#[test]
fn configuration_where_fk_fails_is_dropped_and_reported() {
    let (_, mut src) = robot(6, NoiseModel::default());
    let mut data = collect(&mut src, &configurations(14, 8), 2.0).unwrap();
    // readings of an unassemblable configuration
    let th = Vec6::new(-1.0, 1.0, 1.0, 1.0, -1.0, 1.0);
    let bad = nominal().reading_from_theta(&th);
    assert!(rss6_core::fk(
        &nominal(),
        &th,
        &rss6_core::home_pose(),
        &Default::default()
    )
    .is_err());
    data.configurations[5].kappa = bad.into();
    let r = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap();
    assert_eq!(r.dropped.len(), 1);
    assert_eq!(r.dropped[0].index, 5);
    assert!(
        r.dropped[0].reason.contains("forward kinematics"),
        "{}",
        r.dropped[0].reason
    );
}

#[test]
fn rank_deficient_data_name_the_unseen_parameters() {
    // leg 3 never moves and sits at a non-zero angle: eta_3 and dtheta_3 cannot be told apart
    let (_, mut src) = robot(7, NoiseModel::none());
    let mut thetas = configurations(16, 9);
    for t in thetas.iter_mut() {
        t[2] = 0.2;
    }
    let data = collect(&mut src, &thetas, 0.0).unwrap();
    let err = rpba(&data, &nominal(), &CalibrationOptions::default()).unwrap_err();
    match &err {
        IdentError::RankDeficient {
            rank,
            expected,
            unseen,
        } => {
            assert_eq!(*expected, 56);
            assert!(*rank < 56);
            assert!(
                unseen.iter().any(|u| u == "deta3" || u == "dtheta3"),
                "{unseen:?}"
            );
        }
        e => panic!("unexpected {e}"),
    }
    assert!(err.to_string().contains("cannot see"), "{err}");
}

#[test]
fn calibration_data_round_trips_through_serde() {
    let (_, mut src) = robot(8, NoiseModel::default());
    let mut data = collect(&mut src, &configurations(3, 10), 2.0).unwrap();
    data.configurations[1].sensor_pose = None;
    let s = serde_json::to_string(&data).unwrap();
    let back: CalibrationData = serde_json::from_str(&s).unwrap();
    assert_eq!(back, data);
}

/// α close to π so that the ±1e-4 samples straddle the ±π wrap.
const ALPHA: f64 = std::f64::consts::PI - 4e-5;

/// A stepped robot with deterministic alternating noise, camera every 34 ticks.
struct Mock {
    tick: u64,
    cmd: Vec6,
    kp: KinematicParams,
}

impl rss6_exp::Robot for Mock {
    fn dt(&self) -> f64 {
        1e-3
    }
    fn time(&self) -> f64 {
        self.tick as f64 * 1e-3
    }
    fn step_joint_command(&mut self, theta_cmd: &Vec6) -> rss6_exp::Result<()> {
        self.cmd = *theta_cmd;
        self.tick += 1;
        Ok(())
    }
    fn camera(&mut self) -> Option<Vec6> {
        if self.tick % 34 == 0 {
            let s = if (self.tick / 34) % 2 == 0 { 1.0 } else { -1.0 };
            Some(Vec6::new(0.1, 0.2, 0.3, ALPHA, 0.0, 0.0) + Vec6::repeat(1e-4 * s))
        } else {
            None
        }
    }
    fn potentiometers(&self) -> Vec6 {
        let s = if self.tick % 4 < 2 { 0.5 } else { -0.5 };
        self.kp.reading_from_theta(&self.cmd).add_scalar(s)
    }
}

#[test]
fn dwell_runner_averages_over_the_dwell() {
    let kp = nominal();
    let mut src = rss6_exp::dwell::DwellSession::new(
        Mock {
            tick: 0,
            cmd: Vec6::zeros(),
            kp,
        },
        Vec6::zeros(),
        rss6_exp::dwell::DwellSpec::default(),
    );
    let th = Vec6::new(0.1, -0.2, 0.3, 0.0, 0.05, -0.1);
    let c = src.measure(&th, 2.0).unwrap();
    assert_eq!(c.kappa_samples, 1000);
    assert!(
        (c.camera_frames as i64 - 59).abs() <= 1,
        "{}",
        c.camera_frames
    );
    let expect = kp.reading_from_theta(&th);
    assert!((c.kappa_vec() - expect).amax() < 1e-9);
    let p = c.sensor_pose_vec().unwrap();
    // α near π averaged without a wrap-around jump
    assert!((p[3].abs() - ALPHA).abs() < 2e-4, "{p}");
    assert!((p[0] - 0.1).abs() < 2e-4);
    assert!(src.measure(&th, 0.0).is_err());
}

#[test]
fn selection_returns_the_initial_configuration_first_and_raises_o1() {
    let kp = nominal();
    let s = (-0.5, 0.5);
    let opts = SelectionOptions {
        start: 13,
        candidates: 150,
        stroke: Some(s),
        // no margin: the comparison with random configurations below is in the same box
        margin_sigma: 0.0,
        prior_robots: 0,
    };
    for method in [Method::Rpba, Method::Implicit] {
        let rep = select_configurations_with(&kp, method, 3, &opts).unwrap();
        assert_eq!(rep.thetas[0], Vec6::zeros());
        assert!(rep
            .thetas
            .iter()
            .all(|t| t.iter().all(|v| *v >= s.0 && *v <= s.1)));
        let o1 = observability_index(&kp, method, &rep.thetas).unwrap();
        assert!((o1 - rep.index).abs() < 1e-9 * o1, "{o1} vs {}", rep.index);
        let random = configurations(rep.thetas.len() - 1, 123);
        let o1_random = observability_index(&kp, method, &random).unwrap();
        assert!(
            o1 > o1_random,
            "{method}: selected {o1} vs random {o1_random}"
        );
        for t in &rep.thetas {
            assert!(rss6_core::fk(&kp, t, &rss6_core::home_pose(), &Default::default()).is_ok());
        }
    }
}

#[test]
fn selection_with_margin_stays_inside_the_shrunk_stroke() {
    let kp = nominal();
    let s = (-0.5, 0.5);
    let inner = stroke_margin(&kp, s, 3.0);
    // 3σ of Δθ alone is 0.15 rad, and η's 6.5 % relative error adds to it at the ends
    assert!(inner.1 < s.1 - 0.15 && inner.1 > 0.2, "{inner:?}");
    assert!((inner.0 + inner.1).abs() < 1e-12);
    assert_eq!(stroke_margin(&kp, s, 0.0), s);
    let opts = SelectionOptions {
        start: 13,
        candidates: 60,
        stroke: Some(s),
        ..SelectionOptions::default()
    };
    let rep = select_configurations_with(&kp, Method::Rpba, 3, &opts).unwrap();
    assert_eq!(rep.inner_stroke, inner);
    assert!(rep
        .thetas
        .iter()
        .all(|t| t.iter().all(|v| *v >= inner.0 && *v <= inner.1)));
}

#[test]
fn stroke_box_is_feasible_and_tight() {
    let kp = nominal();
    let opts = StrokeOptions {
        bisection_steps: 7,
        random_points: 16,
        path_steps: 8,
        ..Default::default()
    };
    let (lo, hi) = stroke_with(&kp, &opts).unwrap();
    assert!(
        lo < -0.3 && hi > 0.3 && lo > -1.2 && hi < 1.2,
        "({lo}, {hi})"
    );
    let sign = [1.0, -1.0, 1.0, -1.0, 1.0, -1.0];
    let vertex_ok = |s: f64, v: u32| {
        let th = Vec6::from_fn(|i, _| if v & (1 << i) != 0 { s * hi } else { s * lo });
        let Ok(sol) = rss6_core::fk(&kp, &th, &rss6_core::home_pose(), &Default::default()) else {
            return false;
        };
        let Ok(back) = ik(&kp, &sol.pose) else {
            return false;
        };
        let a1 = rss6_core::jacobian_a1(&kp, &sol.pose).unwrap();
        (back - th).amax() < 1e-7 && (0..6).all(|i| a1[i] * sign[i] > 0.0)
    };
    assert!((0..64).all(|v| vertex_ok(1.0, v)));
    assert!(
        !(0..64).all(|v| vertex_ok(1.3, v)),
        "a 30 % larger box should leave the feasible region"
    );
}
