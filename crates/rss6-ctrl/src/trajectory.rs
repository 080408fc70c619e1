//! Reference trajectories with analytic χ_d, χ̇_d, χ̈_d: the sinusoids of Experiment 1 (§6.5.1) and the
//! finite Fourier series of eq. 5.11 / 6.43 (Experiment 2, §6.5.2).
//!
//! Both stay inside the box ±20 mm / ±0.05 rad around the home pose [0, 0, 0.115, 0, 0, 0], which the
//! nominal geometry keeps free of both singularity types (docs/kinematics.md, "The singularity-free
//! box"). Both start away from home in the axes the thesis says, so a robot resting at home sees an
//! initial step.

use libm::{cos, sin};
use rss6_core::{home_pose, Vec6};

/// One sample of a reference: χ_d (m, rad), χ̇_d (m/s, rad/s), χ̈_d (m/s², rad/s²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reference {
    /// Desired pose χ_d.
    pub pose: Vec6,
    /// Desired pose rate χ̇_d.
    pub pose_dot: Vec6,
    /// Desired pose acceleration χ̈_d.
    pub pose_ddot: Vec6,
}

impl Reference {
    /// A constant reference (zero rates) at `pose`.
    pub fn hold(pose: &Vec6) -> Self {
        Reference {
            pose: *pose,
            pose_dot: Vec6::zeros(),
            pose_ddot: Vec6::zeros(),
        }
    }

    /// `true` if every component is finite.
    pub fn is_finite(&self) -> bool {
        crate::error::all_finite(self.pose.as_slice())
            && crate::error::all_finite(self.pose_dot.as_slice())
            && crate::error::all_finite(self.pose_ddot.as_slice())
    }
}

/// Anything that yields a reference at time t (s). Implementations must be allocation-free and bounded.
pub trait Trajectory {
    /// The reference at time `t` (s, from the start of the experiment).
    fn sample(&self, t: f64) -> Reference;
}

/// Per-axis sinusoid χ_d,i(t) = c_i + a_i sin(ω t + φ_i) (Experiment 1, §6.5.1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    /// Centre c (m, rad).
    pub center: Vec6,
    /// Amplitude a (m, rad).
    pub amplitude: Vec6,
    /// Phase φ (rad).
    pub phase: Vec6,
    /// Angular frequency ω (rad/s).
    pub omega: f64,
}

impl Sinusoid {
    /// Experiment 1: ω = 0.5 rad/s; amplitudes 10, 8, 6 mm and 0.03 rad; y starts 8 mm and z 5 mm off
    /// home (the initial step in y and z), x and the angles start at home. Peak excursion 11 mm / 0.03 rad.
    ///
    /// ```
    /// use rss6_ctrl::{Sinusoid, Trajectory};
    /// let r = Sinusoid::experiment1().sample(0.0);
    /// let step = r.pose - rss6_core::home_pose();
    /// assert!((step[1] - 0.008).abs() < 1e-12 && (step[2] - 0.005).abs() < 1e-12);
    /// assert!((r.pose_dot[0] - 0.010 * 0.5).abs() < 1e-12); // analytic χ̇_d
    /// ```
    pub fn experiment1() -> Self {
        let home = home_pose();
        Sinusoid {
            center: home + Vec6::new(0.0, 0.0, 0.005, 0.0, 0.0, 0.0),
            amplitude: Vec6::new(0.010, 0.008, 0.006, 0.03, 0.03, 0.03),
            phase: Vec6::new(0.0, core::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0),
            omega: rss6_core::thesis::EXPERIMENT1_OMEGA,
        }
    }
}

impl Trajectory for Sinusoid {
    fn sample(&self, t: f64) -> Reference {
        let w = self.omega;
        let mut r = Reference::hold(&self.center);
        for i in 0..6 {
            let arg = w * t + self.phase[i];
            let (s, c) = (sin(arg), cos(arg));
            let a = self.amplitude[i];
            r.pose[i] += a * s;
            r.pose_dot[i] = a * w * c;
            r.pose_ddot[i] = -a * w * w * s;
        }
        r
    }
}

