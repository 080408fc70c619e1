//! Dynamics model checks (thesis §3.5–3.6, §5.2, §6.2): properties of M̃ and C̃, an independent energy
//! derivation from body positions, J̇ against finite differences, the regressor, forward/inverse
//! round trips and power balance of an RK4 run.
#![allow(
    non_snake_case,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rss6_core::*;

const BOX_XYZ: f64 = 0.020;
const BOX_ANG: f64 = 0.05;

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn uniform6(r: &mut ChaCha8Rng, lin: f64, ang: f64) -> Vec6 {
    Vec6::from_fn(|i, _| {
        let s = if i < 3 { lin } else { ang };
        r.random_range(-s..=s)
    })
}

fn random_pose(r: &mut ChaCha8Rng) -> Vec6 {
    home_pose() + uniform6(r, BOX_XYZ, BOX_ANG)
}

fn random_rate(r: &mut ChaCha8Rng) -> Vec6 {
    uniform6(r, 0.2, 1.0)
}

fn random_acc(r: &mut ChaCha8Rng) -> Vec6 {
    uniform6(r, 2.0, 10.0)
}

/// Random Ξ around nominal (±50 % per entry) with random friction.
fn random_xi(r: &mut ChaCha8Rng) -> DynamicParams {
    let mut x = DynamicParams::nominal().to_vector();
    for v in x.iter_mut().take(52) {
        *v *= r.random_range(0.5..1.5);
    }
    for v in x.iter_mut().skip(52) {
        *v = r.random_range(0.0..0.5);
    }
    DynamicParams::from_vector(&x)
}

/// Every other sample: a robot with kinematic errors (±2 mm on joints and lengths, B_i off the base
/// plane), so the model is exercised beyond the symmetric nominal geometry.
fn robot(k: usize, r: &mut ChaCha8Rng) -> KinematicParams {
    if k % 2 == 0 {
        return KinematicParams::nominal();
    }
    let mut b = [0.0; N_KIN_ERRORS];
    for v in b.iter_mut().take(48) {
        *v = r.random_range(-0.002..=0.002);
    }
    KinematicParams::perturbed(&b)
}

/// 4th-order central difference of f along a scalar parameter at 0.
fn d4<T, F>(f: F, h: f64) -> T
where
    F: Fn(f64) -> T,
    T: core::ops::Sub<Output = T> + core::ops::Add<Output = T> + core::ops::Mul<f64, Output = T>,
{
    (f(-2.0 * h) - f(2.0 * h) + (f(h) - f(-h)) * 8.0) * (1.0 / (12.0 * h))
}

/// 6th-order central difference of f along a scalar parameter at 0.
fn d6<T, F>(f: F, h: f64) -> T
where
    F: Fn(f64) -> T,
    T: core::ops::Sub<Output = T> + core::ops::Add<Output = T> + core::ops::Mul<f64, Output = T>,
{
    ((f(h) - f(-h)) * 45.0 + (f(-2.0 * h) - f(2.0 * h)) * 9.0 + (f(3.0 * h) - f(-3.0 * h)))
        * (1.0 / (60.0 * h))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

fn box_corners() -> impl Iterator<Item = Vec6> {
    (0..64u32).map(|bits| {
        home_pose()
            + Vec6::from_fn(|i, _| {
                let s = if i < 3 { BOX_XYZ } else { BOX_ANG };
                if bits & (1 << i) != 0 {
                    s
                } else {
                    -s
                }
            })
    })
}

#[test]
fn mass_matrix_is_symmetric_positive_definite_over_the_box() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let mut r = rng(1);
    let mut min_eig = f64::INFINITY;
    let mut max_eig: f64 = 0.0;
    let poses: Vec<Vec6> = box_corners()
        .chain((0..300).map(|_| random_pose(&mut r)))
        .chain(core::iter::once(home_pose()))
        .collect();
    for p in &poses {
        let m = mass_matrix(&kp, &dp, p).unwrap();
        let asym = (m - m.transpose()).amax() / m.amax();
        assert!(asym < 1e-14, "asymmetry {asym} at {p}");
        let eig = m.symmetric_eigen().eigenvalues;
        min_eig = min_eig.min(eig.min());
        max_eig = max_eig.max(eig.max());
        assert!(m.cholesky().is_some(), "not PD at {p}");
    }
    println!(
        "M~ eigenvalues over {} poses: min {min_eig:.4e}, max {max_eig:.4e}",
        poses.len()
    );
    assert!(min_eig > 0.0);
}

