//! A rigid load fixed to the platform ([`PlatformLoad`]) and the environment of a dynamics call
//! ([`Environment`]: gravity and an optional load).
//!
//! Ξ (eq. 5.1) describes the platform as a body with its centre of mass at E and a diagonal inertia in
//! ΣE; a payload whose centre of mass is offset from E, or whose inertia is not diagonal in ΣE, has no
//! place in it. The load is therefore a 14th body, rigidly attached to ΣE, outside Ξ (the regressor
//! and identification are unchanged). With c = R·c' (c' the load's centre of mass in ΣE, m),
//! I_c = R·I'_c·Rᵀ (its inertia about its centre of mass, rotated to the base frame) and the platform
//! twist v_E = [Ė; ω], the load's centre of mass moves with ṗ = Ė + ω × c, so its body Jacobian is
//! J_L = [I, −[c]×; 0, I] and
//!
//! ```text
//! M_L = J_Lᵀ diag(m I, I_c) J_L = [ m I      −m [c]×          ]
//!                                 [ m [c]×    I_c − m [c]×[c]× ]     (parallel axis: −[c]×[c]× = |c|²I − c cᵀ)
//! f   = m (Ë + ω̇ × c + ω × (ω × c) − g)                          (Newton, at the load's centre of mass)
//! F_L = [ f ; c × f + I_c ω̇ + ω × (I_c ω) ]                      (J_Lᵀ [f; n]: moment about E)
//! C_L = [ 0  −m [ċ]× ; 0  −m [c]×[ċ]× + [ω]× I_c ],  ċ = ω × c     (C_L v_E = F_L at ω̇ = 0, Ë = 0, g = 0)
//! G_L = [ −m g ; −m c × g ],  V_L = −m gᵀ (E + c)
//! ```
//!
//! C_L = J_Lᵀ M_b J̇_L + J_Lᵀ [0 0; 0 [ω]× I_c] J_L is built like the other bodies' terms, so
//! Ṁ − 2C stays skew-symmetric (Property 2) with the load.

use super::GRAVITY;
use crate::error::{check_finite, CoreError, Result};
use crate::types::{Mat3, Mat6, Vec3, Vec6};

/// A rigid body fixed to the platform (a payload, a tool): its own mass, centre of mass and inertia,
/// kept apart from Ξ (the platform's entry in [`crate::DynamicParams`] keeps its meaning).
///
/// ```
/// use rss6_core::{Mat3, PlatformLoad, Vec3};
/// // 2 kg, centre of mass 5 cm along x_E, 3 cm above E; a 10 cm solid sphere about its centre.
/// let load = PlatformLoad::new(2.0, Vec3::new(0.05, 0.0, 0.03), Mat3::identity() * (0.4 * 2.0 * 0.05 * 0.05));
/// assert!(load.validate().is_ok());
/// // parallel axis: about E, the moment about z_E adds m·(x² + y²)
/// let i_e = load.inertia_about_e();
/// assert!((i_e[(2, 2)] - (0.002 + 2.0 * 0.05 * 0.05)).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlatformLoad {
    /// Mass m (kg), > 0.
    pub mass: f64,
    /// Centre of mass c' in the end-effector frame ΣE (m).
    pub com: Vec3,
    /// Inertia tensor I'_c about the load's own centre of mass, axes of ΣE (kg·m²); symmetric positive
    /// semi-definite (a point mass has zero inertia).
    pub inertia: Mat3,
}

impl PlatformLoad {
    /// A load of mass `mass` (kg) with centre of mass `com` (m, in ΣE) and inertia `inertia` (kg·m²,
    /// about its centre of mass, ΣE axes). Not checked; see [`PlatformLoad::validate`].
    pub const fn new(mass: f64, com: Vec3, inertia: Mat3) -> Self {
        PlatformLoad { mass, com, inertia }
    }

    /// A point mass `mass` (kg) at `com` (m, in ΣE).
    pub fn point(mass: f64, com: Vec3) -> Self {
        Self::new(mass, com, Mat3::zeros())
    }

    /// Checks the load: every value finite ([`CoreError::NonFinite`]), mass > 0, inertia symmetric
    /// (to 10⁻¹² of its largest entry) and positive semi-definite (every principal minor ≥ 0 to the
    /// same relative tolerance) ([`CoreError::InvalidParameter`]). The triangle inequality of the
    /// principal moments is not required (Table 5.1's own bodies violate it).
    ///
    /// The dynamics functions only check finiteness on every call; validate a load once when it is
    /// built.
    pub fn validate(&self) -> Result<()> {
        check_finite(&[self.mass])?;
        check_finite(self.com.as_slice())?;
        check_finite(self.inertia.as_slice())?;
        if self.mass <= 0.0 {
            return Err(CoreError::InvalidParameter("load mass must be > 0"));
        }
        let i = &self.inertia;
        let scale = i.amax();
        let tol = 1e-12 * scale;
        if (i - i.transpose()).amax() > tol {
            return Err(CoreError::InvalidParameter(
                "load inertia must be symmetric",
            ));
        }
        // Sylvester for semi-definiteness: all principal minors (not only the leading ones) ≥ 0.
        let minor = |a: usize, b: usize| i[(a, a)] * i[(b, b)] - i[(a, b)] * i[(b, a)];
        let psd = (0..3).all(|k| i[(k, k)] >= -tol)
            && [minor(0, 1), minor(0, 2), minor(1, 2)]
                .iter()
                .all(|&m| m >= -tol * scale)
            && i.determinant() >= -tol * scale * scale;
        if !psd {
            return Err(CoreError::InvalidParameter(
                "load inertia must be positive semi-definite",
            ));
        }
        Ok(())
    }

