//! Bindings of the identification loop (Fig. 5.1) and of CLOE (thesis §5.3): the loop run on a
//! robot with rss6-exp's runner ([`rss6_exp::ident::run`]), the loop simulated on the model
//! ([`rss6_ident::simulate_loop`]) and the estimator ([`rss6_ident::cloe_observed`]).
//! `rss6.identify` wraps them (`collect`, `simulate`, `cloe`).

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rss6_core::{Mat3, PlatformLoad, Vec3, Vec6};
use rss6_ctrl::{CartesianPidGains, PidGains};
use rss6_exp::ident::{self, IdentSpec};
use rss6_exp::{Externals, Flow, Observer, Progress, Record};
use rss6_ident::{
    cloe_observed, simulate_loop, table_5_2_truth, CloeData, CloeOptions, Consistent, Excitation,
    IdentError, LoopConfig, LoopParams,
};

use crate::calib::ident_err;
use crate::convert::{exact, out1, out_dmatrix, out_rows6, rows6, vec6, vecn};
use crate::errors::{invalid, make, shape, Attr};
use crate::exp::{create_log, finish_log, Interrupt};
use crate::identify::{collect_metadata, excitation};
use crate::params::{PyDynamicParams, PyKinematicParams};
use crate::plant::with_robot;

/// Maps the identification errors of rss6-ident onto `rss6.IdentificationError` (attributes: `names`
/// for a parameter that is not identifiable, `iterations` and `cost_history` for no convergence) or
/// `rss6.SimulationError`; the others as for calibration.
pub(crate) fn cloe_err(e: IdentError) -> PyErr {
    let msg = e.to_string();
    match e {
        IdentError::Unidentifiable { names } => {
            make("IdentificationError", msg, vec![("names", Attr::SL(names))])
        }
        IdentError::NotConverged {
            iterations,
            cost_history,
        } => make(
            "IdentificationError",
            msg,
            vec![
                ("iterations", Attr::I(iterations as i64)),
                ("cost_history", Attr::FL(cost_history)),
            ],
        ),
        IdentError::NoCameraFrames(_) => make("IdentificationError", msg, vec![]),
        IdentError::Simulation { time, .. } => {
            make("SimulationError", msg, vec![("time", Attr::F(time))])
        }
        other => ident_err(other),
    }
}

/// Per tick and per consumed camera frame, what an identification run shows its observer.
#[derive(Default)]
struct Collector {
    t: Vec<f64>,
    kappa: Vec<Vec6>,
    theta_cmd: Vec<Vec6>,
    reference: Vec<Vec6>,
    true_pose: Vec<Vec6>,
    frame_t: Vec<f64>,
    measured: Vec<Vec6>,
    progress: Option<Py<PyAny>>,
    interrupt: Interrupt,
}

impl Observer for Collector {
    fn record(&mut self, r: &Record) -> Flow {
        self.t.push(r.t);
        self.kappa.push(r.kappa);
        self.theta_cmd.push(r.theta_cmd);
        self.reference.push(
            r.reference
                .map_or(Vec6::repeat(f64::NAN), |reference| reference.pose),
        );
        self.true_pose
            .push(r.truth.map_or(Vec6::repeat(f64::NAN), |truth| truth.pose));
        if let Some(chi) = r.camera {
            self.frame_t.push(r.t);
            self.measured.push(chi);
        }
        Flow::Continue
    }

    fn progress(&mut self, p: &Progress) -> Flow {
        let cb = &self.progress;
        self.interrupt.call(|py| {
            if let Some(cb) = cb {
                cb.call1(py, (p.done, p.total))?;
            }
            Ok(())
        })
    }
}

