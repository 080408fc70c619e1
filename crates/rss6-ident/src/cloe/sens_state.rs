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
    /// Scratch space of the RK4 step's sensitivities (stage χ, χ̇, χ̈ and the two weighted sums),
    /// allocated once per run.
    pub rk4: [Sens; 5],
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
            rk4: [z(), z(), z(), z(), z()],
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
    let s_e = &s.command - &s.theta_meas;
    let s_de = &s_e - &s.prev_error;
    let mut s_d = match (primed, t_f > 0.0) {
        (false, _) => Sens::zeros(s_e.ncols()),
        (true, false) => s_de * (gains.ld / dt),
        (true, true) => (&s.prev_derivative * t_f + s_de * gains.ld) / (t_f + dt),
    };
    let col = |a: usize| s.columns.iter().position(|&c| c == a);
    let (c_lp, c_li, c_ld) = (col(N_DYN), col(N_DYN + 1), col(N_DYN + 2));
    if let Some(c) = c_ld {
        for (i, term) in terms.iter().enumerate() {
            s_d[(i, c)] += term.1;
        }
    }
    let s_int = &s.integral + &s_e * dt;
    let mut s_tau = &s_e * gains.lp + &s_int * gains.li + &s_d;
    for i in 0..LEGS {
        if unclamped[i] {
            if let Some(c) = c_lp {
                s_tau[(i, c)] += terms[i].0;
            }
            if let Some(c) = c_li {
                s_tau[(i, c)] += terms[i].2;
            }
            s.integral.set_row(i, &s_int.row(i));
        } else {
            s_tau.row_mut(i).fill(0.0);
        }
    }
    s.prev_error = s_e;
    s.prev_derivative = s_d;
    s_tau
}
