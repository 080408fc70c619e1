//! A physically consistent parametrisation of A (eq. 5.6): every value of ψ ∈ ℝ⁴³ is a physical
//! robot, so every Levenberg–Marquardt iterate is one.
//!
//! ψ holds the logarithms of the quantities the model uses (see `rss6_core`'s dynamics docs):
//!
//! * platform: log m and the logs of the second moments Σ_xx, Σ_yy, Σ_zz of its mass distribution in
//!   its principal frame (I_x = Σ_yy + Σ_zz, I_y = Σ_xx + Σ_zz, I_z = Σ_xx + Σ_yy): any Σ > 0 gives
//!   moments that meet the triangle inequalities;
//! * wrench i: log m and log I_z (the only moment the model uses; I_x, I_y stay at the guess's);
//! * link i: log m and log I_t with I_t = (I_x + I_y)/2 the transverse moment the model uses
//!   (I_x and I_y scale together from the guess, I_z stays);
//! * joint friction: log f_c,i, log f_v,i; drive PID: log l_p, log l_i, log l_d.
//!
//! A relative step in ψ is a relative change of the quantity, so relative standard deviations come
//! straight from the covariance of ψ.

use super::config::{LoopParams, N_A};
use crate::error::{IdentError, Result};
use nalgebra::DMatrix;
use rss6_core::LEGS;

/// Number of consistent parameters ψ.
pub const N_PSI: usize = 4 + 4 * LEGS + 2 * LEGS + 3;

/// The map ψ ↦ A around a guess (which fixes the moments the model never uses).
#[derive(Debug, Clone, PartialEq)]
pub struct Consistent {
    guess: [f64; N_A],
}

impl Consistent {
    /// The parametrisation anchored at `guess`. Errors if a quantity that ψ holds a log of is not
    /// > 0, or the platform's moments violate the triangle inequalities (no Σ > 0 gives them).
    pub fn new(guess: &LoopParams) -> Result<Self> {
        let c = Consistent {
            guess: guess.to_vector(),
        };
        c.psi(guess)?;
        Ok(c)
    }

    /// Names of the entries of ψ.
    pub fn names() -> Vec<String> {
        let mut n: Vec<String> = ["platform.m", "platform.Sxx", "platform.Syy", "platform.Szz"]
            .map(String::from)
            .to_vec();
        for i in 1..=LEGS {
            n.push(format!("wrench{i}.m"));
            n.push(format!("wrench{i}.Iz"));
        }
        for i in 1..=LEGS {
            n.push(format!("link{i}.m"));
            n.push(format!("link{i}.It"));
        }
        for i in 1..=LEGS {
            n.push(format!("fc{i}"));
        }
        for i in 1..=LEGS {
            n.push(format!("fv{i}"));
        }
        n.extend(["lp", "li", "ld"].map(String::from));
        n
    }

    /// The columns of A that ψ moves (the Jacobian columns to propagate).
    pub fn a_columns() -> Vec<usize> {
        let mut c = vec![0, 1, 2, 3];
        for i in 0..LEGS {
            c.extend([4 * (1 + i), 4 * (1 + i) + 3]);
        }
        for i in 0..LEGS {
            c.extend([4 * (7 + i), 4 * (7 + i) + 1, 4 * (7 + i) + 2]);
        }
        c.extend(52..N_A);
        c
    }

    /// The physical quantities φ = exp(ψ) of `a` (before the log).
    fn phi(&self, a: &LoopParams) -> [f64; N_PSI] {
        let x = a.to_vector();
        let mut p = [0.0; N_PSI];
        let (ix, iy, iz) = (x[1], x[2], x[3]);
        p[0] = x[0];
        p[1] = 0.5 * (iy + iz - ix);
        p[2] = 0.5 * (ix + iz - iy);
        p[3] = 0.5 * (ix + iy - iz);
        for i in 0..LEGS {
            p[4 + 2 * i] = x[4 * (1 + i)];
            p[5 + 2 * i] = x[4 * (1 + i) + 3];
            p[16 + 2 * i] = x[4 * (7 + i)];
            p[17 + 2 * i] = 0.5 * (x[4 * (7 + i) + 1] + x[4 * (7 + i) + 2]);
        }
        p[28..34].copy_from_slice(&x[52..58]);
        p[34..40].copy_from_slice(&x[58..64]);
        p[40..43].copy_from_slice(&x[64..67]);
        p
    }

    /// ψ of `a`; errors (naming the quantity) if one is not > 0.
    pub fn psi(&self, a: &LoopParams) -> Result<[f64; N_PSI]> {
        let phi = self.phi(a);
        let names = Self::names();
        let mut psi = [0.0; N_PSI];
        for k in 0..N_PSI {
            if !(phi[k].is_finite() && phi[k] > 0.0) {
                return Err(IdentError::InvalidInput(format!(
                    "{} = {} must be > 0 for the consistent parametrisation (a zero friction guess \
                     needs a small positive value)",
                    names[k], phi[k]
                )));
            }
            psi[k] = phi[k].ln();
        }
        Ok(psi)
    }

