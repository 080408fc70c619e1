//! The lean identification loop of rss6-ident against the experiment layer's loop on the model twin,
//! and its sensitivities against central differences.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use rss6_core::{home_pose, DynamicParams, KinematicParams, Mat3, PlatformLoad, Vec3, Vec6};
use rss6_ctrl::PidGains;
use rss6_exp::{ident, Externals, Record};
use rss6_ident::{
    simulate_loop, simulate_loop_from, simulate_loop_recording, Excitation, LoopConfig, LoopParams,
    N_A,
};
use rss6_sim::{CmmConfig, EffectSpec, ModelSim, RobotSim, SimConfig};

/// A short, gentle at-rest excitation (3 harmonics of 0.5 Hz, one 2 s period).
fn excitation() -> Excitation {
    let free = [
        0.010, -0.004, 0.006, 0.003, // x: s2, c2, s3, c3 (m/s)
        -0.008, 0.005, 0.004, -0.002, // y
        0.006, 0.002, -0.005, 0.004, // z
        0.04, -0.02, 0.03, 0.01, // α (rad/s)
        -0.03, 0.02, 0.02, -0.01, // β
        0.05, 0.01, -0.03, 0.02, // γ
    ];
    Excitation::at_rest(3, 0.5, &home_pose(), &free).unwrap()
}

fn truth() -> LoopParams {
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.3, 0.25, 0.35, 0.3, 0.28, 0.32];
    dp.viscous = [0.08, 0.1, 0.09, 0.07, 0.11, 0.1];
    LoopParams {
        dynamics: dp,
        pid: PidGains::tuned(),
    }
}

/// The realistic drive of the identification runs: a 5 ms derivative filter, smoothed Coulomb
/// friction (ε = 0.5 rad/s) of Table 5.2's size, the 30 N·m clamp on.
const T_F: f64 = 5e-3;
const EPS: f64 = 0.5;

fn realistic_truth() -> LoopParams {
    rss6_ident::table_5_2_truth()
}

#[test]
fn the_lean_loop_gives_the_experiment_layers_chi_s_on_the_twin() {
    lean_loop_equals_twin(&truth(), 0.0, 0.0, false);
}

#[test]
fn with_a_filtered_derivative_and_smooth_friction_the_lean_loop_equals_the_twin() {
    lean_loop_equals_twin(&realistic_truth(), T_F, EPS, false);
}

/// Table 5.2's friction stepped implicitly (stick–slip): the third friction law, shared by the
/// twin, the plant and CLOE.
#[test]
fn with_implicit_stick_slip_friction_the_lean_loop_equals_the_twin() {
    lean_loop_equals_twin(&realistic_truth(), T_F, 0.0, true);
}

/// A 2 kg payload at (5, 2, 3) cm in ΣE and a potentiometer offset drifting at 2 mrad/s on joint 2:
/// the twin's hidden effects and the lean loop's `load` / `offset_drift`.
#[test]
fn with_a_payload_and_a_drifting_offset_the_lean_loop_equals_the_twin() {
    let effects = vec![
        EffectSpec::new(
            "payload",
            &[
                ("mass", 2.0),
                ("x", 0.05),
                ("y", 0.02),
                ("z", 0.03),
                ("inertia", 1e-3),
            ],
        ),
        EffectSpec::new("joint_offset_drift", &[("rate", 2e-3), ("joint", 1.0)]),
    ];
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 2.0);
    cfg.load = Some(PlatformLoad::new(
        2.0,
        Vec3::new(0.05, 0.02, 0.03),
        Mat3::identity() * 1e-3,
    ));
    cfg.offset_drift[1] = 2e-3;
    let worst = lean_vs_twin(&truth(), &cfg, effects.clone());
    // Without the effects in the model the gap is the effects' signature (sanity: the test sees them).
    let plain = LoopConfig::new(KinematicParams::nominal(), home_pose(), 2.0);
    let gap = lean_vs_twin(&truth(), &plain, effects);
    println!(
        "payload + drift: lean vs twin {worst:.2e}, without the effects in the model {gap:.2e}"
    );
    assert!(worst < 1e-12, "{worst}");
    assert!(gap > 1e-5, "{gap}");
}