/// Runs the identification loop of Fig. 5.1 (rss6-exp's runner) on `robot` (rss6.Plant,
/// rss6.ModelSim or any object implementing rss6.types.Robot) for `duration` s from its current
/// state at rest, following the Fourier trajectory (`f0` Hz, `coefficients` (6, 2n + 1)); the
/// visual PID (eq. 5.4, thesis gains) uses `kp_model`'s J_θ and the frames through
/// `sensor_in_base` (ᴼχ_C) and `target_in_effector` (ᴱχ_t). Returns a dict: per tick `t`, `kappa`,
/// `theta_cmd` (drive convention), `reference` (χ_d), `true_pose` (NaN rows on a real robot); per
/// frame the visual PID consumed `frame_t` and `measured` (χ_E); `frames`, `ticks`, `fault`
/// (None or (t, reason)). `progress(done_s, total_s)` every `segment` s of robot time; if it raises
/// (KeyboardInterrupt included) the run stops and the exception propagates; Ctrl-C is checked at
/// the same points. `mcap`: log the run there as it goes. `commands` (T, 6): joint commands
/// (drive convention) sent one per tick instead of the visual PID's (a recorded run replayed;
/// frames are still measured). `outer_gains` (k_p, k_i, k_d): the visual PID's gains on every axis
/// (None: the thesis's). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (robot, f0, coefficients, duration, kp_model, sensor_in_base, target_in_effector, *, segment=1.0, progress=None, mcap=None, commands=None, outer_gains=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn identification_run<'py>(
    py: Python<'py>,
    robot: &Bound<'py, PyAny>,
    f0: f64,
    coefficients: &Bound<'py, PyAny>,
    duration: f64,
    kp_model: &PyKinematicParams,
    sensor_in_base: &Bound<'py, PyAny>,
    target_in_effector: &Bound<'py, PyAny>,
    segment: f64,
    progress: Option<Py<PyAny>>,
    mcap: Option<std::path::PathBuf>,
    commands: Option<&Bound<'py, PyAny>>,
    outer_gains: Option<(f64, f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let exc = excitation(f0, coefficients)?;
    let externals = Externals {
        sensor_in_base: vec6(sensor_in_base, "sensor_in_base")?,
        target_in_effector: vec6(target_in_effector, "target_in_effector")?,
    };
    let mut spec = IdentSpec::new(kp_model.inner, externals);
    spec.duration = duration;
    spec.segment = segment;
    spec.commands = commands.map(|c| rows6(c, "commands")).transpose()?;
    spec.gains = self::outer_gains(outer_gains)?;
    let mut log = match &mcap {
        Some(path) => Some(create_log(
            path,
            &collect_metadata(&exc, f0, duration, outer_gains),
        )?),
        None => None,
    };
    let mut coll = Collector {
        progress,
        ..Collector::default()
    };
    let outcome = with_robot(robot, |r| {
        py.detach(|| match log.as_mut() {
            // The log first: a segment is on disk before `progress` hears of it.
            Some(l) => ident::run(r, &spec, &exc, &mut (l, &mut coll)),
            None => ident::run(r, &spec, &exc, &mut coll),
        })
    })?;
    let fault = outcome
        .as_ref()
        .ok()
        .and_then(|o| o.first_fault)
        .map(|(t, r)| (t, r.to_string()));
    let end: Vec<(&str, String)> = fault
        .iter()
        .map(|(t, r)| ("fault", format!("t = {t:.3} s: {r}")))
        .collect();
    let outcome = finish_log(py, log, outcome, coll.interrupt.take(), &end)?;
    let d = PyDict::new(py);
    d.set_item("t", out1(py, &coll.t))?;
    for (key, v) in [
        ("kappa", &coll.kappa),
        ("theta_cmd", &coll.theta_cmd),
        ("reference", &coll.reference),
        ("true_pose", &coll.true_pose),
        ("measured", &coll.measured),
    ] {
        d.set_item(key, out_rows6(py, v))?;
    }
    d.set_item("frame_t", out1(py, &coll.frame_t))?;
    d.set_item("frames", outcome.frames)?;
    d.set_item("ticks", outcome.ticks)?;
    d.set_item("fault", fault)?;
    Ok(d)
}

/// (frame times (F,), χ_s (F, 6), clamped joint-ticks).
type SimulatedFrames<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, numpy::PyArray2<f64>>,
    usize,
    Bound<'py, numpy::PyArray2<f64>>,
);

/// An unidentifiable quantity, what it combines into (name, coefficient), and the misfit.
type AliasTuple = (String, Vec<(String, f64)>, f64);

/// (ψ (43,), dynamics, (l_p, l_i, l_d)).
type PsiAndParams<'py> = (Bound<'py, PyArray1<f64>>, PyDynamicParams, (f64, f64, f64));

pub(crate) fn pid_gains((lp, li, ld): (f64, f64, f64)) -> PidGains {
    PidGains { lp, li, ld }
}