#[test]
fn property2_mdot_minus_2c_is_skew() {
    let dp = DynamicParams::nominal();
    let mut r = rng(2);
    let mut worst: f64 = 0.0;
    let mut worst_full: f64 = 0.0;
    let mut worst_terms: f64 = 0.0;
    for n in 0..40 {
        let kp = robot(n, &mut r);
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let pdd = random_acc(&mut r);
        // dM̃/dt along the motion χ(t) = χ + χ̇ t + ½ χ̈ t² (only χ̇ matters at t = 0).
        let m_dot = d6(
            |t| mass_matrix(&kp, &dp, &(p + pd * t + pdd * (0.5 * t * t))).unwrap(),
            1e-4,
        );
        let c = coriolis(&kp, &dp, &p, &pd).unwrap();
        let s = m_dot - c * 2.0;
        for _ in 0..5 {
            let x = uniform6(&mut r, 1.0, 1.0);
            let q = x.dot(&(s * x));
            let scale = x.dot(&(m_dot * x)).abs() + 2.0 * x.dot(&(c * x)).abs();
            worst = worst.max(q.abs() / scale);
            // magnitude of the terms that cancel: Σ|x_i (|Ṁ_ij| + 2|C_ij|) x_j|
            let xa = x.abs();
            let terms = xa.dot(&((m_dot.abs() + c.abs() * 2.0) * xa));
            worst_terms = worst_terms.max(q.abs() / terms);
        }
        // Equivalent full statement: Ṁ = C + Cᵀ.
        worst_full = worst_full.max((m_dot - c - c.transpose()).amax() / m_dot.amax());
    }
    println!(
        "Property 2: max |xᵀ(Ṁ−2C)x| / (|xᵀṀx| + 2|xᵀCx|) = {worst:.3e}; \
         / Σ|x_i|(|Ṁ_ij|+2|C_ij|)|x_j| = {worst_terms:.3e}; max|Ṁ − C − Cᵀ|/max|Ṁ| = {worst_full:.3e}"
    );
    assert!(worst < 1e-9, "{worst}");
    assert!(worst_terms < 1e-9, "{worst_terms}");
    assert!(worst_full < 1e-8, "{worst_full}");
}

/// Body "measurements" from IK geometry alone: platform E, R; wrench COM, θ; link COM, unit axis.
struct Bodies {
    e: Vec3,
    rot: Mat3,
    theta: Vec6,
    cw: [Vec3; 6],
    cl: [Vec3; 6],
    u: [Vec3; 6],
}

fn bodies(kp: &KinematicParams, pose: &Vec6) -> Bodies {
    let g = LegGeometry::at_pose(kp, pose).unwrap();
    let mut b = Bodies {
        e: Vec3::new(pose[0], pose[1], pose[2]),
        rot: g.rot,
        theta: g.theta,
        cw: [Vec3::zeros(); 6],
        cl: [Vec3::zeros(); 6],
        u: [Vec3::zeros(); 6],
    };
    for i in 0..6 {
        b.cw[i] = (g.b[i] + g.t[i]) * 0.5;
        b.cl[i] = (g.t[i] + g.a[i]) * 0.5;
        b.u[i] = (g.a[i] - g.t[i]).normalize();
    }
    b
}

/// Kinetic energy of the 13 bodies from finite differences of their positions and orientations.
fn kinetic_energy_fd(kp: &KinematicParams, dp: &DynamicParams, p: &Vec6, pd: &Vec6) -> f64 {
    let h = 1e-4;
    let at = |t: f64| bodies(kp, &(p + pd * t));
    let b0 = at(0.0);
    let e_dot = d4(|t| at(t).e, h);
    let r_dot = d4(|t| at(t).rot, h);
    let wx = r_dot * b0.rot.transpose();
    let omega = Vec3::new(wx[(2, 1)], wx[(0, 2)], wx[(1, 0)]);
    let ip = b0.rot * Matrix3::from_diagonal(&dp.platform.inertia) * b0.rot.transpose();
    let mut t = 0.5 * dp.platform.mass * e_dot.norm_squared() + 0.5 * omega.dot(&(ip * omega));
    let th_dot = d4(|t| at(t).theta, h);
    for i in 0..6 {
        let cw_dot = d4(|t| at(t).cw[i], h);
        let cl_dot = d4(|t| at(t).cl[i], h);
        let u_dot = d4(|t| at(t).u[i], h);
        let (w, l) = (&dp.wrenches[i], &dp.links[i]);
        // wrench: translation + spin θ̇ about ŝ with I_z; link: translation + tumbling |u̇| with I_t
        t += 0.5 * w.mass * cw_dot.norm_squared() + 0.5 * w.inertia[2] * th_dot[i].powi(2);
        t += 0.5 * l.mass * cl_dot.norm_squared()
            + 0.5 * 0.5 * (l.inertia[0] + l.inertia[1]) * u_dot.norm_squared();
    }
    t
}

type Matrix3 = nalgebra::Matrix3<f64>;