fn lean_vs_twin(a: &LoopParams, cfg: &LoopConfig, effects: Vec<EffectSpec>) -> f64 {
    let exc = excitation();
    let mut sc = SimConfig::new(KinematicParams::nominal(), a.dynamics, a.pid);
    sc.effects = effects;
    sc.pot_noise = 0.0;
    sc.cmm = CmmConfig {
        pose_noise: Some([0.0, 0.0]),
        ..CmmConfig::table_4_1()
    };
    let recs = twin_records(sc, cfg.duration);
    let frames: Vec<Vec6> = recs.iter().filter_map(|r| r.camera).collect();
    let run = simulate_loop(cfg, a, &exc, None).unwrap();
    assert_eq!(run.chi.len(), frames.len());
    run.chi
        .iter()
        .zip(&frames)
        .map(|(c, f)| (c - f).amax())
        .fold(0.0, f64::max)
}

fn lean_loop_equals_twin(a: &LoopParams, t_f: f64, eps: f64, implicit: bool) {
    let a = *a;
    let exc = excitation();
    let duration = 2.0;
    // The twin, noise-free, as the experiment layer runs it.
    let mut sc = SimConfig::new(KinematicParams::nominal(), a.dynamics, a.pid);
    sc.drive_derivative_filter = t_f;
    sc.friction_smoothing = eps;
    sc.implicit_friction = implicit;
    sc.pot_noise = 0.0;
    sc.cmm = CmmConfig {
        pose_noise: Some([0.0, 0.0]),
        ..CmmConfig::table_4_1()
    };
    let recs = twin_records(sc, duration);
    let frames: Vec<(f64, Vec6)> = recs
        .iter()
        .filter_map(|r| r.camera.map(|c| (r.t, c)))
        .collect();

    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), duration);
    cfg.derivative_filter = t_f;
    cfg.friction_smoothing = eps;
    cfg.implicit_friction = implicit;
    let run = simulate_loop(&cfg, &a, &exc, None).unwrap();
    println!(
        "T_f = {t_f}, ε = {eps}, implicit {implicit}: {} saturated joint-ticks, {} inexact friction ticks",
        run.saturated, run.inexact_friction
    );
    assert_eq!(run.inexact_friction, 0);
    assert_eq!(run.t.len(), frames.len());
    let mut worst: f64 = 0.0;
    for ((t, chi), (tr, cr)) in run.t.iter().zip(&run.chi).zip(&frames) {
        assert_eq!(t, tr);
        worst = worst.max((chi - cr).amax());
    }
    println!("lean loop vs ident::run on the twin: worst |Δχ_s| = {worst:.3e}");
    // The twin's frame goes through ᴼχ_C ∘ ᶜχ_t ∘ (ᴱχ_t)⁻¹ (rounding ~1e-16 per frame, fed back);
    // measured ≈ 1e-15; the bound leaves room but catches any rule difference (≥ 1e-6).
    assert!(worst < 1e-12, "{worst}");
}

#[test]
fn sensitivities_match_central_differences() {
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    // The torque clamp off: its switching (the derivative kick at each frame) is a non-smooth event
    // that limits the central-difference reference's step (docs/identification.md).
    cfg.torque_limit = 1e4;
    sensitivities_match(&cfg, &truth());
}

#[test]
fn with_a_payload_sensitivities_match_central_differences() {
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    cfg.torque_limit = 1e4;
    cfg.load = Some(PlatformLoad::new(
        2.0,
        Vec3::new(0.05, 0.02, 0.03),
        Mat3::identity() * 1e-3,
    ));
    sensitivities_match(&cfg, &truth());
}

#[test]
fn with_the_realistic_drive_sensitivities_match_central_differences() {
    // The 30 N·m clamp on: the filtered derivative keeps the drive off it.
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    cfg.derivative_filter = T_F;
    cfg.friction_smoothing = EPS;
    sensitivities_match(&cfg, &realistic_truth());
}

#[test]
fn with_implicit_stick_slip_friction_sensitivities_match_central_differences() {
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    cfg.derivative_filter = T_F;
    cfg.implicit_friction = true;
    sensitivities_match(&cfg, &realistic_truth());
}

