//! The exact χ derivative of the rigid bodies' torques at a fixed (χ̇, χ̈): the tangent of
//! [`twist_force`](super::newton_euler::twist_force), of the load's force and of J_adᵀ along each
//! pose direction, through the leg geometry's own tangent (θ along J_θ, the platform joints and
//! the orientation along the rotation J_e δφ). One product-rule pass per direction instead of the
//! two stepped Newton–Euler passes of a central difference.

use super::load::LoadAt;
use super::rate_tangent::{bottom, stack, top};
use super::{link_transverse_inertia, platform_inertia, wrench_axial_inertia};
use super::{twist_and_rate, z_cross, z_triple};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::leg_jacobians::leg_m;
use crate::params::DynamicParams;
use crate::pose::euler_rate_jacobian;
use crate::types::{Mat3, Mat6, Vec3, Vec6, LEGS};

/// One pose direction e_k: the platform's displacement δE and rotation δφ (world frame), and the
/// changes of the twist v and its rate v̇ at the held χ̇, χ̈.
#[derive(Clone, Copy)]
struct Direction {
    e: Vec3,
    phi: Vec3,
    v: Vec6,
    v_dot: Vec6,
}

/// ∂J_e/∂α and ∂J_e/∂β.
fn euler_rate_jacobian_partials(alpha: f64, beta: f64) -> (Mat3, Mat3) {
    let (sa, ca) = (libm::sin(alpha), libm::cos(alpha));
    let (sb, cb) = (libm::sin(beta), libm::cos(beta));
    (
        Mat3::new(0.0, 0.0, 0.0, 0.0, -sa, -cb * ca, 0.0, ca, -cb * sa),
        Mat3::new(0.0, 0.0, cb, 0.0, 0.0, sb * sa, 0.0, 0.0, -sb * ca),
    )
}

