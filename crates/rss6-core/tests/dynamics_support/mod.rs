//! Helpers shared by the dynamics test binaries: seeded random states in the workspace box, perturbed
//! robots, finite differences, and body positions from IK geometry alone (an independent energy model).
#![allow(
    dead_code,
    unreachable_pub,
    clippy::unwrap_used,
    clippy::needless_range_loop
)]

use rand::{Rng, SeedableRng};
pub use rand_chacha::ChaCha8Rng;
use rss6_core::*;

pub const BOX_XYZ: f64 = 0.020;
pub const BOX_ANG: f64 = 0.05;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

pub fn uniform6(r: &mut ChaCha8Rng, lin: f64, ang: f64) -> Vec6 {
    Vec6::from_fn(|i, _| {
        let s = if i < 3 { lin } else { ang };
        r.random_range(-s..=s)
    })
}

pub fn random_pose(r: &mut ChaCha8Rng) -> Vec6 {
    home_pose() + uniform6(r, BOX_XYZ, BOX_ANG)
}

pub fn random_rate(r: &mut ChaCha8Rng) -> Vec6 {
    uniform6(r, 0.2, 1.0)
}

pub fn random_acc(r: &mut ChaCha8Rng) -> Vec6 {
    uniform6(r, 2.0, 10.0)
}

/// Random Ξ around nominal (±50 % per entry) with random friction.
pub fn random_xi(r: &mut ChaCha8Rng) -> DynamicParams {
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
pub fn robot(k: usize, r: &mut ChaCha8Rng) -> KinematicParams {
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
pub fn d4<T, F>(f: F, h: f64) -> T
where
    F: Fn(f64) -> T,
    T: core::ops::Sub<Output = T> + core::ops::Add<Output = T> + core::ops::Mul<f64, Output = T>,
{
    (f(-2.0 * h) - f(2.0 * h) + (f(h) - f(-h)) * 8.0) * (1.0 / (12.0 * h))
}

/// 6th-order central difference of f along a scalar parameter at 0.
pub fn d6<T, F>(f: F, h: f64) -> T
where
    F: Fn(f64) -> T,
    T: core::ops::Sub<Output = T> + core::ops::Add<Output = T> + core::ops::Mul<f64, Output = T>,
{
    ((f(h) - f(-h)) * 45.0 + (f(-2.0 * h) - f(2.0 * h)) * 9.0 + (f(3.0 * h) - f(-3.0 * h)))
        * (1.0 / (60.0 * h))
}

pub fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-300)
}

pub fn box_corners() -> impl Iterator<Item = Vec6> {
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

/// Body "measurements" from IK geometry alone: platform E, R; wrench COM, θ; link COM, unit axis.
pub struct Bodies {
    pub e: Vec3,
    pub rot: Mat3,
    pub theta: Vec6,
    pub cw: [Vec3; 6],
    pub cl: [Vec3; 6],
    pub u: [Vec3; 6],
}

pub fn bodies(kp: &KinematicParams, pose: &Vec6) -> Bodies {
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
pub fn kinetic_energy_fd(kp: &KinematicParams, dp: &DynamicParams, p: &Vec6, pd: &Vec6) -> f64 {
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

pub fn potential_energy_bodies(kp: &KinematicParams, dp: &DynamicParams, p: &Vec6) -> f64 {
    let b = bodies(kp, p);
    let g = 9.81;
    let mut v = dp.platform.mass * g * b.e[2];
    for i in 0..6 {
        v += dp.wrenches[i].mass * g * b.cw[i][2] + dp.links[i].mass * g * b.cl[i][2];
    }
    v
}