    /// The load's inertia about E in ΣE axes (kg·m²): I'_c + m(|c'|² I − c' c'ᵀ) (parallel axis).
    pub fn inertia_about_e(&self) -> Mat3 {
        let c = self.com;
        self.inertia + (Mat3::identity() * c.norm_squared() - c * c.transpose()) * self.mass
    }

    pub(super) fn check(&self) -> Result<()> {
        check_finite(&[self.mass])?;
        check_finite(self.com.as_slice())?;
        check_finite(self.inertia.as_slice())
    }
}

/// What a dynamics call needs besides the robot: the gravity vector and an optional
/// [`PlatformLoad`]. `Environment::default()` is g = [`GRAVITY`], no load — the plain functions
/// (`inverse_dynamics`, …) and the `*_with_gravity` variants are the `*_with_env` functions with
/// `Environment { gravity: g, load: None }`, with identical results.
///
/// ```
/// use rss6_core::*;
/// let (kp, dp) = (KinematicParams::nominal(), DynamicParams::nominal());
/// let env = Environment::default().with_load(PlatformLoad::point(2.0, Vec3::new(0.05, 0.02, 0.03)));
/// let (pose, z) = (home_pose(), Vec6::zeros());
/// let hold = inverse_dynamics_with_env(&kp, &dp, &pose, &z, &z, &env)?;       // N·m
/// let bare = inverse_dynamics(&kp, &dp, &pose, &z, &z)?;
/// assert!((hold - bare).amax() > 0.1);
/// // at rest the hold torques give zero acceleration
/// let acc = forward_dynamics_with_env(&kp, &dp, &pose, &z, &hold, &env)?;
/// assert!(acc.amax() < 1e-9);
/// # Ok::<(), CoreError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Environment {
    /// Gravity in the base frame (m/s²).
    pub gravity: Vec3,
    /// A load fixed to the platform, if any.
    pub load: Option<PlatformLoad>,
}

impl Default for Environment {
    fn default() -> Self {
        Environment::with_gravity(GRAVITY)
    }
}

impl Environment {
    /// Gravity `gravity` (m/s², base frame), no load.
    pub const fn with_gravity(gravity: Vec3) -> Self {
        Environment {
            gravity,
            load: None,
        }
    }

    /// The same environment with `load` fixed to the platform.
    pub const fn with_load(self, load: PlatformLoad) -> Self {
        Environment {
            gravity: self.gravity,
            load: Some(load),
        }
    }

    /// `Err(NonFinite)` unless gravity and the load are finite.
    pub(super) fn check(&self) -> Result<()> {
        check_finite(self.gravity.as_slice())?;
        match &self.load {
            Some(l) => l.check(),
            None => Ok(()),
        }
    }
}

/// The load at one platform orientation: mass, c = R c' and I_c = R I'_c Rᵀ in the base frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct LoadAt {
    m: f64,
    c: Vec3,
    i: Mat3,
}

impl LoadAt {
    #[inline]
    pub(super) fn new(load: &PlatformLoad, rot: &Mat3) -> Self {
        LoadAt {
            m: load.mass,
            c: rot * load.com,
            i: rot * load.inertia * rot.transpose(),
        }
    }

    /// Adds M_L (twist coordinates) to `m`.
    #[inline]
    pub(super) fn add_mass(&self, m: &mut Mat6) {
        let cx = self.c.cross_matrix() * self.m;
        for k in 0..3 {
            m[(k, k)] += self.m;
        }
        let mut tr = m.fixed_view_mut::<3, 3>(0, 3);
        tr -= cx;
        let mut bl = m.fixed_view_mut::<3, 3>(3, 0);
        bl += cx;
        let mut br = m.fixed_view_mut::<3, 3>(3, 3);
        br += self.i - self.c.cross_matrix() * cx;
    }

    /// Adds C_L (twist coordinates, for the twist `v`) to `c`.
    #[inline]
    pub(super) fn add_coriolis(&self, c: &mut Mat6, v: &Vec6) {
        let omega = Vec3::new(v[3], v[4], v[5]);
        let cdx = omega.cross(&self.c).cross_matrix() * self.m;
        let mut tr = c.fixed_view_mut::<3, 3>(0, 3);
        tr -= cdx;
        let mut br = c.fixed_view_mut::<3, 3>(3, 3);
        br += omega.cross_matrix() * self.i - self.c.cross_matrix() * cdx;
    }

