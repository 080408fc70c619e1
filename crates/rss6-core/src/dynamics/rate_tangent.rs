//! The exact χ̇ derivative of the twist-space force at a fixed pose: the tangent of
//! [`twist_force`](super::newton_euler::twist_force) (and of a load's force) along directions of
//! the twist v and its rate v̇. At a fixed pose the force is quadratic in v and linear in v̇, so
//! its derivative is a product-rule pass over the same leg recursion, one pass per direction
//! instead of the two evaluations a central difference takes.

use super::lanes::{self, Lane, Lanes, Pair};
use super::leg_state::{Leg, LegAcc, LegTerms};
use super::load::LoadAt;
use super::{platform_inertia, z_cross, z_triple};
use crate::jacobian::LegGeometry;
use crate::params::DynamicParams;
use crate::pose::RateTrig;
use crate::types::{Mat6, Vec6};
use nalgebra::{Vector3, Vector6};

/// The linear (first three) entries of a twist-like 6-vector.
pub(super) fn top<T: Lane>(u: &Vector6<T>) -> Vector3<T> {
    Vector3::new(u[0], u[1], u[2])
}

/// The angular (last three) entries of a twist-like 6-vector.
pub(super) fn bottom<T: Lane>(u: &Vector6<T>) -> Vector3<T> {
    Vector3::new(u[3], u[4], u[5])
}

/// [a; b].
pub(super) fn stack<T: Lane>(a: &Vector3<T>, b: &Vector3<T>) -> Vector6<T> {
    Vector6::new(a[0], a[1], a[2], b[0], b[1], b[2])
}

/// (∂v/∂χ̇, ∂v̇/∂χ̇) at (χ, χ̇) (`trig` of χ): J_s, and the χ̇ derivative of v̇ = J_s χ̈ + J̇_s(χ̇) χ̇ (J̇_e is
/// linear in α̇, β̇, so this is exact).
pub(super) fn twist_rate_directions(trig: &RateTrig, pose_dot: &Vec6) -> (Mat6, Mat6) {
    let phi_dot = bottom(pose_dot);
    let je_dot = trig.je_dot(pose_dot[3], pose_dot[4]);
    let d_alpha = trig.je_dot(1.0, 0.0) * phi_dot;
    let d_beta = trig.je_dot(0.0, 1.0) * phi_dot;
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
    (trig.js(), dvd)
}

/// ∂f/∂χ̇ for f the twist-space force of the rigid bodies and the load (the `f` of
/// `rigid_forces`) at a fixed geometry: column k is the tangent of f along (dv e_k, dvd e_k). The
/// platform's and the load's part from [`Self::new`], each pair of legs' from [`Self::add_pair`]
/// (legs 0 to 5 in turn).
pub(super) struct RateTangents {
    e_dot: Vector3<Pair>,
    omega: Vector3<Pair>,
    dv: Mat6,
    dvd: Mat6,
    pub(super) out: Mat6,
}

impl RateTangents {
    pub(super) fn new(
        geom: &LegGeometry,
        dp: &DynamicParams,
        load: Option<&LoadAt>,
        v: &Vec6,
        (dv, dvd): (&Mat6, &Mat6),
    ) -> Self {
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
        RateTangents {
            e_dot: e_dot.splat(),
            omega: omega.splat(),
            dv: *dv,
            dvd: *dvd,
            out,
        }
    }

    /// Adds the next two legs (`leg`, side by side).
    pub(super) fn add_pair(&mut self, leg: &Leg<Pair>) {
        for c in 0..6 {
            let d_v = self.dv.column(c).into_owned().splat();
            let d_vd = self.dvd.column(c).into_owned().splat();
            // χ̇'s first three move only Ė, its last three only ω and ω̇ (J_s = diag(I, J_e), J̇_s
            // likewise): each column skips the other's zero terms (the same sums).
            let d_f = if c < 3 {
                leg.column::<true, false>(&self.e_dot, &self.omega, &d_v, &d_vd)
            } else {
                leg.column::<false, true>(&self.e_dot, &self.omega, &d_v, &d_vd)
            };
            for lane in 0..2 {
                let mut col = self.out.column_mut(c);
                col += lanes::lane(&d_f, lane);
            }
        }
    }
}