fn sensitivities_match(cfg: &LoopConfig, a: &LoopParams) {
    let (cfg, a) = (cfg.clone(), *a);
    let exc = excitation();
    // A spread of columns: platform m, Ix, Iz; wrench 1 m and Iz; link 2 m and Ix; fc3, fv4; gains.
    let cols = [0usize, 1, 3, 4, 7, 32, 33, 54, 61, 64, 65, 66];
    let run = simulate_loop(&cfg, &a, &exc, Some(&cols)).unwrap();
    assert_eq!(run.saturated, 0);
    if cfg.implicit_friction {
        // The run must contain sticking joints, or the stick rows of the derivative go untested.
        println!("{} stuck joint-ticks of {}", run.stuck_joint_ticks, 6000);
        assert!(run.stuck_joint_ticks > 100, "{}", run.stuck_joint_ticks);
        assert_eq!(run.inexact_friction, 0);
    }
    let jac = run.jacobian.as_ref().unwrap();
    let base = a.to_vector();
    let mut worst: f64 = 0.0;
    // The FD reference has two errors: rounding, amplified by the loop (∝ 1/h), and for larger h
    // steps that move a Coulomb sign(θ̇) event (the discrete loop is not differentiable there;
    // its exact derivative almost everywhere ignores them). So each column is compared with the
    // best of four relative steps. Measured (release): best errors 7.6e-9 … 5.0e-7 (the bound,
    // the 1e-6, is 2× the worst).
    for (c, &col) in cols.iter().enumerate() {
        let an = jac.column(c);
        let mut best = f64::INFINITY;
        for rel_h in [1e-3, 1e-4, 1e-5, 1e-6] {
            let h = rel_h * base[col].abs().max(1e-6);
            let sim = |d: f64| {
                let mut x = base;
                x[col] += d;
                simulate_loop(&cfg, &LoopParams::from_vector(&x), &exc, None).unwrap()
            };
            let (p, m) = (sim(h), sim(-h));
            let fd: Vec<f64> = p
                .chi
                .iter()
                .zip(&m.chi)
                .flat_map(|(a, b)| ((a - b) / (2.0 * h)).iter().copied().collect::<Vec<_>>())
                .collect();
            let err = fd
                .iter()
                .zip(an.iter())
                .map(|(f, s)| (f - s).powi(2))
                .sum::<f64>()
                .sqrt();
            best = best.min(err / an.norm().max(1e-300));
        }
        println!(
            "column {col:2}: |∂χ_s/∂A| = {:.3e}, best relative error vs central differences {best:.2e}",
            an.norm()
        );
        worst = worst.max(best);
    }
    assert_eq!(N_A, 67);
    assert!(worst < 1e-6, "{worst}");
}

/// The worst relative column error of the sensitivities under `mode` against the exact ones, on
/// `cfg`'s loop with the truth's parameters (a 1 s run, twelve columns of A of every kind).
fn worst_column_error(cfg: &LoopConfig, mode: rss6_ident::StateJacobians) -> f64 {
    let (a, exc) = (truth(), excitation());
    let cols = [0usize, 1, 3, 4, 7, 32, 33, 54, 61, 64, 65, 66];
    let run = |mode| {
        let c = LoopConfig {
            state_jacobians: mode,
            ..cfg.clone()
        };
        simulate_loop(&c, &a, &exc, Some(&cols))
            .unwrap()
            .jacobian
            .unwrap()
    };
    let (exact, approx) = (run(rss6_ident::StateJacobians::Exact), run(mode));
    (0..cols.len())
        .map(|c| (approx.column(c) - exact.column(c)).norm() / exact.column(c).norm())
        .fold(0.0, f64::max)
}

#[test]
fn per_tick_state_jacobians_approximate_the_exact_sensitivities() {
    let cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    let worst = worst_column_error(&cfg, rss6_ident::StateJacobians::PerTick);
    println!("per-tick state Jacobians: worst relative column error {worst:.2e}");
    assert!(worst < BOUND_PER_TICK, "{worst}");
}