/// The outer visual PID's gains (k_p, k_i 1/s, k_d s) on every axis, the thesis's anti-windup bound
/// kept; `None`: the thesis's (0.3, 2.4, 0.001).
pub(crate) fn outer_gains(g: Option<(f64, f64, f64)>) -> PyResult<CartesianPidGains> {
    let mut gains = CartesianPidGains::thesis();
    if let Some((kp, ki, kd)) = g {
        if !(kp.is_finite()
            && kp > 0.0
            && ki.is_finite()
            && ki >= 0.0
            && kd.is_finite()
            && kd >= 0.0)
        {
            return Err(invalid(format!(
                "outer_gains must be finite with k_p > 0 and k_i, k_d >= 0, got ({kp}, {ki}, {kd})"
            )));
        }
        gains.kp = Vec6::repeat(kp);
        gains.ki = Vec6::repeat(ki);
        gains.kd = Vec6::repeat(kd);
    }
    Ok(gains)
}

/// The loop's configuration: `LoopConfig::new` with the given fields set.
#[allow(clippy::too_many_arguments)]
pub(crate) fn loop_config(
    kp: &PyKinematicParams,
    start: &Bound<'_, PyAny>,
    duration: f64,
    torque_limit: f64,
    camera_latency: f64,
    dt: f64,
    derivative_filter: f64,
    (friction_smoothing, implicit_friction): (f64, bool),
    effects: Effects<'_>,
) -> PyResult<LoopConfig> {
    let mut cfg = LoopConfig::new(kp.inner, vec6(start, "start")?, duration);
    cfg.torque_limit = torque_limit;
    cfg.derivative_filter = derivative_filter;
    cfg.friction_smoothing = friction_smoothing;
    cfg.implicit_friction = implicit_friction;
    cfg.camera_latency = camera_latency;
    cfg.dt = dt;
    let (gravity, load, offset_drift) = effects;
    apply_effects(&mut cfg, gravity, load, offset_drift)?;
    Ok(cfg)
}

/// The model effects of a binding call: `gravity`, `load`, `offset_drift` (see [`apply_effects`]).
type Effects<'a> = (
    Option<&'a Bound<'a, PyAny>>,
    Option<(f64, Bound<'a, PyAny>, Bound<'a, PyAny>)>,
    Option<&'a Bound<'a, PyAny>>,
);