fn potential_energy_bodies(kp: &KinematicParams, dp: &DynamicParams, p: &Vec6) -> f64 {
    let b = bodies(kp, p);
    let g = 9.81;
    let mut v = dp.platform.mass * g * b.e[2];
    for i in 0..6 {
        v += dp.wrenches[i].mass * g * b.cw[i][2] + dp.links[i].mass * g * b.cl[i][2];
    }
    v
}

#[test]
fn kinetic_energy_matches_bodies_by_finite_differences() {
    let mut r = rng(3);
    let mut worst: f64 = 0.0;
    for k in 0..30 {
        let kp = robot(k / 2, &mut r);
        // nominal and random (unequal I_x, I_y) parameters
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let m = mass_matrix(&kp, &dp, &p).unwrap();
        let t_model = 0.5 * pd.dot(&(m * pd));
        let t_fd = kinetic_energy_fd(&kp, &dp, &p, &pd);
        worst = worst.max(rel(t_model, t_fd));
        assert!((kinetic_energy(&kp, &dp, &p, &pd).unwrap() - t_model).abs() <= 1e-14 * t_model);
    }
    println!("kinetic energy: max rel. err. model vs bodies-by-FD = {worst:.3e}");
    assert!(worst <= 1e-6, "{worst}");
}

#[test]
fn gravity_is_gradient_of_body_potential() {
    let mut r = rng(4);
    let mut worst: f64 = 0.0;
    for k in 0..30 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let p = random_pose(&mut r);
        let g = gravity(&kp, &dp, &p).unwrap();
        let grad = Vec6::from_fn(|j, _| {
            let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
            d4(|t| potential_energy_bodies(&kp, &dp, &(p + e * t)), 1e-4)
        });
        worst = worst.max((g - grad).norm() / grad.norm());
        let v_lib = potential_energy_with_gravity(&kp, &dp, &p, &GRAVITY).unwrap();
        assert!(rel(v_lib, potential_energy_bodies(&kp, &dp, &p)) < 1e-12);
    }
    println!("gravity: max rel. err. G~ vs grad V (FD) = {worst:.3e}");
    assert!(worst <= 1e-6, "{worst}");
}

#[test]
fn tilted_gravity_is_gradient_too() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let g = Vec3::new(0.3, -0.2, -9.8);
    let p = home_pose() + Vec6::new(0.01, -0.005, 0.004, 0.02, -0.03, 0.01);
    let gv = gravity_with(&kp, &dp, &p, &g).unwrap();
    let grad = Vec6::from_fn(|j, _| {
        let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
        d4(
            |t| potential_energy_with_gravity(&kp, &dp, &(p + e * t), &g).unwrap(),
            1e-4,
        )
    });
    assert!((gv - grad).norm() / grad.norm() < 1e-8, "{gv} {grad}");
}

/// Euler–Lagrange: C̃χ̇ = Ṁ̃χ̇ − ½ ∂(χ̇ᵀM̃χ̇)/∂χ, each side by finite differences of M̃ only.
#[test]
fn coriolis_force_matches_lagrange_equations() {
    let dp = DynamicParams::nominal();
    let mut r = rng(5);
    let mut worst: f64 = 0.0;
    for n in 0..20 {
        let kp = robot(n, &mut r);
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let m = |q: &Vec6| mass_matrix(&kp, &dp, q).unwrap();
        let m_dot = d4(|t| m(&(p + pd * t)), 1e-4);
        let dtdq = Vec6::from_fn(|j, _| {
            let e = Vec6::from_fn(|i, _| if i == j { 1.0 } else { 0.0 });
            d4(|t| pd.dot(&(m(&(p + e * t)) * pd)), 1e-4)
        });
        let expect = m_dot * pd - dtdq * 0.5;
        let got = coriolis(&kp, &dp, &p, &pd).unwrap() * pd;
        worst = worst.max((got - expect).norm() / expect.norm());
    }
    println!("Coriolis: max rel. err. C~χ̇ vs Lagrange (FD) = {worst:.3e}");
    assert!(worst < 1e-7, "{worst}");
}

