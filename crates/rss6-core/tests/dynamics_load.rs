//! A load fixed to the platform (`PlatformLoad` through an `Environment`): checked against the platform
//! body of Ξ (COM at E), against statics and virtual work done by hand, against the load's kinetic
//! energy from finite differences of its pose, and by the round trip, the two dynamics paths (Newton–
//! Euler vs M̃, C̃, G̃), Property 2, M̃ SPD and energy conservation of the RK4 run.
#![allow(
    non_snake_case,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)]

mod dynamics_support;

use dynamics_support::*;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rss6_core::*;

/// The load of the sim test: 2 kg at (0.05, 0.02, 0.03) m in ΣE with a full (non-diagonal) inertia.
fn offset_load() -> PlatformLoad {
    let i = Mat3::new(
        4.0e-3, 0.6e-3, -0.3e-3, //
        0.6e-3, 3.0e-3, 0.4e-3, //
        -0.3e-3, 0.4e-3, 5.0e-3,
    );
    PlatformLoad::new(2.0, Vec3::new(0.05, 0.02, 0.03), i)
}

/// A random physical load: 0.2–5 kg, COM within ±8 cm, inertia A Aᵀ (SPD, non-diagonal).
fn random_load(r: &mut ChaCha8Rng) -> PlatformLoad {
    let a = Mat3::from_fn(|_, _| r.random_range(-0.05..0.05));
    let com = Vec3::from_fn(|_, _| r.random_range(-0.08..0.08));
    PlatformLoad::new(r.random_range(0.2..5.0), com, a * a.transpose())
}

fn tilted() -> Vec3 {
    rotation(0.1, -0.07, 0.0).transpose() * GRAVITY
}

fn env_of(load: PlatformLoad, g: Vec3) -> Environment {
    Environment::with_gravity(g).with_load(load)
}

/// Case k of the random-load tests: robot k / 2, the nominal Ξ on even k and a random one on odd,
/// a random load, gravity tilted on every third case.
fn loaded_case(k: usize, r: &mut ChaCha8Rng) -> (KinematicParams, DynamicParams, Environment) {
    let kp = robot(k / 2, r);
    let dp = if k % 2 == 0 {
        DynamicParams::nominal()
    } else {
        random_xi(r)
    };
    let env = env_of(random_load(r), if k % 3 == 0 { tilted() } else { GRAVITY });
    (kp, dp, env)
}

#[test]
fn load_validation_is_typed() {
    assert!(offset_load().validate().is_ok());
    assert!(PlatformLoad::point(1.0, Vec3::new(0.1, 0.0, 0.0))
        .validate()
        .is_ok());
    let bad = |l: PlatformLoad| l.validate().unwrap_err();
    let mut l = offset_load();
    l.mass = 0.0;
    assert!(matches!(bad(l), CoreError::InvalidParameter(_)));
    let mut l = offset_load();
    l.com[1] = f64::NAN;
    assert_eq!(bad(l), CoreError::NonFinite);
    let mut l = offset_load();
    l.inertia[(0, 1)] += 1e-4; // asymmetric
    assert!(matches!(bad(l), CoreError::InvalidParameter(m) if m.contains("symmetric")));
    // Positive diagonal but indefinite: a 2 × 2 principal minor < 0 (not a leading one).
    let i = Mat3::new(1e-3, 0.0, 2e-3, 0.0, 1e-3, 0.0, 2e-3, 0.0, 1e-3);
    let l = PlatformLoad::new(1.0, Vec3::zeros(), i);
    assert!(matches!(bad(l), CoreError::InvalidParameter(m) if m.contains("semi-definite")));
    // Non-finite loads are refused by every dynamics function, no NaN comes out.
    let (kp, dp, z) = (
        KinematicParams::nominal(),
        DynamicParams::nominal(),
        Vec6::zeros(),
    );
    let mut l = offset_load();
    l.inertia[(2, 2)] = f64::INFINITY;
    let env = env_of(l, GRAVITY);
    let p = home_pose();
    assert_eq!(
        inverse_dynamics_with_env(&kp, &dp, &p, &z, &z, &env),
        Err(CoreError::NonFinite)
    );
    assert_eq!(
        forward_dynamics_with_env(&kp, &dp, &p, &z, &z, &env),
        Err(CoreError::NonFinite)
    );
    assert_eq!(
        mass_matrix_with_env(&kp, &dp, &p, &env),
        Err(CoreError::NonFinite)
    );
    assert_eq!(
        rk4_step_with_env(&kp, &dp, &ModelState::at_rest(&p), &z, 1e-3, &env),
        Err(CoreError::NonFinite)
    );
}

