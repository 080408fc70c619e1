//! The exact χ derivative of the rigid bodies' torques at a fixed (χ̇, χ̈): the tangent of
//! [`twist_force`](super::newton_euler::twist_force), of the load's force and of J_adᵀ along each
//! pose direction, through the leg geometry's own tangent (θ along J_θ, the platform joints and
//! the orientation along the rotation J_e δφ). One product-rule pass per direction instead of the
//! two stepped Newton–Euler passes of a central difference.

use super::lanes::{self, Lane, Lanes, Pair};
use super::leg_state::{Leg, LegAcc, LegTerms};
use super::load::{Environment, LoadAt};
use super::newton_euler::rigid_forces;
use super::platform_inertia;
use super::rate_tangent::{bottom, stack, top};
use super::{z_cross, z_triple};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::params::DynamicParams;
use crate::params::KinematicParams;
use crate::pose::RateTrig;
use crate::types::{Mat3, Mat6, Vec3, Vec6};
use nalgebra::{Vector3, Vector6};

/// One pose direction e_k: the platform's displacement δE and rotation δφ (world frame), and the
/// changes of the twist v and its rate v̇ at the held χ̇, χ̈.
#[derive(Clone, Copy)]
struct Direction<T: Lane> {
    e: Vector3<T>,
    phi: Vector3<T>,
    v: Vector6<T>,
    v_dot: Vector6<T>,
}

/// ∂J_e/∂α and ∂J_e/∂β.
fn euler_rate_jacobian_partials(trig: &RateTrig) -> (Mat3, Mat3) {
    let RateTrig { sa, ca, sb, cb } = *trig;
    (
        Mat3::new(0.0, 0.0, 0.0, 0.0, -sa, -cb * ca, 0.0, ca, -cb * sa),
        Mat3::new(0.0, 0.0, cb, 0.0, 0.0, sb * sa, 0.0, 0.0, -sb * ca),
    )
}

/// ∂J̇_e/∂α and ∂J̇_e/∂β at rates α̇, β̇.
fn euler_rate_jacobian_dot_partials(trig: &RateTrig, ad: f64, bd: f64) -> (Mat3, Mat3) {
    let RateTrig { sa, ca, sb, cb } = *trig;
    (
        Mat3::new(
            0.0,
            0.0,
            0.0,
            0.0,
            -ca * ad,
            sb * ca * bd + cb * sa * ad,
            0.0,
            -sa * ad,
            sb * sa * bd - cb * ca * ad,
        ),
        Mat3::new(
            0.0,
            0.0,
            -sb * bd,
            0.0,
            0.0,
            cb * sa * bd + sb * ca * ad,
            0.0,
            0.0,
            -cb * ca * bd + sb * sa * ad,
        ),
    )
}

fn directions(trig: &RateTrig, pose_dot: &Vec6, pose_ddot: &Vec6) -> [Direction<f64>; 6] {
    let je = trig.je();
    let (pd, pdd) = (bottom(pose_dot), bottom(pose_ddot));
    let (ja, jb) = euler_rate_jacobian_partials(trig);
    let (jda, jdb) = euler_rate_jacobian_dot_partials(trig, pose_dot[3], pose_dot[4]);
    let zero = Vec3::zeros();
    core::array::from_fn(|k| {
        if k < 3 {
            let mut e = zero;
            e[k] = 1.0;
            Direction {
                e,
                phi: zero,
                v: Vec6::zeros(),
                v_dot: Vec6::zeros(),
            }
        } else {
            let (dje, djed) = match k {
                3 => (ja, jda),
                4 => (jb, jdb),
                _ => (Mat3::zeros(), Mat3::zeros()),
            };
            Direction {
                e: zero,
                phi: je.column(k - 3).into_owned(),
                v: stack(&zero, &(dje * pd)),
                v_dot: stack(&zero, &(dje * pdd + djed * pd)),
            }
        }
    })
}