#[test]
fn leg_jacobian_derivatives_match_finite_differences() {
    let mut r = rng(6);
    let (mut wa, mut wb, mut wd) = (0.0f64, 0.0f64, 0.0f64);
    for n in 0..20 {
        let kp = robot(n, &mut r);
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let pdd = random_acc(&mut r);
        let traj = |t: f64| p + pd * t + pdd * (0.5 * t * t);
        let legs = leg_jacobians(&kp, &p, &pd).unwrap();
        let at = |t: f64| leg_jacobians(&kp, &traj(t), &Vec6::zeros()).unwrap();
        // J maps v_E; its derivative along the trajectory:
        for i in 0..6 {
            let ja_dot = d4(|t| at(t)[i].j_a, 1e-4);
            let jb_dot = d4(|t| at(t)[i].j_b, 1e-4);
            let jd_dot = d4(|t| at(t)[i].j_ad, 1e-4);
            wa = wa.max((legs[i].j_a_dot - ja_dot).amax() / ja_dot.amax());
            wb = wb.max((legs[i].j_b_dot - jb_dot).amax() / jb_dot.amax());
            wd = wd.max((legs[i].j_ad_dot - jd_dot).amax() / jd_dot.amax());
        }
        // θ̇ and ω_2 agree with the Jacobians and J_θ
        let th_dot = jacobian_theta(&kp, &p).unwrap() * pd;
        for i in 0..6 {
            assert!((legs[i].theta_dot - th_dot[i]).abs() < 1e-12 * th_dot.amax());
        }
    }
    println!("J̇ vs FD max rel: J_a {wa:.3e}, J_b {wb:.3e}, J_ad row {wd:.3e}");
    assert!(wa < 1e-8 && wb < 1e-8 && wd < 1e-8, "{wa} {wb} {wd}");
}

#[test]
fn leg_jacobians_map_body_velocities() {
    // J_a v_E and J_b v_E equal the FD velocities of the wrench / link centres of mass.
    let kp = KinematicParams::nominal();
    let mut r = rng(7);
    for _ in 0..10 {
        let p = random_pose(&mut r);
        let pd = random_rate(&mut r);
        let v = twist_jacobian(&p) * pd;
        let legs = leg_jacobians(&kp, &p, &pd).unwrap();
        for i in 0..6 {
            let cw_dot = d4(|t| bodies(&kp, &(p + pd * t)).cw[i], 1e-4);
            let cl_dot = d4(|t| bodies(&kp, &(p + pd * t)).cl[i], 1e-4);
            let u_dot = d4(|t| bodies(&kp, &(p + pd * t)).u[i], 1e-4);
            let va = legs[i].j_a * v;
            let vb = legs[i].j_b * v;
            let u = bodies(&kp, &p).u[i];
            assert!((va.fixed_rows::<3>(0) - cw_dot).norm() < 1e-9 * (1.0 + cw_dot.norm()));
            assert!((vb.fixed_rows::<3>(0) - cl_dot).norm() < 1e-9 * (1.0 + cl_dot.norm()));
            let w2 = vb.fixed_rows::<3>(3).into_owned();
            assert!(w2.dot(&u).abs() < 1e-12, "ω2 not ⊥ link");
            assert!((w2.cross(&u) - u_dot).norm() < 1e-9 * (1.0 + u_dot.norm()));
            assert!((va.fixed_rows::<3>(3) - legs[i].omega1).norm() < 1e-15);
        }
    }
}

#[test]
fn inverse_dynamics_matches_matrix_form() {
    // Newton–Euler vector path vs J_θ^{-T}(M̃χ̈ + C̃χ̇ + G̃ + τ̃_f) assembled from the matrices.
    let mut r = rng(8);
    let mut worst: f64 = 0.0;
    for n in 0..30 {
        let kp = robot(n, &mut r);
        let dp = random_xi(&mut r);
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let t = dynamics_terms(&kp, &dp, &p, &pd).unwrap();
        let rhs = t.m * pdd + t.c * pd + t.g + t.f;
        let lhs = t.j_theta.transpose() * tau;
        worst = worst.max((lhs - rhs).norm() / rhs.norm());
        // one-pass terms equal the individual functions
        assert!((t.m - mass_matrix(&kp, &dp, &p).unwrap()).amax() <= 1e-13 * t.m.amax());
        assert!((t.c - coriolis(&kp, &dp, &p, &pd).unwrap()).amax() <= 1e-12 * t.c.amax());
        assert!((t.g - gravity(&kp, &dp, &p).unwrap()).amax() <= 1e-12 * t.g.amax());
        assert!((t.f - friction(&kp, &dp, &p, &pd).unwrap()).amax() <= 1e-12 * t.f.amax());
        assert!((t.j_theta - jacobian_theta(&kp, &p).unwrap()).amax() <= 1e-12 * t.j_theta.amax());
    }
    println!("inverse dynamics vector vs matrix form: max rel {worst:.3e}");
    assert!(worst < 1e-11, "{worst}");
}

#[test]
fn regressor_times_xi_is_inverse_dynamics() {
    let mut r = rng(9);
    let mut worst: f64 = 0.0;
    for n in 0..50 {
        let kp = robot(n, &mut r);
        let dp = random_xi(&mut r);
        let xi = nalgebra::SVector::<f64, 64>::from_column_slice(&dp.to_vector());
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let gamma = regressor(&kp, &p, &pd, &pdd).unwrap();
        let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        worst = worst.max((gamma * xi - tau).amax() / tau.amax().max(1.0));
        // τ_g form: J_adᵀ τ_a
        let gg = regressor_tau_g(&kp, &p, &pd, &pdd).unwrap();
        let j_ad = jacobian_ad(&kp, &p).unwrap();
        let tg = j_ad.transpose() * tau;
        assert!((gg * xi - tg).amax() <= 1e-10 * tg.amax().max(1.0));
    }
    println!("regressor: max |Γ·Ξ − τ_a| / max(1, |τ_a|) = {worst:.3e}");
    assert!(worst <= 1e-10, "{worst}");
}