#[test]
fn sensitivities_from_a_recorded_run_are_the_plain_calls_bit_for_bit() {
    // The public pair CLOE's iterations use: a recording primal run, then the sensitivities
    // taken from it (stages ahead on the rayon threads when there are several) — equal to
    // simulate_loop's, exact and per tick, and with no recording.
    let a = truth();
    let exc = excitation();
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 0.3);
    cfg.implicit_friction = true;
    cfg.derivative_filter = 5e-3;
    let cols = [0usize, 4, 33, 54, 64, 66];
    use rss6_ident::StateJacobians;
    for mode in [
        StateJacobians::Exact,
        StateJacobians::PerTick,
        StateJacobians::FirstStage,
    ] {
        let mut c = cfg.clone();
        c.state_jacobians = mode;
        let (plain, rec) = simulate_loop_recording(&cfg, &a, &exc).unwrap();
        assert_eq!(plain.chi, simulate_loop(&cfg, &a, &exc, None).unwrap().chi);
        let want = simulate_loop(&c, &a, &exc, Some(&cols)).unwrap();
        for r in [rec, None] {
            let got = simulate_loop_from(&c, &a, &exc, &cols, r).unwrap();
            assert_eq!(got.chi, want.chi);
            assert_eq!(got.jacobian, want.jacobian);
        }
    }
}

/// ≈ 3× the measured worst column error of the per-tick approximation (8.8e-4, release).
const BOUND_PER_TICK: f64 = 3e-3;

/// The loop CLOE iterates on (implicit stick–slip friction, filtered derivative): the first
/// stage's derivatives serving all four stages approximate the exact sensitivities as well as the
/// per-tick state Jacobians do; with the sign law's stiff tick the mode is refused.
#[test]
fn first_stage_derivatives_approximate_the_exact_sensitivities_with_the_implicit_law() {
    use rss6_ident::StateJacobians;
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 1.0);
    cfg.state_jacobians = StateJacobians::FirstStage;
    let err = simulate_loop(&cfg, &truth(), &excitation(), Some(&[0])).unwrap_err();
    assert!(err.to_string().contains("needs implicit_friction"), "{err}");
    cfg.implicit_friction = true;
    cfg.derivative_filter = T_F;
    let per_tick = worst_column_error(&cfg, StateJacobians::PerTick);
    let first = worst_column_error(&cfg, StateJacobians::FirstStage);
    println!("implicit law, worst relative column error: per tick {per_tick:.2e}, first stage {first:.2e}");
    assert!(per_tick < BOUND_PER_TICK, "{per_tick}");
    assert!(first < BOUND_FIRST_STAGE, "{first}");
}

/// ≈ 3× the measured worst column error of the first-stage approximation under the implicit law.
const BOUND_FIRST_STAGE: f64 = 3e-3;

#[test]
fn friction_too_stiff_for_the_integrator_is_refused_with_the_smallest_smoothing() {
    // Table 5.2's Coulomb friction smoothed with ε = 0.1 rad/s: λ·dt ≈ 3 near rest, beyond RK4's
    // stable range (measured: LM then stalls on a non-smooth cost).
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 0.1);
    cfg.friction_smoothing = 0.1;
    let err = simulate_loop(&cfg, &realistic_truth(), &excitation(), None).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("too stiff") && msg.contains("ε must be at least"),
        "{msg}"
    );
    cfg.friction_smoothing = EPS;
    assert!(simulate_loop(&cfg, &realistic_truth(), &excitation(), None).is_ok());
}

/// The twin with Table 5.2's friction stepped implicitly and a noisy camera (Table 4.1 pixel
/// noise; potentiometers noise-free): its records, for the recorded-command loop.
fn noisy_implicit_twin_run(a: &LoopParams, duration: f64) -> Vec<Record> {
    let mut sc = SimConfig::new(KinematicParams::nominal(), a.dynamics, a.pid);
    sc.drive_derivative_filter = T_F;
    sc.implicit_friction = true;
    sc.pot_noise = 0.0;
    twin_records(sc, duration)
}

/// `ident::run` of the test excitation on the twin built from `sc`, from rest at home: its records.
fn twin_records(sc: SimConfig, duration: f64) -> Vec<Record> {
    let ext = Externals {
        sensor_in_base: sc.sensor_in_base,
        target_in_effector: sc.target_in_effector,
    };
    let mut twin = ModelSim::new(sc).unwrap();
    twin.reset(&home_pose()).unwrap();
    let mut spec = ident::IdentSpec::new(KinematicParams::nominal(), ext);
    spec.duration = duration;
    let mut recs: Vec<Record> = Vec::new();
    ident::run(&mut twin, &spec, &excitation(), &mut recs).unwrap();
    recs
}