/// The pose derivatives at a fixed (χ̇, χ̈) of the rigid bodies' torques, column k for e_k:
/// ∂f − ∂J_adᵀ τ_rigid (to be mapped by J_adᵀ⁻¹), ∂θ̇ (for the viscous term) and, with `twist`,
/// ∂(J_ad ν) at ν held: the platform's and the load's part from [`Self::new`], each pair of legs'
/// from [`Self::add_pair`] (legs 0 to 5 in turn), the sums from [`Self::finish`].
pub(super) struct PoseTangents {
    /// The directions in both lanes.
    dirs: [Direction<Pair>; 6],
    body: Body<Pair>,
    nu: Option<Vector6<Pair>>,
    b: Mat6,
    /// The legs' columns summed lane by lane (legs 0, 2, 4 and 1, 3, 5), added to `b` at the end.
    legs: [Vector6<Pair>; 6],
    d_theta_dot: Mat6,
    d_rates: Option<Mat6>,
}

impl PoseTangents {
    pub(super) fn new(
        geom: &LegGeometry,
        dp: &DynamicParams,
        load: Option<&LoadAt>,
        (pose_dot, pose_ddot): (&Vec6, &Vec6),
        (v, v_dot, trig): (&Vec6, &Vec6, &RateTrig),
        g: &Vec3,
        twist: Option<&Vec6>,
    ) -> Self {
        let (e_dot, omega) = (top(v), bottom(v));
        let omega_dot = bottom(v_dot);
        let dirs = directions(trig, pose_dot, pose_ddot);
        let ip = platform_inertia(&geom.rot, &dp.platform);
        let (ip_omega, ip_omega_dot) = (ip * omega, ip * omega_dot);
        let mut b = Mat6::zeros();
        for (c, d) in dirs.iter().enumerate() {
            if c < 3 && load.is_none() {
                // A translation moves neither the orientation nor the twist: the platform's
                // force does not change (its terms are all zero products).
                continue;
            }
            let (d_omega, d_omega_dot) = (bottom(&d.v), bottom(&d.v_dot));
            // ∂I_p = [δφ]× I_p − I_p [δφ]×, applied to vectors only.
            let d_ip = |x: &Vec3, ip_x: &Vec3| d.phi.cross(ip_x) - ip * d.phi.cross(x);
            let f_lin = top(&d.v_dot) * dp.platform.mass;
            let f_ang = d_ip(&omega_dot, &ip_omega_dot)
                + ip * d_omega_dot
                + d_omega.cross(&ip_omega)
                + omega.cross(&(d_ip(&omega, &ip_omega) + ip * d_omega));
            let mut f = stack(&f_lin, &f_ang);
            if let Some(load) = load {
                f += load.force_pose_tangent(v, v_dot, g, &d.phi, &d.v, &d.v_dot);
            }
            b.set_column(c, &f);
        }
        let zero = Direction {
            e: Vector3::zeros(),
            phi: Vector3::zeros(),
            v: Vector6::zeros(),
            v_dot: Vector6::zeros(),
        };
        let mut t = PoseTangents {
            dirs: [zero; 6],
            legs: [Vector6::zeros(); 6],
            body: Body {
                v: v.splat(),
                v_dot: v_dot.splat(),
                e_dot: e_dot.splat(),
                omega: omega.splat(),
                omega_dot: omega_dot.splat(),
                g: g.splat(),
            },
            nu: twist.map(Lanes::splat),
            b,
            d_theta_dot: Mat6::zeros(),
            d_rates: twist.map(|_| Mat6::zeros()),
        };
        // In place (an array `map` copies the ≈ 2.3 KB it builds).
        for (two, d) in t.dirs.iter_mut().zip(&dirs) {
            two.e = d.e.splat();
            two.phi = d.phi.splat();
            two.v = d.v.splat();
            two.v_dot = d.v_dot.splat();
        }
        t
    }

    /// Adds legs 2k and 2k + 1 (`leg`, side by side): their joint angles move by J_θ e_c along
    /// direction c; `tau_rigid` is J_adᵀ⁻¹ f at the state.
    pub(super) fn add_pair(&mut self, k: usize, leg: &Leg<Pair>, j_theta: &Mat6, tau_rigid: &Vec6) {
        let (i, j) = (2 * k, 2 * k + 1);
        let tau = Pair::new(tau_rigid[i], tau_rigid[j]);
        for (c, d) in self.dirs.iter().enumerate() {
            let dth = Pair::new(j_theta[(i, c)], j_theta[(j, c)]);
            // The translations move neither the orientation nor the twist; the yaw turns the
            // platform at an unchanged twist: their zero terms skipped (the sums are the same).
            let (df, dr, d_th_d) = match c {
                0..=2 => leg.direction::<false, false>(&self.body, d, dth),
                5 => leg.direction::<true, false>(&self.body, d, dth),
                _ => leg.direction::<true, true>(&self.body, d, dth),
            };
            self.legs[c] += df - dr * tau;
            let dr_nu = self.nu.map(|nu| dr.dot(&nu));
            for (lane, leg) in [i, j].into_iter().enumerate() {
                self.d_theta_dot[(leg, c)] = d_th_d.get(lane);
                if let (Some(out), Some(x)) = (self.d_rates.as_mut(), dr_nu) {
                    out[(leg, c)] = x.get(lane);
                }
            }
        }
    }