    /// A of ψ.
    pub fn params(&self, psi: &[f64]) -> LoopParams {
        let p: Vec<f64> = psi.iter().map(|v| v.exp()).collect();
        let mut x = self.guess;
        x[0] = p[0];
        x[1] = p[2] + p[3];
        x[2] = p[1] + p[3];
        x[3] = p[1] + p[2];
        for i in 0..LEGS {
            x[4 * (1 + i)] = p[4 + 2 * i];
            x[4 * (1 + i) + 3] = p[5 + 2 * i];
            x[4 * (7 + i)] = p[16 + 2 * i];
            let (gx, gy) = (self.guess[4 * (7 + i) + 1], self.guess[4 * (7 + i) + 2]);
            let s = p[17 + 2 * i] / (0.5 * (gx + gy));
            x[4 * (7 + i) + 1] = gx * s;
            x[4 * (7 + i) + 2] = gy * s;
        }
        x[52..58].copy_from_slice(&p[28..34]);
        x[58..64].copy_from_slice(&p[34..40]);
        x[64..67].copy_from_slice(&p[40..43]);
        LoopParams::from_vector(&x)
    }

    /// ∂A/∂ψ at ψ, restricted to the rows [`Self::a_columns`] (49 × 43).
    pub fn jacobian(&self, psi: &[f64]) -> DMatrix<f64> {
        let cols = Self::a_columns();
        let x = self.params(psi).to_vector();
        let p: Vec<f64> = psi.iter().map(|v| v.exp()).collect();
        let row = |a: usize| cols.iter().position(|&c| c == a).unwrap_or(usize::MAX);
        let mut d = DMatrix::zeros(cols.len(), N_PSI);
        let mut set = |a: usize, k: usize, v: f64| {
            let r = row(a);
            if r != usize::MAX {
                d[(r, k)] = v;
            }
        };
        set(0, 0, p[0]);
        // I_x = Σ_yy + Σ_zz, I_y = Σ_xx + Σ_zz, I_z = Σ_xx + Σ_yy; ∂Σ/∂ψ = Σ.
        set(1, 2, p[2]);
        set(1, 3, p[3]);
        set(2, 1, p[1]);
        set(2, 3, p[3]);
        set(3, 1, p[1]);
        set(3, 2, p[2]);
        for i in 0..LEGS {
            set(4 * (1 + i), 4 + 2 * i, p[4 + 2 * i]);
            set(4 * (1 + i) + 3, 5 + 2 * i, p[5 + 2 * i]);
            set(4 * (7 + i), 16 + 2 * i, p[16 + 2 * i]);
            set(4 * (7 + i) + 1, 17 + 2 * i, x[4 * (7 + i) + 1]);
            set(4 * (7 + i) + 2, 17 + 2 * i, x[4 * (7 + i) + 2]);
        }
        for k in 0..15 {
            set(52 + k, 28 + k, p[28 + k]);
        }
        d
    }

    /// The rows of [`Self::jacobian`] for the columns `cols` of A (each one of
    /// [`Self::a_columns`]), in their order.
    pub(crate) fn jacobian_rows(&self, psi: &[f64], cols: &[usize]) -> DMatrix<f64> {
        let all = Self::a_columns();
        let rows: Vec<usize> = (cols.iter())
            .filter_map(|c| all.iter().position(|a| a == c))
            .collect();
        self.jacobian(psi).select_rows(&rows)
    }

    /// The columns of A (of [`Self::a_columns`]) that the quantities ψ_j, j ∈ `active`, move:
    /// ∂A/∂ψ's entries are exp(ψ_k) or a second moment, never zero, so its pattern is the same at
    /// every ψ.
    pub(crate) fn columns_moved_by(&self, psi: &[f64], active: &[usize]) -> Vec<usize> {
        let d = self.jacobian(psi);
        let all = Self::a_columns();
        (0..all.len())
            .filter(|&r| active.iter().any(|&j| d[(r, j)] != 0.0))
            .filter_map(|r| all.get(r).copied())
            .collect()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::cloe::truth::table_5_2_truth;

    /// Every ψ moves every propagated column; one ψ moves only its own (a second moment two).
    #[test]
    fn the_columns_each_quantity_moves() {
        let cons = Consistent::new(&table_5_2_truth()).unwrap();
        let psi = cons.psi(&table_5_2_truth()).unwrap();
        let names = Consistent::names();
        let at = |n: &str| names.iter().position(|m| m == n).unwrap();
        let all: Vec<usize> = (0..N_PSI).collect();
        assert_eq!(cons.columns_moved_by(&psi, &all), Consistent::a_columns());
        assert_eq!(cons.columns_moved_by(&psi, &[at("platform.m")]), [0]);
        assert_eq!(cons.columns_moved_by(&psi, &[at("platform.Sxx")]), [2, 3]);
        assert_eq!(cons.columns_moved_by(&psi, &[at("link2.It")]), [33, 34]);
        assert_eq!(
            cons.columns_moved_by(&psi, &[at("ld"), at("fc1")]),
            [52, 66]
        );
        // The rows of ∂A/∂ψ for a subset, in the subset's order.
        let rows = cons.jacobian_rows(&psi, &[66, 0]);
        let d = cons.jacobian(&psi);
        assert_eq!(rows.row(0), d.row(48));
        assert_eq!(rows.row(1), d.row(0));
    }
}