/// Worst |χ_s − true χ| of `run` over its frames against the twin's true poses in `recs`.
fn worst_gap(recs: &[Record], run: &rss6_ident::LoopRun) -> f64 {
    let truth_at = |t: f64| {
        recs.iter()
            .find(|r| (r.t - t).abs() < 1e-9)
            .and_then(|r| r.truth)
            .unwrap()
            .pose
    };
    run.t
        .iter()
        .zip(&run.chi)
        .map(|(&t, c)| (c - truth_at(t)).amax())
        .fold(0.0, f64::max)
}

fn recorded_loop(duration: f64, recs: &[Record]) -> LoopConfig {
    let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), duration);
    cfg.derivative_filter = T_F;
    cfg.implicit_friction = true;
    cfg.recorded_commands = Some(
        recs.iter()
            .filter(|r| r.camera.is_some())
            .map(|r| r.theta_cmd)
            .collect(),
    );
    cfg
}

/// With the robot's own commands held, the lean loop reproduces the twin's *true* motion exactly,
/// camera noise and all: the noise acted through the commands, which are now the input. Without
/// them (the thesis's loop) the noise fed back through the visual PID is a systematic gap.
#[test]
fn with_the_recorded_commands_the_lean_loop_reproduces_the_noisy_twins_true_motion() {
    let a = realistic_truth();
    let duration = 2.0;
    let recs = noisy_implicit_twin_run(&a, duration);
    let cfg = recorded_loop(duration, &recs);
    let gap = |run: &rss6_ident::LoopRun| worst_gap(&recs, run);
    let run = simulate_loop(&cfg, &a, &excitation(), None).unwrap();
    let mut thesis = cfg.clone();
    thesis.recorded_commands = None;
    let closed = simulate_loop(&thesis, &a, &excitation(), None).unwrap();
    let (g_rec, g_closed) = (gap(&run), gap(&closed));
    println!(
        "recorded commands: worst |χ_s − true χ| {g_rec:.2e}; outer loop simulated {g_closed:.2e}"
    );
    // Measured: exactly 0 and 6.9e-4 (0.7 mm: the camera noise's motion through stick–slip).
    assert!(g_rec < 1e-12, "{g_rec}");
    assert!(g_closed > 1e-5, "{g_closed}");
    // Too few recorded commands: a typed error naming the frame.
    let mut short = cfg.clone();
    if let Some(c) = short.recorded_commands.as_mut() {
        c.truncate(10);
    }
    let err = simulate_loop(&short, &a, &excitation(), None).unwrap_err();
    assert!(err.to_string().contains("end at frame 10"), "{err}");
}

/// With the twin's potentiometer noise on, the recorded commands alone no longer reproduce its
/// motion (the drive reacted to noisy readings); replaying the noise itself (`pot_dither`, here the
/// exact one: reading minus the true angle) does, exactly.
#[test]
fn replaying_the_potentiometer_noise_reproduces_the_twins_motion() {
    let a = realistic_truth();
    let duration = 2.0;
    let mut sc = SimConfig::new(KinematicParams::nominal(), a.dynamics, a.pid);
    sc.drive_derivative_filter = T_F;
    sc.implicit_friction = true;
    let recs = twin_records(sc, duration);
    let cfg = recorded_loop(duration, &recs);
    let kp = KinematicParams::nominal();
    let dither: Vec<Vec6> = recs
        .iter()
        .map(|r| {
            let theta = rss6_core::ik(&kp, &r.truth.unwrap().pose).unwrap();
            Vec6::from_fn(|i, _| kp.eta[i] * r.kappa[i] + kp.dtheta[i] - theta[i])
        })
        .collect();
    let gap = |run: &rss6_ident::LoopRun| worst_gap(&recs, run);
    let clean = simulate_loop(&cfg, &a, &excitation(), None).unwrap();
    let mut with = cfg.clone();
    with.pot_dither = Some(dither.clone());
    let replayed = simulate_loop(&with, &a, &excitation(), None).unwrap();
    let (g_clean, g_dither) = (gap(&clean), gap(&replayed));
    let rms =
        (dither.iter().map(|d| d.norm_squared()).sum::<f64>() / (6 * dither.len()) as f64).sqrt();
    println!("potentiometer noise RMS {rms:.2e} rad; worst |χ_s − true χ|: clean readings {g_clean:.2e}, noise replayed {g_dither:.2e}");
    // Measured: 8.8e-5 (88 µm from 0.26 mrad of potentiometer noise) and 1.5e-16.
    assert!(g_dither < 1e-12, "{g_dither}");
    assert!(g_clean > 1e-5, "{g_clean}");
    // Sensitivities with the dither replayed (first second): still the loop's exact derivative.
    let mut first = with.clone();
    first.duration = 1.0;
    sensitivities_match(&first, &a);
    // A dither that ends early or holds a NaN: typed errors.
    let mut short = with.clone();
    short.pot_dither.as_mut().unwrap().truncate(100);
    let err = simulate_loop(&short, &a, &excitation(), None).unwrap_err();
    assert!(err.to_string().contains("ends at tick 100"), "{err}");
    let mut bad = with;
    bad.pot_dither.as_mut().unwrap()[3][2] = f64::NAN;
    let err = simulate_loop(&bad, &a, &excitation(), None).unwrap_err();
    assert!(err.to_string().contains("row 3"), "{err}");
}