/// ∂J̇_e/∂α and ∂J̇_e/∂β at rates α̇, β̇.
fn euler_rate_jacobian_dot_partials(alpha: f64, beta: f64, ad: f64, bd: f64) -> (Mat3, Mat3) {
    let (sa, ca) = (libm::sin(alpha), libm::cos(alpha));
    let (sb, cb) = (libm::sin(beta), libm::cos(beta));
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

fn directions(pose: &Vec6, pose_dot: &Vec6, pose_ddot: &Vec6) -> [Direction; 6] {
    let (al, be) = (pose[3], pose[4]);
    let je = euler_rate_jacobian(al, be);
    let (pd, pdd) = (bottom(pose_dot), bottom(pose_ddot));
    let (ja, jb) = euler_rate_jacobian_partials(al, be);
    let (jda, jdb) = euler_rate_jacobian_dot_partials(al, be, pose_dot[3], pose_dot[4]);
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
/// ∂(J_ad ν) at ν held. `tau_rigid` is J_adᵀ⁻¹ f at the state.
#[allow(clippy::too_many_arguments)]
pub(super) fn rigid_pose_tangents(
    geom: &LegGeometry,
    j_theta: &Mat6,
    dp: &DynamicParams,
    load: Option<&LoadAt>,
    pose_dot: &Vec6,
    pose_ddot: &Vec6,
    g: &Vec3,
    tau_rigid: &Vec6,
    twist: Option<&Vec6>,
) -> Result<(Mat6, Mat6, Option<Mat6>)> {
    let (v, v_dot) = twist_and_rate(&geom.pose, pose_dot, pose_ddot);
    let (e_dot, omega) = (top(&v), bottom(&v));
    let (e_ddot, omega_dot) = (top(&v_dot), bottom(&v_dot));
    let dirs = directions(&geom.pose, pose_dot, pose_ddot);
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let ip_omega = ip * omega;
    let mut b = Mat6::zeros();
    let mut d_theta_dot = Mat6::zeros();
    let mut d_rates = twist.map(|_| Mat6::zeros());
    for (c, d) in dirs.iter().enumerate() {
        let (d_omega, d_omega_dot) = (bottom(&d.v), bottom(&d.v_dot));
        let sx = d.phi.cross_matrix();
        let d_ip = sx * ip - ip * sx;
        let f_lin = top(&d.v_dot) * dp.platform.mass;
        let f_ang = d_ip * omega_dot
            + ip * d_omega_dot
            + d_omega.cross(&ip_omega)
            + omega.cross(&(d_ip * omega + ip * d_omega));
        let mut f = stack(&f_lin, &f_ang);
        if let Some(load) = load {
            f += load.force_pose_tangent(&v, &v_dot, g, &d.phi, &d.v, &d.v_dot);
        }
        b.set_column(c, &f);
    }
    for i in 0..LEGS {
        let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
        let inv_m = 1.0 / leg_m(&w, &l)?;
        let al = a.cross(&l);
        let r = stack(&l, &al) * inv_m;
        let th_d = r.dot(&v);
        let s_w = z_cross(&w);
        let w_dot = s_w * th_d;
        let a_dot = omega.cross(&a);
        let l_dot = e_dot + a_dot - w_dot;
        let m_dot = z_triple(&w_dot, &l) + z_triple(&w, &l_dot);
        let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
        let num = l_dot.dot(&e_dot) + al_dot.dot(&omega) - m_dot * th_d;
        let th_dd = r.dot(&v_dot) + num * inv_m;
        let t_acc = s_w * th_dd + z_cross(&w_dot) * th_d;
        let l_acc = e_ddot + omega_dot.cross(&a) + omega.cross(&a_dot) - t_acc;
        let inv_l2 = 1.0 / l.norm_squared();
        let omega2 = l.cross(&l_dot) * inv_l2;
        let c2 = 2.0 * l.dot(&l_dot) * inv_l2;
        let omega2_dot = l.cross(&l_acc) * inv_l2 - omega2 * c2;
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let (iz, it) = (wrench_axial_inertia(wb), link_transverse_inertia(lb));
        let s_cw = s_w * 0.5;
        let cw_acc = t_acc * 0.5;
        let cl_acc = t_acc + l_acc * 0.5;
        let q_w = wb.mass * s_cw.dot(&(cw_acc - g)) + iz * th_dd;
        let f_l = (cl_acc - g) * lb.mass;
        let n_l = omega2_dot * it;
        let cl = l * 0.5;
        let u = cl.cross(&f_l) + n_l;
        let p = u.cross(&l);
        let ap = a.cross(&p);
        let kk = z_triple(&p, &w);
        let jv = stack(&p, &ap) + r * kk;
        let s_f = q_w + z_triple(&w, &f_l);
        let leg = Leg {
            w,
            l,
            a,
            s_w,
            inv_m,
            al,
            r,
            th_d,
            w_dot,
            a_dot,
            l_dot,
            m_dot,
            al_dot,
            num,
            th_dd,
            l_acc,
            inv_l2,
            omega2,
            c2,
            iz,
            it,
            s_cw,
            cw_acc,
            mass_w: wb.mass,
            mass_l: lb.mass,
            f_l,
            cl,
            u,
            p,
            kk,
            jv,
            s_f,
        };
        let body = Body {
            v: &v,
            v_dot: &v_dot,
            e_dot,
            omega,
            omega_dot,
            g,
        };
        for (c, d) in dirs.iter().enumerate() {
            // The translations move neither the orientation nor the twist; the yaw turns the
            // platform at an unchanged twist: their zero terms skipped (the sums are the same).
            let dth = j_theta[(i, c)];
            let (df, dr, d_th_d) = match c {
                0..=2 => leg.direction::<false, false>(&body, d, dth),
                5 => leg.direction::<true, false>(&body, d, dth),
                _ => leg.direction::<true, true>(&body, d, dth),
            };
            let mut col = b.column_mut(c);
            col += df - dr * tau_rigid[i];
            d_theta_dot[(i, c)] = d_th_d;
            if let (Some(dr_nu), Some(nu)) = (d_rates.as_mut(), twist) {
                dr_nu[(i, c)] = dr.dot(nu);
            }
        }
    }
    Ok((b, d_theta_dot, d_rates))
}

/// The platform's motion at the state, shared by every leg.
struct Body<'a> {
    v: &'a Vec6,
    v_dot: &'a Vec6,
    e_dot: Vec3,
    omega: Vec3,
    omega_dot: Vec3,
    g: &'a Vec3,
}

/// One leg's kinematics and forces at the state (the names of [`rigid_pose_tangents`]).
struct Leg {
    w: Vec3,
    l: Vec3,
    a: Vec3,
    s_w: Vec3,
    inv_m: f64,
    al: Vec3,
    r: Vec6,
    th_d: f64,
    w_dot: Vec3,
    a_dot: Vec3,
    l_dot: Vec3,
    m_dot: f64,
    al_dot: Vec3,
    num: f64,
    th_dd: f64,
    l_acc: Vec3,
    inv_l2: f64,
    omega2: Vec3,
    c2: f64,
    iz: f64,
    it: f64,
    s_cw: Vec3,
    cw_acc: Vec3,
    mass_w: f64,
    mass_l: f64,
    f_l: Vec3,
    cl: Vec3,
    u: Vec3,
    p: Vec3,
    kk: f64,
    jv: Vec6,
    s_f: f64,
}

impl Leg {
    /// The leg's tangent along `d` (its joint angle moving by `dth`): the change of the
    /// twist-space force, of the rate row r and of θ̇. `TURN`: the direction turns the platform
    /// (δφ ≠ 0); `RATE`: it changes the twist or its rate. A term a direction makes zero is
    /// left out, which changes no sum.
    #[inline(always)]
    fn direction<const TURN: bool, const RATE: bool>(
        &self,
        body: &Body<'_>,
        d: &Direction,
        dth: f64,
    ) -> (Vec6, Vec6, f64) {
        let Leg {
            w,
            l,
            a,
            s_w,
            inv_m,
            al,
            r,
            th_d,
            w_dot,
            a_dot,
            l_dot,
            m_dot,
            al_dot,
            num,
            th_dd,
            l_acc,
            inv_l2,
            omega2,
            c2,
            iz,
            it,
            s_cw,
            cw_acc,
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
        let zero = Vec3::zeros();
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
        let d_inv_l2 = -2.0 * l.dot(&dl) * inv_l2 * inv_l2;
        let d_omega2 = (dl.cross(l_dot) + l.cross(&dl_dot)) * inv_l2 + l.cross(l_dot) * d_inv_l2;
        let dc2 = 2.0 * (dl.dot(l_dot) + l.dot(&dl_dot)) * inv_l2 + 2.0 * l.dot(l_dot) * d_inv_l2;
        let d_omega2_dot = (dl.cross(l_acc) + l.cross(&dl_acc)) * inv_l2
            + l.cross(l_acc) * d_inv_l2
            - d_omega2 * c2
            - omega2 * dc2;
        let dq_w = mass_w * (z_cross(&dw).dot(&(cw_acc - *g)) * 0.5 + s_cw.dot(&(dt_acc * 0.5)))
            + iz * d_th_dd;
        let df_l = (dt_acc + dl_acc * 0.5) * *mass_l;
        let dn_l = d_omega2_dot * *it;
        let du = (dl * 0.5).cross(f_l) + cl.cross(&df_l) + dn_l;
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
