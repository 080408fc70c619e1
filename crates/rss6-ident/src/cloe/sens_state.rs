//! The sensitivity state the CLOE loop carries beside its own state: the derivative of every
//! state variable to the active columns of A.

use super::friction::Sens;
use rss6_core::{Mat6, Vec6, LEGS, N_DYN};
use rss6_ctrl::PidGains;

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

/// The drive PID's sensitivity (see [`Lean::drive_pid`]) for all joints at once: ∂e, ∂D (the
/// same recursion as D plus its explicit dependence on l_d), ∂I and ∂τ, zero on clamped joints
/// (whose integral is frozen too). `terms[i]` = (e, ∂D/∂l_d, I) of joint i.
pub(super) fn drive_pid_sensitivity(
    s: &mut SensState,
    gains: PidGains,
    primed: bool,
    dt: f64,
    t_f: f64,
    unclamped: &[bool; LEGS],
    terms: &[(f64, f64, f64); LEGS],
) -> Sens {
    let col = |a: usize| s.columns.iter().position(|&c| c == a);
    let (c_lp, c_li, c_ld) = (col(N_DYN), col(N_DYN + 1), col(N_DYN + 2));
    // Entry by entry in place (the same sums, in the same order, as the block operations
    // ∂e = ∂U − ∂θ_m, ∂D, ∂I = ∂I + ∂e dt, ∂τ = l_p ∂e + l_i ∂I + ∂D): no temporary blocks.
    let mut s_tau = Sens::zeros(s.command.ncols());
    for c in 0..s_tau.ncols() {
        let e: Vec6 = s.command.column(c) - s.theta_meas.column(c);
        let de = e - s.prev_error.column(c);
        let mut d = match (primed, t_f > 0.0) {
            (false, _) => Vec6::zeros(),
            (true, false) => de * (gains.ld / dt),
            (true, true) => (s.prev_derivative.column(c) * t_f + de * gains.ld) / (t_f + dt),
        };
        if c_ld == Some(c) {
            d += Vec6::from_fn(|i, _| terms[i].1);
        }
        let integral = s.integral.column(c) + e * dt;
        let mut tau = e * gains.lp + integral * gains.li + d;
        for (i, term) in terms.iter().enumerate() {
            if unclamped[i] {
                if c_lp == Some(c) {
                    tau[i] += term.0;
                }
                if c_li == Some(c) {
                    tau[i] += term.2;
                }
                s.integral[(i, c)] = integral[i];
            } else {
                tau[i] = 0.0;
            }
        }
        s_tau.set_column(c, &tau);
        s.prev_error.set_column(c, &e);
        s.prev_derivative.set_column(c, &d);
    }
    s_tau
}