/// (a) A load with its COM at E and a diagonal inertia is the same as adding its mass and inertia to
/// the platform body of Ξ: every function agrees to 1e-12 (relative).
#[test]
fn centred_diagonal_load_equals_heavier_platform() {
    let mut r = rng(41);
    let mut worst: f64 = 0.0;
    for k in 0..20 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let (m, d) = (
            r.random_range(0.2..5.0),
            Vec3::from_fn(|_, _| r.random_range(0.0..0.01)),
        );
        let env = env_of(
            PlatformLoad::new(m, Vec3::zeros(), Mat3::from_diagonal(&d)),
            if k % 3 == 0 { tilted() } else { GRAVITY },
        );
        let mut heavy = dp;
        heavy.platform.mass += m;
        heavy.platform.inertia += d;
        let g = env.gravity;
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let tau_a = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &pdd, &env).unwrap();
        let tau_b = inverse_dynamics_with_gravity(&kp, &heavy, &p, &pd, &pdd, &g).unwrap();
        let acc_a = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau_b, &env).unwrap();
        let acc_b = forward_dynamics_with_gravity(&kp, &heavy, &p, &pd, &tau_b, &g).unwrap();
        let ta = dynamics_terms_with_env(&kp, &dp, &p, &pd, &env).unwrap();
        let tb = dynamics_terms_with_gravity(&kp, &heavy, &p, &pd, &g).unwrap();
        let ma = mass_matrix_with_env(&kp, &dp, &p, &env).unwrap();
        let s = ModelState {
            pose: p,
            pose_dot: pd,
        };
        let sa = rk4_step_with_env(&kp, &dp, &s, &tau_b, 1e-3, &env).unwrap();
        let sb = rk4_step_with_gravity(&kp, &heavy, &s, &tau_b, 1e-3, &g).unwrap();
        let va = potential_energy_with_env(&kp, &dp, &p, &env).unwrap();
        let vb = potential_energy_with_gravity(&kp, &heavy, &p, &g).unwrap();
        let r6 = |a: Vec6, b: Vec6| (a - b).amax() / b.amax().max(1e-300);
        let rm = |a: Mat6, b: Mat6| (a - b).amax() / b.amax();
        let errs = [
            r6(tau_a, tau_b),
            r6(acc_a, acc_b),
            rm(ta.m, tb.m),
            rm(ta.c, tb.c),
            r6(ta.g, tb.g),
            rm(ma, tb.m),
            r6(sa.pose_dot, sb.pose_dot),
            r6(sa.pose, sb.pose),
            rel(va, vb),
        ];
        worst = errs.iter().fold(worst, |w, e| w.max(*e));
    }
    println!("centred load vs heavier platform: max rel. diff {worst:.3e}");
    assert!(worst <= 1e-12, "{worst}");
}