#[test]
fn with_recorded_commands_sensitivities_match_central_differences() {
    let recs = noisy_implicit_twin_run(&realistic_truth(), 1.0);
    sensitivities_match(&recorded_loop(1.0, &recs), &realistic_truth());
}

/// Stages evaluated ahead on other threads (`LoopConfig::parallel_stages`) give the sequential run's
/// χ_s and Jacobian bit for bit, for every friction law and both state-Jacobian modes, and take
/// every stage from the blocks; from inside a rayon worker the loop stays sequential.
#[test]
fn stages_evaluated_ahead_in_parallel_give_the_sequential_result_bit_for_bit() {
    // Two threads even on a one-core machine (this test binary's global pool).
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build_global();
    let cols = [0usize, 1, 3, 4, 7, 32, 33, 54, 61, 64, 65, 66];
    let base = || {
        let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 0.5);
        cfg.torque_limit = 1e4;
        cfg
    };
    let mut cases = Vec::new();
    cases.push(("sign", base(), truth()));
    let mut c = base();
    (c.derivative_filter, c.friction_smoothing) = (T_F, EPS);
    cases.push(("smoothed", c, realistic_truth()));
    let mut c = base();
    (c.derivative_filter, c.implicit_friction) = (T_F, true);
    cases.push(("implicit", c.clone(), realistic_truth()));
    c.state_jacobians = rss6_ident::StateJacobians::PerTick;
    c.load = Some(PlatformLoad::new(
        2.0,
        Vec3::new(0.05, 0.02, 0.03),
        Mat3::identity() * 1e-3,
    ));
    cases.push(("implicit, per tick, payload", c, realistic_truth()));
    let exc = excitation();
    for (name, mut cfg, a) in cases {
        cfg.parallel_stages = false;
        let seq = simulate_loop(&cfg, &a, &exc, Some(&cols)).unwrap();
        cfg.parallel_stages = true;
        let par = simulate_loop(&cfg, &a, &exc, Some(&cols)).unwrap();
        // 500 ticks, four stages each.
        assert_eq!((seq.stages_ahead, par.stages_ahead), (0, 2000), "{name}");
        assert!(seq.chi == par.chi, "{name}: χ_s differs");
        assert!(seq.jacobian == par.jacobian, "{name}: the Jacobians differ");
        assert_eq!(seq.stuck_joint_ticks, par.stuck_joint_ticks, "{name}");
        // Without sensitivities an implicit tick is rss6-core's one call (first stage shared
        // with the friction step): still the same χ_s, bit for bit.
        let plain = simulate_loop(&cfg, &a, &exc, None).unwrap();
        assert!(plain.chi == seq.chi, "{name}: the primal χ_s differs");
        assert_eq!(plain.stuck_joint_ticks, seq.stuck_joint_ticks, "{name}");
        assert_eq!(plain.inexact_friction, seq.inexact_friction, "{name}");
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let inside = pool.install(|| simulate_loop(&cfg, &a, &exc, Some(&cols)).unwrap());
        assert_eq!(inside.stages_ahead, 0, "{name}");
        assert!(
            inside.jacobian == seq.jacobian,
            "{name}: the Jacobians differ"
        );
    }
}