/// The effects the model can express, on a loop configuration: `gravity` (3,), `load` = (mass,
/// centre of mass (3,), inertia (3, 3)), `offset_drift` (6,).
fn apply_effects(
    cfg: &mut LoopConfig,
    gravity: Option<&Bound<'_, PyAny>>,
    load: Option<(f64, Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    offset_drift: Option<&Bound<'_, PyAny>>,
) -> PyResult<()> {
    if let Some(g) = gravity {
        cfg.gravity = Vec3::from(vecn::<3>(g, "gravity")?);
    }
    if let Some((mass, com, inertia)) = load {
        let c = vecn::<3>(&com, "load centre of mass")?;
        let i = exact(&inertia, "load inertia", &[3, 3])?;
        cfg.load = Some(PlatformLoad::new(
            mass,
            Vec3::from(c),
            Mat3::from_row_slice(&i),
        ));
    }
    if let Some(d) = offset_drift {
        cfg.offset_drift = vec6(d, "offset_drift")?;
    }
    Ok(())
}

/// Simulates the identification loop on the model (`kp`, `dp`, drive gains `pid` = (l_p, l_i,
/// l_d)) from rest at `start` for `duration` s following the Fourier trajectory (`f0`,
/// `coefficients`). `derivative_filter` T_f (s) of the drive's derivative and `friction_smoothing` ε
/// (rad/s) of the model's Coulomb friction (0: as printed); `implicit_friction`: Coulomb + viscous
/// friction stepped implicitly per tick instead (stick–slip, the twin's and plant's shared law).
/// `commands` (F, 6): the robot's joint commands (drive convention) issued at each consumed frame,
/// held instead of the simulated visual PID's (None: the loop of eq. 5.4 closed on χ_s). Effects the model can express (the
/// discrepancy workflow's candidates): `gravity` (3,) in the base frame (a tilted base), `load` =
/// (mass kg, centre of mass (3,) m in ΣE, inertia (3, 3) kg·m² about it) fixed to the platform,
/// `offset_drift` (6,) rad/s of the potentiometer offsets. `pot_dither` (T, 6): potentiometer
/// noise (drive convention, rad) added to the model's reading at each sampling tick (row = tick).
/// Returns (frame times (F,), χ_s (F, 6), joint-ticks with the torque clamped, the model's
/// noise-free potentiometer angles at its sampling ticks (S, 6), drive convention).
#[pyfunction]
#[pyo3(signature = (kp, dp, pid, f0, coefficients, *, start, duration, torque_limit=30.0, camera_latency=0.0, dt=1e-3, derivative_filter=0.0, friction_smoothing=0.0, implicit_friction=false, commands=None, gravity=None, load=None, offset_drift=None, outer_gains=None, pot_dither=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate_identification<'py>(
    py: Python<'py>,
    kp: &PyKinematicParams,
    dp: &PyDynamicParams,
    pid: (f64, f64, f64),
    f0: f64,
    coefficients: &Bound<'py, PyAny>,
    start: &Bound<'py, PyAny>,
    duration: f64,
    torque_limit: f64,
    camera_latency: f64,
    dt: f64,
    derivative_filter: f64,
    friction_smoothing: f64,
    implicit_friction: bool,
    commands: Option<&Bound<'py, PyAny>>,
    gravity: Option<&Bound<'py, PyAny>>,
    load: Option<(f64, Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    offset_drift: Option<&Bound<'py, PyAny>>,
    outer_gains: Option<(f64, f64, f64)>,
    pot_dither: Option<&Bound<'py, PyAny>>,
) -> PyResult<SimulatedFrames<'py>> {
    let exc = excitation(f0, coefficients)?;
    let mut cfg = loop_config(
        kp,
        start,
        duration,
        torque_limit,
        camera_latency,
        dt,
        derivative_filter,
        (friction_smoothing, implicit_friction),
        (gravity, load, offset_drift),
    )?;
    cfg.gains = self::outer_gains(outer_gains)?;
    if let Some(c) = commands {
        cfg.recorded_commands = Some(rows6(c, "commands")?);
    }
    if let Some(d) = pot_dither {
        cfg.pot_dither = Some(rows6(d, "pot_dither")?);
    }
    cfg.record_pot_angles = true;
    let a = LoopParams {
        dynamics: dp.inner,
        pid: pid_gains(pid),
    };
    let run = py
        .detach(|| simulate_loop(&cfg, &a, &exc, None))
        .map_err(cloe_err)?;
    Ok((
        out1(py, &run.t),
        out_rows6(py, &run.chi),
        run.saturated,
        out_rows6(py, &run.pot_angles),
    ))
}