/// (b) Statics done by hand: at rest, J_adᵀ Δτ = [−m g; −(R c') × m g] (the wrench that holds the load
/// about E), Δτ = τ(with load) − τ(without); and G̃ is the gradient of the bodies' potential plus the
/// load's −m gᵀ(E + R c'), by finite differences.
#[test]
fn static_hold_torques_balance_the_offset_weight() {
    let mut r = rng(42);
    let (mut worst_statics, mut worst_grad): (f64, f64) = (0.0, 0.0);
    let z = Vec6::zeros();
    for k in 0..20 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let load = if k == 0 {
            offset_load()
        } else {
            random_load(&mut r)
        };
        let g = if k % 3 == 1 { tilted() } else { GRAVITY };
        let env = env_of(load, g);
        let p = random_pose(&mut r);
        let tau = inverse_dynamics_with_env(&kp, &dp, &p, &z, &z, &env).unwrap();
        let tau0 = inverse_dynamics_with_gravity(&kp, &dp, &p, &z, &z, &g).unwrap();
        let c = pose_rotation(&p) * load.com;
        let w = -g * load.mass;
        let f_e = Vec6::new(w[0], w[1], w[2], 0.0, 0.0, 0.0);
        let n = c.cross(&w);
        let f_e = f_e + Vec6::new(0.0, 0.0, 0.0, n[0], n[1], n[2]);
        let expected = jacobian_ad(&kp, &p)
            .unwrap()
            .transpose()
            .lu()
            .solve(&f_e)
            .unwrap();
        worst_statics = worst_statics.max((tau - tau0 - expected).amax() / expected.amax());
        // Virtual work: G̃ = ∂V/∂χ with V = bodies + load, both by hand.
        if g == GRAVITY {
            let v_load = |q: &Vec6| {
                let e = Vec3::new(q[0], q[1], q[2]);
                -load.mass * g.dot(&(e + pose_rotation(q) * load.com))
            };
            let grad = Vec6::from_fn(|j, _| {
                let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
                d4(
                    |t| {
                        let q = p + e * t;
                        potential_energy_bodies(&kp, &dp, &q) + v_load(&q)
                    },
                    1e-4,
                )
            });
            let gv = gravity_with_env(&kp, &dp, &p, &env).unwrap();
            worst_grad = worst_grad.max((gv - grad).norm() / grad.norm());
            // and the hold torques are J_θ⁻ᵀ G̃ (χ coordinates)
            let jt = jacobian_theta(&kp, &p).unwrap();
            let via_g = jt.transpose().lu().solve(&gv).unwrap();
            worst_statics = worst_statics.max((via_g - tau).amax() / tau.amax());
        }
    }
    println!(
        "statics: max rel. err. of Δτ vs J_ad⁻ᵀ[−mg; −m c×g] = {worst_statics:.3e}; G̃ vs FD gradient {worst_grad:.3e}"
    );
    assert!(worst_statics <= 1e-10, "{worst_statics}");
    assert!(worst_grad <= 1e-8, "{worst_grad}");
}

/// (c) Forward ∘ inverse and inverse ∘ forward with an offset load (friction on).
#[test]
fn forward_and_inverse_round_trip_with_load() {
    let mut r = rng(43);
    let (mut w1, mut w2): (f64, f64) = (0.0, 0.0);
    for k in 0..40 {
        let (kp, dp, env) = loaded_case(k, &mut r);
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let tau = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &pdd, &env).unwrap();
        let acc = forward_dynamics_with_env(&kp, &dp, &p, &pd, &tau, &env).unwrap();
        w1 = w1.max((acc - pdd).amax() / pdd.amax());
        let t2 = Vec6::from_fn(|_, _| r.random_range(-3.0..3.0));
        let a2 = forward_dynamics_with_env(&kp, &dp, &p, &pd, &t2, &env).unwrap();
        let back = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &a2, &env).unwrap();
        w2 = w2.max((back - t2).amax() / t2.amax());
    }
    println!("with load: FD(ID(χ̈)) − χ̈: {w1:.3e} rel; ID(FD(τ)) − τ: {w2:.3e} rel");
    assert!(w1 <= 1e-10 && w2 <= 1e-10, "{w1} {w2}");
}