#[test]
fn regressor_unused_columns_are_zero() {
    let kp = KinematicParams::nominal();
    let mut r = rng(10);
    let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
    let g = regressor(&kp, &p, &pd, &pdd).unwrap();
    for i in 0..6 {
        let w = 4 * (1 + i);
        let l = 4 * (7 + i);
        assert_eq!(g.column(w + 1).amax(), 0.0);
        assert_eq!(g.column(w + 2).amax(), 0.0);
        assert_eq!(g.column(l + 3).amax(), 0.0);
        assert_eq!(g.column(l + 1), g.column(l + 2));
        assert!(
            g.column(w).amax() > 0.0 && g.column(w + 3).amax() > 0.0 && g.column(l).amax() > 0.0
        );
    }
}

#[test]
fn forward_and_inverse_dynamics_round_trip() {
    let mut r = rng(11);
    let (mut w1, mut w2) = (0.0f64, 0.0f64);
    for k in 0..40 {
        let kp = robot(k / 2, &mut r);
        let dp = if k % 2 == 0 {
            DynamicParams::nominal()
        } else {
            random_xi(&mut r)
        };
        let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
        let tau = inverse_dynamics(&kp, &dp, &p, &Vec6::zeros(), &Vec6::zeros()).unwrap()
            + uniform6(&mut r, 5.0, 5.0);
        let acc = forward_dynamics(&kp, &dp, &p, &pd, &tau).unwrap();
        let back = inverse_dynamics(&kp, &dp, &p, &pd, &acc).unwrap();
        w1 = w1.max((back - tau).amax() / tau.amax());
        let pdd = random_acc(&mut r);
        let t2 = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let a2 = forward_dynamics(&kp, &dp, &p, &pd, &t2).unwrap();
        w2 = w2.max((a2 - pdd).amax() / pdd.amax());
    }
    println!("ID(FD(τ)) − τ: {w1:.3e} rel; FD(ID(χ̈)) − χ̈: {w2:.3e} rel");
    assert!(w1 < 1e-10 && w2 < 1e-9, "{w1} {w2}");
}

#[test]
fn static_hold_torques_are_gravity_only_and_home_symmetric() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap();
    // three-fold symmetry: legs 1, 3, 5 equal; 2, 4, 6 equal; mirror pairs opposite in sign
    for i in [2, 4] {
        assert!(
            (tau[i] - tau[0]).abs() < 1e-9 && (tau[i + 1] - tau[1]).abs() < 1e-9,
            "{tau}"
        );
    }
    assert!((tau[0] + tau[1]).abs() < 1e-9, "{tau}");
    // the static torques do work against gravity: J_θᵀ τ = G̃
    let g = gravity(&kp, &dp, &home_pose()).unwrap();
    let jt = jacobian_theta(&kp, &home_pose()).unwrap();
    assert!((jt.transpose() * tau - g).norm() < 1e-10 * g.norm());
    let total_mass = 24.0 + 6.0 * (0.685 + 1.31);
    assert!(g[2] > 9.81 * 24.0 && g[2] < 9.81 * total_mass, "{g}");
    println!("home hold torques {tau:.4}");
}

#[test]
fn friction_opposes_joint_motion() {
    let kp = KinematicParams::nominal();
    let mut dp = DynamicParams::nominal();
    dp.coulomb = [0.3; 6];
    dp.viscous = [0.1; 6];
    let mut r = rng(12);
    let (p, pd) = (random_pose(&mut r), random_rate(&mut r));
    let f = friction(&kp, &dp, &p, &pd).unwrap();
    assert!(
        f.dot(&pd) > 0.0,
        "friction must dissipate: χ̇ᵀτ̃_f = θ̇ᵀτ_f > 0"
    );
    let th_dot = jacobian_theta(&kp, &p).unwrap() * pd;
    let tf = joint_friction(&dp, &th_dot);
    for i in 0..6 {
        assert!((tf[i] - (0.3 * th_dot[i].signum() + 0.1 * th_dot[i])).abs() < 1e-15);
    }
    let smooth = joint_friction_smooth(&dp, &th_dot, 1e-6);
    assert!((smooth - tf).amax() < 1e-9);
    assert_eq!(joint_friction(&dp, &Vec6::zeros()), Vec6::zeros());
}

