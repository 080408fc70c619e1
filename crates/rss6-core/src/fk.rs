//! Forward kinematics χ = H_fwd(θ) (eq. 3.17).
//!
//! [`fk`] is the thesis's quasi-Stewart method (eq. 3.18–3.20, steps 1–4): the wrench tips T_i are fixed
//! by θ once (eq. 3.18), and Newton's method runs on the leg lengths of the equivalent Stewart platform
//! whose base points are T_i and whose legs must have the link lengths l_AT. The thesis adds the
//! rotational part of Δχ = J'⁻¹Δl directly to the Euler angles; J' (eq. 3.19) actually maps the twist
//! [Ė; ω], so we convert with J_e⁻¹ (eq. 3.22) — identical at zero tilt, and it keeps the quadratic
//! convergence of Newton's method away from it.
//!
//! [`fk_theta_newton`] is the "normal" method of Fig. 3.2: Newton on the joint angles, which needs an IK
//! (new T_i) and J_θ at every iterate.

use crate::error::{check_finite, CoreError, Result, SingularKind};
use crate::ik::{ik, wrench_tips};
use crate::jacobian::{stewart_rows, LegGeometry, Rows6};
use crate::params::KinematicParams;
use crate::pose::EulerTrig;
use crate::types::{Vec3, Vec6, LEGS};

/// Stopping rules of the iterative FK solvers (step 1 of §3.4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkOptions {
    /// ε_c: stop when every leg-length residual |Δl_i| < ε_c (m).
    pub eps_c: f64,
    /// ε_p: stop when every component of the pose update |Δχ_j| < ε_p (m or rad).
    pub eps_p: f64,
    /// Hard bound on iterations; the solver never runs longer.
    pub max_iterations: u32,
}

impl Default for FkOptions {
    /// ε_c = 1e-13 m, ε_p = 1e-13, 30 iterations: round trips exact to ~1e-12.
    fn default() -> Self {
        FkOptions {
            eps_c: 1e-13,
            eps_p: 1e-13,
            max_iterations: 30,
        }
    }
}

/// A converged FK solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkSolution {
    /// The pose χ (m, rad).
    pub pose: Vec6,
    /// Newton iterations used (updates applied).
    pub iterations: u32,
    /// Largest leg-closure residual at `pose` (m).
    pub residual: f64,
}

fn check_inputs(theta: &Vec6, guess: &Vec6, opts: &FkOptions) -> Result<()> {
    check_finite(theta.as_slice())?;
    check_finite(guess.as_slice())?;
    if !(opts.eps_c >= 0.0 && opts.eps_p >= 0.0) {
        return Err(CoreError::InvalidParameter("FK tolerances must be >= 0"));
    }
    Ok(())
}

/// Solves A x = b (6 × 6, A given by rows) by Gaussian elimination with partial pivoting on the stack; `None` if a
/// pivot is zero or not finite. nalgebra's `lu().solve()` does the same but copies the matrix and the
/// right-hand side; this was ~40 % of an FK solve, so the two Newton loops use this instead.
fn solve6(mut m: Rows6, b: Vec6) -> Option<Vec6> {
    // Rows are contiguous, so the row operations vectorise.
    let mut y: [f64; 6] = b.into();
    for k in 0..6 {
        let (mut p, mut max) = (k, m[k][k].abs());
        for (r, row) in m.iter().enumerate().skip(k + 1) {
            let v = row[k].abs();
            if v > max {
                (p, max) = (r, v);
            }
        }
        if max == 0.0 || !max.is_finite() {
            return None;
        }
        m.swap(k, p);
        y.swap(k, p);
        let pivot = m[k];
        let yk = y[k];
        let inv = 1.0 / pivot[k];
        for (row, yr) in m.iter_mut().zip(y.iter_mut()).skip(k + 1) {
            let f = row[k] * inv;
            for (x, pv) in row.iter_mut().zip(pivot.iter()) {
                *x -= f * pv;
            }
            *yr -= f * yk;
        }
    }
    let mut x = [0.0; 6];
    for k in (0..6).rev() {
        let mut s = y[k];
        for c in k + 1..6 {
            s -= m[k][c] * x[c];
        }
        x[k] = s / m[k][k];
    }
    Some(Vec6::from(x))
}

/// Converts a twist-space step [ΔE; Δω] into a pose step [ΔE; Δφ] (Δφ = J_e⁻¹ Δω, eq. 3.22).
fn twist_step_to_pose_step(trig: &EulerTrig, dv: &Vec6) -> Result<Vec6> {
    let dphi = trig
        .euler_rates(&Vec3::new(dv[3], dv[4], dv[5]))
        .ok_or(CoreError::Singular(SingularKind::Euler))?;
    Ok(Vec6::new(dv[0], dv[1], dv[2], dphi[0], dphi[1], dphi[2]))
}