/// The Newton–Euler path (load force F_L) equals the matrix path (M_L, C_L, G_L):
/// J_θᵀ τ_a = M̃χ̈ + C̃χ̇ + G̃ + τ̃_f with the load.
#[test]
fn newton_euler_matches_matrix_form_with_load() {
    let mut r = rng(44);
    let mut worst: f64 = 0.0;
    for k in 0..30 {
        let kp = robot(k / 2, &mut r);
        let dp = random_xi(&mut r);
        let env = env_of(
            random_load(&mut r),
            if k % 2 == 0 { tilted() } else { GRAVITY },
        );
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let tau = inverse_dynamics_with_env(&kp, &dp, &p, &pd, &pdd, &env).unwrap();
        let t = dynamics_terms_with_env(&kp, &dp, &p, &pd, &env).unwrap();
        let rhs = t.m * pdd + t.c * pd + t.g + t.f;
        worst = worst.max((t.j_theta.transpose() * tau - rhs).amax() / rhs.amax());
    }
    println!("with load: Newton–Euler vs M̃χ̈ + C̃χ̇ + G̃ + τ̃_f: max rel. err. {worst:.3e}");
    assert!(worst <= 1e-12, "{worst}");
}

/// The load's kinetic energy from finite differences of its own centre of mass and orientation,
/// ½ m |ṗ|² + ½ ωᵀ R I'_c Rᵀ ω, equals ½χ̇ᵀ(M̃_env − M̃)χ̇; C̃ with the load satisfies Euler–Lagrange
/// (C̃χ̇ = Ṁ̃χ̇ − ½∂(χ̇ᵀM̃χ̇)/∂χ by FD) and Property 2 (Ṁ̃ = C̃ + C̃ᵀ).
#[test]
fn load_kinetic_energy_and_coriolis_match_finite_differences() {
    let mut r = rng(45);
    let (mut w_t, mut w_el, mut w_p2): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for k in 0..20 {
        let kp = robot(k / 2, &mut r);
        let dp = random_xi(&mut r);
        let load = random_load(&mut r);
        let env = env_of(load, GRAVITY);
        let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
        let h = 1e-4;
        let com = |t: f64| {
            let q = p + pd * t;
            Vec3::new(q[0], q[1], q[2]) + pose_rotation(&q) * load.com
        };
        let p_dot = d4(com, h);
        let rot = pose_rotation(&p);
        let wx = d4(|t| pose_rotation(&(p + pd * t)), h) * rot.transpose();
        let omega = Vec3::new(wx[(2, 1)], wx[(0, 2)], wx[(1, 0)]);
        let t_load = 0.5 * load.mass * p_dot.norm_squared()
            + 0.5 * omega.dot(&(rot * load.inertia * rot.transpose() * omega));
        let t_env = kinetic_energy_with_env(&kp, &dp, &p, &pd, &env).unwrap();
        let t_bare = kinetic_energy(&kp, &dp, &p, &pd).unwrap();
        w_t = w_t.max(rel(t_env - t_bare, t_load));

        let m_at = |q: &Vec6| mass_matrix_with_env(&kp, &dp, q, &env).unwrap();
        let m_dot = d6(|t| m_at(&(p + pd * t)), 1e-4);
        let grad = Vec6::from_fn(|j, _| {
            let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
            d6(|t| pd.dot(&(m_at(&(p + e * t)) * pd)), 1e-4)
        });
        let c = dynamics_terms_with_env(&kp, &dp, &p, &pd, &env).unwrap().c;
        let el = m_dot * pd - grad * 0.5;
        w_el = w_el.max((c * pd - el).amax() / el.amax());
        w_p2 = w_p2.max((m_dot - c - c.transpose()).amax() / m_dot.amax());
    }
    println!(
        "load: kinetic energy vs FD {w_t:.3e} rel; C̃χ̇ vs Euler–Lagrange {w_el:.3e}; Ṁ̃ − C̃ − C̃ᵀ {w_p2:.3e}"
    );
    assert!(w_t <= 1e-8, "{w_t}");
    assert!(w_el <= 1e-7, "{w_el}");
    assert!(w_p2 <= 1e-8, "{w_p2}");
}