    /// (∂f − ∂J_adᵀ τ_rigid, ∂θ̇, ∂(J_ad ν) if asked).
    pub(super) fn finish(mut self) -> (Mat6, Mat6, Option<Mat6>) {
        for (c, t) in self.legs.iter().enumerate() {
            let mut col = self.b.column_mut(c);
            col += lanes::lane(t, 0) + lanes::lane(t, 1);
        }
        (self.b, self.d_theta_dot, self.d_rates)
    }
}

/// The pose columns of [`PoseTangents`] by forward differences with step `h_pose`: the geometry
/// at χ + h e_k with the IK linearised along the step, θ + h J_θ e_k (h as taken).
#[allow(clippy::too_many_arguments)]
pub(super) fn stepped_pose_columns(
    kp: &KinematicParams,
    geom: &LegGeometry,
    j_theta: &Mat6,
    dp: &DynamicParams,
    (pose_dot, pose_ddot): (&Vec6, &Vec6),
    env: &Environment,
    tau_rigid: &Vec6,
    twist: Option<&Vec6>,
    h_pose: f64,
) -> Result<(Mat6, Mat6, Option<Mat6>)> {
    let pose = &geom.pose;
    // The state's twist-space force, θ̇ and J_adᵀ, evaluated as the steps are.
    let (f0, td0, j0) = rigid_forces(geom, dp, pose, pose_dot, pose_ddot, env)?;
    let mut d_rates = twist.map(|_| Mat6::zeros());
    let (mut b_pose, mut d_rate_pose) = (Mat6::zeros(), Mat6::zeros());
    for k in 0..6 {
        let mut pp = *pose;
        pp[k] += h_pose;
        let h = pp[k] - pose[k];
        let gp = LegGeometry::from_pose_and_theta(kp, &pp, &(geom.theta + j_theta.column(k) * h));
        let (fp, tdp, jp) = rigid_forces(&gp, dp, &pp, pose_dot, pose_ddot, env)?;
        b_pose.set_column(k, &((fp - f0 - (jp - j0) * tau_rigid) / h));
        d_rate_pose.set_column(k, &((tdp - td0) / h));
        if let (Some(d), Some(nu)) = (d_rates.as_mut(), twist) {
            d.set_column(k, &((jp - j0).tr_mul(nu) / h));
        }
    }
    Ok((b_pose, d_rate_pose, d_rates))
}

/// The platform's motion at the state, shared by every leg (in both lanes).
struct Body<T: Lane> {
    v: Vector6<T>,
    v_dot: Vector6<T>,
    e_dot: Vector3<T>,
    omega: Vector3<T>,
    omega_dot: Vector3<T>,
    g: Vector3<T>,
}

