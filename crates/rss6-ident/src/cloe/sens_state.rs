//! The sensitivity state the CLOE loop carries beside its own state: the derivative of every
//! state variable to the active columns of A.

use super::friction::Sens;
use rss6_core::{Mat6, Vec6};

/// ∂(state)/∂A of the loop: model (χ, χ̇), held potentiometer angle, drive PID, visual PID.
pub(super) struct SensState {
    pub columns: Vec<usize>,
    /// Scale η_nom/η_model of the potentiometer angle in the drive's convention.
    pub pot_scale: Vec6,
    pub p: Sens,
    pub v: Sens,
    pub theta_meas: Sens,
    pub integral: Sens,
    pub prev_error: Sens,
    pub prev_derivative: Sens,
    pub command: Sens,
    pub v_integral: Sens,
    pub last_frame: Option<Sens>,
}

impl SensState {
    pub(super) fn zeros(columns: Vec<usize>, pot_scale: Vec6) -> Self {
        let z = || Sens::zeros(columns.len());
        SensState {
            p: z(),
            v: z(),
            theta_meas: z(),
            integral: z(),
            prev_error: z(),
            prev_derivative: z(),
            command: z(),
            v_integral: z(),
            last_frame: None,
            columns,
            pot_scale,
        }
    }
}

/// out += m·x column by column: a 6 × 6 times a 6 × p block with fixed-size products (no packing,
/// no allocation; the generic product of a dynamic block goes through a general GEMM).
pub(super) fn mul_add(out: &mut Sens, m: &Mat6, x: &Sens) {
    for (mut o, xc) in out.column_iter_mut().zip(x.column_iter()) {
        o += m * xc;
    }
}