/// CLOE (eq. 5.6–5.9) of the measured frames `measured` (F, 6) at times `t` (F,) collected with the
/// identification loop following the Fourier trajectory (`f0`, `coefficients`) from rest at
/// `start`, from the guess (`dp_guess`, `pid_guess`). `parameters`: names to estimate (see
/// `cloe_parameter_names`), None for every identifiable one; `hold`: names kept at the guess as
/// known (the identifiable set is then chosen among the others). `derivative_filter`,
/// `friction_smoothing`: as for `simulate_identification`. `prior_log_std`: σ of the Gaussian prior
/// on every estimated log-quantity, centred at the guess (0: none, the pure output error of eq. 5.7). No convergence raises
/// `rss6.IdentificationError` with `iterations`, `cost_history` and the last accepted iterate
/// `last_dynamics`, `last_pid`. The loop's model: `kp`,
/// `torque_limit`, `camera_latency`, `dt`, run for `duration` s. `progress(iteration, cost)` after
/// every accepted step (iteration 0: the guess); if it raises, CLOE stops and the exception
/// propagates. `gravity`, `load`, `offset_drift`: effects of the model, as for
/// `simulate_identification` (re-identification with named effects); `pot_dither` as there;
/// `initial` (dynamics, gains): where LM starts instead of the guess (`CloeOptions::initial`);
/// `noise_covariance` (6, 6): one frame's pose-noise covariance, the residual whitened by it instead
/// of `noise`'s per-axis weights (`CloeOptions::noise_covariance`). Returns a dict (see
/// `rss6.identify.IdentificationResult`). Releases the GIL.
#[pyfunction]
#[pyo3(signature = (t, measured, f0, coefficients, kp, dp_guess, pid_guess, *, start, duration, parameters=None, hold=None, max_iterations=20, torque_limit=30.0, camera_latency=0.0, dt=1e-3, derivative_filter=0.0, friction_smoothing=0.0, implicit_friction=false, commands=None, noise=None, per_tick_jacobians=false, tol_cost=1e-6, tol_step=1e-5, identifiability_threshold=1e-3, poor_std=0.1, prior_log_std=1.0, progress=None, gravity=None, load=None, offset_drift=None, outer_gains=None, pot_dither=None, settle_steps=rss6_ident::SETTLE_STEPS, initial=None, noise_covariance=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn cloe_identify<'py>(
    py: Python<'py>,
    t: Vec<f64>,
    measured: &Bound<'py, PyAny>,
    f0: f64,
    coefficients: &Bound<'py, PyAny>,
    kp: &PyKinematicParams,
    dp_guess: &PyDynamicParams,
    pid_guess: (f64, f64, f64),
    start: &Bound<'py, PyAny>,
    duration: f64,
    parameters: Option<Vec<String>>,
    hold: Option<Vec<String>>,
    max_iterations: usize,
    torque_limit: f64,
    camera_latency: f64,
    dt: f64,
    derivative_filter: f64,
    friction_smoothing: f64,
    implicit_friction: bool,
    commands: Option<&Bound<'py, PyAny>>,
    noise: Option<(f64, f64)>,
    per_tick_jacobians: bool,
    tol_cost: f64,
    tol_step: f64,
    identifiability_threshold: f64,
    poor_std: f64,
    prior_log_std: f64,
    progress: Option<Py<PyAny>>,
    gravity: Option<&Bound<'py, PyAny>>,
    load: Option<(f64, Bound<'py, PyAny>, Bound<'py, PyAny>)>,
    offset_drift: Option<&Bound<'py, PyAny>>,
    outer_gains: Option<(f64, f64, f64)>,
    pot_dither: Option<&Bound<'py, PyAny>>,
    settle_steps: usize,
    initial: Option<(PyRef<'py, PyDynamicParams>, (f64, f64, f64))>,
    noise_covariance: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let measured = rows6(measured, "measured")?;
    if measured.len() != t.len() {
        return Err(shape(format!(
            "measured must have shape ({}, 6) like t, got {} rows",
            t.len(),
            measured.len()
        )));
    }
    let exc: Excitation = excitation(f0, coefficients)?;
    let mut cfg = loop_config(
        kp,
        start,
        duration,
        torque_limit,
        camera_latency,
        dt,
        derivative_filter,
        (friction_smoothing, implicit_friction),
        (gravity, load, offset_drift),
    )?;
    cfg.gains = self::outer_gains(outer_gains)?;
    if let Some(c) = commands {
        cfg.recorded_commands = Some(rows6(c, "commands")?);
    }
    if let Some(d) = pot_dither {
        cfg.pot_dither = Some(rows6(d, "pot_dither")?);
    }
    let guess = LoopParams {
        dynamics: dp_guess.inner,
        pid: pid_gains(pid_guess),
    };
    let mut options = CloeOptions {
        max_iterations,
        tol_cost,
        tol_step,
        parameters,
        hold: hold.unwrap_or_default(),
        identifiability_threshold,
        poor_std,
        per_tick_jacobians,
        prior_log_std: (prior_log_std != 0.0).then_some(prior_log_std),
        settle_steps,
        initial: initial.map(|(d, g)| LoopParams {
            dynamics: d.inner,
            pid: pid_gains(g),
        }),
        ..CloeOptions::default()
    };
    if let Some(c) = noise_covariance {
        options.noise_covariance = Some(crate::convert::mat6_rows(c, "noise_covariance")?);
    }
    if let Some((p, a)) = noise {
        options.noise = [p, a];
    }
    let data = CloeData { t, measured };
    let mut interrupt = Interrupt::default();
    let mut last: Vec<f64> = Vec::new();
    let result = py.detach(|| {
        cloe_observed(&data, &cfg, &exc, &guess, &options, &mut |k, cost, psi| {
            last.clear();
            last.extend_from_slice(psi);
            interrupt.call(|py| {
                if let Some(cb) = &progress {
                    cb.call1(py, (k, cost))?;
                }
                Ok(())
            }) == Flow::Continue
        })
    });
    if let Some(e) = interrupt.take() {
        return Err(e);
    }
    let r = match result {
        Ok(r) => r,
        Err(e @ IdentError::NotConverged { .. }) => {
            // The last accepted iterate goes with the error (`last_dynamics`, `last_pid`): what a
            // report of a run that did not converge shows.
            let err = cloe_err(e);
            if let (Ok(cons), false) = (Consistent::new(&guess), last.is_empty()) {
                let a = cons.params(&last);
                let v = err.value(py);
                v.setattr(
                    "last_dynamics",
                    Py::new(py, PyDynamicParams { inner: a.dynamics })?,
                )?;
                v.setattr("last_pid", (a.pid.lp, a.pid.li, a.pid.ld))?;
            }
            return Err(err);
        }
        Err(e) => return Err(cloe_err(e)),
    };
    let d = PyDict::new(py);
    d.set_item(
        "dynamics",
        Py::new(
            py,
            PyDynamicParams {
                inner: r.params.dynamics,
            },
        )?,
    )?;
    let g = r.params.pid;
    d.set_item("pid", (g.lp, g.li, g.ld))?;
    d.set_item("identified", r.identified)?;
    d.set_item("unidentifiable", r.unidentifiable)?;
    let aliases: Vec<AliasTuple> = r
        .aliases
        .into_iter()
        .map(|a| (a.name, a.like, a.residual))
        .collect();
    d.set_item("aliases", aliases)?;
    d.set_item("relative_std", out1(py, &r.relative_std))?;
    d.set_item("relative_std_wald", out1(py, &r.relative_std_wald))?;
    d.set_item("estimator_map", out_dmatrix(py, &r.estimator_map))?;
    d.set_item("residual_weight", out1(py, &r.residual_weight))?;
    d.set_item(
        "residual_whitening",
        crate::convert::out_rows::<6>(py, &r.residual_whitening),
    )?;
    d.set_item("residual", out_rows6(py, &r.residual))?;
    d.set_item("poorly_identified", r.poorly_identified)?;
    d.set_item("rms_before", out1(py, r.rms_before.as_slice()))?;
    d.set_item("rms_after", out1(py, r.rms_after.as_slice()))?;
    d.set_item("cost_history", out1(py, &r.cost_history))?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("converged_by", r.converged_by.as_str())?;
    d.set_item("reduced_chi2", r.reduced_chi2)?;
    d.set_item("inexact_friction_ticks", r.inexact_friction_ticks)?;
    d.set_item("simulations", r.simulations)?;
    d.set_item("psi", out1(py, &r.psi))?;
    Ok(d)
}

