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
/// two ([`Pair`]): the bodies' accelerations and the forces of
/// [`twist_force`](super::newton_euler::twist_force)'s recursion.
#[derive(Clone, Copy)]
pub(super) struct Leg<T: Lane> {
    pub(super) acc: LegAcc<T>,
    pub(super) iz: T,
    pub(super) it: T,
    pub(super) mass_w: T,
    pub(super) mass_l: T,
    pub(super) f_l: Vector3<T>,
    pub(super) cl: Vector3<T>,
    pub(super) u: Vector3<T>,
    pub(super) p: Vector3<T>,
    pub(super) kk: T,
    /// J_bd,iᵀ u ‖l‖² (u = c_l × f_l + n_l).
    pub(super) jv: Vector6<T>,
    /// The factor of the rate row r in the leg's force.
    pub(super) s_f: T,
}

impl<T: Lane> Leg<T> {
    /// The forces on the bodies whose accelerations are `acc`: the wrench's mass and axial
    /// inertia, the link's mass and transverse inertia, gravity g.
    #[inline(always)]
    fn from_acc(
        acc: LegAcc<T>,
        (mass_w, iz): (T, T),
        (mass_l, it): (T, T),
        g: &Vector3<T>,
    ) -> Self {
        let q_w = mass_w * acc.s_cw.dot(&(acc.cw_acc - g)) + iz * acc.theta_ddot;
        let f_l = (acc.cl_acc - g) * mass_l;
        let n_l = acc.omega2_dot * it;
        let cl = acc.l * T::from(0.5);
        let u = cl.cross(&f_l) + n_l;
        let p = u.cross(&acc.l);
        let ap = acc.a.cross(&p);
        let kk = z_triple(&p, &acc.w);
        let jv = stack(&p, &ap) + acc.r * kk;
        let s_f = q_w + z_triple(&acc.w, &f_l);
        Leg {
            acc,
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
        }
    }

    /// The leg's part of the twist-space force, J_iᵀ (M_i v̇_i + gyroscopic − m_i g).
    #[inline(always)]
    fn force(&self) -> Vector6<T> {
        self.acc.r * self.s_f + self.jv * self.acc.inv_l2
    }
}

impl Leg<f64> {
    /// Leg `i`'s state at the twist v, its rate v̇ and gravity g.
    #[cfg(test)]
    pub(super) fn at(
        geom: &LegGeometry,
        dp: &DynamicParams,
        i: usize,
        v: &Vec6,
        v_dot: &Vec6,
        g: &Vec3,
    ) -> Result<Self> {
        let (wb, lb) = (&dp.wrenches[i], &dp.links[i]);
        Ok(Leg::from_acc(
            leg_acc(geom, i, v, v_dot)?,
            (wb.mass, wrench_axial_inertia(wb)),
            (lb.mass, link_transverse_inertia(lb)),
            g,
        ))
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
        let (i, j) = (2 * k, 2 * k + 1);
        let acc = LegAcc::pair(geom, k, (v, v_dot))?;
        let (wi, wj) = (&dp.wrenches[i], &dp.wrenches[j]);
        let (li, lj) = (&dp.links[i], &dp.links[j]);
        let wrench = (
            Pair::new(wi.mass, wj.mass),
            Pair::new(wrench_axial_inertia(wi), wrench_axial_inertia(wj)),
        );
        let link = (
            Pair::new(li.mass, lj.mass),
            Pair::new(link_transverse_inertia(li), link_transverse_inertia(lj)),
        );
        Ok(Leg::from_acc(acc, wrench, link, &g.splat()))
    }
}

/// Legs' body columns of Γ_g by factors (column i of a matrix, entry i of a vector: leg i): the
/// wrench's mass and axial-inertia columns are r_i `q`_i and r_i θ̈_i, the link's mass column
/// `f_cl`, its I_x and I_y columns `half` each (the same arithmetic as
/// [`crate::regressor::regressor_tau_g`]'s); θ̇ for the friction columns.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegColumns {
    pub(crate) q: Vec6,
    pub(crate) theta_ddot: Vec6,
    pub(crate) theta_dot: Vec6,
    pub(crate) f_cl: Mat6,
    pub(crate) half: Mat6,
}

impl LegColumns {
    pub(crate) fn zeros() -> Self {
        LegColumns {
            q: Vec6::zeros(),
            theta_ddot: Vec6::zeros(),
            theta_dot: Vec6::zeros(),
            f_cl: Mat6::zeros(),
            half: Mat6::zeros(),
        }
    }

