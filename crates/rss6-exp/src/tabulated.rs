//! A reference tabulated on the tick grid (for references computed outside Rust).

use rss6_ctrl::{Reference, Trajectory};

/// Reference samples (χ_d, χ̇_d, χ̈_d) every `dt` seconds from t = 0; sampled at the nearest row,
/// held at the last row after the end.
#[derive(Debug, Clone, PartialEq)]
pub struct Tabulated {
    dt: f64,
    rows: Vec<Reference>,
}

impl Tabulated {
    /// A table with rows every `dt` seconds; `None` if `dt` is not finite and > 0, the table is empty
    /// or a row is not finite.
    pub fn new(dt: f64, rows: Vec<Reference>) -> Option<Self> {
        if !(dt.is_finite() && dt > 0.0) || rows.is_empty() || !rows.iter().all(|r| r.is_finite()) {
            return None;
        }
        Some(Tabulated { dt, rows })
    }

    /// Duration covered (s).
    pub fn duration(&self) -> f64 {
        (self.rows.len() - 1) as f64 * self.dt
    }
}

impl Trajectory for Tabulated {
    fn sample(&self, t: f64) -> Reference {
        let k = if t.is_finite() && t > 0.0 {
            ((t / self.dt).round() as usize).min(self.rows.len() - 1)
        } else {
            0
        };
        self.rows[k]
    }
}
