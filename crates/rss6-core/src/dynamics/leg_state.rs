//! Each leg's kinematics and forces at one state, shared by the pose and rate tangents and
//! held two legs at a time ([`Pair`] lanes).

use super::lanes::{Lane, Lanes, Pair};
use super::rate_tangent::{bottom, stack, top};
use super::{link_transverse_inertia, wrench_axial_inertia, z_cross, z_triple};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::leg_jacobians::leg_m;
use crate::params::DynamicParams;
use crate::types::{Vec3, Vec6};
use nalgebra::{Vector3, Vector6};

/// One leg's kinematics and forces at the state (the names of
/// [`rigid_pose_tangents`](super::pose_tangent::rigid_pose_tangents)), of one leg (`T = f64`) or
/// two ([`Pair`]).
#[derive(Clone, Copy)]
pub(super) struct Leg<T: Lane> {
    pub(super) w: Vector3<T>,
    pub(super) l: Vector3<T>,
    pub(super) a: Vector3<T>,
    pub(super) s_w: Vector3<T>,
    pub(super) inv_m: T,
    pub(super) al: Vector3<T>,
    pub(super) r: Vector6<T>,
    pub(super) th_d: T,
    pub(super) w_dot: Vector3<T>,
    pub(super) a_dot: Vector3<T>,
    pub(super) l_dot: Vector3<T>,
    pub(super) m_dot: T,
    pub(super) al_dot: Vector3<T>,
    pub(super) num: T,
    pub(super) th_dd: T,
    pub(super) l_acc: Vector3<T>,
    pub(super) inv_l2: T,
    pub(super) omega2: Vector3<T>,
    pub(super) c2: T,
    pub(super) iz: T,
    pub(super) it: T,
    pub(super) s_cw: Vector3<T>,
    pub(super) cw_acc: Vector3<T>,
    pub(super) mass_w: T,
    pub(super) mass_l: T,
    pub(super) f_l: Vector3<T>,
    pub(super) cl: Vector3<T>,
    pub(super) u: Vector3<T>,
    pub(super) p: Vector3<T>,
    pub(super) kk: T,
    pub(super) jv: Vector6<T>,
    pub(super) s_f: T,
}

impl Leg<f64> {
    /// Leg `i`'s state: its joint rate and acceleration, the link's rates and the forces of
    /// [`twist_force`](super::newton_euler::twist_force)'s recursion.
    pub(super) fn at(
        geom: &LegGeometry,
        dp: &DynamicParams,
        i: usize,
        v: &Vec6,
        v_dot: &Vec6,
        g: &Vec3,
    ) -> Result<Self> {
        let (e_dot, omega) = (top(v), bottom(v));
        let (e_ddot, omega_dot) = (top(v_dot), bottom(v_dot));
        let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
        let inv_m = 1.0 / leg_m(&w, &l)?;
        let al = a.cross(&l);
        let r = stack(&l, &al) * inv_m;
        let th_d = r.dot(v);
        let s_w = z_cross(&w);
        let w_dot = s_w * th_d;
        let a_dot = omega.cross(&a);
        let l_dot = e_dot + a_dot - w_dot;
        let m_dot = z_triple(&w_dot, &l) + z_triple(&w, &l_dot);
        let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
        let num = l_dot.dot(&e_dot) + al_dot.dot(&omega) - m_dot * th_d;
        let th_dd = r.dot(v_dot) + num * inv_m;
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
        let (mass_w, mass_l) = (wb.mass, lb.mass);
        Ok(Leg {
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
        })
    }

    /// Legs `a` and `b` side by side.
    #[inline(always)]
    pub(super) fn zip(a: &Self, b: &Self) -> Leg<Pair> {
        Leg {
            w: Lanes::zip(&a.w, &b.w),
            l: Lanes::zip(&a.l, &b.l),
            a: Lanes::zip(&a.a, &b.a),
            s_w: Lanes::zip(&a.s_w, &b.s_w),
            inv_m: Lanes::zip(&a.inv_m, &b.inv_m),
            al: Lanes::zip(&a.al, &b.al),
            r: Lanes::zip(&a.r, &b.r),
            th_d: Lanes::zip(&a.th_d, &b.th_d),
            w_dot: Lanes::zip(&a.w_dot, &b.w_dot),
            a_dot: Lanes::zip(&a.a_dot, &b.a_dot),
            l_dot: Lanes::zip(&a.l_dot, &b.l_dot),
            m_dot: Lanes::zip(&a.m_dot, &b.m_dot),
            al_dot: Lanes::zip(&a.al_dot, &b.al_dot),
            num: Lanes::zip(&a.num, &b.num),
            th_dd: Lanes::zip(&a.th_dd, &b.th_dd),
            l_acc: Lanes::zip(&a.l_acc, &b.l_acc),
            inv_l2: Lanes::zip(&a.inv_l2, &b.inv_l2),
            omega2: Lanes::zip(&a.omega2, &b.omega2),
            c2: Lanes::zip(&a.c2, &b.c2),
            iz: Lanes::zip(&a.iz, &b.iz),
            it: Lanes::zip(&a.it, &b.it),
            s_cw: Lanes::zip(&a.s_cw, &b.s_cw),
            cw_acc: Lanes::zip(&a.cw_acc, &b.cw_acc),
            mass_w: Lanes::zip(&a.mass_w, &b.mass_w),
            mass_l: Lanes::zip(&a.mass_l, &b.mass_l),
            f_l: Lanes::zip(&a.f_l, &b.f_l),
            cl: Lanes::zip(&a.cl, &b.cl),
            u: Lanes::zip(&a.u, &b.u),
            p: Lanes::zip(&a.p, &b.p),
            kk: Lanes::zip(&a.kk, &b.kk),
            jv: Lanes::zip(&a.jv, &b.jv),
            s_f: Lanes::zip(&a.s_f, &b.s_f),
        }
    }
}

impl Leg<Pair> {
    /// Legs 2k and 2k + 1 side by side at the twist v, its rate v̇ and gravity g (inlined: its
    /// result is too big to copy).
    #[inline(always)]
    pub(super) fn pair(
        geom: &LegGeometry,
        dp: &DynamicParams,
        k: usize,
        (v, v_dot): (&Vec6, &Vec6),
        g: &Vec3,
    ) -> Result<Self> {
        let at = |i| Leg::at(geom, dp, i, v, v_dot, g);
        Ok(Leg::zip(&at(2 * k)?, &at(2 * k + 1)?))
    }
}
