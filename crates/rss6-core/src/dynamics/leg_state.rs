//! Each leg's kinematics and forces at one state, shared by the pose and rate tangents and
//! held two legs at a time ([`Pair`] lanes).

use super::lanes::{self, Lane, Lanes, Pair};
use super::rate_tangent::{bottom, stack, top};
use super::{link_transverse_inertia, wrench_axial_inertia, z_cross, z_triple};
use crate::error::Result;
use crate::jacobian::LegGeometry;
use crate::leg_jacobians::leg_m;
use crate::params::DynamicParams;
use crate::types::{Mat6, Vec3, Vec6, LEGS};
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
        let k = leg_acc(geom, i, v, v_dot)?;
        let LegTerms {
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
        } = k.terms;
        let (w, l, a, r, inv_l2) = (k.w, k.l, k.a, k.r, k.inv_l2);
        let (th_d, th_dd, s_cw, cw_acc) = (k.theta_dot, k.theta_ddot, k.s_cw, k.cw_acc);
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        let (iz, it) = (wrench_axial_inertia(wb), link_transverse_inertia(lb));
        let q_w = wb.mass * s_cw.dot(&(cw_acc - g)) + iz * th_dd;
        let f_l = (k.cl_acc - g) * lb.mass;
        let n_l = k.omega2_dot * it;
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

// ---------------------------------------------------------------------------------------------
// Vector (Newton–Euler) path: body accelerations of one leg (or two side by side).

/// Accelerations of one leg's bodies (`T = f64`) or two legs' ([`Pair`]) for twist v and twist
/// rate v̇.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegAcc<T: Lane = f64> {
    /// Row i of J_ad.
    pub(crate) r: Vector6<T>,
    pub(crate) theta_dot: T,
    pub(crate) theta_ddot: T,
    pub(crate) w: Vector3<T>,
    pub(crate) l: Vector3<T>,
    pub(crate) a: Vector3<T>,
    pub(crate) inv_l2: T,
    /// ŝ × c_w (c_w = w/2).
    pub(crate) s_cw: Vector3<T>,
    /// c̈_w (wrench centre-of-mass acceleration).
    pub(crate) cw_acc: Vector3<T>,
    /// c̈_l (link centre-of-mass acceleration).
    pub(crate) cl_acc: Vector3<T>,
    /// ω̇_2.
    pub(crate) omega2_dot: Vector3<T>,
    /// The intermediate terms the tangents reuse ([`Leg`]): ŝ × w, 1/m, a × l, ẇ, ȧ, l̇, ṁ,
    /// (a × l)˙, θ̈'s numerator (θ̈ = J_ad,i v̇_E + num/m), l̈, ω_2 and 2 (l·l̇)/‖l‖².
    pub(crate) terms: LegTerms<T>,
}

/// See [`LegAcc::terms`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegTerms<T: Lane> {
    pub(crate) s_w: Vector3<T>,
    pub(crate) inv_m: T,
    pub(crate) al: Vector3<T>,
    pub(crate) w_dot: Vector3<T>,
    pub(crate) a_dot: Vector3<T>,
    pub(crate) l_dot: Vector3<T>,
    pub(crate) m_dot: T,
    pub(crate) al_dot: Vector3<T>,
    pub(crate) num: T,
    pub(crate) l_acc: Vector3<T>,
    pub(crate) omega2: Vector3<T>,
    pub(crate) c2: T,
}

impl<T: Lane> LegAcc<T> {
    /// J_bd,iᵀ u for a 3-vector u (no matrix formed).
    #[inline]
    pub(crate) fn jbd_t(&self, u: &Vector3<T>) -> Vector6<T> {
        let p = u.cross(&self.l);
        let ap = self.a.cross(&p);
        let k = z_triple(&p, &self.w);
        (stack(&p, &ap) + self.r * k) * self.inv_l2
    }

    /// Generalised force of a force f at the link's centre of mass: J_buᵀ f.
    #[inline]
    pub(crate) fn jbu_t(&self, f: &Vector3<T>) -> Vector6<T> {
        let cl = self.l * T::from(0.5);
        self.r * z_triple(&self.w, f) + self.jbd_t(&cl.cross(f))
    }