impl<T: Lane> Leg<T> {
    /// The leg's part of column (d_v, d_vd) of ∂f/∂χ̇ at the platform's twist (`e_dot`, `omega`).
    /// `LIN`: d_v moves only Ė; `ANG`: d_v moves only ω and d_vd only ω̇ (χ̇'s columns: J_s and
    /// J̇_s are block-diagonal, J̇_s zero on Ė); both: any direction. A term a column makes zero
    /// is left out, which changes no sum.
    #[inline(always)]
    pub(super) fn column<const LIN: bool, const ANG: bool>(
        &self,
        e_dot: &Vector3<T>,
        omega: &Vector3<T>,
        d_v: &Vector6<T>,
        d_vd: &Vector6<T>,
    ) -> Vector6<T> {
        let Leg {
            acc:
                LegAcc {
                    r,
                    theta_dot: th_d,
                    w,
                    l,
                    a,
                    inv_l2,
                    s_cw,
                    terms:
                        LegTerms {
                            inv_m,
                            s_w,
                            w_dot,
                            a_dot,
                            l_dot,
                            m_dot,
                            al_dot,
                            omega2,
                            c2,
                            ..
                        },
                    ..
                },
            iz,
            it,
            cl,
            mass_w,
            mass_l,
            ..
        } = self;
        let (theta_dot, inv_m, m_dot, ll, inv_l2) = (*th_d, *inv_m, *m_dot, *c2, *inv_l2);
        let half = T::from(0.5);
        let (d_e_dot, d_omega) = (top(d_v), bottom(d_v));
        let d_omega_dot = bottom(d_vd);
        let (r_lin, r_ang) = (top(r), bottom(r));
        let d_theta_dot = match (LIN, ANG) {
            (true, false) => r_lin.dot(&d_e_dot),
            (false, true) => r_ang.dot(&d_omega),
            _ => r.dot(d_v),
        };
        let d_w_dot = s_w * d_theta_dot;
        let d_a_dot = d_omega.cross(a);
        let d_l_dot = match (LIN, ANG) {
            (true, false) => d_e_dot - d_w_dot,
            (false, true) => d_a_dot - d_w_dot,
            _ => d_e_dot + d_a_dot - d_w_dot,
        };
        let d_m_dot = d_w_dot[0] * l[1] - d_w_dot[1] * l[0] + w[0] * d_l_dot[1] - w[1] * d_l_dot[0];
        let d_al_dot = if ANG {
            d_a_dot.cross(l) + a.cross(&d_l_dot)
        } else {
            a.cross(&d_l_dot)
        };
        let mut num = d_l_dot.dot(e_dot);
        if LIN {
            num += l_dot.dot(&d_e_dot);
        }
        num += d_al_dot.dot(omega);
        if ANG {
            num += al_dot.dot(&d_omega);
        }
        num = num - d_m_dot * theta_dot - m_dot * d_theta_dot;
        let d_theta_ddot = match (LIN, ANG) {
            (true, false) => num * inv_m,
            (false, true) => r_ang.dot(&d_omega_dot) + num * inv_m,
            _ => r.dot(d_vd) + num * inv_m,
        };
        let d_t_acc =
            s_w * d_theta_ddot + z_cross(&d_w_dot) * theta_dot + z_cross(w_dot) * d_theta_dot;
        let d_l_acc = match (LIN, ANG) {
            (true, false) => -d_t_acc,
            (false, true) => {
                d_omega_dot.cross(a) + d_omega.cross(a_dot) + omega.cross(&d_a_dot) - d_t_acc
            }
            _ => {
                top(d_vd) + d_omega_dot.cross(a) + d_omega.cross(a_dot) + omega.cross(&d_a_dot)
                    - d_t_acc
            }
        };
        let d_omega2 = l.cross(&d_l_dot) * inv_l2;
        let d_omega2_dot = l.cross(&d_l_acc) * inv_l2
            - d_omega2 * ll
            - omega2 * (T::from(2.0) * l.dot(&d_l_dot) * inv_l2);
        let d_q_w = *mass_w * s_cw.dot(&(d_t_acc * half)) + *iz * d_theta_ddot;
        let d_f_l = (d_t_acc + d_l_acc * half) * *mass_l;
        let d_n_l = d_omega2_dot * *it;
        // J_bd,iᵀ u for u = c_l × ∂f_l + ∂n_l (`LegAcc::jbd_t`).
        let u = cl.cross(&d_f_l) + d_n_l;
        let p = u.cross(l);
        let ap = a.cross(&p);
        let kk = z_triple(&p, w);
        let jbd = (stack(&p, &ap) + *r * kk) * inv_l2;
        *r * (d_q_w + z_triple(w, &d_f_l)) + jbd
    }
}