/// RK4 run with friction off and a zero-order-hold joint PD: per step the work of the held torque is
/// τᵀΔθ, so E(T) − E(0) = Σ τ_kᵀ Δθ_k (d(T+V)/dt = θ̇ᵀτ_a, integrated exactly over each step).
#[test]
fn power_balance_on_rk4_run() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let hold = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap();
    let energy = |s: &ModelState| {
        kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap()
            + potential_energy_with_gravity(&kp, &dp, &s.pose, &GRAVITY).unwrap()
    };
    let dt = 1e-3;
    let mut s = ModelState {
        pose: home_pose() + Vec6::new(0.005, 0.0, 0.0, 0.0, 0.01, 0.0),
        pose_dot: Vec6::zeros(),
    };
    let e0 = energy(&s);
    let mut work = 0.0;
    let mut work_abs = 0.0;
    let mut k_max: f64 = 0.0;
    let mut theta = ik(&kp, &s.pose).unwrap();
    for step in 0..500 {
        let t = step as f64 * dt;
        let th_dot = jacobian_theta(&kp, &s.pose).unwrap() * s.pose_dot;
        let theta_ref = Vec6::from_fn(|i, _| 0.05 * libm::sin(8.0 * t + i as f64));
        let tau = hold + (theta_ref - theta) * 40.0 - th_dot * 0.5;
        s = rk4_step(&kp, &dp, &s, &tau, dt).unwrap();
        let th_new = ik(&kp, &s.pose).unwrap();
        let dw = tau.dot(&(th_new - theta));
        work += dw;
        work_abs += dw.abs();
        theta = th_new;
        k_max = k_max.max(kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap());
    }
    let de = energy(&s) - e0;
    let err = (de - work).abs() / work_abs;
    println!(
        "power balance over 0.5 s: ΔE = {de:.6e} J, Σ τᵀΔθ = {work:.6e} J, Σ|τᵀΔθ| = {work_abs:.3e} J, max T = {k_max:.3e} J, rel err {err:.3e}"
    );
    assert!(k_max > 1e-3, "the run must actually move");
    assert!(err < 1e-6, "{err}");
}

#[test]
fn errors_are_typed() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let far = Vec6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0);
    assert!(matches!(
        mass_matrix(&kp, &dp, &far),
        Err(CoreError::Unreachable { .. })
    ));
    let nan = Vec6::new(f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0);
    assert_eq!(
        inverse_dynamics(&kp, &dp, &home_pose(), &nan, &Vec6::zeros()),
        Err(CoreError::NonFinite)
    );
    assert_eq!(
        forward_dynamics(&kp, &dp, &nan, &Vec6::zeros(), &Vec6::zeros()),
        Err(CoreError::NonFinite)
    );
}

/// Eq. 6.2 read literally omits J_a,iᵀ M_w,i J_a,i J̇_s (and the link analogue) from C̃. This test
/// documents that the literal form breaks Property 2 whenever the Euler angles move, while the
/// library's C̃ (which keeps those terms) satisfies it — the reason for the deviation.
#[test]
fn literal_eq_6_2_coriolis_breaks_property2() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let mut r = rng(13);
    let p = random_pose(&mut r);
    let pd = random_rate(&mut r);
    let js = twist_jacobian(&p);
    let js_dot = twist_jacobian_dot(&p, &pd);
    let v = js * pd;
    let legs = leg_jacobians(&kp, &p, &pd).unwrap();
    let ip = platform_inertia(&pose_rotation(&p), &dp.platform);
    let mut mp = Mat6::zeros();
    mp.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Mat3::identity() * dp.platform.mass));
    mp.fixed_view_mut::<3, 3>(3, 3).copy_from(&ip);
    let mut cp = Mat6::zeros();
    let omega = Vec3::new(v[3], v[4], v[5]);
    cp.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(omega.cross_matrix() * ip));
    let mut c_lit = js.transpose() * (mp * js_dot + cp * js);
    for (i, lj) in legs.iter().enumerate() {
        let mut mw = Mat6::zeros();
        mw.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Mat3::identity() * dp.wrenches[i].mass));
        mw[(5, 5)] = wrench_axial_inertia(&dp.wrenches[i]);
        let mut ml = Mat6::zeros();
        ml.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Mat3::identity() * dp.links[i].mass));
        ml.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Mat3::identity() * link_transverse_inertia(&dp.links[i])));
        c_lit += js.transpose() * lj.j_a.transpose() * mw * lj.j_a_dot * js
            + js.transpose() * lj.j_b.transpose() * ml * lj.j_b_dot * js;
    }
    let m_dot = d4(|t| mass_matrix(&kp, &dp, &(p + pd * t)).unwrap(), 2e-5);
    let c = coriolis(&kp, &dp, &p, &pd).unwrap();
    // the literal form differs from ours exactly by Σ J_sᵀ J_kᵀ M_k J_k J̇_s over the legs
    let lit_err = (m_dot - c_lit - c_lit.transpose()).amax() / m_dot.amax();
    let our_err = (m_dot - c - c.transpose()).amax() / m_dot.amax();
    println!("Property 2 residual: literal eq. 6.2 {lit_err:.3e}, library {our_err:.3e}");
    assert!(our_err < 1e-8);
    assert!(
        lit_err > 1e-3,
        "literal form unexpectedly satisfies Property 2: {lit_err}"
    );
}