/// Names of the quantities CLOE estimates (the consistent parameters ψ: "platform.m",
/// "platform.Sxx", …, "wrench1.Iz", "link1.It", "fc1", "fv1", "lp", "li", "ld").
#[pyfunction]
pub(crate) fn cloe_parameter_names() -> Vec<String> {
    Consistent::names()
}

/// The documented simulated truth shaped like Table 5.2 (`rss6_ident::table_5_2_truth`):
/// (DynamicParams, (l_p, l_i, l_d)).
#[pyfunction]
pub(crate) fn table_5_2_truth_params() -> (PyDynamicParams, (f64, f64, f64)) {
    let a = table_5_2_truth();
    (
        PyDynamicParams { inner: a.dynamics },
        (a.pid.lp, a.pid.li, a.pid.ld),
    )
}

/// The parameters of the loop with consistent ψ (43,) anchored at the guess (`dp`, `pid`): ψ ↦
/// (DynamicParams, (l_p, l_i, l_d)); with `psi` None, ψ of the guess.
#[pyfunction]
#[pyo3(signature = (dp, pid, psi=None))]
pub(crate) fn cloe_psi<'py>(
    py: Python<'py>,
    dp: &PyDynamicParams,
    pid: (f64, f64, f64),
    psi: Option<Vec<f64>>,
) -> PyResult<PsiAndParams<'py>> {
    let guess = LoopParams {
        dynamics: dp.inner,
        pid: pid_gains(pid),
    };
    let cons = Consistent::new(&guess).map_err(cloe_err)?;
    let p: Vec<f64> = match psi {
        Some(p) if p.len() == rss6_ident::N_PSI => p,
        Some(p) => {
            return Err(shape(format!(
                "psi must have {} entries, got {}",
                rss6_ident::N_PSI,
                p.len()
            )))
        }
        None => cons.psi(&guess).map_err(cloe_err)?.to_vec(),
    };
    if p.iter().any(|v| !v.is_finite()) {
        return Err(invalid("psi must be finite"));
    }
    let a = cons.params(&p);
    Ok((
        out1(py, &p),
        PyDynamicParams { inner: a.dynamics },
        (a.pid.lp, a.pid.li, a.pid.ld),
    ))
}
