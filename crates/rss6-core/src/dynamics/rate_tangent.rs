//! The exact χ̇ derivative of the twist-space force at a fixed pose: the tangent of
//! [`twist_force`](super::newton_euler::twist_force) (and of a load's force) along directions of
//! the twist v and its rate v̇. At a fixed pose the force is quadratic in v and linear in v̇, so
//! its derivative is a product-rule pass over the same leg recursion, one pass per direction
//! instead of the two evaluations a central difference takes.

use super::load::LoadAt;
use super::newton_euler::leg_acc;
use super::{link_transverse_inertia, platform_inertia, wrench_axial_inertia, z_cross, z_triple};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::params::DynamicParams;
use crate::pose::{euler_rate_jacobian_dot, twist_jacobian};
use crate::types::{Mat6, Vec3, Vec6, LEGS};

/// The linear (first three) entries of a twist-like 6-vector.
pub(super) fn top(u: &Vec6) -> Vec3 {
    Vec3::new(u[0], u[1], u[2])
}

/// The angular (last three) entries of a twist-like 6-vector.
pub(super) fn bottom(u: &Vec6) -> Vec3 {
    Vec3::new(u[3], u[4], u[5])
}

/// [a; b].
pub(super) fn stack(a: &Vec3, b: &Vec3) -> Vec6 {
    Vec6::new(a[0], a[1], a[2], b[0], b[1], b[2])
}

/// (∂v/∂χ̇, ∂v̇/∂χ̇) at (χ, χ̇): J_s, and the χ̇ derivative of v̇ = J_s χ̈ + J̇_s(χ̇) χ̇ (J̇_e is
/// linear in α̇, β̇, so this is exact).
pub(super) fn twist_rate_directions(pose: &Vec6, pose_dot: &Vec6) -> (Mat6, Mat6) {
    let (al, be) = (pose[3], pose[4]);
    let phi_dot = bottom(pose_dot);
    let je_dot = euler_rate_jacobian_dot(al, be, pose_dot[3], pose_dot[4]);
    let d_alpha = euler_rate_jacobian_dot(al, be, 1.0, 0.0) * phi_dot;
    let d_beta = euler_rate_jacobian_dot(al, be, 0.0, 1.0) * phi_dot;
    let mut dvd = Mat6::zeros();
    for k in 0..3 {
        let mut c = je_dot.column(k).into_owned();
        if k == 0 {
            c += d_alpha;
        } else if k == 1 {
            c += d_beta;
        }
        dvd.fixed_view_mut::<3, 1>(3, 3 + k).copy_from(&c);
    }
    (twist_jacobian(pose), dvd)
}

/// ∂f/∂χ̇ for f the twist-space force of the rigid bodies and the load (the `f` of
/// `rigid_forces`) at a fixed geometry: column k is the tangent of f along (dv e_k, dvd e_k).
pub(super) fn force_rate_tangents(
    geom: &LegGeometry,
    dp: &DynamicParams,
    load: Option<&LoadAt>,
    v: &Vec6,
    v_dot: &Vec6,
    dv: &Mat6,
    dvd: &Mat6,
) -> Result<Mat6> {
    let (e_dot, omega) = (top(v), bottom(v));
    let ip = platform_inertia(&geom.rot, &dp.platform);
    let ip_omega = ip * omega;
    let mut out = Mat6::zeros();
    for c in 0..6 {
        let (d_v, d_vd) = (dv.column(c).into_owned(), dvd.column(c).into_owned());
        let (d_omega, d_omega_dot) = (bottom(&d_v), bottom(&d_vd));
        let f_lin = top(&d_vd) * dp.platform.mass;
        let f_ang = ip * d_omega_dot + d_omega.cross(&ip_omega) + omega.cross(&(ip * d_omega));
        let mut f = stack(&f_lin, &f_ang);
        if let Some(load) = load {
            f += load.force_tangent(v, &d_v, &d_vd);
        }
        out.set_column(c, &f);
    }
    for i in 0..LEGS {
        let k = leg_acc(geom, i, v, v_dot)?;
        let (w, l, a) = (k.w, k.l, k.a);
        // m = (w × l)·ẑ, checked against type I by `leg_acc`.
        let inv_m = 1.0 / z_triple(&w, &l);
        let s_w = z_cross(&w);
        let w_dot = s_w * k.theta_dot;
        let a_dot = omega.cross(&a);
        let l_dot = e_dot + a_dot - w_dot;
        let m_dot = w_dot[0] * l[1] - w_dot[1] * l[0] + w[0] * l_dot[1] - w[1] * l_dot[0];
        let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
        let omega2 = l.cross(&l_dot) * k.inv_l2;
        let ll = 2.0 * l.dot(&l_dot) * k.inv_l2;
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let (iz, it) = (wrench_axial_inertia(wb), link_transverse_inertia(lb));
        let cl = l * 0.5;
        for c in 0..6 {
            let (d_v, d_vd) = (dv.column(c), dvd.column(c));
            let (d_e_dot, d_omega) = (top(&d_v.into_owned()), bottom(&d_v.into_owned()));
            let (d_e_ddot, d_omega_dot) = (top(&d_vd.into_owned()), bottom(&d_vd.into_owned()));
            let d_theta_dot = k.r.dot(&d_v);
            let d_w_dot = s_w * d_theta_dot;
            let d_a_dot = d_omega.cross(&a);
            let d_l_dot = d_e_dot + d_a_dot - d_w_dot;
            let d_m_dot =
                d_w_dot[0] * l[1] - d_w_dot[1] * l[0] + w[0] * d_l_dot[1] - w[1] * d_l_dot[0];
            let d_al_dot = d_a_dot.cross(&l) + a.cross(&d_l_dot);
            let d_theta_ddot = k.r.dot(&d_vd)
                + (d_l_dot.dot(&e_dot)
                    + l_dot.dot(&d_e_dot)
                    + d_al_dot.dot(&omega)
                    + al_dot.dot(&d_omega)
                    - d_m_dot * k.theta_dot
                    - m_dot * d_theta_dot)
                    * inv_m;
            let d_t_acc = s_w * d_theta_ddot
                + z_cross(&d_w_dot) * k.theta_dot
                + z_cross(&w_dot) * d_theta_dot;
            let d_l_acc =
                d_e_ddot + d_omega_dot.cross(&a) + d_omega.cross(&a_dot) + omega.cross(&d_a_dot)
                    - d_t_acc;
            let d_omega2 = l.cross(&d_l_dot) * k.inv_l2;
            let d_omega2_dot = l.cross(&d_l_acc) * k.inv_l2
                - d_omega2 * ll
                - omega2 * (2.0 * l.dot(&d_l_dot) * k.inv_l2);
            let d_q_w = wb.mass * k.s_cw.dot(&(d_t_acc * 0.5)) + iz * d_theta_ddot;
            let d_f_l = (d_t_acc + d_l_acc * 0.5) * lb.mass;
            let d_n_l = d_omega2_dot * it;
            let d_f = k.r * (d_q_w + z_triple(&w, &d_f_l)) + k.jbd_t(&(cl.cross(&d_f_l) + d_n_l));
            let mut col = out.column_mut(c);
            col += d_f;
        }
    }
    Ok(out)
}