    /// F_L = J_Lᵀ [m(p̈ − g); I_c ω̇ + ω × I_c ω] for the twist `v`, its rate `v_dot` and gravity `g`.
    #[inline]
    pub(super) fn force(&self, v: &Vec6, v_dot: &Vec6, g: &Vec3) -> Vec6 {
        let omega = Vec3::new(v[3], v[4], v[5]);
        let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
        let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
        let p_ddot = e_ddot + omega_dot.cross(&self.c) + omega.cross(&omega.cross(&self.c));
        let f = (p_ddot - g) * self.m;
        let n = self.c.cross(&f) + self.i * omega_dot + omega.cross(&(self.i * omega));
        Vec6::new(f[0], f[1], f[2], n[0], n[1], n[2])
    }

    /// The tangent of [`force`](Self::force) along (δv, δv̇) at twist v (gravity drops out).
    #[inline]
    pub(super) fn force_tangent(&self, v: &Vec6, d_v: &Vec6, d_v_dot: &Vec6) -> Vec6 {
        let omega = Vec3::new(v[3], v[4], v[5]);
        let d_omega = Vec3::new(d_v[3], d_v[4], d_v[5]);
        let d_e_ddot = Vec3::new(d_v_dot[0], d_v_dot[1], d_v_dot[2]);
        let d_omega_dot = Vec3::new(d_v_dot[3], d_v_dot[4], d_v_dot[5]);
        let d_p_ddot = d_e_ddot
            + d_omega_dot.cross(&self.c)
            + d_omega.cross(&omega.cross(&self.c))
            + omega.cross(&d_omega.cross(&self.c));
        let d_f = d_p_ddot * self.m;
        let d_n = self.c.cross(&d_f)
            + self.i * d_omega_dot
            + d_omega.cross(&(self.i * omega))
            + omega.cross(&(self.i * d_omega));
        Vec6::new(d_f[0], d_f[1], d_f[2], d_n[0], d_n[1], d_n[2])
    }

    /// The tangent of [`force`](Self::force) along a pose direction: the load turned by δφ (c and
    /// I_c turn with the platform) and the twist and its rate changed by (δv, δv̇).
    #[inline]
    pub(super) fn force_pose_tangent(
        &self,
        v: &Vec6,
        v_dot: &Vec6,
        g: &Vec3,
        d_phi: &Vec3,
        d_v: &Vec6,
        d_v_dot: &Vec6,
    ) -> Vec6 {
        let omega = Vec3::new(v[3], v[4], v[5]);
        let e_ddot = Vec3::new(v_dot[0], v_dot[1], v_dot[2]);
        let omega_dot = Vec3::new(v_dot[3], v_dot[4], v_dot[5]);
        let d_omega = Vec3::new(d_v[3], d_v[4], d_v[5]);
        let d_e_ddot = Vec3::new(d_v_dot[0], d_v_dot[1], d_v_dot[2]);
        let d_omega_dot = Vec3::new(d_v_dot[3], d_v_dot[4], d_v_dot[5]);
        let d_c = d_phi.cross(&self.c);
        let sx = d_phi.cross_matrix();
        let d_i = sx * self.i - self.i * sx;
        let p_ddot = e_ddot + omega_dot.cross(&self.c) + omega.cross(&omega.cross(&self.c));
        let f = (p_ddot - g) * self.m;
        let d_p_ddot = d_e_ddot
            + d_omega_dot.cross(&self.c)
            + omega_dot.cross(&d_c)
            + d_omega.cross(&omega.cross(&self.c))
            + omega.cross(&(d_omega.cross(&self.c) + omega.cross(&d_c)));
        let d_f = d_p_ddot * self.m;
        let d_n = d_c.cross(&f)
            + self.c.cross(&d_f)
            + d_i * omega_dot
            + self.i * d_omega_dot
            + d_omega.cross(&(self.i * omega))
            + omega.cross(&(d_i * omega + self.i * d_omega));
        Vec6::new(d_f[0], d_f[1], d_f[2], d_n[0], d_n[1], d_n[2])
    }

    /// G_L = [−m g; −m c × g] (twist coordinates).
    #[inline]
    pub(super) fn gravity(&self, g: &Vec3) -> Vec6 {
        let f = -g * self.m;
        let n = self.c.cross(&f);
        Vec6::new(f[0], f[1], f[2], n[0], n[1], n[2])
    }

    /// V_L = −m gᵀ(E + c) (J).
    #[inline]
    pub(super) fn potential(&self, e: &Vec3, g: &Vec3) -> f64 {
        -self.m * g.dot(&(e + self.c))
    }
}