    /// The accelerations from the leg vectors w, l, a, 1/m (m = (w × l)·ẑ, checked by the
    /// caller) and 1/‖l‖².
    #[inline(always)]
    fn from_vectors(
        (w, l, a): (Vector3<T>, Vector3<T>, Vector3<T>),
        (inv_m, inv_l2): (T, T),
        v: &Vector6<T>,
        v_dot: &Vector6<T>,
    ) -> Self {
        let (e_dot, omega) = (top(v), bottom(v));
        let (e_ddot, omega_dot) = (top(v_dot), bottom(v_dot));
        let al = a.cross(&l);
        let r = stack(&l, &al) * inv_m;
        let theta_dot = r.dot(v);
        let s_w = z_cross(&w);
        let w_dot = s_w * theta_dot;
        let a_dot = omega.cross(&a);
        let l_dot = e_dot + a_dot - w_dot;
        let m_dot = w_dot[0] * l[1] - w_dot[1] * l[0] + w[0] * l_dot[1] - w[1] * l_dot[0];
        let al_dot = a_dot.cross(&l) + a.cross(&l_dot);
        // θ̈ = J_ad,i v̇_E + J̇_ad,i v_E with J̇_ad,i = ([l̇; ȧ × l + a × l̇] − ṁ J_ad,i)/m
        let num = l_dot.dot(&e_dot) + al_dot.dot(&omega) - m_dot * theta_dot;
        let theta_ddot = r.dot(v_dot) + num * inv_m;
        // T̈ = θ̈ ŝ × w + θ̇ ŝ × ẇ
        let t_acc = s_w * theta_ddot + z_cross(&w_dot) * theta_dot;
        let l_acc = e_ddot + omega_dot.cross(&a) + omega.cross(&a_dot) - t_acc;
        // ω_2 = l × l̇ / ‖l‖²  ⇒  ω̇_2 = l × l̈ / ‖l‖² − 2 (l·l̇)/‖l‖² ω_2
        let omega2 = l.cross(&l_dot) * inv_l2;
        let c2 = T::from(2.0) * l.dot(&l_dot) * inv_l2;
        let omega2_dot = l.cross(&l_acc) * inv_l2 - omega2 * c2;
        let half = T::from(0.5);
        LegAcc {
            r,
            theta_dot,
            theta_ddot,
            w,
            l,
            a,
            inv_l2,
            s_cw: s_w * half,
            cw_acc: t_acc * half,
            cl_acc: t_acc + l_acc * half,
            omega2_dot,
            terms: LegTerms {
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
        }
    }
}

/// A leg's vectors (w, l, a) and (1/m, 1/‖l‖²).
type LegVectors = ((Vec3, Vec3, Vec3), (f64, f64));

/// Leg i's vectors w, l, a and (1/m, 1/‖l‖²); errors at a type I singularity (m = 0).
#[inline(always)]
fn leg_vectors(geom: &LegGeometry, i: usize) -> Result<LegVectors> {
    let (w, l, a) = (geom.w[i], geom.l[i], geom.a_rel[i]);
    let m = leg_m(&w, &l)?;
    Ok(((w, l, a), (1.0 / m, 1.0 / l.norm_squared())))
}

/// Accelerations of leg i's bodies for twist v and twist rate v̇.
#[inline(always)]
pub(crate) fn leg_acc(geom: &LegGeometry, i: usize, v: &Vec6, v_dot: &Vec6) -> Result<LegAcc> {
    let (vectors, inverses) = leg_vectors(geom, i)?;
    Ok(LegAcc::from_vectors(vectors, inverses, v, v_dot))
}

/// Adds every leg's part of the twist-space force Σ_k J_kᵀ (M_k v̇_k + gyroscopic − m_k g) to `f`
/// (legs 0 to 5 in turn, two at a time in [`Pair`] lanes), and writes θ̇ and J_adᵀ (its columns are
/// the rows J_ad,i).
pub(super) fn add_leg_forces(
    geom: &LegGeometry,
    dp: &DynamicParams,
    (v, v_dot): (&Vec6, &Vec6),
    g: &Vec3,
    f: &mut Vec6,
    theta_dot: &mut Vec6,
    j_ad_t: &mut Mat6,
) -> Result<()> {
    let (v2, v_dot2, g2) = (v.splat(), v_dot.splat(), g.splat());
    for k in 0..LEGS / 2 {
        let (i, j) = (2 * k, 2 * k + 1);
        let ((wi, li, ai), (mi, l2i)) = leg_vectors(geom, i)?;
        let ((wj, lj, aj), (mj, l2j)) = leg_vectors(geom, j)?;
        let vectors = (
            Lanes::zip(&wi, &wj),
            Lanes::zip(&li, &lj),
            Lanes::zip(&ai, &aj),
        );
        let inverses = (Pair::new(mi, mj), Pair::new(l2i, l2j));
        let ka = LegAcc::from_vectors(vectors, inverses, &v2, &v_dot2);
        let (wb, lb) = (
            (&dp.wrenches[i], &dp.wrenches[j]),
            (&dp.links[i], &dp.links[j]),
        );
        let mass_w = Pair::new(wb.0.mass, wb.1.mass);
        let iz = Pair::new(wrench_axial_inertia(wb.0), wrench_axial_inertia(wb.1));
        let mass_l = Pair::new(lb.0.mass, lb.1.mass);
        let it = Pair::new(link_transverse_inertia(lb.0), link_transverse_inertia(lb.1));
        let q_w = mass_w * ka.s_cw.dot(&(ka.cw_acc - g2)) + iz * ka.theta_ddot;
        let f_l = (ka.cl_acc - g2) * mass_l;
        let n_l = ka.omega2_dot * it;
        let cl = ka.l * Pair::from(0.5);
        let part = ka.r * (q_w + z_triple(&ka.w, &f_l)) + ka.jbd_t(&(cl.cross(&f_l) + n_l));
        for (lane, leg) in [i, j].into_iter().enumerate() {
            theta_dot[leg] = ka.theta_dot.get(lane);
            j_ad_t.set_column(leg, &lanes::lane(&ka.r, lane));
            *f += lanes::lane(&part, lane);
        }
    }
    Ok(())
}