/// Structural identifiability of Ξ from τ_a = ΓΞ (nominal robot). Of 64 columns:
/// * 18 are identically zero (wrench I_x, I_y; link I_z) and link I_x, I_y share one column (−6);
/// * with vertical gravity each wrench's mass column is (l_TB/2)² times its I_z column, since
///   ŝ × c_w ⊥ g: only m (l_TB/2)² + I_z about the axis is seen (−6);
/// * a link of mass m is kinetically m/4 at T_i + m/4 at A_i plus a tumbling term in the same
///   direction as its I_t column, and its gravity is m/2 at A_i. Point masses μ_i at the coplanar
///   platform joints A'_i (z = 0) look exactly like platform mass and diagonal inertia whenever
///   Σ μ_i A'_i = 0 (2 conditions) and Σ μ_i x_i y_i = 0 (1 condition): a 3-dimensional family (−3).
///
/// So 64 − 18 − 6 − 6 − 3 = 31 identifiable combinations, and 37 on a tilted base (wrench masses
/// separable). The gap in the singular values must be clean.
#[test]
fn regressor_rank_is_31_with_vertical_gravity() {
    let kp = KinematicParams::nominal();
    let mut r = rng(14);
    let rank_of = |g: &Vec3, r: &mut ChaCha8Rng| {
        // Gram matrix HᵀH of the stacked regressor (no heap matrices in this no-alloc nalgebra)
        let mut gram = nalgebra::SMatrix::<f64, 64, 64>::zeros();
        for _ in 0..120 {
            let (p, pd, pdd) = (random_pose(r), random_rate(r), random_acc(r));
            let gamma = regressor_with_gravity(&kp, &p, &pd, &pdd, g).unwrap();
            gram += gamma.transpose() * gamma;
        }
        // column scaling so that the rank does not depend on units
        let d = nalgebra::SVector::<f64, 64>::from_fn(|i, _| {
            let x = gram[(i, i)];
            if x > 0.0 {
                1.0 / x.sqrt()
            } else {
                0.0
            }
        });
        let scaled = nalgebra::SMatrix::<f64, 64, 64>::from_fn(|i, j| gram[(i, j)] * d[i] * d[j]);
        let ev = scaled.symmetric_eigen().eigenvalues;
        // σ_k² = λ_k: keep singular values above 1e-6 σ_max
        let tol = 1e-12 * ev.max();
        let mut sv: Vec<f64> = ev.iter().map(|&l| l.max(0.0).sqrt()).collect();
        sv.sort_by(|a, b| b.partial_cmp(a).unwrap());
        (ev.iter().filter(|&&l| l > tol).count(), sv)
    };
    let (rank, sv) = rank_of(&GRAVITY, &mut r);
    let (rank_tilt, sv_t) = rank_of(&Vec3::new(0.5, 0.3, -9.8), &mut r);
    println!(
        "regressor rank: {rank} (vertical g; σ around the cut {:.2e} {:.2e}), {rank_tilt} (tilted g; {:.2e} {:.2e})",
        sv[rank - 1] / sv[0],
        sv[rank] / sv[0],
        sv_t[rank_tilt - 1] / sv_t[0],
        sv_t[rank_tilt] / sv_t[0]
    );
    assert_eq!(rank, 31);
    assert_eq!(rank_tilt, 37);
    assert!(sv[rank] / sv[rank - 1] < 1e-5 && sv_t[rank_tilt] / sv_t[rank_tilt - 1] < 1e-5);
}

/// Instantaneous power balance with a constant torque (friction off): along the RK4 trajectory,
/// dE/dt from a 4th-order difference of E over consecutive steps equals θ̇ᵀτ_a at every step.
#[test]
fn instantaneous_power_balance_constant_torque() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap()
        + Vec6::new(0.4, -0.3, 0.2, 0.5, -0.1, 0.3);
    let energy = |s: &ModelState| {
        kinetic_energy(&kp, &dp, &s.pose, &s.pose_dot).unwrap()
            + potential_energy_with_gravity(&kp, &dp, &s.pose, &GRAVITY).unwrap()
    };
    let dt = 1e-3;
    let mut states = vec![ModelState::at_rest(&home_pose())];
    for _ in 0..200 {
        let s = rk4_step(&kp, &dp, states.last().unwrap(), &tau, dt).unwrap();
        states.push(s);
    }
    let e: Vec<f64> = states.iter().map(energy).collect();
    let mut worst: f64 = 0.0;
    let mut p_max: f64 = 0.0;
    for k in 2..states.len() - 2 {
        let de = (e[k - 2] - e[k + 2] + 8.0 * (e[k + 1] - e[k - 1])) / (12.0 * dt);
        let th_dot = jacobian_theta(&kp, &states[k].pose).unwrap() * states[k].pose_dot;
        let p = th_dot.dot(&tau);
        p_max = p_max.max(p.abs());
        worst = worst.max((de - p).abs());
    }
    let rel_err = worst / p_max;
    println!("instantaneous power: max |dE/dt − θ̇ᵀτ| = {worst:.3e} W, max |θ̇ᵀτ| = {p_max:.3e} W, rel {rel_err:.3e}");
    assert!(p_max > 1e-2, "the run must do work");
    assert!(rel_err < 1e-6, "{rel_err}");
}