/// Finite Fourier series of eq. 5.11 / 6.43 with `N` harmonics:
/// χ_d,i(t) = Σ_l [sin(ω0 l t)/(ω0 l)·s_i^l − cos(ω0 l t)/(ω0 l)·c_i^l] + χ0_i,
/// χ̇_d,i = Σ_l [cos(ω0 l t) s_i^l + sin(ω0 l t) c_i^l],
/// χ̈_d,i = Σ_l ω0 l [−sin(ω0 l t) s_i^l + cos(ω0 l t) c_i^l].
/// (Eq. 5.10's θ̈ carries a stray factor t in its second term; the derivative above is the exact one.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fourier<const N: usize> {
    /// Sine coefficients s_i^l (m/s, rad/s), `[axis][harmonic]`.
    pub s: [[f64; N]; 6],
    /// Cosine coefficients c_i^l (m/s, rad/s), `[axis][harmonic]`.
    pub c: [[f64; N]; 6],
    /// Offsets χ0 (m, rad).
    pub offset: Vec6,
    /// Fundamental frequency ω0 (rad/s).
    pub omega0: f64,
}

impl Fourier<5> {
    /// Experiment 2: n = 5, ω0 = 0.15 rad/s, χ0 = home. Harmonic l has amplitude
    /// [4, 3, 2, 1.5, 1] mm for x, y, z and [12, 9, 6, 4.5, 3]·10⁻³ rad for α, β, γ, with fixed
    /// axis- and harmonic-dependent phases, so every axis starts off home (the initial step in all
    /// dimensions) and stays within 11.5 mm / 0.0345 rad of home.
    pub fn experiment2() -> Self {
        const POS: [f64; 5] = [4e-3, 3e-3, 2e-3, 1.5e-3, 1e-3];
        const ANG: [f64; 5] = [12e-3, 9e-3, 6e-3, 4.5e-3, 3e-3];
        let omega0 = rss6_core::thesis::EXPERIMENT2_OMEGA0;
        let mut s = [[0.0; 5]; 6];
        let mut c = [[0.0; 5]; 6];
        for (i, (si, ci)) in s.iter_mut().zip(c.iter_mut()).enumerate() {
            let amps = if i < 3 { &POS } else { &ANG };
            for (l, ((sl, cl), a)) in si
                .iter_mut()
                .zip(ci.iter_mut())
                .zip(amps.iter())
                .enumerate()
            {
                // Phase chosen so that cos φ and sin φ are both well away from zero.
                let phi = 0.35 + 0.9 * i as f64 + 1.3 * l as f64;
                let w = omega0 * (l + 1) as f64;
                *sl = a * w * cos(phi);
                *cl = a * w * sin(phi);
            }
        }
        Fourier {
            s,
            c,
            offset: home_pose(),
            omega0,
        }
    }
}

impl<const N: usize> Trajectory for Fourier<N> {
    fn sample(&self, t: f64) -> Reference {
        let mut r = Reference::hold(&self.offset);
        for (i, (si, ci)) in self.s.iter().zip(self.c.iter()).enumerate() {
            let (mut p, mut v, mut a) = (0.0, 0.0, 0.0);
            for (l, (sl, cl)) in si.iter().zip(ci.iter()).enumerate() {
                let w = self.omega0 * (l + 1) as f64;
                let (sn, cs) = (sin(w * t), cos(w * t));
                p += sn / w * sl - cs / w * cl;
                v += cs * sl + sn * cl;
                a += w * (-sn * sl + cs * cl);
            }
            r.pose[i] += p;
            r.pose_dot[i] = v;
            r.pose_ddot[i] = a;
        }
        r
    }
}

impl Trajectory for Reference {
    /// A constant reference: the same sample at every time.
    fn sample(&self, _t: f64) -> Reference {
        *self
    }
}