/// (e) M̃ with the load is symmetric positive definite over the box corners and random poses, and
/// exceeds M̃ without it by a positive semi-definite M_L.
#[test]
fn mass_matrix_with_load_is_spd() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let env = env_of(offset_load(), GRAVITY);
    let mut r = rng(46);
    let (mut asym, mut lo, mut hi, mut d_lo): (f64, f64, f64, f64) = (0.0, f64::MAX, 0.0, f64::MAX);
    let poses: Vec<Vec6> = box_corners()
        .chain((0..200).map(|_| random_pose(&mut r)))
        .chain(core::iter::once(home_pose()))
        .collect();
    for p in &poses {
        let m = mass_matrix_with_env(&kp, &dp, p, &env).unwrap();
        asym = asym.max((m - m.transpose()).amax() / m.amax());
        let ev = m.symmetric_eigenvalues();
        lo = lo.min(ev.min());
        hi = hi.max(ev.max());
        assert!(m.cholesky().is_some());
        let d = m - mass_matrix(&kp, &dp, p).unwrap();
        d_lo = d_lo.min(d.symmetric_eigenvalues().min() / d.amax());
    }
    println!(
        "M̃ with load: asymmetry {asym:.1e}, eigenvalues {lo:.3} … {hi:.3}; min eig of M̃_L / max|M̃_L| {d_lo:.1e}"
    );
    assert!(asym < 1e-14 && lo > 0.0);
    assert!(d_lo > -1e-12, "the load's M̃_L must be PSD ({d_lo})");
}

/// One RK4 run (1 ms steps, friction off, constant joint torques `tau0`) with the offset load;
/// returns (max |E − E0|, initial and largest kinetic energy) with E = T + V − τ₀ᵀθ (T and V include
/// the load; a constant torque is a conservative force with potential −τ₀ᵀθ).
fn energy_run(env: &Environment, tau0: &Vec6, start: ModelState, steps: usize) -> (f64, f64, f64) {
    let kp = KinematicParams::nominal();
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.0; 6];
    dp.viscous = [0.0; 6];
    let kin =
        |s: &ModelState| kinetic_energy_with_env(&kp, &dp, &s.pose, &s.pose_dot, env).unwrap();
    let energy = |s: &ModelState| {
        kin(s) + potential_energy_with_env(&kp, &dp, &s.pose, env).unwrap()
            - tau0.dot(&ik(&kp, &s.pose).unwrap())
    };
    let (e0, t0) = (energy(&start), kin(&start));
    let mut s = start;
    let (mut drift, mut t_max): (f64, f64) = (0.0, 0.0);
    for step in 0..steps {
        s = match rk4_step_with_env(&kp, &dp, &s, tau0, 1e-3, env) {
            Ok(s) => s,
            Err(e) => panic!("step {step}: {e:?} at {:?}", s.pose),
        };
        drift = drift.max((energy(&s) - e0).abs());
        t_max = t_max.max(kin(&s));
    }
    (drift, t0, t_max)
}