/// J' and the leg lengths at `pose` (one evaluation of sin/cos shared by R and J_e).
fn stewart_at(
    kp: &KinematicParams,
    pose: &Vec6,
    tips: &[Vec3; LEGS],
) -> Result<(EulerTrig, Rows6, Vec6)> {
    let trig = EulerTrig::of_pose(pose);
    let (jp, len) = stewart_rows(kp, &trig.rotation(), pose, tips)?;
    Ok((trig, jp, len))
}

/// Quasi-Stewart forward kinematics (§3.4): pose χ from physical joint angles θ (rad), starting at
/// `guess` (e.g. the previous solution, or [`crate::home_pose`]).
///
/// Errors: [`CoreError::NonFinite`], [`CoreError::Singular`] (J' lost rank),
/// [`CoreError::NotConverged`] after `opts.max_iterations`.
///
/// ```
/// use rss6_core::{fk, ik, home_pose, FkOptions, KinematicParams, Vec6};
/// let kp = KinematicParams::nominal();
/// let target = Vec6::new(0.01, -0.005, 0.12, 0.02, -0.01, 0.03);
/// let sol = fk(&kp, &ik(&kp, &target).unwrap(), &home_pose(), &FkOptions::default()).unwrap();
/// assert!((sol.pose - target).amax() < 1e-10);
/// ```
pub fn fk(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    opts: &FkOptions,
) -> Result<FkSolution> {
    check_inputs(theta, guess, opts)?;
    let tips = wrench_tips(kp, theta);
    let target = Vec6::from_column_slice(&kp.link_lengths);
    let mut pose = *guess;
    let mut iterations = 0;
    loop {
        let (trig, jp, len) = stewart_at(kp, &pose, &tips)?;
        let dl = target - len;
        let residual = dl.amax();
        if !residual.is_finite() {
            return Err(CoreError::NonFinite);
        }
        if residual < opts.eps_c {
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
        if iterations >= opts.max_iterations {
            return Err(CoreError::NotConverged {
                iterations,
                residual,
            });
        }
        let dv = solve6(jp, dl).ok_or(CoreError::Singular(SingularKind::StewartJacobian))?;
        let step = twist_step_to_pose_step(&trig, &dv)?;
        pose += step;
        iterations += 1;
        if step.amax() < opts.eps_p {
            let (_, _, len) = stewart_at(kp, &pose, &tips)?;
            let residual = (target - len).amax();
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
    }
}

/// The "normal" FK of Fig. 3.2: Newton on θ, Δχ = J_θ⁻¹ (θ − θ(χ)) with an IK and J_θ per iterate.
/// Same stopping rules as [`fk`], with ε_c applied to the joint-angle residual (rad); the reported
/// `residual` is the joint-angle residual (rad).
pub fn fk_theta_newton(
    kp: &KinematicParams,
    theta: &Vec6,
    guess: &Vec6,
    opts: &FkOptions,
) -> Result<FkSolution> {
    check_inputs(theta, guess, opts)?;
    let mut pose = *guess;
    let mut iterations = 0;
    loop {
        let geo = LegGeometry::at_pose(kp, &pose)?;
        let dth = theta - geo.theta;
        let residual = dth.amax();
        if residual < opts.eps_c {
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
        if iterations >= opts.max_iterations {
            return Err(CoreError::NotConverged {
                iterations,
                residual,
            });
        }
        let rows: Rows6 = geo.j_theta()?.transpose().into();
        let step = solve6(rows, dth).ok_or(CoreError::Singular(SingularKind::TypeII))?;
        pose += step;
        iterations += 1;
        if step.amax() < opts.eps_p {
            let residual = (theta - ik(kp, &pose)?).amax();
            return Ok(FkSolution {
                pose,
                iterations,
                residual,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::Mat6;

    #[test]
    fn solve6_matches_nalgebra_lu() {
        // Deterministic, varied matrices incl. ones that need row pivoting.
        for seed in 0..200u32 {
            let s = f64::from(seed);
            let a = Mat6::from_fn(|r, c| {
                let (r, c) = (r as f64, c as f64);
                libm::sin(1.3 * r + 0.7 * c * c + s)
                    + if (r as usize + seed as usize) % 6 == c as usize {
                        0.0
                    } else {
                        0.1 * r
                    }
            });
            let b = Vec6::from_fn(|r, _| libm::cos(r as f64 + 0.3 * s));
            let x = solve6(a.transpose().into(), b);
            match a.lu().solve(&b) {
                Some(y) => {
                    let x = x.unwrap_or_else(Vec6::zeros);
                    assert!((a * x - b).amax() <= 1e-9 * (1.0 + y.amax()), "seed {seed}");
                }
                None => assert!(x.is_none(), "seed {seed}"),
            }
        }
        let mut singular = Mat6::identity();
        singular.set_row(4, &singular.row(2).clone_owned());
        assert!(solve6(singular.transpose().into(), Vec6::repeat(1.0)).is_none());
        assert!(solve6([[f64::NAN; 6]; 6], Vec6::repeat(1.0)).is_none());
    }
}
