//! The leg Jacobians (J̇ against finite differences, body velocities) and the regressor (eq. 5.1): Γ·Ξ is
//! the inverse dynamics, unused columns are zero, rank 31 with vertical gravity.
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