    /// Every leg's at the twist v, its rate v̇ and gravity g, two legs at a time.
    pub(crate) fn at(geom: &LegGeometry, (v, v_dot): (&Vec6, &Vec6), g: &Vec3) -> Result<Self> {
        let mut c = LegColumns::zeros();
        for k in 0..LEGS / 2 {
            c.add_pair(k, &LegAcc::pair(geom, k, (v, v_dot))?, g);
        }
        Ok(c)
    }

    /// Legs 2k and 2k + 1 from their accelerations (side by side).
    #[inline(always)]
    pub(crate) fn add_pair(&mut self, k: usize, acc: &LegAcc<Pair>, g: &Vec3) {
        let g = g.splat();
        let q = acc.s_cw.dot(&(acc.cw_acc - g));
        let f_cl = acc.jbu_t(&(acc.cl_acc - g));
        let half = acc.jbd_t(&acc.omega2_dot) * Pair::from(0.5);
        for lane in 0..2 {
            let i = 2 * k + lane;
            self.q[i] = q.get(lane);
            self.theta_ddot[i] = acc.theta_ddot.get(lane);
            self.theta_dot[i] = acc.theta_dot.get(lane);
            self.f_cl.set_column(i, &lanes::lane(&f_cl, lane));
            self.half.set_column(i, &lanes::lane(&half, lane));
        }
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

impl LegAcc<Pair> {
    /// Legs 2k and 2k + 1's accelerations side by side at the twist v and its rate v̇.
    #[inline(always)]
    pub(crate) fn pair(geom: &LegGeometry, k: usize, (v, v_dot): (&Vec6, &Vec6)) -> Result<Self> {
        let ((wi, li, ai), (mi, l2i)) = leg_vectors(geom, 2 * k)?;
        let ((wj, lj, aj), (mj, l2j)) = leg_vectors(geom, 2 * k + 1)?;
        let vectors = (
            Lanes::zip(&wi, &wj),
            Lanes::zip(&li, &lj),
            Lanes::zip(&ai, &aj),
        );
        let inverses = (Pair::new(mi, mj), Pair::new(l2i, l2j));
        Ok(LegAcc::from_vectors(
            vectors,
            inverses,
            &v.splat(),
            &v_dot.splat(),
        ))
    }
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
        let (al, r, theta_dot) = rate_row(&l, &a, inv_m, v);
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

/// a × l, the row J_ad,i = [l; a × l]/m and θ̇_i = J_ad,i v of a leg (or two) at the twist v.
#[inline(always)]
fn rate_row<T: Lane>(
    l: &Vector3<T>,
    a: &Vector3<T>,
    inv_m: T,
    v: &Vector6<T>,
) -> (Vector3<T>, Vector6<T>, T) {
    let al = a.cross(l);
    let r = stack(l, &al) * inv_m;
    let theta_dot = r.dot(v);
    (al, r, theta_dot)
}

/// J_adᵀ (its columns the rows J_ad,i) and θ̇ at the twist v: the same values, bit for bit, as
/// [`add_leg_forces`] writes (two legs at a time, the same arithmetic), without the forces.
pub(super) fn joint_rates(geom: &LegGeometry, v: &Vec6) -> Result<(Mat6, Vec6)> {
    let (mut j_ad_t, mut theta_dot) = (Mat6::zeros(), Vec6::zeros());
    let v2 = v.splat();
    for k in 0..LEGS / 2 {
        let ((_, li, ai), (mi, _)) = leg_vectors(geom, 2 * k)?;
        let ((_, lj, aj), (mj, _)) = leg_vectors(geom, 2 * k + 1)?;
        let (l, a) = (Lanes::zip(&li, &lj), Lanes::zip(&ai, &aj));
        let (_, r, td) = rate_row(&l, &a, Pair::new(mi, mj), &v2);
        for (lane, leg) in [2 * k, 2 * k + 1].into_iter().enumerate() {
            theta_dot[leg] = td.get(lane);
            j_ad_t.set_column(leg, &lanes::lane(&r, lane));
        }
    }
    Ok((j_ad_t, theta_dot))
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
    for k in 0..LEGS / 2 {
        let (i, j) = (2 * k, 2 * k + 1);
        let leg = Leg::pair(geom, dp, k, (v, v_dot), g)?;
        let (ka, part) = (&leg.acc, leg.force());
        for (lane, leg) in [i, j].into_iter().enumerate() {
            theta_dot[leg] = ka.theta_dot.get(lane);
            j_ad_t.set_column(leg, &lanes::lane(&ka.r, lane));
            *f += lanes::lane(&part, lane);
        }
    }
    Ok(())
}