/// (d) Energy conservation with the offset load, friction off, RK4 at 1 ms:
/// * no gravity, no torques, 1 s of coasting from a twist that turns the platform (the load's
///   offset, parallel-axis and gyroscopic terms at work): T (incl. the load) is conserved;
/// * gravity with the constant hold torques of the home pose (no control), 0.25 s from a small
///   displacement: T + V − τ₀ᵀθ is conserved. This equilibrium is unstable (measured: the robot
///   leaves the workspace after ≈ 0.4 s), hence the shorter run.
#[test]
fn energy_is_conserved_with_offset_load() {
    let load = offset_load();
    let start = ModelState {
        pose: home_pose() + Vec6::new(0.002, -0.001, 0.0, 0.0, 0.01, 0.0),
        pose_dot: Vec6::new(0.005, -0.003, 0.004, 0.1, -0.08, 0.15),
    };
    let free = env_of(load, Vec3::zeros());
    let (d_free, t0, tm) = energy_run(&free, &Vec6::zeros(), start, 1000);
    println!("no gravity, no torque, 1 s: max |T − T0| = {d_free:.3e} J of T0 = {t0:.3e} J (max T {tm:.3e} J)");

    let env = env_of(load, GRAVITY);
    let z = Vec6::zeros();
    let (kp, mut dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    dp.coulomb = [0.0; 6];
    dp.viscous = [0.0; 6];
    let tau0 = inverse_dynamics_with_env(&kp, &dp, &home_pose(), &z, &z, &env).unwrap();
    let start_g = ModelState {
        pose: home_pose() + Vec6::new(0.0002, -0.0001, 0.0, 0.0, 0.001, 0.0),
        pose_dot: Vec6::new(0.0, 0.001, 0.0, 0.01, 0.0, 0.02),
    };
    let (d_g, t0_g, tm_g) = energy_run(&env, &tau0, start_g, 250);
    println!("gravity, hold torques, 0.25 s: max |E − E0| = {d_g:.3e} J, T0 = {t0_g:.3e} J, max T = {tm_g:.3e} J");
    assert!(
        tm > 1e-4 && tm_g > 1e-4,
        "the runs must move ({tm}, {tm_g} J)"
    );
    // Bounds: see DRIFT_FREE, DRIFT_GRAVITY. (The gyroscopic ω × I_c ω does no work, so these runs do
    // not see it; `centred_diagonal_load_equals_heavier_platform` and the Newton–Euler vs matrix test
    // do.)
    assert!(d_free <= DRIFT_FREE, "{d_free} J");
    assert!(d_g <= DRIFT_GRAVITY, "{d_g} J");
}

/// Drift without gravity: measured 4.0e-17 J (3 · 10⁻¹⁵ of T0, round-off); 3× that would test the
/// float rounding, so the bound is 10⁻¹⁵ J, still 2000× below what dropping the load's centripetal
/// term m ω × (ω × c) gives (2.0e-6 J).
const DRIFT_FREE: f64 = 1e-15;
/// ≈ 3 × the drift measured with gravity (4.7e-13 J; dropping the centripetal term gives 4.5e-6 J).
const DRIFT_GRAVITY: f64 = 1.5e-12;

/// The state Jacobians with a load and tilted gravity (exact tangents, the load's included) against
/// central differences of the forward dynamics itself (Coulomb off: its sign is held in one and not the
/// other). At a fixed pose χ̈ is quadratic in χ̇, so the χ̇ reference is exact up to rounding.
#[test]
fn state_jacobians_with_load_match_the_forward_dynamics() {
    let mut r = rng(47);
    let (mut wp, mut wv): (f64, f64) = (0.0, 0.0);
    for k in 0..40 {
        let (kp, mut dp, env) = loaded_case(k, &mut r);
        dp.coulomb = [0.0; 6];
        let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
        let tau = Vec6::from_fn(|_, _| r.random_range(-3.0..3.0));
        let req = JacobianRequest {
            state: true,
            ..JacobianRequest::default()
        };
        let mut fj = ForwardJacobians::default();
        forward_dynamics_jacobians_with_env(&kp, &dp, &p, &pd, &tau, &env, &req, &mut fj).unwrap();
        let (fp, fv) = fj.d_state.unwrap();
        let f = |x: &Vec6, v: &Vec6| forward_dynamics_with_env(&kp, &dp, x, v, &tau, &env).unwrap();
        for c in 0..6 {
            let e = Vec6::from_fn(|i, _| if i == c { 1.0 } else { 0.0 });
            let cp = (f(&(p + e * 1e-6), &pd) - f(&(p - e * 1e-6), &pd)) / 2e-6;
            let cv = (f(&p, &(pd + e * 1e-2)) - f(&p, &(pd - e * 1e-2))) / 2e-2;
            wp = wp.max((fp.column(c) - cp).amax() / cp.amax().max(1.0));
            wv = wv.max((fv.column(c) - cv).amax() / cv.amax().max(1.0));
        }
    }
    println!("with load: ∂χ̈/∂χ {wp:.3e}, ∂χ̈/∂χ̇ {wv:.3e} rel to central differences");
    // Measured 3.1·10⁻⁹ / 7.6·10⁻¹³ (the print; the χ columns are the reference's own error:
    // 1.7·10⁻⁹ when the call differenced too); ≈ 3× that.
    assert!(wp <= 1e-8 && wv <= 2.5e-12, "{wp:.3e} {wv:.3e}");
}