/// RK4 is 4th order: halving dt divides the error at t = 0.1 s by ≈ 16.
#[test]
fn rk4_converges_at_fourth_order() {
    let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
    let tau = inverse_dynamics(&kp, &dp, &home_pose(), &Vec6::zeros(), &Vec6::zeros()).unwrap()
        + Vec6::new(1.0, -0.5, 0.8, 0.2, -0.6, 0.4);
    let run = |n: usize| {
        let dt = 0.1 / n as f64;
        let mut s = ModelState::at_rest(&home_pose());
        for _ in 0..n {
            s = rk4_step(&kp, &dp, &s, &tau, dt).unwrap();
        }
        s
    };
    let reference = run(400);
    let errs: Vec<f64> = [10usize, 20, 40]
        .iter()
        .map(|&n| (run(n).pose - reference.pose).amax())
        .collect();
    let (r1, r2) = (errs[0] / errs[1], errs[1] / errs[2]);
    println!("RK4 errors {errs:?}, ratios {r1:.2} {r2:.2}");
    assert!(
        (12.0..20.0).contains(&r1) && (12.0..20.0).contains(&r2),
        "{r1} {r2}"
    );
}

/// Twist-coordinate form (eq. 3.41, 3.47, 3.48): J_adᵀ τ_a = M v̇_E + C v_E + G + τ_f, consistent with
/// the χ form (M̃ = J_sᵀ M J_s, C̃ = J_sᵀ(M J̇_s + C J_s), G̃ = J_sᵀ G, τ̃_f = J_sᵀ τ_f) and with
/// dM/dt − 2C skew-symmetric.
#[test]
fn twist_form_is_consistent_with_chi_form() {
    let mut r = rng(15);
    let (mut w_eq, mut w_map, mut w_skew) = (0.0f64, 0.0f64, 0.0f64);
    for n in 0..20 {
        let kp = robot(n, &mut r);
        let dp = random_xi(&mut r);
        let (p, pd, pdd) = (random_pose(&mut r), random_rate(&mut r), random_acc(&mut r));
        let (js, js_dot) = (twist_jacobian(&p), twist_jacobian_dot(&p, &pd));
        let v = js * pd;
        let v_dot = js * pdd + js_dot * pd;
        let m = mass_matrix_twist(&kp, &dp, &p).unwrap();
        let c = coriolis_twist(&kp, &dp, &p, &v).unwrap();
        let g = gravity_twist(&kp, &dp, &p, &GRAVITY).unwrap();
        let f = friction_twist(&kp, &dp, &p, &v).unwrap();
        let tau = inverse_dynamics(&kp, &dp, &p, &pd, &pdd).unwrap();
        let tau_g = jacobian_ad(&kp, &p).unwrap().transpose() * tau;
        let rhs = m * v_dot + c * v + g + f;
        w_eq = w_eq.max((tau_g - rhs).amax() / rhs.amax());
        let t = dynamics_terms(&kp, &dp, &p, &pd).unwrap();
        let jt = js.transpose();
        w_map = w_map
            .max((jt * m * js - t.m).amax() / t.m.amax())
            .max((jt * (m * js_dot + c * js) - t.c).amax() / t.c.amax())
            .max((jt * g - t.g).amax() / t.g.amax())
            .max((jt * f - t.f).amax() / t.f.amax());
        // dM/dt along the motion (the twist form's M depends on χ only)
        let m_dot = d6(
            |s| mass_matrix_twist(&kp, &dp, &(p + pd * s)).unwrap(),
            1e-4,
        );
        w_skew = w_skew.max((m_dot - c - c.transpose()).amax() / m_dot.amax());
    }
    println!("twist form: eq. 3.41 residual {w_eq:.2e}, χ-form mapping {w_map:.2e}, Ṁ − C − Cᵀ {w_skew:.2e}");
    assert!(
        w_eq < 1e-12 && w_map < 1e-12 && w_skew < 1e-8,
        "{w_eq} {w_map} {w_skew}"
    );
}