impl<T: Lane> Leg<T> {
    /// The leg's tangent along `d` (its joint angle moving by `dth`): the change of the
    /// twist-space force, of the rate row r and of θ̇. `TURN`: the direction turns the platform
    /// (δφ ≠ 0); `RATE`: it changes the twist or its rate. A term a direction makes zero is
    /// left out, which changes no sum.
    #[inline(always)]
    fn direction<const TURN: bool, const RATE: bool>(
        &self,
        body: &Body<T>,
        d: &Direction<T>,
        dth: T,
    ) -> (Vector6<T>, Vector6<T>, T) {
        let Leg {
            acc:
                LegAcc {
                    w,
                    l,
                    a,
                    r,
                    theta_dot: th_d,
                    theta_ddot: th_dd,
                    inv_l2,
                    s_cw,
                    cw_acc,
                    terms:
                        LegTerms {
                            s_w,
                            inv_m,
                            al,
                            w_dot,
                            a_dot,
                            l_dot,
                            m_dot,
                            al_dot,
                            num,
                            l_acc,
                            omega2,
                            c2,
                        },
                    ..
                },
            iz,
            it,
            mass_w,
            mass_l,
            f_l,
            cl,
            u,
            p,
            kk,
            jv,
            s_f,
        } = self;
        let (inv_m, th_d, m_dot, num, th_dd, inv_l2, c2) =
            (*inv_m, *th_d, *m_dot, *num, *th_dd, *inv_l2, *c2);
        let Body {
            v,
            v_dot,
            e_dot,
            omega,
            omega_dot,
            g,
        } = body;
        let zero = Vector3::zeros();
        let half = T::from(0.5);
        let (de_dot, d_omega) = (top(&d.v), bottom(&d.v));
        let (de_ddot, d_omega_dot) = (top(&d.v_dot), bottom(&d.v_dot));
        let dw = s_w * dth;
        let da = if TURN { d.phi.cross(a) } else { zero };
        let dl = if TURN { d.e + da - dw } else { d.e - dw };
        let dm = z_triple(&dw, l) + z_triple(w, &dl);
        let d_inv_m = -dm * inv_m * inv_m;
        let dal = if TURN {
            da.cross(l) + a.cross(&dl)
        } else {
            a.cross(&dl)
        };
        let dr = stack(&dl, &dal) * inv_m + stack(l, al) * d_inv_m;
        let mut d_th_d = dr.dot(v);
        if RATE {
            d_th_d += r.dot(&d.v);
        }
        let dw_dot = z_cross(&dw) * th_d + s_w * d_th_d;
        let da_dot = match (TURN, RATE) {
            (true, true) => d_omega.cross(a) + omega.cross(&da),
            (true, false) => omega.cross(&da),
            _ => zero,
        };
        let dl_dot = match (TURN, RATE) {
            (true, true) => de_dot + da_dot - dw_dot,
            (true, false) => da_dot - dw_dot,
            _ => -dw_dot,
        };
        let dm_dot = z_triple(&dw_dot, l)
            + z_triple(w_dot, &dl)
            + z_triple(&dw, l_dot)
            + z_triple(w, &dl_dot);
        let dal_dot = if TURN {
            da_dot.cross(l) + a_dot.cross(&dl) + da.cross(l_dot) + a.cross(&dl_dot)
        } else {
            a_dot.cross(&dl) + a.cross(&dl_dot)
        };
        let mut dnum = dl_dot.dot(e_dot);
        if RATE {
            dnum += l_dot.dot(&de_dot);
        }
        dnum += dal_dot.dot(omega);
        if RATE {
            dnum += al_dot.dot(&d_omega);
        }
        dnum = dnum - dm_dot * th_d - m_dot * d_th_d;
        let mut d_th_dd = dr.dot(v_dot);
        if RATE {
            d_th_dd += r.dot(&d.v_dot);
        }
        d_th_dd = d_th_dd + dnum * inv_m + num * d_inv_m;
        let dt_acc = z_cross(&dw) * th_dd
            + s_w * d_th_dd
            + z_cross(&dw_dot) * th_d
            + z_cross(w_dot) * d_th_d;
        let dl_acc = match (TURN, RATE) {
            (true, true) => {
                de_ddot
                    + d_omega_dot.cross(a)
                    + omega_dot.cross(&da)
                    + d_omega.cross(a_dot)
                    + omega.cross(&da_dot)
                    - dt_acc
            }
            (true, false) => omega_dot.cross(&da) + omega.cross(&da_dot) - dt_acc,
            _ => -dt_acc,
        };
        let d_inv_l2 = T::from(-2.0) * l.dot(&dl) * inv_l2 * inv_l2;
        let d_omega2 = (dl.cross(l_dot) + l.cross(&dl_dot)) * inv_l2 + l.cross(l_dot) * d_inv_l2;
        let two = T::from(2.0);
        let dc2 = two * (dl.dot(l_dot) + l.dot(&dl_dot)) * inv_l2 + two * l.dot(l_dot) * d_inv_l2;
        let d_omega2_dot = (dl.cross(l_acc) + l.cross(&dl_acc)) * inv_l2
            + l.cross(l_acc) * d_inv_l2
            - d_omega2 * c2
            - omega2 * dc2;
        let dq_w = *mass_w * (z_cross(&dw).dot(&(cw_acc - *g)) * half + s_cw.dot(&(dt_acc * half)))
            + *iz * d_th_dd;
        let df_l = (dt_acc + dl_acc * half) * *mass_l;
        let dn_l = d_omega2_dot * *it;
        let du = (dl * half).cross(f_l) + cl.cross(&df_l) + dn_l;
        let dp_ = du.cross(l) + u.cross(&dl);
        let dap = if TURN {
            da.cross(p) + a.cross(&dp_)
        } else {
            a.cross(&dp_)
        };
        let dkk = z_triple(&dp_, w) + z_triple(p, &dw);
        let djv = stack(&dp_, &dap) + dr * *kk + r * dkk;
        let ds_f = dq_w + z_triple(&dw, f_l) + z_triple(w, &df_l);
        let df = dr * *s_f + r * ds_f + djv * inv_l2 + jv * d_inv_l2;
        (df, dr, d_th_d)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::twist_and_rate;
    use super::*;
    use crate::types::Vec3;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Two legs side by side give each leg's own tangents bit for bit (lane 0 leg 2k, lane 1
    /// leg 2k + 1), for every kind of direction and for the rate columns.
    #[test]
    fn paired_legs_give_each_legs_scalar_tangents_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let kp = KinematicParams::nominal();
        let mut checked = 0;
        for _ in 0..20 {
            let mut u = |s: f64| Vec6::from_fn(|_, _| s * rng.random_range(-1.0..1.0));
            let pose = Vec6::new(0.0, 0.0, 0.12, 0.0, 0.0, 0.0) + u(0.02);
            let (pose_dot, pose_ddot, dth) = (u(0.5), u(3.0), u(2.0));
            let (de, dphi, dv, dvd) = (u(1.0), u(1.0), u(1.0), u(1.0));
            let mut dp = DynamicParams::nominal();
            dp.links[2].mass *= 1.3;
            dp.wrenches[5].mass *= 0.7;
            let geom = LegGeometry::at_pose(&kp, &pose).unwrap();
            let (v, v_dot) = twist_and_rate(&pose, &pose_dot, &pose_ddot);
            let g = Vec3::new(0.3, -0.2, -9.81);
            let body = Body {
                v,
                v_dot,
                e_dot: top(&v),
                omega: bottom(&v),
                omega_dot: bottom(&v_dot),
                g,
            };
            let d = Direction {
                e: top(&de),
                phi: top(&dphi),
                v: dv,
                v_dot: dvd,
            };
            let split = |d: &Direction<f64>| Direction {
                e: d.e.splat(),
                phi: d.phi.splat(),
                v: d.v.splat(),
                v_dot: d.v_dot.splat(),
            };
            let body2 = Body {
                v: v.splat(),
                v_dot: v_dot.splat(),
                e_dot: body.e_dot.splat(),
                omega: body.omega.splat(),
                omega_dot: body.omega_dot.splat(),
                g: g.splat(),
            };
            for k in 0..3 {
                let pair = Leg::pair(&geom, &dp, k, (&v, &v_dot), &g).unwrap();
                let dth2 = Pair::new(dth[2 * k], dth[2 * k + 1]);
                for lane in 0..2 {
                    let leg = Leg::at(&geom, &dp, 2 * k + lane, &v, &v_dot, &g).unwrap();
                    let one = leg.direction::<true, true>(&body, &d, dth[2 * k + lane]);
                    let two = pair.direction::<true, true>(&body2, &split(&d), dth2);
                    assert_eq!(one.0, lanes::lane(&two.0, lane));
                    assert_eq!(one.1, lanes::lane(&two.1, lane));
                    assert_eq!(one.2.to_bits(), two.2.get(lane).to_bits());
                    let one = leg.direction::<false, false>(&body, &d, dth[2 * k + lane]);
                    let two = pair.direction::<false, false>(&body2, &split(&d), dth2);
                    assert_eq!(one.0, lanes::lane(&two.0, lane));
                    let one = leg.column::<true, true>(&body.e_dot, &body.omega, &dv, &dvd);
                    let (e2, w2) = (body.e_dot.splat(), body.omega.splat());
                    let two = pair.column::<true, true>(&e2, &w2, &dv.splat(), &dvd.splat());
                    assert_eq!(one, lanes::lane(&two, lane));
                    assert!(one.amax() > 0.0);
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 120);
    }
}
