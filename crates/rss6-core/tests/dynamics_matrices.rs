//! Properties of M̃ and C̃ (§6.2): symmetry and positive definiteness, Property 2 (Ṁ̃ − 2C̃ skew), the
//! Coriolis force against Lagrange's equations, the literal eq. 6.2 counter-example, and the twist form.
#![allow(
    non_snake_case,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::needless_range_loop
)] // tests may panic; legs are indexed as in the thesis

mod dynamics_support;

use dynamics_support::*;
use rss6_core::*;

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
